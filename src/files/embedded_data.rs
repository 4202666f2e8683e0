//! The bundled data (`data/`: robots, dynamics profiles, the sample dataset), compiled into
//! the binary by `build.rs` and written out once to a cache directory, so an installed
//! `thorarena` finds its robots, profiles and sample without the checkout it was built
//! from, and always the ones it was built with.
//!
//! The copy lives in `$XDG_CACHE_HOME/thorarena/data-<hash>` (else `~/.cache/…`, else the
//! system temporary directory), keyed by a hash of the contents: binaries of different
//! versions never share a copy, and a copy is never modified once complete. Written into
//! a temporary sibling and renamed, so concurrent first runs (a sweep starting many
//! processes) never see a half-written copy. Every process checks the copy against the
//! embedded bytes before using it (2 MB, about a millisecond) and refuses directories
//! another user owns or may write to: an edited copy is written again, a planted one is
//! passed over for the next place.

use sha2::{Digest, Sha256};
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

include!(concat!(env!("OUT_DIR"), "/embedded_data.rs"));

/// Marker written last into a complete copy.
const COMPLETE: &str = ".complete";

/// The first 16 hex digits of SHA-256 over every (path, length, contents).
pub fn content_hash() -> &'static str {
    static HASH: OnceLock<String> = OnceLock::new();
    HASH.get_or_init(|| {
        let mut h = Sha256::new();
        for (path, bytes) in FILES {
            h.update(path.as_bytes());
            h.update([0]);
            h.update((bytes.len() as u64).to_le_bytes());
            h.update(bytes);
        }
        h.finalize()[..8]
            .iter()
            .map(|b| format!("{b:02x}"))
            .collect()
    })
}

/// The cache directories tried in order.
fn cache_roots() -> Vec<PathBuf> {
    let mut roots = Vec::new();
    if let Some(x) = std::env::var_os("XDG_CACHE_HOME").filter(|x| !x.is_empty()) {
        roots.push(PathBuf::from(x));
    }
    if let Some(home) = std::env::var_os("HOME").filter(|x| !x.is_empty()) {
        roots.push(PathBuf::from(home).join(".cache"));
    }
    roots.push(std::env::temp_dir());
    roots
}

/// The extracted copy, written on first use; `Err` lists every place that failed.
pub fn extracted() -> Result<PathBuf, String> {
    static DIR: OnceLock<Result<PathBuf, String>> = OnceLock::new();
    DIR.get_or_init(|| {
        let name = format!("data-{}", content_hash());
        let mut failures = Vec::new();
        for root in cache_roots() {
            let dir = root.join("thorarena").join(&name);
            match extract_into(&dir) {
                Ok(()) => return Ok(dir),
                Err(e) => failures.push(format!("{}: {e}", dir.display())),
            }
        }
        Err(failures.join("; "))
    })
    .clone()
}

/// Makes `dir` a complete, verified copy: an existing one is used only when it is ours and
/// private and equals the embedded data byte for byte (a cache in a shared temporary
/// directory could have been planted; any copy could have been edited), else rewritten.
fn extract_into(dir: &Path) -> std::io::Result<()> {
    let parent = dir.parent().expect("a cache directory has a parent");
    create_private_dir(parent)?;
    if dir.join(COMPLETE).is_file() {
        check_private(dir)?;
        match differs(dir) {
            None => return Ok(()),
            Some(what) => {
                log::warn!(
                    "the data cache {} differs from this binary's data ({what}): writing it again",
                    dir.display()
                );
                std::fs::remove_dir_all(dir)?;
            }
        }
    }
    let tmp = parent.join(format!(
        ".{}.tmp-{}",
        dir.file_name().expect("named").to_string_lossy(),
        std::process::id()
    ));
    let _ = std::fs::remove_dir_all(&tmp);
    create_private_dir(&tmp)?;
    for (path, bytes) in FILES {
        let dest = tmp.join(path);
        std::fs::create_dir_all(dest.parent().expect("under tmp"))?;
        std::fs::write(dest, bytes)?;
    }
    std::fs::write(tmp.join(COMPLETE), content_hash())?;
    match std::fs::rename(&tmp, dir) {
        Ok(()) => Ok(()),
        // Another process finished first: its copy is used if it verifies.
        Err(_) if dir.join(COMPLETE).is_file() => {
            let _ = std::fs::remove_dir_all(&tmp);
            check_private(dir)?;
            match differs(dir) {
                None => Ok(()),
                Some(what) => Err(std::io::Error::other(format!(
                    "{} differs from this binary's data ({what})",
                    dir.display()
                ))),
            }
        }
        Err(e) => {
            let _ = std::fs::remove_dir_all(&tmp);
            Err(e)
        }
    }
}

