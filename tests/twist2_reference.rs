//! The published TWIST2 policy (`../shared/reference/twist2/twist2_1017_25k.onnx`) walks
//! the three released TWIST2 walks in ThorArena as it does in MuJoCo, TWIST2's own
//! setting: survival 1.0 on each walk without force, and a TWIST9 keypoint error within
//! 10 % of the MuJoCo figure of SOURCES.md, TWIST2 in MuJoCo (28.0 / 31.1 / 33.5 mm). A constant 30 N push
//! on both hands makes it fall, as in MuJoCo (SOURCES.md, TWIST2 in MuJoCo: survival 0.30 at 30 N). The
//! Python adapter builds the same observation (1e-5) and, with ONNX Runtime, the same
//! action (1e-4) as the Rust policy with tract, step by step over an episode. Skipped,
//! saying so, when `../shared/reference` (or, for the last, Python's onnxruntime) is absent.

use std::path::{Path, PathBuf};
use std::process::Command;

#[path = "common/dump.rs"]
mod dump;
#[path = "common/walks.rs"]
mod walks;
use walks::{import_walks, MUJOCO_TWIST9_MM};
mod prereq;
mod readme;

const BIN: &str = env!("CARGO_BIN_EXE_thorarena");

/// The published TWIST2 artifacts, or `None` after a recorded skip.
fn reference_dir(test: &str) -> Option<PathBuf> {
    prereq::reference(test, "twist2/twist2_1017_25k.onnx")
        .and_then(|onnx| onnx.parent().map(PathBuf::from))
}

fn run(args: &[&str]) -> String {
    let out = Command::new(BIN).args(args).output().unwrap();
    assert!(
        out.status.success(),
        "thorarena {args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8_lossy(&out.stdout).into_owned()
}

/// Per walk: (survival, mean TWIST9 keypoint error in mm) of one setting.
fn evaluate(
    reference: &Path,
    dataset: &Path,
    setting: &str,
    out: &Path,
) -> Vec<(String, f64, f64)> {
    let policy = format!(
        "twist2:{}",
        reference.join("twist2_1017_25k.onnx").display()
    );
    run(&[
        "eval",
        "--dataset",
        dataset.to_str().unwrap(),
        "--policy",
        &policy,
        "--profile",
        "twist2",
        "--keypoints",
        "twist9",
        "--settings",
        setting,
        "--out",
        out.to_str().unwrap(),
    ]);
    std::fs::read_to_string(out.join("episodes.jsonl"))
        .unwrap()
        .lines()
        .map(|l| {
            let r: serde_json::Value = serde_json::from_str(l).unwrap();
            let s = &r["series"];
            let e: Vec<f64> = s["kp_err_m"]
                .as_array()
                .unwrap()
                .iter()
                .map(|v| v.as_f64().unwrap())
                .collect();
            let survival = e.len() as f64 / s["steps_ref"].as_f64().unwrap();
            let mean_mm = 1e3 * e.iter().sum::<f64>() / e.len().max(1) as f64;
            (
                r["sequence_id"].as_str().unwrap().to_string(),
                survival,
                mean_mm,
            )
        })
        .collect()
}

/// Held by each test of this file while it runs: the latency bench times a round trip and
/// the network call inside it in microseconds, which a simulation beside it on the same two
/// cores would disturb (a C ABI row once measured its round trip's median 3 µs under its
/// network call's with the walks running beside it).
static ONE_AT_A_TIME: std::sync::Mutex<()> = std::sync::Mutex::new(());

fn one_at_a_time() -> std::sync::MutexGuard<'static, ()> {
    ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner())
}

#[test]
fn the_published_twist2_policy_walks_the_released_walks_as_in_mujoco() {
    let _alone = one_at_a_time();
    let Some(reference) = reference_dir("twist2_reference::walks") else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let walks = dir.path().join("walks");
    import_walks(&reference, &walks);

    let results = evaluate(&reference, &walks, "no-force", &dir.path().join("no-force"));
    assert_eq!(results.len(), 3);
    for (walk, survival, mm) in &results {
        let mujoco = MUJOCO_TWIST9_MM.iter().find(|(w, _)| w == walk).unwrap().1;
        eprintln!("{walk}: survival {survival:.2}, TWIST9 {mm:.1} mm (MuJoCo {mujoco} mm)");
        assert_eq!(*survival, 1.0, "{walk} fell without force");
        assert!(
            (mm - mujoco).abs() <= 0.1 * mujoco,
            "{walk}: TWIST9 error {mm:.1} mm is not within 10 % of MuJoCo's {mujoco} mm"
        );
    }

    let pushed = evaluate(&reference, &walks, "push:30", &dir.path().join("push-30"));
    let mean_survival = pushed.iter().map(|r| r.1).sum::<f64>() / pushed.len() as f64;
    for (walk, survival, mm) in &pushed {
        eprintln!("{walk} under a 30 N push: survival {survival:.2}, TWIST9 {mm:.1} mm");
    }
    // Trained without hand forces, TWIST2 falls under a sustained 30 N push (MuJoCo: 0.30
    // survival over 18 motions): the push must reach the hands.
    assert!(
        mean_survival < 0.9,
        "survival {mean_survival:.2} under a 30 N push"
    );

    // docs/policies.md's table is these measurements, to the digits it prints.
    let table = readme::readme_table("twist2-walks");
    assert_eq!(table.len(), 3);
    for row in &table {
        let walk = &row[0];
        let (_, survival, mm) = results.iter().find(|r| &r.0 == walk).unwrap();
        let mujoco = MUJOCO_TWIST9_MM.iter().find(|(w, _)| w == walk).unwrap().1;
        let pushed = pushed.iter().find(|r| &r.0 == walk).unwrap().1;
        let measured = [
            format!("{survival:.2}"),
            format!("{mm:.1} / {mujoco:.1}"),
            format!("{pushed:.2}"),
        ];
        assert_eq!(
            row[1..],
            measured,
            "docs/policies.md's TWIST2 row for {walk} differs from what was measured"
        );
    }
}

