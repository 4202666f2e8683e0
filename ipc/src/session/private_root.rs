//! Where a session's iceoryx2 files live: a directory of this user's own and a file-name
//! prefix of this user's own, so that no other user on the machine can stop, read or
//! spoof a ThorArena session, and every user can run one.
//!
//! iceoryx2's defaults are one machine-wide root (`/tmp/iceoryx2`, created 0750 by
//! whoever runs first, which every other user then cannot enter) and one machine-wide
//! management segment in `/dev/shm` (`iox2_node…`, created world-writable: 16 bytes from
//! any local user and every later node creation fails). Here:
//!
//! - the root is `$THORARENA_IPC_ROOT`, else `/tmp/thorarena-iceoryx2-<uid>`: made 0700 if
//!   missing, and refused — naming it and what is wrong — when it is a symbolic link, not
//!   a directory, another user's, or writable by others;
//! - every file iceoryx2 makes starts with `iox2_ta<uid>_<token>_`, and those in
//!   `/dev/shm` are made readable and writable by this user only. The token is 16 random
//!   hex digits kept in the root (`session-token`, 0600), so another user cannot guess the
//!   names and plant one before a session makes it. `/dev/shm` lists its names to
//!   everyone while a session runs, so a user who watched it may still plant a file with
//!   the prefix: then the token is replaced by a new one (under a lock in the root, so
//!   the processes of one user agree on it) and the planted file is stepped around, never
//!   opened — a session is never blocked by another user's file.
//!
//! The Python client computes the same root, token and prefix (`thorarena/private_root.py`);
//! both sides of a session must be the same user.

use super::IpcError;
use iceoryx2::config::Config;
use iceoryx2::prelude::*;
use std::os::unix::fs::{DirBuilderExt, MetadataExt, PermissionsExt};
use std::path::PathBuf;

/// Overrides the root directory (it must still be this user's, not writable by others).
pub const ROOT_ENV: &str = "THORARENA_IPC_ROOT";

/// Where this user's shared-memory files are listed.
const SHM_DIR: &str = "/dev/shm";

/// This user's root directory for iceoryx2.
pub fn root_dir() -> PathBuf {
    std::env::var_os(ROOT_ENV)
        .filter(|v| !v.is_empty())
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from(format!("/tmp/thorarena-iceoryx2-{}", euid())))
}

/// The file in the root that holds this user's token.
pub const TOKEN_FILE: &str = "session-token";
/// The lock the processes of one user take in the root while they read or replace it.
const TOKEN_LOCK: &str = ".session-token.lock";
/// Hex digits of a token.
const TOKEN_DIGITS: usize = 16;

/// The prefix of every file iceoryx2 makes for this user now: `iox2_ta<uid>_<token>_`
/// (the token as the root holds it; `iox2_ta<uid>_` before any session made one).
pub fn file_prefix() -> String {
    prefix_of(&read_token(&root_dir()).unwrap_or_default())
}

fn prefix_of(token: &str) -> String {
    if token.is_empty() {
        format!("iox2_ta{}_", euid())
    } else {
        format!("iox2_ta{}_{token}_", euid())
    }
}

/// The token in `root`, if it holds a valid one (a regular file of ours, 16 hex digits).
fn read_token(root: &std::path::Path) -> Option<String> {
    let path = root.join(TOKEN_FILE);
    let meta = std::fs::symlink_metadata(&path).ok()?;
    if !meta.is_file() || meta.uid() != euid() || meta.len() > 64 {
        return None;
    }
    let text = std::fs::read_to_string(&path).ok()?;
    let token = text.trim();
    (token.len() == TOKEN_DIGITS && token.bytes().all(|b| b.is_ascii_hexdigit()))
        .then(|| token.to_string())
}

