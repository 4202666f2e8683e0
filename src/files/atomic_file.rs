//! Writing a whole file so that its readers only ever see the old content or the new, never
//! an empty or half-written one: the bytes go to a temporary file beside it, reach the disk,
//! and are renamed over the destination (rename within a directory is atomic on POSIX).
//!
//! Why not `std::fs::write`: it truncates first and writes second, so a kill, a full disk
//! (ENOSPC) or a crash between the two leaves an empty `summary.json` or `report.html`
//! where a good one was.
//!
//! The temporary file is created exclusively (`O_CREAT|O_EXCL|O_NOFOLLOW`): whatever
//! already stands under its name — a stale file, or a link another user planted in a
//! shared directory — is stepped around with the next name, never opened. The rename
//! replaces a link at the destination itself, not the file it points to.

use std::io::Write;
use std::path::{Path, PathBuf};

/// How many temporary names a write tries before giving up: each taken one was planted
/// or left by a crashed writer of the same pid.
const TEMPORARY_NAME_TRIES: u32 = 64;

/// Writes `bytes` to `path`, replacing it atomically. The temporary file
/// (`.<name>.tmp-<pid>[-<n>]` in the same directory) is removed when anything fails.
pub fn write(path: impl AsRef<Path>, bytes: impl AsRef<[u8]>) -> std::io::Result<()> {
    let path = path.as_ref();
    let (mut file, tmp) = create_temporary_beside(path)?;
    let written = (|| {
        file.write_all(bytes.as_ref())?;
        file.sync_all()?;
        std::fs::rename(&tmp, path)
    })();
    if written.is_err() {
        let _ = std::fs::remove_file(&tmp);
        return written;
    }
    // The rename reaches the disk with its directory's entry.
    if let Some(parent) = path.parent() {
        let parent = if parent.as_os_str().is_empty() {
            Path::new(".")
        } else {
            parent
        };
        if let Ok(d) = std::fs::File::open(parent) {
            let _ = d.sync_all();
        }
    }
    Ok(())
}

/// Creates `dir/.<name>.tmp-<pid>` (then `-1`, `-2`, … while a name is taken): hidden,
/// unique per process, on the destination's file system, and new — never an existing file
/// or link.
fn create_temporary_beside(path: &Path) -> std::io::Result<(std::fs::File, PathBuf)> {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let pid = std::process::id();
    for n in 0..TEMPORARY_NAME_TRIES {
        let tmp = match n {
            0 => path.with_file_name(format!(".{name}.tmp-{pid}")),
            n => path.with_file_name(format!(".{name}.tmp-{pid}-{n}")),
        };
        match super::no_follow::open(
            super::no_follow::options().write(true).create_new(true),
            &tmp,
        ) {
            Ok(file) => return Ok((file, tmp)),
            Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => continue,
            Err(e) => return Err(e),
        }
    }
    Err(std::io::Error::new(
        std::io::ErrorKind::AlreadyExists,
        format!(
            "{TEMPORARY_NAME_TRIES} temporary names beside {} are all taken (.{name}.tmp-{pid}*): \
             remove them",
            path.display()
        ),
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn replaces_the_content_and_leaves_no_temporary_file() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("summary.json");
        std::fs::write(&path, b"old").unwrap();
        write(&path, b"new").unwrap();
        assert_eq!(std::fs::read(&path).unwrap(), b"new");
        let entries: Vec<_> = std::fs::read_dir(dir.path()).unwrap().collect();
        assert_eq!(entries.len(), 1);
    }

    #[test]
    fn a_planted_temporary_link_is_stepped_around() {
        let dir = tempfile::tempdir().unwrap();
        let target = dir.path().join("someone-elses-file");
        std::fs::write(&target, b"theirs").unwrap();
        let path = dir.path().join("report.html");
        let planted = dir
            .path()
            .join(format!(".report.html.tmp-{}", std::process::id()));
        std::os::unix::fs::symlink(&target, &planted).unwrap();
        // The destination itself is a link too: the rename replaces the link.
        std::os::unix::fs::symlink(&target, &path).unwrap();
        write(&path, b"report").unwrap();
        assert_eq!(std::fs::read(&target).unwrap(), b"theirs");
        assert!(!path.symlink_metadata().unwrap().file_type().is_symlink());
        assert_eq!(std::fs::read(&path).unwrap(), b"report");
    }

    #[test]
    fn a_failed_write_keeps_the_old_file() {
        let dir = tempfile::tempdir().unwrap();
        // The destination is a directory: the rename fails, the "old file" stays.
        let path = dir.path().join("report.html");
        std::fs::create_dir(&path).unwrap();
        assert!(write(&path, b"new").is_err());
        assert!(path.is_dir());
        let entries: Vec<_> = std::fs::read_dir(dir.path()).unwrap().collect();
        assert_eq!(entries.len(), 1, "the temporary file was left behind");
    }
}