/// What tells copy `dir` from the embedded data, if anything: a file changed, missing or
/// added.
fn differs(dir: &Path) -> Option<String> {
    for (path, bytes) in FILES {
        match std::fs::read(dir.join(path)) {
            Ok(found) if found == *bytes => {}
            Ok(_) => return Some(format!("{path} changed")),
            Err(_) => return Some(format!("{path} missing")),
        }
    }
    let expected: std::collections::HashSet<PathBuf> = FILES
        .iter()
        .map(|(p, _)| dir.join(p))
        .chain([dir.join(COMPLETE)])
        .collect();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        let Ok(entries) = std::fs::read_dir(&d) else {
            return Some(format!("{} unreadable", d.display()));
        };
        for entry in entries.flatten() {
            let path = entry.path();
            if path.is_dir() {
                stack.push(path);
            } else if !expected.contains(&path) {
                return Some(format!("{} added", path.display()));
            }
        }
    }
    None
}

/// Creates `dir` (and its parents) if missing; then it must be ours and private.
fn create_private_dir(dir: &Path) -> std::io::Result<()> {
    use std::os::unix::fs::DirBuilderExt;
    if !dir.exists() {
        std::fs::DirBuilder::new()
            .recursive(true)
            .mode(0o755)
            .create(dir)?;
        // The umask may have opened it wider than asked for.
        use std::os::unix::fs::PermissionsExt;
        std::fs::set_permissions(dir, std::fs::Permissions::from_mode(0o755))?;
    }
    check_private(dir)
}

/// Refuses a directory another user owns or may write to: its contents could be theirs.
fn check_private(dir: &Path) -> std::io::Result<()> {
    use std::os::unix::fs::MetadataExt;
    let meta = std::fs::symlink_metadata(dir)?;
    // SAFETY: geteuid has no preconditions and cannot fail.
    let me = unsafe { libc::geteuid() };
    if !meta.is_dir() {
        return Err(std::io::Error::other(format!(
            "{} is not a directory (a symbolic link is not trusted)",
            dir.display()
        )));
    }
    if meta.uid() != me {
        return Err(std::io::Error::other(format!(
            "{} belongs to user {}, not to us ({me}): not trusted",
            dir.display(),
            meta.uid()
        )));
    }
    if meta.mode() & 0o022 != 0 {
        return Err(std::io::Error::other(format!(
            "{} is writable by other users (mode {:o}): not trusted",
            dir.display(),
            meta.mode() & 0o777
        )));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_bundle_holds_the_robot_profiles_and_sample() {
        let names: Vec<&str> = FILES.iter().map(|(p, _)| *p).collect();
        for needed in [
            "robots/g1_29dof/robot.toml",
            "robots/g1_29dof/g1_29dof.urdf",
            "profiles/default.toml",
            "profiles/twist2.toml",
            "sample/manifest.json",
        ] {
            assert!(names.contains(&needed), "{needed} not bundled");
        }
    }

    #[test]
    fn an_extracted_copy_equals_the_checkout_byte_for_byte() {
        let tmp = tempfile::tempdir().unwrap();
        let dir = tmp.path().join("copy");
        extract_into(&dir).unwrap();
        // A second call finds the complete copy and leaves it alone.
        extract_into(&dir).unwrap();
        let checkout = Path::new(env!("CARGO_MANIFEST_DIR")).join("data");
        for (path, bytes) in FILES {
            assert_eq!(&std::fs::read(dir.join(path)).unwrap(), bytes, "{path}");
            assert_eq!(
                &std::fs::read(checkout.join(path)).unwrap(),
                bytes,
                "{path}"
            );
        }
        let leftovers = std::fs::read_dir(tmp.path()).unwrap().count();
        assert_eq!(leftovers, 1, "no temporary directory left behind");
    }

    #[test]
    fn an_edited_copy_is_written_again_before_use() {
        let tmp = tempfile::tempdir().unwrap();
        let dir = tmp.path().join("copy");
        extract_into(&dir).unwrap();
        let profile = dir.join("profiles/default.toml");
        let text = std::fs::read_to_string(&profile).unwrap();
        std::fs::write(&profile, text.replace('6', "9")).unwrap();
        std::fs::write(dir.join("profiles/planted.toml"), "x").unwrap();
        extract_into(&dir).unwrap();
        assert_eq!(std::fs::read_to_string(&profile).unwrap(), text);
        assert!(!dir.join("profiles/planted.toml").exists());
    }

    #[test]
    fn a_directory_others_may_write_to_is_not_trusted() {
        use std::os::unix::fs::PermissionsExt;
        let tmp = tempfile::tempdir().unwrap();
        let shared = tmp.path().join("shared");
        std::fs::create_dir(&shared).unwrap();
        std::fs::set_permissions(&shared, std::fs::Permissions::from_mode(0o777)).unwrap();
        let e = extract_into(&shared.join("copy")).unwrap_err().to_string();
        assert!(e.contains("writable by other users"), "{e}");
        assert!(!shared.join("copy").exists());
    }
}