/// A new token from the kernel's random source.
fn new_token(root: &std::path::Path) -> Result<String, IpcError> {
    use std::io::Read;
    let mut bytes = [0u8; TOKEN_DIGITS / 2];
    std::fs::File::open("/dev/urandom")
        .and_then(|mut f| f.read_exact(&mut bytes))
        .map_err(|e| {
            refused(
                root,
                format!("cannot read /dev/urandom for a session token: {e}"),
            )
        })?;
    Ok(bytes.iter().map(|b| format!("{b:02x}")).collect())
}

/// Writes `token` as the root's token: a new file renamed over the old, so a reader sees
/// the old token or the new, never half of one.
fn write_token(root: &std::path::Path, token: &str) -> Result<(), IpcError> {
    use std::io::Write;
    use std::os::unix::fs::OpenOptionsExt;
    let tmp = root.join(format!(".{TOKEN_FILE}.{}", std::process::id()));
    let _ = std::fs::remove_file(&tmp);
    std::fs::OpenOptions::new()
        .write(true)
        .create_new(true)
        .mode(0o600)
        .custom_flags(libc::O_NOFOLLOW)
        .open(&tmp)
        .and_then(|mut f| f.write_all(token.as_bytes()))
        .and_then(|()| std::fs::rename(&tmp, root.join(TOKEN_FILE)))
        .map_err(|e| refused(root, format!("cannot write the session token: {e}")))
}

/// Holds the root's token lock while it lives (`flock`, released on drop).
struct TokenLock {
    _file: std::fs::File,
}

impl TokenLock {
    fn take(root: &std::path::Path) -> Result<Self, IpcError> {
        use std::os::unix::fs::OpenOptionsExt;
        use std::os::unix::io::AsRawFd;
        let path = root.join(TOKEN_LOCK);
        let file = std::fs::OpenOptions::new()
            .read(true)
            .write(true)
            .create(true)
            .mode(0o600)
            .custom_flags(libc::O_NOFOLLOW)
            .open(&path)
            .map_err(|e| refused(&path, format!("cannot open the token lock: {e}")))?;
        // SAFETY: flock on a descriptor this value owns.
        if unsafe { libc::flock(file.as_raw_fd(), libc::LOCK_EX) } != 0 {
            return Err(refused(
                &path,
                format!("cannot lock it: {}", std::io::Error::last_os_error()),
            ));
        }
        Ok(Self { _file: file })
    }
}

/// This user's token, made if the root holds none, and replaced while another user's file
/// carries its prefix in `/dev/shm` (the planted files are returned: stepped around).
fn current_token(root: &std::path::Path) -> Result<(String, Vec<PathBuf>), IpcError> {
    let _lock = TokenLock::take(root)?;
    let mut token = match read_token(root) {
        Some(token) => token,
        None => {
            let token = new_token(root)?;
            write_token(root, &token)?;
            token
        }
    };
    let mut planted = Vec::new();
    // A fresh token is planted on only by a user who saw it within this lock: a few
    // rounds, then give up naming the files.
    for _ in 0..4 {
        let foreign = foreign_files(&prefix_of(&token));
        if foreign.is_empty() {
            return Ok((token, planted));
        }
        planted.extend(foreign);
        token = new_token(root)?;
        write_token(root, &token)?;
    }
    Err(refused(
        &planted[0],
        "files with your session files' prefix keep appearing, owned by another user, as fast as the prefix changes; ask an administrator to see who plants them".into(),
    ))
}

fn euid() -> u32 {
    // SAFETY: geteuid has no preconditions and cannot fail.
    unsafe { libc::geteuid() }
}

fn refused(path: &std::path::Path, problem: String) -> IpcError {
    IpcError::PrivateRoot {
        path: path.to_path_buf(),
        problem,
    }
}

