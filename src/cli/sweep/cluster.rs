//! `sweep slurm` and `sweep k8s`: job scripts and manifests for the cluster engines.

use super::{K8sArgs, SlurmArgs};
use anyhow::{bail, Context};
use std::path::{Path, PathBuf};
use std::process::Command;
use thorarena::sweep::CheckedCensus;
use thorarena::sweep::{compact_ranges, k8s_manifest, K8sRequest, Plan};
pub(super) fn absolute(p: &Path) -> anyhow::Result<PathBuf> {
    std::fs::canonicalize(p).with_context(|| format!("{} does not exist", p.display()))
}

pub(super) fn slurm(args: &SlurmArgs) -> anyhow::Result<()> {
    let plan = Plan::load(&args.dir)?;
    let dir = absolute(&args.dir)?;
    if args.cpus_per_task == 0 {
        bail!("--cpus-per-task must be at least 1");
    }
    let not_done = CheckedCensus::of(&dir, &plan)?.not_done();
    if not_done.is_empty() {
        println!("every task of {} is done: nothing to submit", dir.display());
        return Ok(());
    }
    let exe = match &args.thorarena {
        Some(p) => absolute(p)?,
        None => std::env::current_exe()?,
    };
    let mut array = compact_ranges(&not_done);
    if let Some(k) = args.max_parallel {
        if k == 0 {
            bail!("--max-parallel must be at least 1");
        }
        array += &format!("%{k}");
    }
    // Checked before anything is written: a value sbatch cannot read literally is refused.
    let s = thorarena::sweep::sbatch_script(&thorarena::sweep::SbatchRequest {
        dir: &dir,
        thorarena: &exe,
        array: &array,
        cpus_per_task: args.cpus_per_task,
        partition: args.partition.as_deref(),
        time: args.time.as_deref(),
    })?;
    let script = thorarena::sweep::write_sbatch_script(&dir, &s)?;
    println!(
        "wrote {} ({} tasks: --array={array})",
        script.display(),
        not_done.len()
    );
    if !args.submit {
        println!("submit with: sbatch {}", script.display());
        return Ok(());
    }
    let mut cmd = Command::new("sbatch");
    if args.wait {
        cmd.arg("--wait");
    }
    let status = cmd
        .arg(&script)
        .status()
        .context("running sbatch (is Slurm's client installed and configured?)")?;
    if !status.success() {
        let c = CheckedCensus::of(&dir, &plan)?;
        bail!(
            "sbatch {}: {status}; {} task(s) failed, {} not done (`thorarena sweep status {}`)",
            if args.wait { "--wait" } else { "" },
            c.census.failed.len(),
            c.not_done().len(),
            dir.display()
        );
    }
    if args.wait {
        let c = CheckedCensus::of(&dir, &plan)?;
        if !c.not_done().is_empty() {
            bail!(
                "the array finished with {} task(s) not done: {}",
                c.not_done().len(),
                compact_ranges(&c.not_done())
            );
        }
        println!("all {} tasks done", plan.tasks.len());
    }
    Ok(())
}

pub(super) fn k8s(args: &K8sArgs) -> anyhow::Result<()> {
    let plan = Plan::load(&args.dir)?;
    let dir = absolute(&args.dir)?;
    if args.cpus_per_task == 0 {
        bail!("--cpus-per-task must be at least 1");
    }
    let parallelism = args.parallelism.unwrap_or(plan.tasks.len());
    if parallelism == 0 {
        bail!("--parallelism must be at least 1");
    }
    let y = k8s_manifest(
        &plan,
        &K8sRequest {
            dir: &dir,
            image: &args.image,
            claim: &args.claim,
            sub_path: args.sub_path.as_deref(),
            parallelism,
            cpus_per_task: args.cpus_per_task,
        },
    );
    let path = thorarena::sweep::write_k8s_manifest(&dir, &y)?;
    println!(
        "wrote {} ({} tasks); run with: kubectl apply -f {}",
        path.display(),
        plan.tasks.len(),
        path.display()
    );
    Ok(())
}
