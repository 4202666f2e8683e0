//! Issue 42, probe items 1 and 8: a run directory has one writer at a time, and no file is
//! ever left half-written.
//!
//! - Two `eval`s given one `--out` used to interleave their records, both exiting 0, and
//!   the run was lost. Now the second is refused, naming the first's pid, and the first
//!   run ends whole.
//! - `report.html` (like `tables.md` and `summary.json`) was truncated, then written: a
//!   writer stopped between the two (here by the file-size limit, as a full disk would)
//!   left an empty or cut file where a good one was. Now the old file stays.

use std::path::Path;
use std::process::{Command, Stdio};

const ROOT: &str = env!("CARGO_MANIFEST_DIR");
const BIN: &str = env!("CARGO_BIN_EXE_thorarena");

fn eval(out: &Path, extra: &[&str]) -> Command {
    let mut c = Command::new(BIN);
    c.args(["eval", "--dataset", &format!("{ROOT}/data/sample")])
        .args(["--policy", "balance", "--workers", "1", "--envs", "1"])
        .args(["--out", out.to_str().unwrap()])
        .args(extra)
        .stdout(Stdio::null())
        .stderr(Stdio::piped());
    c
}

#[test]
fn a_second_writer_of_a_run_is_refused_and_the_first_run_ends_whole() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("run");
    let first = eval(&out, &[]).spawn().unwrap();
    // The first writer has the directory once its pid is in the lock file.
    let lock = out.join(thorarena::eval::results::LOCK_FILE);
    let pid = first.id().to_string();
    let t0 = std::time::Instant::now();
    while std::fs::read_to_string(&lock).ok().as_deref() != Some(pid.as_str()) {
        assert!(
            t0.elapsed().as_secs() < 60,
            "the first eval never took the lock"
        );
        std::thread::sleep(std::time::Duration::from_millis(5));
    }
    let second = eval(&out, &["--overwrite"]).output().unwrap();
    let first = first.wait_with_output().unwrap();
    assert!(
        first.status.success(),
        "{}",
        String::from_utf8_lossy(&first.stderr)
    );
    let refusal = String::from_utf8_lossy(&second.stderr);
    assert!(!second.status.success(), "the second writer ran: {refusal}");
    assert!(
        refusal.contains("being written by another thorarena process")
            && refusal.contains(&format!("pid {pid}")),
        "{refusal}"
    );
    // The first run is whole: every planned episode once.
    let header: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("run.json")).unwrap()).unwrap();
    let planned = header["sequences"].as_array().unwrap().len()
        * header["settings"].as_array().unwrap().len();
    let records = std::fs::read_to_string(out.join("episodes.jsonl")).unwrap();
    let mut keys: Vec<String> = records
        .lines()
        .map(|l| {
            let r: serde_json::Value = serde_json::from_str(l).unwrap();
            format!("{}/{}", r["sequence_id"], r["setting"])
        })
        .collect();
    keys.sort();
    keys.dedup();
    assert_eq!(records.lines().count(), planned);
    assert_eq!(keys.len(), planned);
}

#[test]
fn a_lock_held_by_a_library_writer_refuses_eval_and_merge() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("run");
    let run = thorarena::eval::results::RunDir::new(&out);
    let held = run.lock().unwrap();
    let refused = eval(&out, &[]).output().unwrap();
    assert!(!refused.status.success());
    let err = String::from_utf8_lossy(&refused.stderr);
    assert!(
        err.contains(&format!("pid {}", std::process::id())),
        "{err}"
    );
    drop(held);
    // Released with its holder: the same command now runs.
    let ran = eval(&out, &["--overwrite"]).output().unwrap();
    assert!(
        ran.status.success(),
        "{}",
        String::from_utf8_lossy(&ran.stderr)
    );
}

#[test]
fn a_report_stopped_mid_write_leaves_the_previous_report_whole() {
    let dir = tempfile::tempdir().unwrap();
    let run = dir.path().join("run");
    let ran = eval(&run, &["--settings", "no-force"]).output().unwrap();
    assert!(ran.status.success());
    let report = dir.path().join("report.html");
    let write_report = |limit_blocks: Option<u32>| {
        let cmd = format!(
            "{}exec {BIN} report {} --out {} --overwrite",
            limit_blocks
                .map(|b| format!("ulimit -f {b}; "))
                .unwrap_or_default(),
            run.display(),
            report.display()
        );
        Command::new("bash")
            .args(["-c", &cmd])
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .status()
            .unwrap()
    };
    assert!(write_report(None).success());
    let good = std::fs::read(&report).unwrap();
    assert!(good.len() > 64 * 1024, "report of {} bytes", good.len());
    // 16 blocks of 1 KiB: the writer is stopped (SIGXFSZ) part-way through the report.
    let cut = write_report(Some(16));
    assert!(
        !cut.success(),
        "the report fit the size limit: test nothing"
    );
    assert_eq!(
        std::fs::read(&report).unwrap(),
        good,
        "a writer stopped mid-way changed the report"
    );
}
