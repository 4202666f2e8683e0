//! Network inputs the simulator builds for a policy process that asks for one by name in
//! its hello (`Hello::input`), written into the batch's policy-input block: one
//! `[n_envs, n_inputs]` float32 array, the tensor the network takes.
//!
//! Why the simulator builds them: a policy process in Python pays numpy's per-call cost
//! for every term of an observation, which for TWIST2's 1432 floats was most of its
//! per-step time (docs/performance.md, "Policy round trip"). The same vector is built here
//! by the code the in-process policy uses ([`super::twist2::observation_into`]), once per
//! environment, while the simulator holds the data anyway; the client only runs its
//! network on a zero-copy view.

use super::twist2;
use super::Observation;
use thorarena_ipc::{InputOffer, ObsBatchMut};

/// The inputs this simulator builds for a robot of `n_joints` joints: TWIST2's for the
/// 29-joint G1 only (its observation has 29 joint positions per frame; the handshake's
/// joint-name hash holds a policy to the G1's names).
pub fn offers(n_joints: usize) -> Vec<InputOffer> {
    let twist2 = InputOffer {
        name: TWIST2.into(),
        n_inputs: twist2::OBS_LEN,
        reference_offsets_s: vec![0.0, twist2::MIMIC_LOOKAHEAD_S],
    };
    (n_joints == twist2::N_JOINTS)
        .then_some(twist2)
        .into_iter()
        .collect()
}

/// TWIST2's 1432-float observation, with its per-environment history.
const TWIST2: &str = "twist2";

/// Builds one named input for every environment slot of a session, keeping whatever
/// per-slot state it needs (TWIST2's history) across steps.
pub struct InputBuilder {
    /// The pose `q` is taken relative to (the profile's action offset), rad.
    default_pose: Vec<f64>,
    histories: Vec<twist2::History>,
}

impl InputBuilder {
    /// The builder of input `name` for `n_envs` slots, or `None` for a name [`offers`]
    /// does not list for `default_pose`'s joint count (the handshake refuses those first).
    pub fn new(name: &str, n_envs: usize, default_pose: &[f64]) -> Option<Self> {
        let offered = offers(default_pose.len()).iter().any(|o| o.name == name);
        offered.then(|| Self {
            default_pose: default_pose.to_vec(),
            histories: vec![twist2::History::default(); n_envs],
        })
    }

    /// Writes `obs`'s input into `out` (its slot's row) and advances that slot's state.
    /// `prepared`: every row of the batch `out` belongs to went through [`Self::prepare`]
    /// after the last `write`, so what it wrote there is not written again.
    pub fn write(&mut self, obs: &Observation, out: &mut [f32], prepared: bool) {
        let history = &mut self.histories[obs.env];
        twist2::observation_onto(obs, &self.default_pose, history, out, prepared);
    }

    /// Writes into every slot's row of the next batch what its next `write` would write
    /// there from the state it already has (TWIST2's history: 10 of its 11 frames), while
    /// the policy process computes the current step
    /// ([`thorarena_ipc::SimSession::step_prepared`]).
    pub fn prepare(&self, next: &mut ObsBatchMut) {
        for (slot, history) in self.histories.iter().enumerate() {
            twist2::history_into(history, next.policy_input(slot));
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn twist2s_input_is_offered_for_the_29_joint_g1_only() {
        assert_eq!(offers(29).len(), 1);
        assert!(offers(23).is_empty());
        assert!(InputBuilder::new(TWIST2, 2, &[0.0; 29]).is_some());
        assert!(InputBuilder::new(TWIST2, 2, &[0.0; 23]).is_none());
        assert!(InputBuilder::new("gmt", 2, &[0.0; 29]).is_none());
    }
}
