//! Every file the binary reads is read bounded, as a regular file only: a profile given
//! with `--profile`, a data directory's `robot.toml`, a run's `run.json`,
//! `episodes.jsonl` and `summary.json` (for `report`, `merge` and `eval --resume`) and
//! the manifest `data synth --force` would replace, each as a link to `/dev/zero` and as
//! a FIFO, is refused at once with a message naming the file and what it is — never read
//! until memory gives out, never waited on.

use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

const BIN: &str = env!("CARGO_BIN_EXE_thorarena");
const DATA: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/data");
const SAMPLE: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/data/sample");

/// Long enough for a slow machine to start and refuse, far shorter than a read of
/// `/dev/zero` takes to fill memory or a FIFO to be given up on.
const LIMIT: Duration = Duration::from_secs(20);

/// `thorarena args…` in `cwd` with `envs`, killed (and the test failed) after [`LIMIT`].
fn thorarena_within(cwd: &Path, args: &[&str], envs: &[(&str, &Path)]) -> Output {
    let mut child = Command::new(BIN)
        .current_dir(cwd)
        .args(args)
        .envs(envs.iter().map(|(k, v)| (k, v)))
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let started = Instant::now();
    while child.try_wait().unwrap().is_none() {
        if started.elapsed() > LIMIT {
            child.kill().unwrap();
            let o = child.wait_with_output().unwrap();
            panic!(
                "{args:?} still running after {LIMIT:?}: {}",
                String::from_utf8_lossy(&o.stderr)
            );
        }
        std::thread::sleep(Duration::from_millis(50));
    }
    child.wait_with_output().unwrap()
}

/// What is planted in place of a file.
#[derive(Clone, Copy, Debug)]
enum Planted {
    /// A symbolic link to `/dev/zero`.
    Zero,
    /// A FIFO nobody writes.
    Fifo,
}

impl Planted {
    const BOTH: [Self; 2] = [Self::Zero, Self::Fifo];

    /// Replaces `path` (if there) with the planted thing.
    fn plant(self, path: &Path) {
        let _ = std::fs::remove_file(path);
        match self {
            Self::Zero => std::os::unix::fs::symlink("/dev/zero", path).unwrap(),
            Self::Fifo => {
                let c = std::ffi::CString::new(path.to_str().unwrap()).unwrap();
                // SAFETY: a valid NUL-terminated path; mkfifo does not retain it.
                assert_eq!(unsafe { libc::mkfifo(c.as_ptr(), 0o600) }, 0);
            }
        }
    }

    /// What the refusal calls it.
    fn said(self) -> &'static str {
        match self {
            Self::Zero => "it is a device, not a file",
            Self::Fifo => "it is a FIFO, not a file",
        }
    }
}

/// The command failed plainly, naming `file` and what was planted there.
fn refused(o: &Output, file: &Path, planted: Planted, what: &str) {
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success(), "{what} ({planted:?}): succeeded: {e}");
    assert!(!e.contains("panicked"), "{what}: a panic: {e}");
    let name = file.file_name().unwrap().to_str().unwrap();
    assert!(
        e.contains(name) && e.contains(planted.said()),
        "{what} ({planted:?}): {e}"
    );
}

#[test]
fn a_profile_that_is_a_device_or_fifo_is_refused_at_once() {
    let tmp = tempfile::tempdir().unwrap();
    for planted in Planted::BOTH {
        let profile = tmp.path().join("mine.toml");
        planted.plant(&profile);
        let o = thorarena_within(
            tmp.path(),
            &[
                "eval",
                "--dataset",
                SAMPLE,
                "--policy",
                "hold",
                "--profile",
                profile.to_str().unwrap(),
                "--out",
                "out",
            ],
            &[],
        );
        refused(&o, &profile, planted, "--profile");
    }
}

#[test]
fn a_data_directorys_robot_file_that_is_a_device_or_fifo_is_refused_at_once() {
    let tmp = tempfile::tempdir().unwrap();
    // A data directory (`THORARENA_DATA`) with the bundled robot, its robot.toml planted.
    let data = tmp.path().join("data");
    let robot = data.join("robots/g1_29dof");
    std::fs::create_dir_all(&robot).unwrap();
    for entry in std::fs::read_dir(Path::new(DATA).join("robots/g1_29dof")).unwrap() {
        let from = entry.unwrap().path();
        std::fs::copy(&from, robot.join(from.file_name().unwrap())).unwrap();
    }
    std::os::unix::fs::symlink(Path::new(DATA).join("profiles"), data.join("profiles")).unwrap();
    let toml = robot.join("robot.toml");
    for planted in Planted::BOTH {
        planted.plant(&toml);
        let o = thorarena_within(
            tmp.path(),
            &["data", "info", SAMPLE],
            &[("THORARENA_DATA", &data)],
        );
        refused(&o, &toml, planted, "robot.toml");
    }
}

/// A run of `hold` on one sample sequence, in `dir/run`.
fn one_run(dir: &Path) -> PathBuf {
    let o = thorarena_within(dir, &eval_args("run", false), &[]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    dir.join("run")
}

fn eval_args(out: &str, resume: bool) -> Vec<&str> {
    let mut args = vec![
        "eval",
        "--dataset",
        SAMPLE,
        "--policy",
        "hold",
        "--sequences",
        "clean_table_000",
        "--settings",
        "no-force",
        "--workers",
        "1",
        "--out",
        out,
    ];
    if resume {
        args.push("--resume");
    }
    args
}

#[test]
fn a_run_file_that_is_a_device_or_fifo_is_refused_by_report_merge_and_resume() {
    let tmp = tempfile::tempdir().unwrap();
    let run = one_run(tmp.path());
    // `summary.json` is read by `report` only: `merge` and `--resume` compute it again
    // and write it whole over whatever stands there.
    let cases: [(&str, &[&str]); 3] = [
        ("run.json", &["report", "merge", "resume"]),
        ("episodes.jsonl", &["report", "merge", "resume"]),
        ("summary.json", &["report"]),
    ];
    for (file, commands) in cases {
        for &command in commands {
            for planted in Planted::BOTH {
                let copy = tmp.path().join("planted");
                let _ = std::fs::remove_dir_all(&copy);
                std::fs::create_dir(&copy).unwrap();
                for entry in std::fs::read_dir(&run).unwrap() {
                    let from = entry.unwrap().path();
                    std::fs::copy(&from, copy.join(from.file_name().unwrap())).unwrap();
                }
                let path = copy.join(file);
                planted.plant(&path);
                let args: Vec<&str> = match command {
                    "report" => vec!["report", "planted", "--out", "report.html"],
                    "merge" => vec!["merge", "planted", "--out", "merged"],
                    _ => eval_args("planted", true),
                };
                let o = thorarena_within(tmp.path(), &args, &[]);
                refused(&o, &path, planted, &format!("{command} with {file}"));
                assert!(
                    std::fs::symlink_metadata(&path).is_ok_and(|m| !m.is_file()),
                    "{command} with {file}: written over"
                );
            }
        }
    }
}

#[test]
fn a_manifest_that_is_a_device_or_fifo_is_refused_by_synth_force() {
    let tmp = tempfile::tempdir().unwrap();
    let ds = tmp.path().join("ds");
    std::fs::create_dir(&ds).unwrap();
    let manifest = ds.join("manifest.json");
    for planted in Planted::BOTH {
        planted.plant(&manifest);
        let o = thorarena_within(
            tmp.path(),
            &["data", "synth", "--out", "ds", "--per-task", "1", "--force"],
            &[],
        );
        refused(&o, &manifest, planted, "synth --force");
    }
}
