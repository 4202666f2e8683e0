//! Issue 42, probe item 2: on a shared machine every user can run policy processes and
//! none can disturb another's. Before, iceoryx2's root `/tmp/iceoryx2` was made 0750 by
//! the first user (every later user's session failed with `InternalError`), and its
//! management segment in `/dev/shm` was world-writable (16 bytes from any user and every
//! later session failed with `UnableToGenerateUniqueNodeId`).
//!
//! Real users, not mocks: the test runs `thorarena` as two unprivileged uids through
//! `setpriv`, so it needs root (CI runs as root; elsewhere it is counted as skipped).

use std::path::Path;
use std::process::{Command, Output, Stdio};

mod prereq;

const ROOT: &str = env!("CARGO_MANIFEST_DIR");
const BIN: &str = env!("CARGO_BIN_EXE_thorarena");

/// Two uids no account uses, distinct per test process.
fn uids() -> (u32, u32) {
    let base = 40_000 + (std::process::id() % 10_000) * 2;
    (base, base + 1)
}

fn can_switch_users(test: &str) -> bool {
    // SAFETY: geteuid has no preconditions.
    if unsafe { libc::geteuid() } != 0 {
        prereq::skip(
            test,
            "needs root, to run thorarena as two other users (setpriv)",
        );
        return false;
    }
    if Command::new("setpriv").arg("--version").output().is_err() {
        prereq::skip(test, "setpriv (util-linux) is missing");
        return false;
    }
    true
}

/// `program` run as `uid` (its own group, no supplementary groups).
fn as_uid(uid: u32, program: &str) -> Command {
    let mut c = Command::new("setpriv");
    c.args([
        &format!("--reuid={uid}"),
        &format!("--regid={uid}"),
        "--clear-groups",
        "--",
        program,
    ]);
    c
}

/// `thorarena ARGS` as `uid`, with a home of its own.
fn as_user(uid: u32, args: &[&str]) -> Command {
    let mut c = as_uid(uid, BIN);
    c.args(args)
        .env_remove("THORARENA_IPC_ROOT")
        .env_remove("XDG_CACHE_HOME")
        .env("HOME", home_of(uid))
        .stdout(Stdio::null())
        .stderr(Stdio::piped());
    c
}

/// A home directory of `uid`'s own (its data cache goes there).
fn home_of(uid: u32) -> std::path::PathBuf {
    let home = std::env::temp_dir().join(format!("thorarena-test-home-{uid}"));
    std::fs::create_dir_all(&home).unwrap();
    let c = std::ffi::CString::new(home.to_str().unwrap()).unwrap();
    // SAFETY: chown on a path this test made; no memory is shared.
    assert_eq!(unsafe { libc::chown(c.as_ptr(), uid, uid) }, 0);
    home
}

/// One whole session as `uid`: `eval` over shared memory with `thorarena client`, on one
/// sample sequence. Returns both outputs.
fn session(uid: u32, out: &Path, name: &str) -> (Output, Output) {
    let session = format!("users-{name}-{}", std::process::id());
    let eval = as_user(
        uid,
        &[
            "eval",
            "--dataset",
            &format!("{ROOT}/data/sample"),
            "--policy",
            &format!("ipc:{session}"),
            "--settings",
            "no-force",
            "--sequences",
            "push_chair_001",
            "--connect-timeout",
            "60",
            "--out",
            out.to_str().unwrap(),
        ],
    )
    .spawn()
    .unwrap();
    let client = as_user(
        uid,
        &[
            "client",
            "--session",
            &session,
            "--policy",
            "hold",
            "--connect-timeout",
            "60",
        ],
    )
    .spawn()
    .unwrap();
    (
        eval.wait_with_output().unwrap(),
        client.wait_with_output().unwrap(),
    )
}

fn assert_ran(what: &str, (eval, client): &(Output, Output)) {
    assert!(
        eval.status.success() && client.status.success(),
        "{what}: eval: {}\nclient: {}",
        String::from_utf8_lossy(&eval.stderr),
        String::from_utf8_lossy(&client.stderr)
    );
}

fn writable_dir() -> tempfile::TempDir {
    use std::os::unix::fs::PermissionsExt;
    let dir = tempfile::tempdir().unwrap();
    std::fs::set_permissions(dir.path(), std::fs::Permissions::from_mode(0o777)).unwrap();
    dir
}