#[test]
fn the_python_twist2_adapter_builds_the_same_observations_and_actions() {
    let _alone = one_at_a_time();
    use thorarena::eval::episode::EpisodeSetup;
    use thorarena::eval::TerminationRule;
    use thorarena::policy::{Policy, Twist2Policy};
    const TEST: &str = "twist2_reference::python_adapter";
    let Some(reference) = reference_dir(TEST) else {
        return;
    };
    if !prereq::python_modules(
        TEST,
        &["onnxruntime", "iceoryx2", "numpy"],
        "pip install './adapters/python[policies]'",
    ) {
        return;
    }
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let robot = thorarena::sim::robot::load_bundled("g1_29dof").unwrap();
    let profile = thorarena::sim::profile::load_profile(
        &thorarena::sim::profile::bundled_profile_path("twist2"),
        &robot,
    )
    .unwrap();
    let onnx = reference.join("twist2_1017_25k.onnx");
    let mut policy = Twist2Policy::load(&onnx, profile.action_offset_rad.clone()).unwrap();
    let offsets = policy.reference_offsets_s();
    let ds = thorarena::sim::motion::Dataset::open(&root.join("data/sample"), &robot).unwrap();
    let seq = ds
        .load_all()
        .unwrap()
        .into_iter()
        .find(|s| s.task == "syn_carry")
        .unwrap();
    let setup = EpisodeSetup {
        robot: &robot,
        profile: &profile,
        keypoints: robot.keypoint_set("twist9").unwrap(),
        termination: TerminationRule::default(),
        force_coefficient: 1.0,
        push_n: 0.0,
        push_heading_deg: None,
        disturbance: None,
        reference_offsets_s: offsets.clone(),
    };
    let steps = dump::record_episode(
        &mut policy,
        |p| p.last_inputs()[0].clone(),
        &setup,
        &seq,
        150,
    );
    assert!(steps.len() >= 100, "the episode ran {} steps", steps.len());
    let dir = tempfile::tempdir().unwrap();
    let (agrees, report) = dump::python_agrees("twist2", &onnx, &setup, steps, dir.path());
    assert!(agrees, "Python and Rust TWIST2 disagree: {report}");
}

/// `bench ipc --clients twist2` times the Python adapter with the real network and the
/// network alone inside it, in one run, with the observation built by the simulator (the
/// session over iceoryx2's Python binding, then over the C ABI this build left beside the
/// binary) and by the adapter: every column is measured (a round trip holds a network call, so it is
/// never the shorter; only the simulator-built rows spend time building), one row per
/// environment count and builder.
#[test]
fn bench_ipc_times_the_python_adapter_against_its_own_network_call() {
    let _alone = one_at_a_time();
    const TEST: &str = "twist2_reference::bench_ipc_adapter";
    let Some(reference) = reference_dir(TEST) else {
        return;
    };
    if !prereq::python_modules(
        TEST,
        &["onnxruntime", "iceoryx2", "numpy"],
        "pip install './adapters/python[policies]'",
    ) {
        return;
    }
    let onnx = reference.join("twist2_1017_25k.onnx");
    let out = run(&[
        "bench",
        "ipc",
        "--clients",
        "twist2",
        "--onnx",
        onnx.to_str().unwrap(),
        "--envs",
        "1,4",
        "--warmup",
        "20",
        "--adapter-steps",
        "200",
        "--python",
        "python3",
    ]);
    // | envs | built by | round trip p50 | p90 | p99 | build p50 | prepared p50
    // | network p50 | network p90 | overhead p50 | overhead p90 | noticed polling % |
    let rows: Vec<(String, Vec<f64>)> = out
        .lines()
        .filter(|l| l.starts_with("| ") && !l.starts_with("| envs"))
        .map(|l| {
            let cells: Vec<&str> = l.trim_matches('|').split('|').map(str::trim).collect();
            let numbers = cells
                .iter()
                .enumerate()
                .filter(|(i, _)| *i != 1)
                .map(|(_, c)| c.parse::<f64>().unwrap())
                .collect();
            (cells[1].to_string(), numbers)
        })
        .collect();
    let over_c_abi = "simulator (Rust), C ABI client";
    assert_eq!(
        rows.len(),
        6,
        "three rows (simulator, simulator over the C ABI, adapter) per environment count:\n{out}"
    );
    for ((built_by, row), (envs, by)) in rows.iter().zip([
        (1.0, "simulator (Rust)"),
        (1.0, over_c_abi),
        (1.0, "adapter (numpy)"),
        (4.0, "simulator (Rust)"),
        (4.0, over_c_abi),
        (4.0, "adapter (numpy)"),
    ]) {
        let (rt_p50, build_p50, prepared_p50, net_p50, overhead_p50) =
            (row[1], row[4], row[5], row[6], row[8]);
        assert_eq!((row[0], built_by.as_str()), (envs, by), "{out}");
        // Each step's round trip holds its network call.
        assert!(
            net_p50 > 0.0 && rt_p50 >= net_p50 && overhead_p50 > 0.0,
            "{out}"
        );
        assert_eq!(build_p50 > 0.0, by.starts_with("simulator"), "{out}");
        assert_eq!(prepared_p50 > 0.0, by.starts_with("simulator"), "{out}");
        let noticed_polling = row[10];
        assert!((0.0..=100.0).contains(&noticed_polling), "{out}");
    }
}
