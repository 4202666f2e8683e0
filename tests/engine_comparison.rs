//! The two engines side by side (cargo feature `mujoco`): `crosscheck` on the same
//! episodes (per setting and push force, joint divergence, the feet's slip and when it
//! parts), its refusal of bad arguments before anything runs, the feet in both engines'
//! traces, the known `push_chair` gap kept in view (docs/engines.md "Why the engines part under
//! force: the feet"), scripted stepping under a pull falling alike on both, and `report`
//! refusing to mix engines unless asked. In a build without the feature these tests are
//! counted as skipped (and fail in CI, which builds it).

use std::path::Path;
use std::process::Command;

mod prereq;

const BIN: &str = env!("CARGO_BIN_EXE_thorarena");

/// Bound on the mean RMS joint-angle divergence of the `hold` policy between the engines
/// over the first second without force, rad: 0.002 measured on the sample data; the
/// open-loop cross-check's goal (docs/performance.md "Measured") is 0.005.
const NO_FORCE_DIVERGENCE_BOUND_RAD: f64 = 0.01;

fn run(args: &[&str]) -> std::process::Output {
    Command::new(BIN).args(args).output().unwrap()
}

/// `eval --policy hold` on the sample data without force on `engine`, into `out`.
fn hold_on_sample(engine: &str, out: &Path, extra: &[&str]) {
    let sample = Path::new(env!("CARGO_MANIFEST_DIR")).join("data/sample");
    let mut args = vec![
        "eval",
        "--policy",
        "hold",
        "--dataset",
        sample.to_str().unwrap(),
        "--settings",
        "no-force",
        "--engine",
        engine,
        "--out",
        out.to_str().unwrap(),
    ];
    args.extend_from_slice(extra);
    let o = run(&args);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
}

#[test]
fn report_refuses_runs_of_two_engines_unless_asked() {
    if !cfg!(feature = "mujoco") {
        return prereq::skip(
            "engine_comparison::report_mixed_engines",
            "built without the `mujoco` feature",
        );
    }
    let dir = tempfile::tempdir().unwrap();
    let mut runs = Vec::new();
    for engine in ["rapier", "mujoco"] {
        let out = dir.path().join(engine);
        hold_on_sample(engine, &out, &[]);
        // The run's own tables name the engine that produced them.
        let tables = std::fs::read_to_string(out.join("tables.md")).unwrap();
        assert!(tables.contains(&format!("engine {engine}")), "{tables}");
        runs.push(out);
    }
    let html = dir.path().join("r.html");
    let base = [
        "report",
        runs[0].to_str().unwrap(),
        runs[1].to_str().unwrap(),
        "--out",
        html.to_str().unwrap(),
    ];
    let o = run(&base);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success() && !html.exists(),
        "reported two engines unasked"
    );
    assert!(
        err.contains("different physics engines") && err.contains("--mixed-engines"),
        "{err}"
    );
    let mut asked = base.to_vec();
    asked.push("--mixed-engines");
    let o = run(&asked);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let md = std::fs::read_to_string(dir.path().join("r.md")).unwrap();
    assert!(
        md.contains("hold (rapier) [rapier]") && md.contains("hold (mujoco) [mujoco]"),
        "{md}"
    );
    let page = std::fs::read_to_string(&html).unwrap();
    assert!(page.contains("<th>engine</th>") && page.contains("mujoco (generated MJCF) at 5 ms"));
}