#[test]
fn two_users_each_run_sessions_and_neither_can_stop_the_others() {
    const TEST: &str = "users_apart::two_users";
    if !can_switch_users(TEST) {
        return;
    }
    let (alice, mallory) = uids();
    let dir = writable_dir();
    // Alice first: her root and her files in /dev/shm are made.
    assert_ran(
        "alice's first session",
        &session(alice, &dir.path().join("alice-1"), "a1"),
    );
    // Mallory, second on the machine, runs sessions too.
    assert_ran(
        "mallory's session after alice's",
        &session(mallory, &dir.path().join("mallory-1"), "m1"),
    );
    // Mallory tries to break alice's files: every one of them is closed to her.
    let alice_files: Vec<_> = std::fs::read_dir("/dev/shm")
        .unwrap()
        .flatten()
        .filter(|e| {
            e.file_name()
                .to_string_lossy()
                .starts_with(&format!("iox2_ta{alice}_"))
        })
        .map(|e| e.path())
        .collect();
    assert!(
        !alice_files.is_empty(),
        "alice's session left no management segment"
    );
    for file in &alice_files {
        let wrote = as_uid(mallory, "dd")
            .args([
                "if=/dev/urandom",
                &format!("of={}", file.display()),
                "bs=16",
                "count=1",
                "conv=notrunc",
            ])
            .stderr(Stdio::null())
            .status()
            .unwrap();
        assert!(!wrote.success(), "mallory wrote into {}", file.display());
    }
    let alice_root = format!("/tmp/thorarena-iceoryx2-{alice}");
    let listed = as_uid(mallory, "ls")
        .arg(&alice_root)
        .stderr(Stdio::null())
        .status()
        .unwrap();
    assert!(!listed.success(), "mallory listed {alice_root}");
    // Alice's next session is untouched by all of it.
    assert_ran(
        "alice's session after mallory's attempts",
        &session(alice, &dir.path().join("alice-2"), "a2"),
    );
    for file in alice_files {
        let _ = std::fs::remove_file(file);
    }
    for uid in [alice, mallory] {
        let _ = std::fs::remove_dir_all(format!("/tmp/thorarena-iceoryx2-{uid}"));
        for e in std::fs::read_dir("/dev/shm").unwrap().flatten() {
            if e.file_name()
                .to_string_lossy()
                .starts_with(&format!("iox2_ta{uid}_"))
            {
                let _ = std::fs::remove_file(e.path());
            }
        }
    }
}

#[test]
fn a_planted_root_is_refused_naming_it() {
    const TEST: &str = "users_apart::planted_root";
    if !can_switch_users(TEST) {
        return;
    }
    let (victim, planter) = uids();
    let (victim, planter) = (victim + 20_000, planter + 20_000);
    let dir = writable_dir();
    // The planter makes the victim's root before the victim's first session.
    let root = format!("/tmp/thorarena-iceoryx2-{victim}");
    let _ = std::fs::remove_dir_all(&root);
    let made = as_uid(planter, "mkdir")
        .args(["-m", "777", &root])
        .status()
        .unwrap();
    assert!(made.success());
    let (eval, _) = session(victim, &dir.path().join("v1"), "v1");
    let err = String::from_utf8_lossy(&eval.stderr);
    let _ = std::fs::remove_dir_all(&root);
    assert!(!eval.status.success());
    assert!(
        err.contains(&root) && err.contains(&format!("belongs to uid {planter}")),
        "{err}"
    );
}

/// Issue 52, probe item 5: a file planted in `/dev/shm` under the victim's session prefix
/// blocked every later session of the victim (who cannot remove it: /dev/shm is sticky)
/// until root acted. The prefix now holds a token from the victim's private root: the
/// old, predictable name no longer matters, and a file planted under the token (learnt
/// from a listing of /dev/shm while a session ran) is stepped around — the token is
/// replaced and the session runs; the planted file is never opened or removed.
#[test]
fn a_planted_session_file_is_stepped_around_and_never_blocks() {
    const TEST: &str = "users_apart::planted_shm";
    if !can_switch_users(TEST) {
        return;
    }
    let (victim, planter) = uids();
    let (victim, planter) = (victim + 24_000, planter + 24_000);
    let dir = writable_dir();
    let root = format!("/tmp/thorarena-iceoryx2-{victim}");
    let _ = std::fs::remove_dir_all(&root);
    // The name a planter could guess before: the uid alone.
    let guessed = format!("/dev/shm/iox2_ta{victim}_node.0_10_0.global_mgmt");
    assert!(as_uid(planter, "touch")
        .arg(&guessed)
        .status()
        .unwrap()
        .success());
    assert_ran(
        "a session beside a file planted under the guessable name",
        &session(victim, &dir.path().join("v1"), "v1"),
    );
    let token_file = format!("{root}/session-token");
    let token = std::fs::read_to_string(&token_file).unwrap();
    assert_eq!(token.trim().len(), 16, "{token:?}");
    // The planter learnt the token (here: read as root) and plants under it.
    let planted = format!("/dev/shm/iox2_ta{victim}_{}_node.planted", token.trim());
    assert!(as_uid(planter, "touch")
        .arg(&planted)
        .status()
        .unwrap()
        .success());
    assert_ran(
        "a session beside a file planted under its token",
        &session(victim, &dir.path().join("v2"), "v2"),
    );
    let replaced = std::fs::read_to_string(&token_file).unwrap();
    assert_ne!(replaced, token, "the token was not replaced");
    use std::os::unix::fs::MetadataExt;
    for file in [&guessed, &planted] {
        let meta = std::fs::metadata(file).unwrap();
        assert_eq!((meta.uid(), meta.len()), (planter, 0), "{file} was touched");
        let _ = std::fs::remove_file(file);
    }
    // And the next session runs under the new token without replacing it again.
    assert_ran(
        "a session after the token was replaced",
        &session(victim, &dir.path().join("v3"), "v3"),
    );
    assert_eq!(std::fs::read_to_string(&token_file).unwrap(), replaced);
    let _ = std::fs::remove_dir_all(&root);
    for e in std::fs::read_dir("/dev/shm").unwrap().flatten() {
        if e.file_name()
            .to_string_lossy()
            .starts_with(&format!("iox2_ta{victim}_"))
        {
            let _ = std::fs::remove_file(e.path());
        }
    }
}
