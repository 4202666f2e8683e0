//! The directories a command makes inside its output directory — a run's `traces/`, a
//! report's `<stem>-figures/`, `data check`'s `rollout-NAME/`, the leaderboard's
//! `runs/NAME-ENGINE` — are never entered through a link planted under their name, nor
//! when another user's directory stands there: the command fails naming it, and the
//! link's target is untouched. (Another user in a shared directory can plant either; a
//! directory of theirs they could swap for a link at any moment.)

#[path = "prereq/mod.rs"]
mod prereq;

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

const BIN: &str = env!("CARGO_BIN_EXE_thorarena");
const SAMPLE: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/data/sample");

fn thorarena(args: &[&str]) -> Output {
    Command::new(BIN).args(args).output().unwrap()
}

/// A directory standing for someone else's (`victim`) with a file in it, and a link to it
/// planted at `at`.
fn plant(at: &Path, victim: &Path) {
    std::fs::create_dir_all(victim).unwrap();
    std::fs::write(victim.join("theirs.txt"), b"theirs").unwrap();
    std::fs::create_dir_all(at.parent().unwrap()).unwrap();
    std::os::unix::fs::symlink(victim, at).unwrap();
}

/// The command failed, naming the link, and wrote nothing into its target.
fn refused(o: &Output, link: &Path, victim: &Path) {
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success(), "went through the link: {e}");
    assert!(!e.contains("panicked"), "{e}");
    assert!(
        e.contains(&link.display().to_string()) && e.contains("is a symbolic link"),
        "{e}"
    );
    let inside: Vec<PathBuf> = std::fs::read_dir(victim)
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    assert_eq!(
        inside,
        vec![victim.join("theirs.txt")],
        "written through the link"
    );
}

fn eval_with_trace(out: &Path) -> Output {
    thorarena(&[
        "eval",
        "--dataset",
        SAMPLE,
        "--policy",
        "hold",
        "--settings",
        "no-force",
        "--trace",
        "push_chair/push_chair_000",
        "--out",
        out.to_str().unwrap(),
    ])
}

#[test]
fn a_runs_traces_directory_planted_as_a_link_is_not_entered() {
    let tmp = tempfile::tempdir().unwrap();
    let (out, victim) = (tmp.path().join("run3"), tmp.path().join("priv"));
    plant(&out.join("traces"), &victim);
    refused(&eval_with_trace(&out), &out.join("traces"), &victim);
}

#[test]
fn a_reports_figures_directory_planted_as_a_link_is_not_entered() {
    let tmp = tempfile::tempdir().unwrap();
    let run = tmp.path().join("run");
    let o = thorarena(&[
        "eval",
        "--dataset",
        SAMPLE,
        "--policy",
        "hold",
        "--settings",
        "no-force",
        "--out",
        run.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let (page, victim) = (tmp.path().join("shared/cmp.html"), tmp.path().join("priv"));
    let figures = tmp.path().join("shared/cmp-figures");
    plant(&figures, &victim);
    let o = thorarena(&[
        "report",
        run.to_str().unwrap(),
        "--out",
        page.to_str().unwrap(),
    ]);
    refused(&o, &figures, &victim);
}

#[test]
fn a_data_checks_rollout_directory_planted_as_a_link_is_not_entered() {
    let tmp = tempfile::tempdir().unwrap();
    let (out, victim) = (tmp.path().join("chk3"), tmp.path().join("priv/rollout"));
    let link = out.join("rollout-replay");
    plant(&link, &victim);
    let o = thorarena(&[
        "data",
        "check",
        SAMPLE,
        "--rollout",
        "replay",
        "--out",
        out.to_str().unwrap(),
    ]);
    refused(&o, &link, &victim);
}

#[test]
fn a_leaderboard_run_directory_planted_as_a_link_is_not_entered() {
    let tmp = tempfile::tempdir().unwrap();
    let (out, victim) = (tmp.path().join("board"), tmp.path().join("priv/run"));
    let link = out.join("runs/hold-rapier");
    plant(&link, &victim);
    let o = thorarena(&[
        "leaderboard",
        "--policy",
        "hold",
        "--engines",
        "rapier",
        "--per-task",
        "1",
        "--dataset",
        SAMPLE,
        "--out",
        out.to_str().unwrap(),
    ]);
    refused(&o, &link, &victim);
}

#[test]
fn another_users_directory_in_place_of_traces_is_not_entered() {
    // SAFETY: geteuid has no preconditions.
    if unsafe { libc::geteuid() } != 0 {
        prereq::skip(
            "planted_directories::another_users_directory_in_place_of_traces_is_not_entered",
            "making a directory another user owns needs root",
        );
        return;
    }
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("run3");
    let traces = out.join("traces");
    std::fs::create_dir_all(&traces).unwrap();
    // SAFETY: a valid NUL-terminated path; 65534 is `nobody`.
    let path = std::ffi::CString::new(traces.to_str().unwrap()).unwrap();
    assert_eq!(unsafe { libc::chown(path.as_ptr(), 65534, 65534) }, 0);
    let o = eval_with_trace(&out);
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success(), "{e}");
    assert!(e.contains("is another user's directory (uid 65534"), "{e}");
    assert_eq!(std::fs::read_dir(&traces).unwrap().count(), 0);
}
