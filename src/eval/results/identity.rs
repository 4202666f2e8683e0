//! Which policy a run ran, by content: the network file it loaded, the profile and the
//! robot it ran under. `run.json` records it ([`super::RunHeader::identity`]) so that the
//! tools that join runs — `--resume`, `merge`, a sweep's collect, the leaderboard's reuse of
//! finished runs — can refuse to join two networks (or two profiles) under one label, and
//! say which hashes differ.

use crate::policy::network_file::{short_hash, NetworkFile};
use crate::policy::Policy;
use crate::sim::profile::Profile;
use crate::sim::robot::RobotModel;
use serde::{Deserialize, Serialize};

/// What a run's policy was, by content.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PolicyIdentity {
    /// The network file the policy loaded (`None`: a built-in, which has none, or a policy
    /// process, whose network this process never sees).
    pub network: Option<NetworkFile>,
    /// [`Profile::fingerprint`] of the profile it ran under.
    pub profile_sha256: String,
    /// [`RobotModel::fingerprint`] of the robot simulated.
    pub robot_sha256: String,
}

impl PolicyIdentity {
    /// The identity of `policy` (as loaded) under `profile` on `robot`.
    pub fn of(policy: &dyn Policy, profile: &Profile, robot: &RobotModel) -> Self {
        Self {
            network: policy.network().cloned(),
            profile_sha256: profile.fingerprint(),
            robot_sha256: robot.fingerprint(),
        }
    }
}

/// How a table names a run's network beside its policy label: `network 126ab9089b6c`, or
/// `network not recorded` for a run written before runs recorded it; `None` for a run
/// that recorded it and had none (a built-in, a policy process).
pub fn network_label(identity: Option<&PolicyIdentity>) -> Option<String> {
    match identity {
        None => Some("network not recorded".into()),
        Some(PolicyIdentity {
            network: Some(n), ..
        }) => Some(format!("network {}", n.short_hash())),
        Some(_) => None,
    }
}

/// What differs between two identities, `a` first and `b` second, each naming both
/// hashes: `network (sha256 126ab9089b6c, 3 402 116 bytes; then 514ea0661a2b, …)`.
pub fn identity_differences(a: Option<&PolicyIdentity>, b: Option<&PolicyIdentity>) -> Vec<String> {
    match (a, b) {
        (None, None) => Vec::new(),
        (None, Some(_)) | (Some(_), None) => {
            let said = |i: Option<&PolicyIdentity>| match i {
                None => "not recorded".to_string(),
                Some(i) => network_text(i.network.as_ref()),
            };
            vec![format!(
                "network ({}; then {}): a run written before runs recorded their network cannot be joined with one that did",
                said(a),
                said(b)
            )]
        }
        (Some(a), Some(b)) => {
            let mut d = Vec::new();
            if a.network != b.network {
                d.push(format!(
                    "network ({}; then {})",
                    network_text(a.network.as_ref()),
                    network_text(b.network.as_ref())
                ));
            }
            for (what, x, y) in [
                ("profile", &a.profile_sha256, &b.profile_sha256),
                ("robot", &a.robot_sha256, &b.robot_sha256),
            ] {
                if x != y {
                    d.push(format!(
                        "{what} content (sha256 {}; then {})",
                        short_hash(x),
                        short_hash(y)
                    ));
                }
            }
            d
        }
    }
}

fn network_text(network: Option<&NetworkFile>) -> String {
    match network {
        Some(n) => format!("sha256 {}, {} bytes, {}", n.short_hash(), n.bytes, n.file),
        None => "no network file".into(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn identity(sha: &str, profile: &str) -> PolicyIdentity {
        PolicyIdentity {
            network: Some(NetworkFile {
                file: format!("/n/{sha}.onnx"),
                sha256: sha.repeat(64 / sha.len()),
                bytes: 10,
            }),
            profile_sha256: profile.repeat(64 / profile.len()),
            robot_sha256: "r".repeat(64),
        }
    }

    #[test]
    fn a_difference_names_both_hashes() {
        let (a, b) = (identity("a", "p"), identity("b", "p"));
        let d = identity_differences(Some(&a), Some(&b));
        assert_eq!(d.len(), 1, "{d:?}");
        assert!(
            d[0].contains("aaaaaaaaaaaa") && d[0].contains("bbbbbbbbbbbb"),
            "{d:?}"
        );
        let c = identity("a", "q");
        let d = identity_differences(Some(&a), Some(&c));
        assert_eq!(
            d,
            ["profile content (sha256 pppppppppppp; then qqqqqqqqqqqq)"]
        );
        assert!(identity_differences(Some(&a), Some(&a.clone())).is_empty());
        let d = identity_differences(None, Some(&a));
        assert!(d[0].contains("not recorded"), "{d:?}");
    }

    #[test]
    fn the_same_network_elsewhere_is_the_same_identity() {
        let a = identity("a", "p");
        let mut moved = a.clone();
        moved.network.as_mut().unwrap().file = "/elsewhere/copy.onnx".into();
        assert_eq!(a, moved);
    }

    #[test]
    fn labels_say_what_is_known() {
        assert_eq!(
            network_label(Some(&identity("a", "p"))).as_deref(),
            Some("network aaaaaaaaaaaa")
        );
        assert_eq!(network_label(None).as_deref(), Some("network not recorded"));
        let builtin = PolicyIdentity {
            network: None,
            ..identity("a", "p")
        };
        assert_eq!(network_label(Some(&builtin)), None);
    }
}
