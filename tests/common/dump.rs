//! Episode dumps for the Python adapters' cross-checks: one environment's observation as
//! the wire carries it, field by field, in the JSON `thorarena.adapters.dump` reads; an
//! in-process policy's episode recorded step by step; and the Python check run on it.
#![allow(dead_code)]

use std::path::Path;
use thorarena::eval::episode::{Episode, EpisodeSetup};
use thorarena::policy::Policy;
use thorarena::sim::motion::Sequence;
use thorarena::sim::physics::{PhysicsSettings, RapierPhysics};

/// Runs `policy` on `seq` in rapier for at most `max_steps` control steps and records each
/// step as the dump format wants it: the wire block, the network input (`last_input`
/// reads it from the policy after `act`) and the action.
pub fn record_episode<P: Policy>(
    policy: &mut P,
    last_input: impl Fn(&P) -> Vec<f32>,
    setup: &EpisodeSetup,
    seq: &Sequence,
    max_steps: usize,
) -> Vec<serde_json::Value> {
    let settings = PhysicsSettings {
        dt_s: setup.profile.physics_dt_s,
        ..Default::default()
    };
    let robot = std::sync::Arc::new(setup.robot.clone());
    let mut physics = RapierPhysics::new(robot, settings, setup.profile.gains.clone());
    let mut ep = Episode::start(setup, seq, &mut physics);
    let offsets = &setup.reference_offsets_s;
    let mut steps = Vec::new();
    let mut actions = vec![vec![0.0; setup.robot.n_joints()]];
    while !ep.is_done() && steps.len() < max_steps {
        let obs = ep.observation();
        policy.act(std::slice::from_ref(&obs), &mut actions);
        steps.push(serde_json::json!({
            "env": wire_json(&obs, offsets),
            "obs": last_input(policy),
            "action": actions[0],
        }));
        ep.advance(&mut physics, &actions[0]);
    }
    steps
}

/// Writes the dump of `steps` (under `setup`'s action mapping) into `dir` and runs
/// `adapters/python/examples/check_against_dump.py --adapter ADAPTER` on it with `onnx`;
/// returns whether the Python adapter agreed, and its report.
pub fn python_agrees(
    adapter: &str,
    onnx: &Path,
    setup: &EpisodeSetup,
    steps: Vec<serde_json::Value>,
    dir: &Path,
) -> (bool, String) {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let dump = serde_json::json!({
        "action_offset_rad": setup.profile.action_offset_rad,
        "action_scale": setup.profile.action_scale,
        "steps": steps,
    });
    let path = dir.join(format!("{adapter}-dump.json"));
    std::fs::write(&path, dump.to_string()).unwrap();
    let mut command = std::process::Command::new("python3");
    command
        .arg(root.join("adapters/python/examples/check_against_dump.py"))
        .args(["--adapter", adapter, "--dump"])
        .arg(&path)
        .arg("--onnx")
        .arg(onnx)
        .env("PYTHONPATH", root.join("adapters/python"));
    // The terms the Rust side took from the profile, for a file that names none.
    if let Some(bm) = setup
        .profile
        .beyondmimic
        .as_ref()
        .filter(|b| !b.observation_names.is_empty())
    {
        command.args(["--observation-names", &bm.observation_names.join(",")]);
    }
    let out = command.output().unwrap();
    let report = String::from_utf8_lossy(&out.stdout).into_owned();
    eprintln!("{report}{}", String::from_utf8_lossy(&out.stderr));
    (out.status.success(), report)
}

/// One environment's wire block as JSON, field by field (what the Python adapter reads).
pub fn wire_json(obs: &thorarena::policy::Observation, offsets: &[f64]) -> serde_json::Value {
    use thorarena_ipc::layout::{ENV_ARRAYS, REF_ARRAYS};
    use thorarena_ipc::{Layout, ObsBatch, ObsBatchMut};
    let layout = Layout {
        n_envs: 1,
        n_joints: obs.q.len(),
        n_refs: offsets.len(),
        n_inputs: 0,
    };
    let mut words = vec![0u64; layout.obs_words()];
    {
        let mut batch = ObsBatchMut::new(layout, bytemuck::cast_slice_mut(&mut words), 0, 0);
        thorarena::policy::wire::write_observation(obs, offsets, &mut batch.env(0), 0);
    }
    let batch = ObsBatch::new(layout, bytemuck::cast_slice(&words)).unwrap();
    let env = batch.env(0);
    let h = env.header();
    let mut map = serde_json::Map::new();
    map.insert("episode_id".into(), h.episode_id.into());
    map.insert("step".into(), h.step.into());
    map.insert("flags".into(), h.flags.into());
    map.insert("time_s".into(), h.time_s.into());
    for (name, _, _) in ENV_ARRAYS {
        map.insert(name.into(), env.array(name).to_vec().into());
    }
    let frames: Vec<serde_json::Value> = (0..layout.n_refs)
        .map(|i| {
            REF_ARRAYS
                .iter()
                .map(|(name, _, _)| {
                    let v = env.reference(i, name);
                    let v = if v.len() == 1 {
                        v[0].into()
                    } else {
                        v.to_vec().into()
                    };
                    (name.to_string(), v)
                })
                .collect::<serde_json::Map<_, _>>()
                .into()
        })
        .collect();
    map.insert("reference".into(), frames.into());
    map.into()
}
