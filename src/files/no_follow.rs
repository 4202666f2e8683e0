//! Opening a file to write without following a symbolic link in its last component.
//!
//! Why: output directories are often shared (`/tmp`, a lab's scratch space), and a file
//! name ThorArena writes is predictable (`episodes.jsonl`, `.writer.lock`,
//! `.report.html.tmp-<pid>`). Another user who can write into the directory could plant a
//! link under that name to a file of ours; opening it with `O_CREAT|O_TRUNC` would write
//! our records into their target. The kernel's `protected_symlinks` does not help when
//! the link sits in the planter's own directory. `O_NOFOLLOW` makes such an open fail
//! (`ELOOP`), which [`refuse_links`] turns into an error that says what happened.
//!
//! The directories a command makes inside its output directory (`traces/`, a report's
//! figures, a data check's `rollout-NAME/`, the leaderboard's and sweeps' run directories)
//! are made by [`make_dir_within`]: created fresh, or, when found, entered only if it is a
//! real directory of this user — never a link, never another user's directory, which its
//! owner could swap for a link at any time. The path the user typed (`--out`) is followed:
//! it is their choice.

use std::fs::{File, OpenOptions};
use std::os::unix::fs::OpenOptionsExt;
use std::path::Path;

/// `OpenOptions` that refuse a symbolic link as the last component; set the access
/// mode and creation flags as usual, then open with [`open`].
pub fn options() -> OpenOptions {
    let mut o = OpenOptions::new();
    o.custom_flags(libc::O_NOFOLLOW);
    o
}

/// Opens `path` with `options` (from [`options`]), turning a planted link into a clear
/// error.
pub fn open(options: &OpenOptions, path: &Path) -> std::io::Result<File> {
    options.open(path).map_err(|e| refuse_links(e, path))
}

/// Creates or truncates `path` for writing, refusing a symbolic link there.
pub fn create(path: &Path) -> std::io::Result<File> {
    open(options().write(true).create(true).truncate(true), path)
}

/// `ELOOP` from an `O_NOFOLLOW` open, said in words; other errors unchanged.
pub fn refuse_links(e: std::io::Error, path: &Path) -> std::io::Error {
    if e.raw_os_error() == Some(libc::ELOOP) {
        std::io::Error::other(format!(
            "{} is a symbolic link: not written through (remove it, or choose another \
             output directory)",
            path.display()
        ))
    } else {
        e
    }
}

/// Makes `dir`, which lies inside `base`: `base` as the user gave it (made if missing,
/// links along it followed), then each level below it with [`make_dir`]. A `dir` outside
/// `base` is made level by level below its parent.
pub fn make_dir_within(base: &Path, dir: &Path) -> std::io::Result<()> {
    let (base, below) = match dir.strip_prefix(base) {
        Ok(below) => (base, below),
        Err(_) => match (dir.parent(), dir.file_name()) {
            (Some(parent), Some(name)) => (parent, Path::new(name)),
            _ => (dir, Path::new("")),
        },
    };
    if !base.as_os_str().is_empty() {
        std::fs::create_dir_all(base)?;
    }
    let mut level = base.to_path_buf();
    for part in below.components() {
        level.push(part);
        make_dir(&level)?;
    }
    Ok(())
}

/// Makes the directory `dir` (its parent must exist), or, when something is there, checks
/// that it is a real directory owned by this user: a link, another kind of file or
/// another user's directory is refused, saying which.
pub fn make_dir(dir: &Path) -> std::io::Result<()> {
    match std::fs::create_dir(dir) {
        Ok(()) => Ok(()),
        Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => own_dir(dir),
        Err(e) => Err(e),
    }
}

/// `dir` is a real directory of this (effective) user.
fn own_dir(dir: &Path) -> std::io::Result<()> {
    use std::os::unix::fs::MetadataExt;
    let meta = std::fs::symlink_metadata(dir)?;
    let refuse = |what: String| {
        Err(std::io::Error::other(format!(
            "{} {what}: not entered (remove it, or choose another output directory)",
            dir.display()
        )))
    };
    if meta.file_type().is_symlink() {
        return refuse("is a symbolic link".into());
    }
    if !meta.is_dir() {
        return refuse("is not a directory".into());
    }
    // SAFETY: geteuid has no preconditions.
    let me = unsafe { libc::geteuid() };
    if meta.uid() != me {
        return refuse(format!(
            "is another user's directory (uid {}, not {me})",
            meta.uid()
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_planted_link_is_refused_and_its_target_untouched() {
        let dir = tempfile::tempdir().unwrap();
        let target = dir.path().join("someone-elses-file");
        std::fs::write(&target, b"theirs").unwrap();
        let link = dir.path().join("episodes.jsonl");
        std::os::unix::fs::symlink(&target, &link).unwrap();
        let e = create(&link).unwrap_err();
        assert!(e.to_string().contains("is a symbolic link"), "{e}");
        assert_eq!(std::fs::read(&target).unwrap(), b"theirs");
    }

    #[test]
    fn a_planted_directory_link_is_not_entered_and_a_real_directory_is() {
        let dir = tempfile::tempdir().unwrap();
        let elsewhere = dir.path().join("elsewhere");
        std::fs::create_dir(&elsewhere).unwrap();
        let out = dir.path().join("out");
        std::fs::create_dir(&out).unwrap();
        std::os::unix::fs::symlink(&elsewhere, out.join("traces")).unwrap();
        let e = make_dir_within(&out, &out.join("traces").join("x")).unwrap_err();
        assert!(e.to_string().contains("is a symbolic link"), "{e}");
        assert!(!elsewhere.join("x").exists());
        make_dir_within(&out, &out.join("runs").join("a")).unwrap();
        make_dir_within(&out, &out.join("runs").join("a")).unwrap();
        std::fs::write(out.join("file"), b"").unwrap();
        let e = make_dir(&out.join("file")).unwrap_err();
        assert!(e.to_string().contains("is not a directory"), "{e}");
    }

    #[test]
    fn a_plain_file_is_created_and_truncated() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("episodes.jsonl");
        std::fs::write(&path, b"old content").unwrap();
        drop(create(&path).unwrap());
        assert_eq!(std::fs::read(&path).unwrap(), b"");
    }
}
