//! FALCON (RSS 2025, github.com/LeCAR-Lab/FALCON, MIT) in process: its observation at two
//! hand-made steps against the values `tests/fixtures/falcon_golden/golden.py` computes
//! from the deploy code's formulas (numpy, independently of this crate), the released
//! network's actions on that observation against the same script's numpy forward pass,
//! and `policy check` on the bundled walk. Skipped, saying so, when
//! `../shared/reference` is absent; never in CI.

use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3};
use std::process::Command;
use thorarena::policy::falcon::commands::{CommandRules, Commands};
use thorarena::policy::falcon::observation::{frame, History, OBS_LEN};
use thorarena::policy::falcon::{
    FalconPolicy, DEFAULT_POSE, MOTOR_POS_LOWER_RAD, MOTOR_POS_UPPER_RAD,
};
use thorarena::policy::Observation;
use thorarena::sim::physics::RootState;

mod common;
mod prereq;

fn numbers(file: &str) -> Vec<f64> {
    common::fixture_numbers("falcon_golden", file)
}

/// The robot of one step: upright or pitched by `pitch` rad, its root-frame angular
/// velocity `w_b`, joints `q`, `qd`.
fn observation(step: usize, pitch: f64, w_b: [f64; 3], q: Vec<f64>, qd: Vec<f64>) -> Observation {
    let rotation = UnitQuaternion::from_euler_angles(0.0, pitch, 0.0);
    let mut root = RootState::at_rest(Isometry3::from_parts(
        Translation3::new(0.0, 0.0, 0.78),
        rotation,
    ));
    root.ang_vel_w = rotation * Vector3::from(w_b);
    Observation {
        env: 0,
        episode_id: 0,
        step,
        time_s: step as f64 * 0.02,
        root,
        q,
        qd,
        last_action: vec![0.0; 29],
        reference: Vec::new(),
    }
}

/// The golden script's two steps (its docstring states them), built with the crate's frame
/// and history.
fn golden_input() -> Vec<f32> {
    let commands = |upper0: f64| {
        let mut upper = [0.0; 14];
        upper[0] = upper0;
        Commands {
            lin_vel: [0.5, 0.0],
            ang_vel: 0.2,
            stand: 1.0,
            base_height_m: 0.75,
            waist: [0.0; 3],
            upper,
        }
    };
    let mut history = History::default();
    let mut input = vec![0.0f32; OBS_LEN];

    let mut qd = vec![0.0; 29];
    qd[3] = 1.0;
    let a1: Vec<f64> = (0..29)
        .map(|i| 0.01 * (i + 1) as f64 * if i % 2 == 0 { 1.0 } else { -1.0 })
        .collect();
    let step1 = observation(0, 0.0, [0.1, -0.2, 0.3], DEFAULT_POSE.to_vec(), qd);
    history.push_into(
        frame(&step1, &DEFAULT_POSE, &a1, &commands(0.0)),
        true,
        &mut input,
    );

    let mut q = DEFAULT_POSE.to_vec();
    q[0] = -0.05;
    q[12] = 0.02;
    q[15] = 0.1;
    let mut qd = vec![0.0; 29];
    qd[3] = 0.5;
    qd[6] = -0.3;
    let a2: Vec<f64> = (0..29).map(|i| -0.02 * (i as f64 - 14.0)).collect();
    let step2 = observation(1, 0.1, [0.05, -0.1, 0.25], q, qd);
    history.push_into(
        frame(&step2, &DEFAULT_POSE, &a2, &commands(0.2)),
        false,
        &mut input,
    );
    input
}

#[test]
fn the_observation_matches_the_deploy_formulas_at_two_hand_made_steps() {
    let golden = numbers("observation_step2.txt");
    assert_eq!(golden.len(), OBS_LEN);
    let ours = golden_input();
    // The four oldest frames are step 1's, repeated as an episode's history starts; a
    // zero-filled start (the deploy's buffer at process start) would fail here.
    for k in 0..4 {
        assert_eq!(golden[k * 115..(k + 1) * 115], golden[345..460]);
    }
    assert!(golden[..115].iter().any(|v| *v != 0.0));
    for (i, (o, g)) in ours.iter().zip(&golden).enumerate() {
        assert!(
            (f64::from(*o) - g).abs() < 1e-7,
            "input {i} (frame {}, offset {}): ours {o}, deploy formulas {g}",
            i / 115,
            i % 115
        );
    }
}

