//! `sweep slurm` and `sweep k8s`: job scripts and manifests for the cluster engines.

use super::{K8sArgs, SlurmArgs};
use anyhow::{bail, Context};
use std::path::{Path, PathBuf};
use std::process::Command;
use thorarena::sweep::{census, compact_ranges, Plan};
pub(super) fn absolute(p: &Path) -> anyhow::Result<PathBuf> {
    std::fs::canonicalize(p).with_context(|| format!("{} does not exist", p.display()))
}

pub(super) fn slurm(args: &SlurmArgs) -> anyhow::Result<()> {
    let plan = Plan::load(&args.dir)?;
    let dir = absolute(&args.dir)?;
    if args.cpus_per_task == 0 {
        bail!("--cpus-per-task must be at least 1");
    }
    let not_done = census(&dir, &plan)?.not_done();
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
    let sdir = dir.join("slurm");
    let logs = sdir.join("logs");
    std::fs::create_dir_all(&logs).with_context(|| format!("creating {}", logs.display()))?;
    let script = sdir.join("sweep.sbatch");
    std::fs::write(&script, &s).with_context(|| format!("writing {}", script.display()))?;
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
        let c = census(&dir, &plan)?;
        bail!(
            "sbatch {}: {status}; {} task(s) failed, {} not done (`thorarena sweep status {}`)",
            if args.wait { "--wait" } else { "" },
            c.failed.len(),
            c.not_done().len(),
            dir.display()
        );
    }
    if args.wait {
        let c = census(&dir, &plan)?;
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

/// A YAML scalar: JSON's string syntax is YAML's double-quoted style.
pub(super) fn yaml_str(s: &str) -> String {
    serde_json::to_string(s).expect("a string serializes")
}

/// The Indexed Job manifest running every task of `plan` (done ones are skipped by
/// `sweep task` itself, so the manifest never needs regenerating).
pub(super) fn k8s_manifest(
    plan: &Plan,
    dir: &Path,
    image: &str,
    claim: &str,
    sub_path: Option<&str>,
    parallelism: usize,
    cpus: usize,
) -> String {
    let name = format!(
        "thorarena-sweep-{}",
        &sha_hex(dir.display().to_string().as_bytes())[..10]
    );
    let n = plan.tasks.len();
    let mount = dir.display().to_string();
    let mut y = String::new();
    y += "# ThorArena sweep as a Kubernetes Indexed Job: pod I runs `thorarena sweep task DIR`\n";
    y += "# with JOB_COMPLETION_INDEX = I. The claim holds the sweep directory, mounted at the\n";
    y += "# same absolute path as where it was planned (datasets likewise).\n";
    y += "apiVersion: batch/v1\nkind: Job\nmetadata:\n";
    y += &format!("  name: {name}\n");
    y += "spec:\n  completionMode: Indexed\n";
    y += &format!("  completions: {n}\n  parallelism: {parallelism}\n");
    y += &format!("  backoffLimitPerIndex: 2\n  maxFailedIndexes: {n}\n");
    y += "  template:\n    spec:\n      restartPolicy: Never\n      containers:\n";
    y += "        - name: task\n";
    y += &format!("          image: {}\n", yaml_str(image));
    y += &format!(
        "          command: [{}, {}, {}, {}, {}, {}]\n",
        yaml_str("thorarena"),
        yaml_str("sweep"),
        yaml_str("task"),
        yaml_str(&mount),
        yaml_str("--workers"),
        yaml_str(&cpus.to_string())
    );
    y += &format!(
        "          resources:\n            requests:\n              cpu: {}\n",
        yaml_str(&cpus.to_string())
    );
    y += "          volumeMounts:\n            - name: sweep\n";
    y += &format!("              mountPath: {}\n", yaml_str(&mount));
    if let Some(sp) = sub_path {
        y += &format!("              subPath: {}\n", yaml_str(sp));
    }
    y += "      volumes:\n        - name: sweep\n          persistentVolumeClaim:\n";
    y += &format!("            claimName: {}\n", yaml_str(claim));
    y
}

pub(super) fn sha_hex(bytes: &[u8]) -> String {
    use sha2::{Digest, Sha256};
    Sha256::digest(bytes)
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect()
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
        &dir,
        &args.image,
        &args.claim,
        args.sub_path.as_deref(),
        parallelism,
        args.cpus_per_task,
    );
    let kdir = dir.join("k8s");
    std::fs::create_dir_all(&kdir).with_context(|| format!("creating {}", kdir.display()))?;
    let path = kdir.join("job.yaml");
    std::fs::write(&path, y).with_context(|| format!("writing {}", path.display()))?;
    println!(
        "wrote {} ({} tasks); run with: kubectl apply -f {}",
        path.display(),
        plan.tasks.len(),
        path.display()
    );
    Ok(())
}
