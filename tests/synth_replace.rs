//! `data synth --force` replaces a dataset only once its successor is complete: the new
//! one is written beside the old and swapped in, so a kill or a full disk at any moment
//! leaves the old dataset readable (`data info` works, its manifest unchanged), and a
//! replacement keeps the directory's files that were never the dataset's.

#[path = "prereq/mod.rs"]
mod prereq;

use std::path::Path;
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

const BIN: &str = env!("CARGO_BIN_EXE_thorarena");

fn thorarena(args: &[&str]) -> Output {
    Command::new(BIN).args(args).output().unwrap()
}

fn ok(o: &Output) {
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
}

/// `data synth --out DIR --per-task 1 --tasks clean_table`: a small dataset.
fn small_dataset(dir: &Path) {
    ok(&thorarena(&[
        "data",
        "synth",
        "--out",
        dir.to_str().unwrap(),
        "--per-task",
        "1",
        "--tasks",
        "clean_table",
    ]));
}

/// The entries of `parent` whose names say they are a synthesis's staging directory.
fn staging_left(parent: &Path) -> Vec<String> {
    std::fs::read_dir(parent)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.contains(".synth-"))
        .collect()
}

/// The old dataset is as it was: `data info` reads it and its manifest is `manifest`.
fn intact(ds: &Path, manifest: &[u8]) {
    let info = thorarena(&["data", "info", ds.to_str().unwrap()]);
    ok(&info);
    assert!(
        String::from_utf8_lossy(&info.stdout).contains("1 sequence,"),
        "{}",
        String::from_utf8_lossy(&info.stdout)
    );
    assert_eq!(
        std::fs::read(ds.join("manifest.json")).unwrap(),
        manifest,
        "the old manifest changed"
    );
}

#[test]
fn a_synth_killed_mid_way_leaves_the_old_dataset_readable() {
    let tmp = tempfile::tempdir().unwrap();
    let ds = tmp.path().join("ds");
    small_dataset(&ds);
    let manifest = std::fs::read(ds.join("manifest.json")).unwrap();
    // 600 sequences take a minute or more: killed after 1 s, mid-way.
    let mut child = Command::new(BIN)
        .args([
            "data",
            "synth",
            "--out",
            ds.to_str().unwrap(),
            "--per-task",
            "100",
            "--force",
        ])
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    std::thread::sleep(Duration::from_secs(1));
    assert!(
        child.try_wait().unwrap().is_none(),
        "the synthesis ended within 1 s"
    );
    child.kill().unwrap();
    let o = child.wait_with_output().unwrap();
    let progress = String::from_utf8_lossy(&o.stderr);
    assert!(
        progress.contains("sequences written"),
        "no progress before the kill: {progress}"
    );
    intact(&ds, &manifest);
}

#[test]
fn a_replacement_keeps_the_directorys_other_files_and_leaves_nothing_beside_it() {
    let tmp = tempfile::tempdir().unwrap();
    let ds = tmp.path().join("ds");
    small_dataset(&ds);
    std::fs::write(ds.join("notes.txt"), "mine").unwrap();
    std::fs::write(ds.join("clean_table/notes.txt"), "mine too").unwrap();
    let o = thorarena(&[
        "data",
        "synth",
        "--out",
        ds.to_str().unwrap(),
        "--per-task",
        "2",
        "--tasks",
        "clean_table",
        "--force",
    ]);
    ok(&o);
    let info = thorarena(&["data", "info", ds.to_str().unwrap()]);
    ok(&info);
    assert!(String::from_utf8_lossy(&info.stdout).contains("2 sequences,"));
    assert_eq!(std::fs::read(ds.join("notes.txt")).unwrap(), b"mine");
    assert_eq!(
        std::fs::read(ds.join("clean_table/notes.txt")).unwrap(),
        b"mine too"
    );
    assert_eq!(staging_left(tmp.path()), Vec::<String>::new());
}

/// Unmounts the tmpfs when the test ends, passed or failed.
struct Mounted<'a>(&'a Path);

impl Drop for Mounted<'_> {
    fn drop(&mut self) {
        let _ = Command::new("umount").arg(self.0).status();
    }
}

#[test]
fn a_synth_into_a_full_file_system_fails_and_keeps_the_old_dataset() {
    const TEST: &str =
        "synth_replace::a_synth_into_a_full_file_system_fails_and_keeps_the_old_dataset";
    // SAFETY: geteuid has no preconditions.
    if unsafe { libc::geteuid() } != 0 {
        prereq::skip(TEST, "mounting a small tmpfs needs root");
        return;
    }
    let tmp = tempfile::tempdir().unwrap();
    let mnt = tmp.path().join("mnt");
    std::fs::create_dir(&mnt).unwrap();
    let mounted = Command::new("mount")
        .args(["-t", "tmpfs", "-o", "size=2m", "tmpfs"])
        .arg(&mnt)
        .output();
    match mounted {
        Ok(o) if o.status.success() => {}
        Ok(o) => {
            prereq::skip(
                TEST,
                &format!(
                    "mount -t tmpfs failed: {}",
                    String::from_utf8_lossy(&o.stderr)
                ),
            );
            return;
        }
        Err(e) => {
            prereq::skip(TEST, &format!("mount could not run: {e}"));
            return;
        }
    }
    let _unmount = Mounted(&mnt);
    let ds = mnt.join("ds");
    small_dataset(&ds);
    let manifest = std::fs::read(ds.join("manifest.json")).unwrap();
    // 12 sequences of about 0.22 MB each: more than the 2 MiB left.
    let started = Instant::now();
    let o = thorarena(&[
        "data",
        "synth",
        "--out",
        ds.to_str().unwrap(),
        "--per-task",
        "12",
        "--tasks",
        "clean_table",
        "--force",
    ]);
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success(), "the synthesis fit in 2 MiB: {e}");
    assert!(!e.contains("panicked"), "{e}");
    assert!(
        e.contains("No space left on device") && e.contains("is as it was"),
        "{e}"
    );
    assert!(started.elapsed() < Duration::from_secs(120));
    intact(&ds, &manifest);
    assert_eq!(staging_left(&mnt), Vec::<String>::new());
}