#[test]
fn the_released_network_gives_the_numpy_forward_pass_actions() {
    const TEST: &str = "the_released_network_gives_the_numpy_forward_pass_actions";
    let Some(onnx) = prereq::reference(TEST, "falcon/g1_29dof_falcon.onnx") else {
        return;
    };
    let robot = common::g1();
    let profile = thorarena::policy::registry::profile("falcon", &robot).unwrap();
    let policy = FalconPolicy::load(&onnx, &profile).unwrap();
    let actions = policy.infer(&golden_input()).unwrap();
    let golden = numbers("actions_step2.txt");
    assert_eq!(actions.len(), golden.len());
    for (i, (a, g)) in actions.iter().zip(&golden).enumerate() {
        assert!(
            (f64::from(*a) - g).abs() < 1e-5,
            "action {i}: ours {a}, numpy {g}"
        );
    }
}

/// The deploy's targets for the golden step-2 output (`targets_step2.txt`: clip ±100,
/// legs and waist at default + 0.25 · a, arms at the reference + 0.25 · a, then the motor
/// limits), reached through the adapter's raw actions and the `falcon` profile; and a
/// target past a motor limit stops at it, as `loco_manip.py:137-138` clips it.
#[test]
fn the_adapter_gives_the_deploys_targets_clipped_to_the_motor_limits() {
    const TEST: &str = "the_adapter_gives_the_deploys_targets_clipped_to_the_motor_limits";
    let Some(onnx) = prereq::reference(TEST, "falcon/g1_29dof_falcon.onnx") else {
        return;
    };
    let robot = common::g1();
    let profile = thorarena::policy::registry::profile("falcon", &robot).unwrap();
    let policy = FalconPolicy::load(&onnx, &profile).unwrap();
    let out: Vec<f32> = numbers("actions_step2.txt")
        .iter()
        .map(|a| *a as f32)
        .collect();
    let mut upper = [0.0; 14];
    upper[0] = 0.2; // step 2's ref_upper (the other arm references are the default pose: 0)
    let mut raw = vec![0.0; 29];
    policy.raw_actions(&out, &upper, &mut raw);
    let mut targets = vec![0.0; 29];
    profile.targets_from_action(&raw, &mut targets);
    let golden = numbers("targets_step2.txt");
    for (c, (t, g)) in targets.iter().zip(&golden).enumerate() {
        assert!((t - g).abs() < 1e-6, "joint {c}: ours {t}, deploy {g}");
    }

    // Far past every limit: each joint stops at the deploy's motor limit.
    for sign in [1.0f32, -1.0] {
        policy.raw_actions(&[sign * 100.0; 29], &[sign as f64 * 10.0; 14], &mut raw);
        profile.targets_from_action(&raw, &mut targets);
        let limits = if sign > 0.0 {
            MOTOR_POS_UPPER_RAD
        } else {
            MOTOR_POS_LOWER_RAD
        };
        for (c, (t, l)) in targets.iter().zip(&limits).enumerate() {
            assert!((t - l).abs() < 1e-9, "joint {c}: target {t}, limit {l}");
        }
    }

    // The ablation `@arm_residual=0`: the arms at their commanded joints, the legs and
    // waist as the network says; and it is a parameter `run.json` records.
    let ablated = FalconPolicy::load(&onnx, &profile)
        .unwrap()
        .with_arm_residual_scale(0.0);
    ablated.raw_actions(&out, &upper, &mut raw);
    profile.targets_from_action(&raw, &mut targets);
    for c in 15..29 {
        assert!(
            (targets[c] - upper[c - 15]).abs() < 1e-9,
            "arm joint {c}: {} vs commanded {}",
            targets[c],
            upper[c - 15]
        );
    }
    for (c, (t, g)) in targets.iter().zip(&golden).enumerate().take(15) {
        assert!((t - g).abs() < 1e-6, "joint {c}: ours {t}, deploy {g}");
    }
    use thorarena::policy::Policy;
    assert_eq!(ablated.parameters(), vec![("arm_residual_scale", 0.0)]);
    assert!(
        policy.parameters().is_empty(),
        "as trained: nothing new named"
    );
    // Training's command rules, each an exception undone, are parameters too.
    let ruled = FalconPolicy::load(&onnx, &profile)
        .unwrap()
        .with_command_rules(CommandRules {
            min_speed_m_s: 0.2,
            yaw_feedforward: 0.0,
            hold_s: CommandRules::BENCHMARK.hold_s,
        });
    assert_eq!(
        ruled.parameters(),
        vec![
            ("command_min_speed_m_s", 0.2),
            ("command_yaw_feedforward", 0.0)
        ]
    );
}