#[test]
fn crosscheck_compares_the_same_episodes_on_both_engines() {
    if !cfg!(feature = "mujoco") {
        return prereq::skip(
            "engine_comparison::crosscheck",
            "built without the `mujoco` feature",
        );
    }
    let dir = tempfile::tempdir().unwrap();
    // The sample as generator v1 made it (square stances): `hold` keeps the default
    // standing pose, so on v2's staggered and widened stances its first second drags the
    // feet into that pose (5 cm on clean_table_000 in MuJoCo) and the slip bounds below,
    // which are about the engines and not about the data, would measure the drag.
    let sample = dir.path().join("sample-v1");
    let o = run(&[
        "data",
        "synth",
        "--out",
        sample.to_str().unwrap(),
        "--per-task",
        "2",
        "--generator",
        "1",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let out = dir.path().join("xc");
    let o = run(&[
        "crosscheck",
        "--policy",
        "hold",
        "--dataset",
        sample.to_str().unwrap(),
        "--settings",
        "no-force,push:30@0,push:30@180",
        "--bootstrap",
        "500",
        "--out",
        out.to_str().unwrap(),
    ]);
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(stdout.contains("| mujoco − rapier [95 % CI] |"), "{stdout}");
    let j: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("crosscheck.json")).unwrap())
            .unwrap();
    let settings = j["settings"].as_array().unwrap();
    assert_eq!(settings.len(), 3);
    let episodes = j["episodes"].as_array().unwrap();
    assert_eq!(
        episodes.len(),
        36,
        "12 sequences × 3 settings, each on both engines"
    );
    for s in settings {
        assert_eq!(s["episodes"], 12);
        for metric in ["survival", "kp_mm", "score", "fats"] {
            let c = &s[metric];
            let (a, b, d) = (
                c["a"].as_f64().unwrap(),
                c["b"].as_f64().unwrap(),
                c["diff"].as_f64().unwrap(),
            );
            assert!(
                (d - (b - a)).abs() < 1e-9,
                "{metric}: the mean difference is b − a"
            );
            let ci = [
                c["ci95"][0].as_f64().unwrap(),
                c["ci95"][1].as_f64().unwrap(),
            ];
            assert!(
                ci[0] <= d + 1e-12 && d <= ci[1] + 1e-12,
                "{metric}: {d} outside {ci:?}"
            );
        }
    }
    // The per-episode numbers are those of the two run directories.
    let csv = std::fs::read_to_string(out.join("crosscheck.csv")).unwrap();
    assert_eq!(csv.lines().count(), 37);
    for engine in ["rapier", "mujoco"] {
        let h: serde_json::Value = serde_json::from_str(
            &std::fs::read_to_string(out.join(engine).join("run.json")).unwrap(),
        )
        .unwrap();
        assert_eq!(h["engine"]["name"], engine);
    }
    // Pushed at 30 N, standing still is not safe: survival falls on both engines.
    let pushed = &settings[1];
    assert!(pushed["survival"]["a"].as_f64().unwrap() < 1.0);
    assert!(pushed["survival"]["b"].as_f64().unwrap() < 1.0);

    // FATS is `eval`'s: each run's summary says the same per setting.
    for (engine, side) in [("rapier", "a"), ("mujoco", "b")] {
        let summary: serde_json::Value = serde_json::from_str(
            &std::fs::read_to_string(out.join(engine).join("summary.json")).unwrap(),
        )
        .unwrap();
        for s in settings {
            let name = s["setting"].as_str().unwrap();
            let fats = summary["settings"][name]["average"]["fats"]
                .as_f64()
                .unwrap();
            let ours = s["fats"][side].as_f64().unwrap();
            assert!(
                (fats - ours).abs() < 1e-9,
                "{engine} {name}: {ours} vs {fats}"
            );
        }
    }

    // Per push force, its two directions pooled.
    assert!(stdout.contains("| push per hand | episodes |"), "{stdout}");
    let levels = j["push_levels"].as_array().unwrap();
    let names: Vec<&str> = levels
        .iter()
        .map(|l| l["setting"].as_str().unwrap())
        .collect();
    assert_eq!(names, ["0 N (1 setting)", "30 N (2 settings)"]);
    assert_eq!(levels[1]["episodes"], 24);
    let pooled = (settings[1]["survival"]["b"].as_f64().unwrap()
        + settings[2]["survival"]["b"].as_f64().unwrap())
        / 2.0;
    assert!((levels[1]["survival"]["b"].as_f64().unwrap() - pooled).abs() < 1e-12);

    // Joint-angle divergence over the first second, per episode and per setting.
    assert!(
        stdout.contains("RMS joint-angle divergence over the first 1 s"),
        "{stdout}"
    );
    assert_eq!(j["divergence_seconds"], 1.0);
    for s in settings {
        let name = s["setting"].as_str().unwrap();
        let per_episode: Vec<f64> = episodes
            .iter()
            .filter(|e| e["setting"] == name)
            .map(|e| {
                let d = &e["joint_divergence"];
                let steps = d["steps"].as_u64().unwrap();
                // The default profile runs at 50 Hz: at most 50 steps end within 1 s.
                assert!((1..=50).contains(&steps), "{name}: {steps} steps");
                let (rms, max) = (
                    d["rms_rad"].as_f64().unwrap(),
                    d["max_rad"].as_f64().unwrap(),
                );
                assert!(rms.is_finite() && rms <= max + 1e-12, "{name}: {d}");
                rms
            })
            .collect();
        let agg = &s["joint_divergence_rad"];
        assert_eq!(agg["episodes"], 12);
        let mean = per_episode.iter().sum::<f64>() / 12.0;
        assert!((agg["mean"].as_f64().unwrap() - mean).abs() < 1e-12);
    }
    // The feet's slip over each whole episode, on both engines: holding the first pose,
    // the feet barely move (a few millimetres to 3 cm while the reference's first frame
    // settles), and the engines' slip never parts by more than the 2 cm margin.
    assert!(stdout.contains("feet's slip parts by > 2 cm"), "{stdout}");
    for e in episodes {
        let f = &e["foot_slip"];
        for side in 0..2 {
            let total = f["total_m"][side].as_f64().unwrap();
            assert!((0.0..0.05).contains(&total), "{e}");
        }
        assert!(f["parts_at_s"].is_null(), "{e}");
    }
    for s in settings {
        assert_eq!(s["slip_parted"], 0);
        let slip = &s["foot_slip_m"];
        assert!(slip["a"].as_f64().unwrap() > 0.0 && slip["b"].as_f64().unwrap() > 0.0);
    }
    assert!(csv
        .lines()
        .next()
        .unwrap()
        .ends_with("foot_slip_m_rapier,foot_slip_m_mujoco,foot_slip_parts_at_s"));
    // Without force, holding the first pose, the engines' joints stay within a few
    // hundredths of a radian of each other over the first second.
    let still = settings[0]["joint_divergence_rad"]["mean"]
        .as_f64()
        .unwrap();
    assert!(
        still > 0.0 && still < NO_FORCE_DIVERGENCE_BOUND_RAD,
        "{still}"
    );
}

