//! The Kubernetes Indexed Job manifest of a sweep: pod I runs `thorarena sweep task DIR`
//! with `JOB_COMPLETION_INDEX = I`. Every value written into it is a YAML double-quoted
//! scalar (JSON's string syntax), so a path or an image name is data whatever it holds.

use super::cluster::absolute;
use super::plan::Plan;
use super::{at_least_one, SweepError};
use std::fmt::{self, Display, Formatter};
use std::path::{Path, PathBuf};

/// What the manifest runs and asks for, as a user gives it.
#[derive(Debug, Clone)]
pub struct K8sRequest<'a> {
    /// The sweep directory (made absolute: mounted at that same path in every pod).
    pub dir: &'a Path,
    /// The container image holding `thorarena`.
    pub image: &'a str,
    /// The PersistentVolumeClaim holding the sweep directory.
    pub claim: &'a str,
    /// The claim's sub-path to mount, if the sweep is not at its root.
    pub sub_path: Option<&'a str>,
    /// Pods at a time [default: every task].
    pub parallelism: Option<usize>,
    /// CPUs each pod requests (and `--workers` of its task).
    pub cpus_per_task: usize,
}

/// Where `sweep k8s` writes the manifest in sweep directory `dir`.
pub fn k8s_manifest_path(dir: &Path) -> PathBuf {
    dir.join("k8s").join("job.yaml")
}

/// The Indexed Job running every task of `plan` (done ones are skipped by `sweep task`
/// itself, so the manifest never needs regenerating). Its name is derived from the sweep
/// directory, so two sweeps in one namespace do not collide. `dir` is the request's
/// directory made absolute; `parallelism` its pods at a time, resolved.
fn k8s_manifest(plan: &Plan, r: &K8sRequest, dir: &Path, parallelism: usize) -> String {
    let name = format!(
        "thorarena-sweep-{}",
        &sha_hex(dir.display().to_string().as_bytes())[..10]
    );
    let n = plan.tasks.len();
    let mount = dir.display().to_string();
    let cpus = r.cpus_per_task.to_string();
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
    y += &format!("          image: {}\n", yaml_str(r.image));
    let command: Vec<String> = std::iter::once("thorarena".to_string())
        .chain(crate::campaign::own_command::sweep_task(
            &mount,
            Some(&cpus),
        ))
        .map(|w| yaml_str(&w))
        .collect();
    y += &format!("          command: [{}]\n", command.join(", "));
    y += &format!(
        "          resources:\n            requests:\n              cpu: {}\n",
        yaml_str(&cpus)
    );
    y += "          volumeMounts:\n            - name: sweep\n";
    y += &format!("              mountPath: {}\n", yaml_str(&mount));
    if let Some(sp) = r.sub_path {
        y += &format!("              subPath: {}\n", yaml_str(sp));
    }
    y += "      volumes:\n        - name: sweep\n          persistentVolumeClaim:\n";
    y += &format!("            claimName: {}\n", yaml_str(r.claim));
    y
}

/// A YAML scalar: JSON's string syntax is YAML's double-quoted style.
fn yaml_str(s: &str) -> String {
    serde_json::to_string(s).expect("a string serializes")
}

use crate::files::content_hash::sha256_hex as sha_hex;

/// Writes `manifest` (`k8s_manifest`'s, for sweep `dir`) to [`k8s_manifest_path`];
/// returns its path.
fn write_k8s_manifest(dir: &Path, manifest: &str) -> Result<PathBuf, SweepError> {
    let path = k8s_manifest_path(dir);
    super::task_dir::write_atomic_in_new_dir(&path, manifest.as_bytes(), None)?;
    Ok(path)
}

/// A written Kubernetes Indexed Job.
#[derive(Debug, Clone)]
pub struct WrittenK8sJob {
    /// The manifest.
    pub path: PathBuf,
    /// Tasks it runs.
    pub tasks: usize,
}

/// Writes the Indexed Job of `job`'s sweep (its options checked first).
pub fn write_k8s_job(job: &K8sRequest) -> Result<WrittenK8sJob, SweepError> {
    let plan = Plan::load(job.dir)?;
    let dir = absolute(job.dir)?;
    at_least_one(job.cpus_per_task, "option.cpus_per_task")?;
    let parallelism = at_least_one(
        job.parallelism.unwrap_or(plan.tasks.len()),
        "option.parallelism",
    )?;
    let manifest = k8s_manifest(&plan, job, &dir, parallelism);
    Ok(WrittenK8sJob {
        path: write_k8s_manifest(&dir, &manifest)?,
        tasks: plan.tasks.len(),
    })
}

impl Display for WrittenK8sJob {
    /// The line `sweep k8s` prints.
    fn fmt(&self, f: &mut Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "wrote {} ({} tasks); run with: kubectl apply -f {}",
            self.path.display(),
            self.tasks,
            self.path.display()
        )
    }
}
