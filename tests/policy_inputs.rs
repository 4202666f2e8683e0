//! A policy process that asks for TWIST2's input gets, in each batch's policy-input block,
//! bit for bit the vector the in-process TWIST2 policy builds for the same observations:
//! per slot, with its own history, refilled when a slot starts a new episode, and zeros
//! in a slot with no episode. The policy end is the Rust client, in a thread.

use std::time::Duration;
use thorarena::campaign::bench::standing_observation;
use thorarena::policy::{twist2, Observation, Policy, RemoteConfig, RemotePolicy};
use thorarena_ipc::{PolicyClient, PolicyConfig, SimConfig};

const N_ENVS: usize = 3;

fn joint_names() -> Vec<String> {
    let robot = thorarena::policy::registry::robot("g1_29dof").unwrap();
    robot.joints.iter().map(|j| j.name.clone()).collect()
}

/// Slot `env` at episode step `step`: standing, with joints and root rates that change
/// from step to step so that the history matters.
fn moving(env: usize, step: u64) -> Observation {
    let mut obs = standing_observation(env, step, 29, 2);
    let phase = env as f64 + step as f64 * 0.1;
    for (j, q) in obs.q.iter_mut().enumerate() {
        *q = 0.05 * (phase + j as f64).sin();
    }
    obs.qd[7] = phase.cos();
    obs.last_action[3] = -phase;
    obs.root.ang_vel_w.z = 0.2 * phase.sin();
    obs.reference[1].joint_pos[0] = 0.01 * phase;
    obs
}

#[test]
fn the_simulator_builds_twist2s_input_as_the_in_process_policy_does() {
    let session = format!("test-inputs-{}", std::process::id());
    let joints = joint_names();
    let default_pose: Vec<f64> = (0..29).map(|j| 0.01 * j as f64).collect();
    let config = RemoteConfig {
        session: SimConfig {
            session: session.clone(),
            n_envs: N_ENVS,
            joint_names: joints.clone(),
            control_dt_s: 0.02,
            action_offset_rad: default_pose.clone(),
            action_scale: vec![0.5; 29],
            budget: None,
            wait: Default::default(),
            inputs: thorarena::policy::inputs::offers(29),
        },
        connect_timeout: Some(Duration::from_secs(20)),
        reconnect: false,
    };
    let client = std::thread::spawn(move || {
        let mut config = PolicyConfig::new(&session, "twist2-client", joints, vec![0.0, 0.02]);
        config.input = "twist2".into();
        let mut client = PolicyClient::connect(&config, Duration::from_secs(20)).unwrap();
        let mut batches = Vec::new();
        client
            .run(|obs, _actions| batches.push(obs.policy_inputs().to_vec()))
            .unwrap();
        batches
    });
    let mut policy = RemotePolicy::connect(
        config,
        &mut |_| Ok(None),
        &mut |m| panic!("{m}"),
        &mut || false,
    )
    .unwrap();
    // Slot 0 runs 12 steps; slot 1 starts a new episode at step 6; slot 2 is idle until
    // step 4.
    let mut expected = Vec::new();
    let mut histories = vec![twist2::History::default(); N_ENVS];
    for k in 0..12u64 {
        let mut observations = vec![moving(0, k)];
        observations.push(moving(1, if k < 6 { k } else { k - 6 }));
        if k >= 4 {
            observations.push(moving(2, k - 4));
        }
        let mut batch = vec![0.0f32; N_ENVS * twist2::OBS_LEN];
        for obs in &observations {
            let row = twist2::observation(obs, &default_pose, &mut histories[obs.env]);
            batch[obs.env * twist2::OBS_LEN..][..twist2::OBS_LEN].copy_from_slice(&row);
        }
        expected.push(batch);
        let mut actions = vec![vec![0.0; 29]; observations.len()];
        policy.act(&observations, &mut actions);
    }
    drop(policy);
    let got = client.join().unwrap();
    assert_eq!(got.len(), expected.len());
    for (k, (got, want)) in got.iter().zip(&expected).enumerate() {
        let same = got
            .iter()
            .zip(want)
            .all(|(a, b)| a.to_bits() == b.to_bits());
        assert!(
            same,
            "step {k}: the block differs from the in-process input"
        );
    }
    // The idle slot was zeros, and the history made later rows differ from the first.
    assert!(got[0][2 * twist2::OBS_LEN..].iter().all(|x| *x == 0.0));
    assert_ne!(got[3][..twist2::OBS_LEN], got[0][..twist2::OBS_LEN]);
}