#[test]
fn a_resumed_crosscheck_keeps_the_divergence_of_episodes_finished_before() {
    if !cfg!(feature = "mujoco") {
        return prereq::skip(
            "engine_comparison::crosscheck_resume",
            "built without the `mujoco` feature",
        );
    }
    let dir = tempfile::tempdir().unwrap();
    let sample = Path::new(env!("CARGO_MANIFEST_DIR")).join("data/sample");
    let out = dir.path().join("xc");
    let crosscheck = |extra: &[&str]| {
        let mut a = vec![
            "crosscheck",
            "--policy",
            "hold",
            "--dataset",
            sample.to_str().unwrap(),
            "--settings",
            "no-force",
            "--bootstrap",
            "100",
            "--out",
            out.to_str().unwrap(),
        ];
        a.extend(extra);
        let o = run(&a);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let j: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(out.join("crosscheck.json")).unwrap())
                .unwrap();
        (
            j["episodes"].clone(),
            String::from_utf8_lossy(&o.stderr).into_owned(),
        )
    };
    let (whole, _) = crosscheck(&[]);
    assert_eq!(whole.as_array().unwrap().len(), 12);
    // As if killed during MuJoCo's run: its last four episodes never finished.
    let log = out.join("mujoco/episodes.jsonl");
    let lines: Vec<String> = std::fs::read_to_string(&log)
        .unwrap()
        .lines()
        .map(str::to_string)
        .collect();
    std::fs::write(&log, lines[..8].join("\n") + "\n").unwrap();
    let (resumed, stderr) = crosscheck(&["--resume"]);
    assert!(!stderr.contains("no joint divergence"), "{stderr}");
    let resumed = resumed.as_array().unwrap();
    assert_eq!(resumed.len(), 12);
    for e in resumed {
        assert!(!e["joint_divergence"].is_null(), "{e}");
        assert!(!e["foot_slip"].is_null(), "{e}");
    }
    assert_eq!(&whole, &serde_json::Value::from(resumed.clone()));
}

#[test]
fn crosscheck_refuses_bad_arguments_before_running_anything() {
    if !cfg!(feature = "mujoco") {
        return prereq::skip(
            "engine_comparison::crosscheck_bad_arguments",
            "built without the `mujoco` feature",
        );
    }
    let dir = tempfile::tempdir().unwrap();
    for (args, expected) in [
        (
            vec!["--mujoco-physics-dt", "0.003"],
            "the MuJoCo run (--mujoco-physics-dt 0.003): --physics-dt 0.003: must be > 0 and divide",
        ),
        (
            vec!["--divergence-seconds", "0"],
            "--divergence-seconds must be a positive number",
        ),
        (vec!["--policy", "ipc:somewhere"], "runs the policy twice in process"),
        (vec!["--engine", "mujoco"], "leave out --engine"),
        // A confidence interval from no resample printed "-0.0 [+0.0, +0.0]"; 2⁶⁴ − 1
        // resamples overflowed an allocation — both only after both evaluations had run.
        (vec!["--bootstrap", "0"], "--bootstrap 0: the confidence intervals need between 1 and 1000000 resamples"),
        (vec!["--bootstrap", "18446744073709551615"], "--bootstrap 18446744073709551615: the confidence intervals need"),
    ] {
        let out = dir.path().join("xc");
        let mut full = vec!["crosscheck", "--out", out.to_str().unwrap()];
        if !args.contains(&"--policy") {
            full.extend(["--policy", "hold"]);
        }
        full.extend(args.iter().copied());
        let o = run(&full);
        let stderr = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(1), "{args:?}: {stderr}");
        assert!(stderr.contains(expected), "{args:?}: {stderr}");
        assert!(!out.join("rapier").exists(), "{args:?}: nothing may run");
    }
}

