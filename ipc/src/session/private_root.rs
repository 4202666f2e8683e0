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
//! - every file iceoryx2 makes starts with `iox2_ta<uid>_`, and those in `/dev/shm` are
//!   made readable and writable by this user only. One that another user owns (planted to
//!   squat on the name) is refused, naming it.
//!
//! The Python client computes the same root and prefix (`thorarena/client.py`,
//! `private_root`); both sides of a session must be the same user.

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

/// The prefix of every file iceoryx2 makes for this user.
pub fn file_prefix() -> String {
    format!("iox2_ta{}_", euid())
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
    refuse_planted_files()?;
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
    config.global.prefix = FileName::new(file_prefix().as_bytes())
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

/// This user's files in `/dev/shm`, with their metadata.
fn own_shm_files() -> Vec<(PathBuf, std::fs::Metadata)> {
    let prefix = file_prefix();
    let Ok(entries) = std::fs::read_dir(SHM_DIR) else {
        return Vec::new();
    };
    entries
        .flatten()
        .filter(|e| e.file_name().to_string_lossy().starts_with(&prefix))
        .filter_map(|e| Some((e.path(), std::fs::symlink_metadata(e.path()).ok()?)))
        .collect()
}

/// Refuses a file named with this user's prefix that another user owns: planted there
/// before this user's first session, iceoryx2 would open it and trust its content.
fn refuse_planted_files() -> Result<(), IpcError> {
    for (path, meta) in own_shm_files() {
        if meta.uid() != euid() {
            return Err(refused(
                &path,
                format!(
                    "it carries your session files' prefix but belongs to uid {}: another user planted it; remove it (as root, or ask its owner)",
                    meta.uid()
                ),
            ));
        }
    }
    Ok(())
}

/// Takes every permission but this user's off this user's files in `/dev/shm`
/// (iceoryx2 makes its management segment world-writable).
pub(crate) fn make_shm_files_private() {
    for (path, meta) in own_shm_files() {
        if meta.uid() == euid() && meta.is_file() && meta.mode() & 0o077 != 0 {
            let _ = std::fs::set_permissions(&path, std::fs::Permissions::from_mode(0o600));
        }
    }
}
