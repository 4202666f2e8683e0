//! Nothing is written through a symbolic link planted under a name ThorArena writes: in a
//! shared directory another user could link `episodes.jsonl`, `.writer.lock` or a report
//! to a file of ours. `eval` refuses such a run directory naming the link and leaves the
//! link's target as it was; `report` replaces a link at its destination with its own file
//! (the temporary files behind it are created exclusively: `files::atomic_file`'s unit
//! tests plant those, whose names hold the writer's pid).

use std::path::Path;
use std::process::{Command, Output};

const BIN: &str = env!("CARGO_BIN_EXE_thorarena");
const SAMPLE: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/data/sample");

fn eval(out: &Path) -> Output {
    Command::new(BIN)
        .args([
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
            out.to_str().unwrap(),
        ])
        .output()
        .unwrap()
}

/// A file standing for one the planter wants overwritten.
fn victim(dir: &Path, name: &str) -> std::path::PathBuf {
    let path = dir.join(name);
    std::fs::write(&path, b"not yours to write").unwrap();
    path
}

fn assert_untouched(path: &Path) {
    assert_eq!(std::fs::read(path).unwrap(), b"not yours to write");
}

#[test]
fn eval_refuses_a_planted_lock_or_episode_log_and_writes_nothing_through_it() {
    for planted in [".writer.lock", "episodes.jsonl"] {
        let dir = tempfile::tempdir().unwrap();
        let target = victim(dir.path(), "someone-elses-file");
        let run = dir.path().join("run");
        std::fs::create_dir(&run).unwrap();
        std::os::unix::fs::symlink(&target, run.join(planted)).unwrap();
        let o = eval(&run);
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(
            !o.status.success(),
            "{planted}: the run went through: {err}"
        );
        assert!(!err.contains("panicked"), "{err}");
        assert!(
            err.contains(planted) && err.contains("is a symbolic link"),
            "{planted}: {err}"
        );
        assert_untouched(&target);
    }
}

/// As root, the real case: another user (`nobody`, through `setpriv`) plants the links in a
/// world-writable sticky directory, and root's run refuses them. Not root: counted as
/// skipped, with the reason (under `CI=true` it fails — CI runs as root).
#[test]
fn a_link_another_user_planted_is_refused_as_root() {
    if unsafe { libc::geteuid() } != 0 || !Path::new("/usr/bin/setpriv").exists() {
        let why = "SKIPPED: planting as another user needs root and /usr/bin/setpriv";
        assert!(std::env::var("CI").as_deref() != Ok("true"), "{why}");
        eprintln!("{why}");
        return;
    }
    use std::os::unix::fs::PermissionsExt;
    let dir = tempfile::tempdir().unwrap();
    std::fs::set_permissions(dir.path(), std::fs::Permissions::from_mode(0o755)).unwrap();
    let target = victim(dir.path(), "roots-file");
    std::fs::set_permissions(&target, std::fs::Permissions::from_mode(0o600)).unwrap();
    let shared = dir.path().join("shared");
    std::fs::create_dir(&shared).unwrap();
    std::fs::set_permissions(&shared, std::fs::Permissions::from_mode(0o1777)).unwrap();
    let run = shared.join("run");
    let planted = Command::new("/usr/bin/setpriv")
        .args([
            "--reuid=65534",
            "--regid=65534",
            "--clear-groups",
            "sh",
            "-c",
        ])
        .arg(r#"mkdir "$1" && ln -s "$2" "$1/episodes.jsonl" && ln -s "$2" "$1/.writer.lock""#)
        .args(["sh", run.to_str().unwrap(), target.to_str().unwrap()])
        .output()
        .unwrap();
    assert!(
        planted.status.success(),
        "planting as nobody: {}",
        String::from_utf8_lossy(&planted.stderr)
    );
    let o = eval(&run);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success(), "root's run went through: {err}");
    assert!(err.contains("is a symbolic link"), "{err}");
    assert_untouched(&target);
}

#[test]
fn report_replaces_a_planted_destination_link_instead_of_writing_through_it() {
    let dir = tempfile::tempdir().unwrap();
    let run = dir.path().join("run");
    let o = eval(&run);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let shared = dir.path().join("shared");
    std::fs::create_dir(&shared).unwrap();
    let html_target = victim(dir.path(), "victim.html");
    let md_target = victim(dir.path(), "victim.md");
    std::os::unix::fs::symlink(&html_target, shared.join("r.html")).unwrap();
    std::os::unix::fs::symlink(&md_target, shared.join("r.md")).unwrap();
    let o = Command::new(BIN)
        .args([
            "report",
            run.to_str().unwrap(),
            "--out",
            shared.join("r.html").to_str().unwrap(),
            "--overwrite",
        ])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert_untouched(&html_target);
    assert_untouched(&md_target);
    for name in ["r.html", "r.md"] {
        let meta = shared.join(name).symlink_metadata().unwrap();
        assert!(meta.file_type().is_file(), "{name} is still a link");
    }
    assert!(std::fs::read_to_string(shared.join("r.html"))
        .unwrap()
        .contains("<html"));
}