#[test]
fn traces_carry_the_feet_on_both_engines() {
    if !cfg!(feature = "mujoco") {
        return prereq::skip(
            "engine_comparison::traces_carry_the_feet",
            "built without the `mujoco` feature",
        );
    }
    // The same episode traced on each engine: both feet every step, their normal forces
    // carrying the robot's weight on average, slip accumulating and never decreasing.
    let g1 = thorarena::sim::robot::load_bundled("g1_29dof").unwrap();
    let weight_n = g1.total_mass_kg() * 9.81;
    let dir = tempfile::tempdir().unwrap();
    for engine in ["rapier", "mujoco"] {
        let out = dir.path().join(engine);
        hold_on_sample(engine, &out, &["--trace", "clean_table/clean_table_000"]);
        let trace: Vec<thorarena::eval::episode::TraceStep> = serde_json::from_str(
            &std::fs::read_to_string(out.join("traces/clean_table-clean_table_000-no-force.json"))
                .unwrap(),
        )
        .unwrap();
        assert!(trace.len() > 50);
        let mut load = 0.0;
        let mut last_slip = [0.0; 2];
        for s in &trace {
            let feet = s.feet.as_ref().expect("every step has the feet");
            let names: Vec<&str> = feet.iter().map(|f| f.body.as_str()).collect();
            assert_eq!(names, ["left_ankle_roll_link", "right_ankle_roll_link"]);
            for (k, f) in feet.iter().enumerate() {
                assert!(
                    f.normal_n >= 0.0 && f.slip_m >= last_slip[k],
                    "{engine}: {f:?}"
                );
                assert_eq!(f.soles.len(), 4);
                if f.normal_n > 0.0 {
                    let r = f.friction_ratio.unwrap();
                    assert!(
                        (0.0..=1.0 + 1e-6).contains(&r),
                        "{engine}: ratio {r} above μ"
                    );
                    assert!(
                        f.cop_w.unwrap()[2].abs() < 0.01,
                        "{engine}: CoP on the ground"
                    );
                }
                last_slip[k] = f.slip_m;
            }
            load += feet.iter().map(|f| f.normal_n).sum::<f64>();
        }
        let mean = load / trace.len() as f64;
        assert!(
            (mean - weight_n).abs() < 0.05 * weight_n,
            "{engine}: mean ground load {mean:.1} N, weight {weight_n:.1} N"
        );
    }
}