#[test]
fn policy_check_passes_on_the_bundled_walk_and_the_network_does_the_work() {
    const TEST: &str = "policy_check_passes_on_the_bundled_walk_and_the_network_does_the_work";
    let Some(onnx) = prereq::reference(TEST, "falcon/g1_29dof_falcon.onnx") else {
        return;
    };
    let out = Command::new(env!("CARGO_BIN_EXE_thorarena"))
        .args(["policy", "check", &format!("falcon:{}", onnx.display())])
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{stdout}\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(stdout.contains("under profile `falcon`"), "{stdout}");
    assert!(stdout.contains("command-following"), "{stdout}");
    assert!(stdout.contains("judged as a command follower"), "{stdout}");
    assert!(stdout.contains("root velocity error"), "{stdout}");
    for check in ["wiring", "stand", "track", "zero_action"] {
        assert!(
            stdout
                .lines()
                .any(|l| l.trim_start().starts_with(&format!("pass {check}"))),
            "{check}: {stdout}"
        );
    }
}

#[test]
fn an_eval_marks_the_cells_outside_falcons_force_curriculum_in_its_own_tables() {
    const TEST: &str = "an_eval_marks_the_cells_outside_falcons_force_curriculum_in_its_own_tables";
    let Some(onnx) = prereq::reference(TEST, "falcon/g1_29dof_falcon.onnx") else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("run");
    let root = env!("CARGO_MANIFEST_DIR");
    // The sample's chair pushes reach 50–65 N horizontal while walking; FALCON's
    // curriculum stops at 40. Without force nothing is judged.
    let o = Command::new(env!("CARGO_BIN_EXE_thorarena"))
        .args([
            "eval",
            "--dataset",
            &format!("{root}/data/sample"),
            "--policy",
            &format!("falcon:{}", onnx.display()),
            "--tasks",
            "push_chair",
            "--settings",
            "force,no-force",
            "--out",
        ])
        .arg(&out)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let run: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("run.json")).unwrap()).unwrap();
    let why = run["outside_training"]["force"]["push_chair"]
        .as_str()
        .unwrap_or_else(|| panic!("run.json: {}", run["outside_training"]));
    assert!(why.contains("horizontal walking, above 40"), "{why}");
    assert!(run["outside_training"].get("no-force").is_none());
    let tables = std::fs::read_to_string(out.join("tables.md")).unwrap();
    let row = tables
        .lines()
        .find(|l| l.starts_with("| push_chair |"))
        .unwrap_or_else(|| panic!("{tables}"));
    let cells: Vec<&str> = row.split('|').map(str::trim).collect();
    let header = tables
        .lines()
        .find(|l| l.starts_with("| Task |"))
        .unwrap_or_else(|| panic!("{tables}"));
    let columns: Vec<&str> = header.split('|').map(str::trim).collect();
    let at = |setting: &str| {
        let name = format!("FATS ({setting}), mean of episodes");
        columns.iter().position(|c| *c == name).unwrap()
    };
    assert!(cells[at("force")].ends_with(" †"), "{row}");
    assert!(!cells[at("no-force")].contains('†'), "{row}");
    assert!(
        tables.contains(&format!("- `force`, push_chair: {why}")),
        "{tables}"
    );
    assert!(
        tables.contains("Its training: a curriculum on both hands"),
        "{tables}"
    );
}
