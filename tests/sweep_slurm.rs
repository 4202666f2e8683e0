//! A sweep through a real Slurm: the test starts a single-node cluster of its own
//! (`tests/slurm/start.sh`: munged, slurmctld, slurmd; Debian's packages, installed when
//! missing and run as root), submits a 4-task sample sweep with
//! `thorarena sweep slurm --submit --wait` from a sweep directory whose name holds an
//! sbatch pattern and shell syntax, checks that `collect` equals the same sweep run
//! locally, and stops the daemons it started by their pids. Without root (the
//! daemons and the install need it) it is recorded as skipped; in CI it must run.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

mod prereq;

const ROOT: &str = env!("CARGO_MANIFEST_DIR");
const BIN: &str = env!("CARGO_BIN_EXE_thorarena");
const TEST: &str = "sweep_slurm::a_sweep_on_slurm_equals_the_local_run";

/// The running test cluster; stopped (by its recorded pids) when dropped, also on panic.
struct Cluster {
    state: PathBuf,
    conf: String,
}

impl Drop for Cluster {
    fn drop(&mut self) {
        let _ = Command::new("bash")
            .arg(Path::new(ROOT).join("tests/slurm/stop.sh"))
            .arg(&self.state)
            .status();
    }
}

/// Starts the cluster, or `None` after recording why it cannot run here.
fn start(state: &Path) -> Option<Cluster> {
    let out = Command::new("bash")
        .arg(Path::new(ROOT).join("tests/slurm/start.sh"))
        .arg(state)
        .output()
        .expect("bash runs");
    let stderr = String::from_utf8_lossy(&out.stderr);
    if out.status.code() == Some(3) {
        prereq::skip(TEST, stderr.trim());
        return None;
    }
    assert!(out.status.success(), "starting Slurm failed:\n{stderr}");
    let stdout = String::from_utf8_lossy(&out.stdout);
    let conf = stdout
        .lines()
        .find_map(|l| l.strip_prefix("export SLURM_CONF="))
        .unwrap_or_else(|| panic!("start.sh printed no SLURM_CONF: {stdout}"))
        .to_string();
    Some(Cluster {
        state: state.to_path_buf(),
        conf,
    })
}

fn ok(o: Output) -> Output {
    assert!(
        o.status.success(),
        "stdout:\n{}\nstderr:\n{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    );
    o
}

fn records(path: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_to_string(path)
        .unwrap()
        .lines()
        .map(str::to_string)
        .collect();
    v.sort();
    v
}

#[test]
fn a_sweep_on_slurm_equals_the_local_run() {
    let tmp = tempfile::tempdir().unwrap();
    let Some(cluster) = start(&tmp.path().join("slurm-state")) else {
        return;
    };
    let spec = tmp.path().join("spec.toml");
    std::fs::write(
        &spec,
        format!(
            "datasets = [\"{ROOT}/data/sample\"]\nsettings = [\"no-force\", \"force\"]\nshards = 2\n[[policy]]\npolicy = \"balance\"\n"
        ),
    )
    .unwrap();
    // `%j` in the directory is sbatch's job-id pattern unless written `%%j`, and `$HOME`
    // is shell syntax: the logs must land in this very directory.
    let (on_slurm, local) = (tmp.path().join("slurm-%j-$HOME"), tmp.path().join("local"));
    for dir in [&on_slurm, &local] {
        ok(Command::new(BIN)
            .args(["sweep", "plan"])
            .arg(&spec)
            .arg("--out")
            .arg(dir)
            .output()
            .unwrap());
    }
    let submitted = ok(Command::new(BIN)
        .args(["sweep", "slurm"])
        .arg(&on_slurm)
        .args(["--cpus-per-task", "1", "--submit", "--wait"])
        .env("SLURM_CONF", &cluster.conf)
        .output()
        .unwrap());
    let said = String::from_utf8_lossy(&submitted.stdout);
    assert!(said.contains("--array=0-3"), "{said}");
    assert!(said.contains("all 4 tasks done"), "{said}");
    for i in 0..4 {
        let log = on_slurm.join(format!("slurm/logs/task-{i}.log"));
        let text = std::fs::read_to_string(&log).unwrap_or_default();
        assert!(
            text.contains(&format!("task {i}: done")),
            "{}: {text}",
            log.display()
        );
    }
    ok(Command::new(BIN)
        .args(["sweep", "run"])
        .arg(&local)
        .args(["--jobs", "2"])
        .output()
        .unwrap());
    for dir in [&on_slurm, &local] {
        ok(Command::new(BIN)
            .args(["sweep", "collect"])
            .arg(dir)
            .output()
            .unwrap());
    }
    for c in 0..2 {
        let cell = format!("cells/{c:06}/episodes.jsonl");
        let (a, b) = (records(&on_slurm.join(&cell)), records(&local.join(&cell)));
        assert_eq!(a.len(), 12);
        assert!(a == b, "cell {c}: Slurm and local records differ");
    }
    // Submitting again finds nothing left to do.
    let again = ok(Command::new(BIN)
        .args(["sweep", "slurm"])
        .arg(&on_slurm)
        .args(["--submit", "--wait"])
        .env("SLURM_CONF", &cluster.conf)
        .output()
        .unwrap());
    assert!(String::from_utf8_lossy(&again.stdout).contains("nothing to submit"));
    drop(cluster);
}
