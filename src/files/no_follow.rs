//! Opening a file to write without following a symbolic link in its last component.
//!
//! Why: output directories are often shared (`/tmp`, a lab's scratch space), and a file
//! name ThorArena writes is predictable (`episodes.jsonl`, `.writer.lock`,
//! `.report.html.tmp-<pid>`). Another user who can write into the directory could plant a
//! link under that name to a file of ours; opening it with `O_CREAT|O_TRUNC` would write
//! our records into their target. The kernel's `protected_symlinks` does not help when
//! the link sits in the planter's own directory. `O_NOFOLLOW` makes such an open fail
//! (`ELOOP`), which [`refuse_links`] turns into an error that says what happened.
//! Directories along the path are followed: they are the user's choice (`--out`).

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
    fn a_plain_file_is_created_and_truncated() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("episodes.jsonl");
        std::fs::write(&path, b"old content").unwrap();
        drop(create(&path).unwrap());
        assert_eq!(std::fs::read(&path).unwrap(), b"");
    }
}
