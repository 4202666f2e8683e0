//! The bundled data (`data/`: robots, dynamics profiles, the sample dataset), compiled into
//! the binary by `build.rs` and written out once to a cache directory, so an installed
//! `thorarena` finds its robots, profiles and sample without the checkout it was built
//! from, and always the ones it was built with.
//!
//! The copy lives in `$XDG_CACHE_HOME/thorarena/data-<hash>` (else `~/.cache/…`, else the
//! system temporary directory), keyed by a hash of the contents: binaries of different
//! versions never share a copy, and a copy is never modified once complete. Written into
//! a temporary sibling and renamed, so concurrent first runs (a sweep starting many
//! processes) never see a half-written copy.

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

/// Makes `dir` a complete copy unless it is one already.
fn extract_into(dir: &Path) -> std::io::Result<()> {
    if dir.join(COMPLETE).is_file() {
        return Ok(());
    }
    let parent = dir.parent().expect("a cache directory has a parent");
    std::fs::create_dir_all(parent)?;
    let tmp = parent.join(format!(
        ".{}.tmp-{}",
        dir.file_name().expect("named").to_string_lossy(),
        std::process::id()
    ));
    let _ = std::fs::remove_dir_all(&tmp);
    for (path, bytes) in FILES {
        let dest = tmp.join(path);
        std::fs::create_dir_all(dest.parent().expect("under tmp"))?;
        std::fs::write(dest, bytes)?;
    }
    std::fs::write(tmp.join(COMPLETE), content_hash())?;
    match std::fs::rename(&tmp, dir) {
        Ok(()) => Ok(()),
        // Another process finished first: its copy is identical.
        Err(_) if dir.join(COMPLETE).is_file() => {
            let _ = std::fs::remove_dir_all(&tmp);
            Ok(())
        }
        Err(e) => {
            let _ = std::fs::remove_dir_all(&tmp);
            Err(e)
        }
    }
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
}