#[test]
fn crosscheck_of_pushed_chairs_shows_where_the_engines_part() {
    // The known difference of docs/engines.md "Why the engines part under force: the feet", kept in
    // view: TWIST2 on 8 synthetic push_chair sequences of generator v1 (where it was
    // measured: v2's real chair forces fell most episodes on both engines) under their
    // forces, rapier against MuJoCo on the generated MJCF at the same 5 ms. Measured:
    // survival 0.763 / 0.315, and the feet's slip parting in 8 of 8 episodes at 2.3–3.0 s,
    // after the chair's break-away shove at 2 s. If a change closes the gap, this test says so.
    if !cfg!(feature = "mujoco") {
        return prereq::skip(
            "engine_comparison::crosscheck_pushed_chairs",
            "built without the `mujoco` feature",
        );
    }
    let Some(onnx) = prereq::reference(
        "engine_comparison::crosscheck_pushed_chairs",
        "twist2/twist2_1017_25k.onnx",
    ) else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let data = dir.path().join("pc");
    let o = run(&[
        "data",
        "synth",
        "--out",
        data.to_str().unwrap(),
        "--tasks",
        "push_chair",
        "--per-task",
        "8",
        "--generator",
        "1",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let out = dir.path().join("xc");
    let policy = format!("twist2:{}", onnx.display());
    let o = run(&[
        "crosscheck",
        "--dataset",
        data.to_str().unwrap(),
        "--policy",
        &policy,
        "--profile",
        "twist2",
        "--keypoints",
        "twist9",
        "--settings",
        "force",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let j: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("crosscheck.json")).unwrap())
            .unwrap();
    let s = &j["settings"][0];
    let (rapier, mujoco) = (
        s["survival"]["a"].as_f64().unwrap(),
        s["survival"]["b"].as_f64().unwrap(),
    );
    assert!(
        rapier - mujoco > 0.2,
        "survival rapier {rapier:.3}, MuJoCo {mujoco:.3}: the known gap changed — update docs/engines.md"
    );
    let episodes = j["episodes"].as_array().unwrap();
    assert_eq!(episodes.len(), 8);
    let parted: Vec<f64> = episodes
        .iter()
        .filter_map(|e| e["foot_slip"]["parts_at_s"].as_f64())
        .collect();
    assert!(
        parted.len() >= 6,
        "slip parted in {} of 8 episodes",
        parted.len()
    );
    assert!(
        parted.iter().all(|t| (2.0..4.0).contains(t)),
        "the feet part after the break-away shove at 2 s: {parted:?}"
    );
}

/// The G1 on stiff standing PD stepping in place open loop (each leg lifted in turn,
/// 1.5 Hz) under a backward pull on both hands: when it falls, s (4 s if it does not).
fn scripted_march_falls_at_s(engine: &thorarena::sim::physics::Engine, pull_n: f64) -> f64 {
    use nalgebra::{Point3, Vector3};
    use thorarena::sim::physics::{
        make_physics, standing_default_pose, standing_gains, ExternalForce, PhysicsSettings,
        PhysicsState,
    };
    let m = std::sync::Arc::new(thorarena::sim::robot::load_bundled("g1_29dof").unwrap());
    let settings = PhysicsSettings::default();
    let mut p = make_physics(engine, m.clone(), settings, standing_gains(&m)).unwrap();
    let start = standing_default_pose(&m);
    p.reset(&start);
    for h in &m.hands {
        let f = &m.frames[h.frame];
        p.set_external_force(ExternalForce {
            body: f.body,
            force_w: Vector3::new(-pull_n, 0.0, 0.0),
            point_b: Point3::from((f.body_from_frame * h.point_hand).coords),
        });
    }
    let joint = |name: &str| m.joint_index(name).unwrap();
    let mut s = PhysicsState::default();
    let z0 = start.root.world_from_root.translation.z;
    let dt = p.settings().dt_s;
    for k in 0..(4.0 / dt) as usize {
        let t = k as f64 * dt;
        let mut q = start.q.clone();
        for (side, phase) in [("left", 0.0), ("right", std::f64::consts::PI)] {
            let lift = (2.0 * std::f64::consts::PI * 1.5 * t + phase)
                .sin()
                .max(0.0);
            q[joint(&format!("{side}_hip_pitch_joint"))] -= 0.5 * lift;
            q[joint(&format!("{side}_knee_joint"))] += lift;
            q[joint(&format!("{side}_ankle_pitch_joint"))] -= 0.5 * lift;
        }
        p.set_targets(&q);
        p.step();
        p.read_state(&mut s);
        let r = s.root.as_ref().unwrap();
        let tilt = r.projected_gravity_b().angle(&-Vector3::z());
        if tilt > 0.8 || (r.world_from_root.translation.z - z0).abs() > 0.25 {
            return t;
        }
    }
    4.0
}

#[test]
fn scripted_stepping_under_a_backward_pull_falls_alike_on_both_engines() {
    // Without a policy reacting, the engines agree on stepping under a sustained pull:
    // measured, the open-loop march falls at 0.97 / 0.96 s without force and 0.62 / 0.61 s
    // at 40 N per hand (rapier / MuJoCo). Their difference under force needs a policy's
    // repeated touchdowns (docs/engines.md, "Why the engines part under force: the feet").
    if !cfg!(feature = "mujoco") {
        return prereq::skip(
            "engine_comparison::scripted_stepping",
            "built without the `mujoco` feature",
        );
    }
    for pull in [0.0, 20.0, 40.0] {
        let rapier = scripted_march_falls_at_s(&thorarena::sim::physics::Engine::Rapier, pull);
        let mujoco = scripted_march_falls_at_s(
            &thorarena::sim::physics::Engine::mujoco_on(None).unwrap(),
            pull,
        );
        eprintln!("{pull} N per hand: falls at {rapier:.3} s (rapier), {mujoco:.3} s (MuJoCo)");
        assert!(rapier < 4.0 && mujoco < 4.0, "an open-loop march falls");
        assert!(
            (rapier - mujoco).abs() <= 0.05,
            "{pull} N: rapier falls at {rapier:.3} s, MuJoCo at {mujoco:.3} s"
        );
    }
}
