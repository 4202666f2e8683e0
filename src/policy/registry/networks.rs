//! The published networks ThorArena knows by content: a file whose SHA-256 is listed runs
//! under the profile it was trained with when no `--profile` is named, whatever its file
//! name — the scale and gains a file needs are a property of the file, not of its family
//! (holosoma's FastSAC and PPO dances are both `beyondmimic:` files and need different
//! action scales).

use crate::policy::network_file::NetworkFile;
use std::path::Path;

/// One published network.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct KnownNetwork {
    /// SHA-256 of the file, lowercase hex.
    pub sha256: &'static str,
    /// Its published file name.
    pub file: &'static str,
    /// The bundled profile it runs under.
    pub profile: &'static str,
    /// The families that run it: its profile is chosen only for an argument of one of
    /// them (TWIST2's file given to `falcon:` does not make FALCON run under `twist2`).
    pub families: &'static [&'static str],
    /// Where it comes from.
    pub source: &'static str,
}

/// Every published network known by content.
pub const KNOWN_NETWORKS: [KnownNetwork; 4] = [
    KnownNetwork {
        sha256: "126ab9089b6ca0be8b6582fc9ef17b0b6c6d6577378f9324a2e10d580fe48f2e",
        file: "twist2_1017_25k.onnx",
        profile: "twist2",
        families: &["twist2"],
        source: "TWIST2's released checkpoint (arXiv 2511.02832)",
    },
    KnownNetwork {
        sha256: "514ea0661a2b92b1bfafb0b0f51b95940b88d6d6f7376f3d044af0c1f8c9f24b",
        file: "fastsac_g1_29dof_dancing.onnx",
        profile: "holosoma-wbt",
        families: &["beyondmimic"],
        source: "holosoma's FastSAC G1 dance (PyPI holosoma-inference 0.1.3)",
    },
    KnownNetwork {
        sha256: "50c0d577bd950e7a1df74be8fb5e2cef597f8090b1b219b300bbd2711eb23e5f",
        file: "ppo_g1_29dof_dancing.onnx",
        profile: "holosoma-ppo",
        families: &["beyondmimic"],
        source: "holosoma's PPO G1 dance (PyPI holosoma-inference 0.1.3)",
    },
    KnownNetwork {
        sha256: "48fdb6ea7181a475116f929fe8cfdcaba86272532d4d94c7753ead1bfb467215",
        file: "wbc_g1_policy.onnx",
        profile: "wbc-mjlab",
        families: &["wbc-mjlab", "beyondmimic"],
        source: "wbc-mjlab/wbc-g1-deploy at 066ab157",
    },
];

/// The known network `path` holds, by content; `None` for an unreadable or unknown file
/// (the family's profile then applies, and loading reports what is wrong with the file).
/// The file is read as a network is ([`NetworkFile::read`]: a regular file, bounded in size),
/// so a device or a FIFO given as a network is never read here.
pub fn known_network(path: &Path) -> Option<&'static KnownNetwork> {
    let (_, file) = NetworkFile::read(path).ok()?;
    KNOWN_NETWORKS.iter().find(|n| n.sha256 == file.sha256)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_known_network_names_a_bundled_profile_once() {
        let bundled = crate::policy::registry::bundled_profile_names();
        for (i, n) in KNOWN_NETWORKS.iter().enumerate() {
            assert!(bundled.iter().any(|b| b == n.profile), "{}", n.profile);
            assert_eq!(n.sha256.len(), 64, "{}", n.file);
            assert!(KNOWN_NETWORKS[..i].iter().all(|m| m.sha256 != n.sha256));
        }
    }

    #[test]
    fn an_unknown_or_unreadable_file_is_no_known_network() {
        let dir = tempfile::tempdir().unwrap();
        let f = dir.path().join("x.onnx");
        std::fs::write(&f, b"not a network").unwrap();
        assert_eq!(known_network(&f), None);
        assert_eq!(known_network(&dir.path().join("absent.onnx")), None);
    }
}
