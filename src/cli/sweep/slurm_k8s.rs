//! `sweep slurm` and `sweep k8s`: [`thorarena::campaign::sweep::slurm_array`] (the array's script
//! written, and submitted on request) and [`thorarena::campaign::sweep::write_k8s_job`].

use super::super::flags::as_flags;
use super::{K8sArgs, SlurmArgs};
use thorarena::campaign::sweep::{slurm_array, write_k8s_job, K8sRequest, SlurmArray};

pub(super) fn slurm(args: &SlurmArgs) -> anyhow::Result<()> {
    let array = SlurmArray {
        dir: &args.dir,
        thorarena: args.thorarena.as_deref(),
        this_binary: &std::env::current_exe()?,
        cpus_per_task: args.cpus_per_task,
        max_parallel: args.max_parallel,
        partition: args.partition.as_deref(),
        time: args.time.as_deref(),
        submit: args.submit,
        wait: args.wait,
    };
    slurm_array(&array, &mut |line| println!("{}", as_flags(line)))?;
    Ok(())
}

pub(super) fn k8s(args: &K8sArgs) -> anyhow::Result<()> {
    let written = write_k8s_job(&K8sRequest {
        dir: &args.dir,
        image: &args.image,
        claim: &args.claim,
        sub_path: args.sub_path.as_deref(),
        parallelism: args.parallelism,
        cpus_per_task: args.cpus_per_task,
    })?;
    println!("{written}");
    Ok(())
}