/// The iceoryx2 configuration of this user's sessions, the root checked (and made): what
/// any other iceoryx2 program must use to reach a ThorArena session.
pub fn config() -> Result<Config, IpcError> {
    let root = root_dir();
    ensure_root(&root)?;
    let (token, planted) = current_token(&root)?;
    if !planted.is_empty() {
        log::warn!(
            "iceoryx2 files: another user planted {} with your session files' prefix; your sessions now use a new one (sessions still running under the old prefix keep their peers, a policy process started meanwhile finds them under the new one only)",
            planted.iter().map(|p| p.display().to_string()).collect::<Vec<_>>().join(", ")
        );
    }
    let mut config = Config::global_config().clone();
    let root_text = root.to_string_lossy();
    let path = Path::new(root_text.as_bytes()).map_err(|_| {
        refused(
            &root,
            "iceoryx2 cannot use this path (too long, or not an absolute path of plain characters)"
                .into(),
        )
    })?;
    config.global.set_root_path(&path);
    config.global.prefix = FileName::new(prefix_of(&token).as_bytes())
        .map_err(|_| refused(&root, "the file prefix is not a valid file name".into()))?;
    Ok(config)
}

/// Makes `root` 0700 if missing; refuses one that is not this user's private directory.
fn ensure_root(root: &std::path::Path) -> Result<(), IpcError> {
    if !root.is_absolute() {
        return Err(refused(
            root,
            format!("{ROOT_ENV} must be an absolute path"),
        ));
    }
    match std::fs::symlink_metadata(root) {
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
            std::fs::DirBuilder::new()
                .mode(0o700)
                .create(root)
                .or_else(|e| {
                    // Made meanwhile by another process of ours: checked below.
                    if e.kind() == std::io::ErrorKind::AlreadyExists {
                        Ok(())
                    } else {
                        Err(e)
                    }
                })
                .map_err(|e| refused(root, format!("cannot create it: {e}")))?;
            check_root(root)
        }
        Err(e) => Err(refused(root, format!("cannot read it: {e}"))),
        Ok(_) => check_root(root),
    }
}

fn check_root(root: &std::path::Path) -> Result<(), IpcError> {
    let meta = std::fs::symlink_metadata(root)
        .map_err(|e| refused(root, format!("cannot read it: {e}")))?;
    if meta.file_type().is_symlink() {
        return Err(refused(
            root,
            "it is a symbolic link (it could lead into another user's directory): remove it".into(),
        ));
    }
    if !meta.is_dir() {
        return Err(refused(root, "it is not a directory: remove it".into()));
    }
    if meta.uid() != euid() {
        return Err(refused(
            root,
            format!(
                "it belongs to uid {}, not to you (uid {}): another user made it; remove it, or set {ROOT_ENV} to a directory of yours",
                meta.uid(),
                euid()
            ),
        ));
    }
    if meta.mode() & 0o022 != 0 {
        return Err(refused(
            root,
            format!(
                "others may write to it (mode {:o}): `chmod 700` it",
                meta.mode() & 0o7777
            ),
        ));
    }
    Ok(())
}

/// The files in `/dev/shm` whose names start with `prefix`, with their metadata.
fn shm_files(prefix: &str) -> Vec<(PathBuf, std::fs::Metadata)> {
    let Ok(entries) = std::fs::read_dir(SHM_DIR) else {
        return Vec::new();
    };
    entries
        .flatten()
        .filter(|e| e.file_name().to_string_lossy().starts_with(prefix))
        .filter_map(|e| Some((e.path(), std::fs::symlink_metadata(e.path()).ok()?)))
        .collect()
}

/// The files carrying `prefix` in `/dev/shm` that another user owns: planted to squat on
/// the names, which iceoryx2 would open and trust.
fn foreign_files(prefix: &str) -> Vec<PathBuf> {
    shm_files(prefix)
        .into_iter()
        .filter(|(_, meta)| meta.uid() != euid())
        .map(|(path, _)| path)
        .collect()
}

/// Takes every permission but this user's off this user's files in `/dev/shm`
/// (iceoryx2 makes its management segment world-writable).
pub(crate) fn make_shm_files_private() {
    for (path, meta) in shm_files(&file_prefix()) {
        if meta.uid() == euid() && meta.is_file() && meta.mode() & 0o077 != 0 {
            let _ = std::fs::set_permissions(&path, std::fs::Permissions::from_mode(0o600));
        }
    }
}
