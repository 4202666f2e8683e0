//! What `thorarena report` and `thorarena view` compute, without a browser: the side-by-side
//! tables hold the runs' own scores (CSV at full precision, Markdown rounded, undefined
//! values empty or a dash), runs that measured different things are flagged, every plot
//! gets a canvas, the viewer's body poses come from forward kinematics of the trace, and
//! both commands write their files — or, without the front-end bundle, say how to build it.

use std::path::{Path, PathBuf};
use std::process::Command;
use thorarena::eval::episode::TraceStep;
use thorarena::eval::metrics::{EpisodeSeries, RegimeThresholds};
use thorarena::eval::results::summarize;
use thorarena::eval::EpisodeRecord;
use thorarena::report::{
    comparison_warnings, diagnostics_multi_table, diagnostics_table, fats_table, load_runs,
    report_html, view_scene, ReportError, TraceContext, WarningKind, WebBundle,
};
use thorarena::sim::robot::{self, forward_kinematics};

const BIN: &str = env!("CARGO_BIN_EXE_thorarena");

#[path = "common/run_dir.rs"]
mod run_dir;
use run_dir::{header, write_run};

/// A finished episode: `steps` of `steps_ref` recorded, error `err_m` at low force and
/// twice that at high force (forces alternate 0 / 10 / 20 N).
fn record(task: &str, id: &str, setting: &str, steps: usize, err_m: f64) -> EpisodeRecord {
    let force = |k: usize| [0.0, 10.0, 20.0][k % 3];
    let err = |k: usize| if force(k) > 15.0 { 2.0 * err_m } else { err_m };
    EpisodeRecord {
        task: task.into(),
        sequence_id: id.into(),
        setting: setting.into(),
        coefficient: if setting == "force" { 1.0 } else { 0.0 },
        policy: "p".into(),
        termination: (steps < 30).then_some(thorarena::eval::Termination::TorsoTilt),
        faults: Default::default(),
        series: EpisodeSeries {
            kp_err_m: (0..steps).map(err).collect(),
            kp_err_upper_m: (0..steps).map(err).collect(),
            kp_err_lower_m: (0..steps).map(err).collect(),
            total_force_n: (0..steps).map(force).collect(),
            power_w: (0..steps).map(|k| 100.0 + force(k)).collect(),
            root_drift_m: vec![0.01; steps],
            kp_err_global_m: (0..steps).map(err).collect(),
            steps_ref: 30,
        },
    }
}

fn standard_records(err_m: f64) -> Vec<EpisodeRecord> {
    let mut v = Vec::new();
    for setting in ["force", "no-force"] {
        for (task, n) in [("clean_table", 30), ("push_chair", 12)] {
            for id in ["000", "001"] {
                v.push(record(task, &format!("{task}_{id}"), setting, n, err_m));
            }
        }
    }
    v
}

/// Two comparable runs (policies `a` and `b`) in a temporary directory.
fn two_runs() -> (tempfile::TempDir, Vec<PathBuf>) {
    let dir = tempfile::tempdir().unwrap();
    let a = dir.path().join("a");
    let b = dir.path().join("b");
    write_run(&a, &header("a"), &standard_records(0.02), false);
    write_run(&b, &header("b"), &standard_records(0.05), true);
    (dir, vec![a, b])
}

fn parse_csv(text: &str) -> Vec<Vec<String>> {
    csv::ReaderBuilder::new()
        .has_headers(false)
        .from_reader(text.as_bytes())
        .records()
        .map(|r| r.unwrap().iter().map(str::to_string).collect())
        .collect()
}

#[test]
fn csv_tables_hold_each_runs_own_scores_at_full_precision() {
    let (_dir, dirs) = two_runs();
    let runs = load_runs(&dirs).unwrap();
    let th = RegimeThresholds::from_forces(&[0.0, 10.0, 20.0]);
    let thresholds = [
        ("clean_table".to_string(), th),
        ("push_chair".to_string(), th),
    ]
    .into_iter()
    .collect();
    let own = summarize(&standard_records(0.05), &thresholds);

    let fats = parse_csv(&fats_table(&runs).csv());
    assert_eq!(
        fats[0],
        [
            "Task",
            "FATS: a (force)",
            "FATS: a (no-force)",
            "FATS: b (force)",
            "FATS: b (no-force)"
        ]
    );
    assert_eq!(
        fats.iter().map(|r| r[0].as_str()).collect::<Vec<_>>(),
        ["Task", "clean_table", "push_chair", "average"]
    );
    let b_force_push: f64 = fats[2][3].parse().unwrap();
    let expected = own["force"]
        .0
        .iter()
        .find(|t| t.task == "push_chair")
        .unwrap();
    assert_eq!(b_force_push, expected.diagnostics.fats, "bit for bit");
    let b_avg: f64 = fats[3][3].parse().unwrap();
    assert_eq!(b_avg, own["force"].1.fats);

    let diag = parse_csv(&diagnostics_multi_table(&runs).csv());
    let survival = diag.iter().find(|r| r[0] == "Survival (mean)").unwrap();
    let s: f64 = survival[3].parse().unwrap();
    assert_eq!(s, own["force"].1.survival);
    assert!(
        (s - (1.0 + 0.4) / 2.0).abs() < 1e-12,
        "clean_table 30/30, push_chair 12/30"
    );
}

#[test]
fn undefined_diagnostics_are_empty_in_csv_and_a_dash_in_markdown() {
    let dir = tempfile::tempdir().unwrap();
    // Constant force: every step is low force, so the high-force error is undefined.
    let mut records = vec![record("clean_table", "clean_table_000", "force", 30, 0.02)];
    records[0].series.total_force_n = vec![0.0; 30];
    let mut h = header("a");
    h.settings.truncate(1);
    write_run(&dir.path().join("a"), &h, &records, false);
    let runs = load_runs(&[dir.path().join("a")]).unwrap();
    let table = diagnostics_multi_table(&runs);
    let csv = parse_csv(&table.csv());
    let high = csv.iter().find(|r| r[0] == "High KP, RMS (mm)").unwrap();
    assert_eq!(high[1], "");
    assert!(table.markdown().contains("| High KP, RMS (mm) | – |"));
    // The single-run table of tables.md says the same.
    assert!(diagnostics_table(&runs[0].results).contains("| High KP, RMS (mm) | – |"));
    assert!(diagnostics_table(&runs[0].results).contains("| Survival (mean) | 1.000 |"));
}

#[test]
fn comparable_runs_raise_no_warning() {
    let (_dir, dirs) = two_runs();
    let runs = load_runs(&dirs).unwrap();
    assert_eq!(comparison_warnings(&runs), []);
    let html = report_html(&runs, "/* bundle */");
    assert!(!html.contains("id=\"comparability-warnings\""));
}

#[test]
fn runs_with_other_datasets_termination_rules_or_profiles_are_flagged() {
    let dir = tempfile::tempdir().unwrap();
    let base = header("a");
    let mut other_data = header("b");
    other_data.dataset_sha256 = "cd".repeat(32);
    let mut other_rule = header("c");
    other_rule.termination.max_torso_tilt_error_rad = 0.5;
    // The same policy under another profile: what a profile changes is then the
    // comparison's subject, unlike policies each on its own profile (next test).
    let mut other_profile = header("a");
    other_profile.profile = "twist2".into();
    let mut shard = header("e");
    shard.shard = Some((0, 2));
    let mut other_engine = header("f");
    other_engine.engine = thorarena::sim::physics::Engine::Mujoco {
        mjcf: Some("g1.xml".into()),
        mjcf_sha256: None,
    };
    other_engine.physics_dt_s = 0.001;
    let cases = [
        ("f", other_engine, WarningKind::Physics),
        ("b", other_data, WarningKind::Dataset),
        ("c", other_rule, WarningKind::Termination),
        ("d", other_profile, WarningKind::Profile),
        ("e", shard, WarningKind::Partial),
    ];
    write_run(&dir.path().join("a"), &base, &standard_records(0.02), false);
    for (name, h, kind) in cases {
        let path = dir.path().join(name);
        write_run(&path, &h, &standard_records(0.03), false);
        let runs = load_runs(&[dir.path().join("a"), path]).unwrap();
        let warnings = comparison_warnings(&runs);
        assert_eq!(
            warnings.iter().map(|w| w.kind).collect::<Vec<_>>(),
            [kind],
            "{warnings:?}"
        );
        let html = report_html(&runs, "");
        assert!(html.contains("id=\"comparability-warnings\""));
        assert!(html.contains(&thorarena::report::escape(&warnings[0].message)));
    }
}

#[test]
fn policies_each_on_its_own_profile_are_a_note_and_an_overridden_profile_a_warning() {
    let dir = tempfile::tempdir().unwrap();
    let base = header("a");
    let mut own_profile = header("b");
    own_profile.profile = "twist2".into();
    own_profile.control_dt_s = 0.02;
    write_run(&dir.path().join("a"), &base, &standard_records(0.02), false);
    write_run(
        &dir.path().join("b"),
        &own_profile,
        &standard_records(0.03),
        false,
    );
    let runs = load_runs(&[dir.path().join("a"), dir.path().join("b")]).unwrap();
    assert_eq!(comparison_warnings(&runs), []);
    let notes = thorarena::report::comparison_notes(&runs);
    assert!(
        notes
            .iter()
            .any(|n| n.contains("by design") && n.contains("`twist2`")),
        "{notes:?}"
    );
    // A run whose profile contradicted its family (--profile-mismatch-ok) is not one the
    // comparison can take as by design.
    let mut overridden = own_profile.clone();
    overridden.profile_mismatch_ok = true;
    write_run(
        &dir.path().join("c"),
        &overridden,
        &standard_records(0.03),
        false,
    );
    let runs = load_runs(&[dir.path().join("a"), dir.path().join("c")]).unwrap();
    assert_eq!(
        comparison_warnings(&runs)
            .iter()
            .map(|w| w.kind)
            .collect::<Vec<_>>(),
        [WarningKind::Profile]
    );
}

#[test]
fn datasets_and_mjcfs_are_compared_by_content_and_a_path_is_only_a_note() {
    let dir = tempfile::tempdir().unwrap();
    let base = header("a");
    // The same dataset content read from another path (the cache copy, a sweep's
    // absolute path): comparable, said as a note.
    let mut moved = header("b");
    moved.dataset = "/elsewhere/sample".into();
    write_run(&dir.path().join("a"), &base, &standard_records(0.02), false);
    write_run(
        &dir.path().join("b"),
        &moved,
        &standard_records(0.03),
        false,
    );
    let runs = load_runs(&[dir.path().join("a"), dir.path().join("b")]).unwrap();
    assert_eq!(comparison_warnings(&runs), []);
    let notes = thorarena::report::comparison_notes(&runs);
    assert_eq!(notes.len(), 1, "{notes:?}");
    assert!(notes[0].contains("/elsewhere/sample"), "{notes:?}");
    let html = report_html(&runs, "");
    assert!(!html.contains("id=\"comparability-warnings\""));
    assert!(html.contains("id=\"comparability-notes\""));
    // One MJCF path, two contents: not comparable.
    let mujoco = |hash: &str| thorarena::sim::physics::Engine::Mujoco {
        mjcf: Some("g1.xml".into()),
        mjcf_sha256: Some(hash.repeat(32)),
    };
    let (mut c, mut d) = (header("c"), header("d"));
    c.engine = mujoco("ab");
    d.engine = mujoco("cd");
    write_run(&dir.path().join("c"), &c, &standard_records(0.02), false);
    write_run(&dir.path().join("d"), &d, &standard_records(0.03), false);
    let runs = load_runs(&[dir.path().join("c"), dir.path().join("d")]).unwrap();
    let kinds: Vec<_> = comparison_warnings(&runs).iter().map(|w| w.kind).collect();
    assert_eq!(kinds, [WarningKind::Physics]);
}

#[test]
fn runs_of_the_same_policy_get_distinct_labels() {
    let dir = tempfile::tempdir().unwrap();
    let (x, y) = (dir.path().join("ckpt-1"), dir.path().join("ckpt-2"));
    write_run(&x, &header("twist2"), &standard_records(0.02), false);
    write_run(&y, &header("twist2"), &standard_records(0.03), false);
    let runs = load_runs(&[x, y]).unwrap();
    assert_eq!(runs[0].label, "twist2 (ckpt-1)");
    assert_eq!(runs[1].label, "twist2 (ckpt-2)");
}

#[test]
fn the_report_page_has_a_canvas_per_plot_and_latency_plots_only_for_policy_server_runs() {
    let (_dir, dirs) = two_runs();
    let runs = load_runs(&dirs).unwrap();
    let html = report_html(&runs, "/* bundle */");
    for id in [
        "radar-force",
        "radar-no-force",
        "scatter-tracking-survival",
        "kp-regimes-force",
        "kp-regimes-no-force",
        "latency-percentiles",
        "latency-faults",
    ] {
        assert!(
            html.contains(&format!("<canvas id=\"{id}\"></canvas>")),
            "no canvas #{id}"
        );
    }
    for id in ["fats-table", "diagnostics-table", "policy-io-table"] {
        assert!(
            html.contains(&format!("<table id=\"{id}\"")),
            "no table #{id}"
        );
    }
    assert!(html.contains("/* bundle */"));
    // In-process runs alone: their latency is in the table, but nothing is plotted.
    let html = report_html(&runs[..1], "");
    assert!(html.contains("id=\"policy-io-table\"") && !html.contains("latency-percentiles"));
}

fn trace(with_reference: bool) -> Vec<TraceStep> {
    let g1 = robot::load_bundled("g1_29dof").unwrap();
    let q = g1.default_pose();
    (0..5)
        .map(|k| TraceStep {
            time_s: 0.02 * (k + 1) as f64,
            root_pos: [0.1 * k as f64, 0.0, 0.78],
            root_quat_wxyz: [1.0, 0.0, 0.0, 0.0],
            q: q.iter().map(|x| x + 0.01 * k as f64).collect(),
            targets: q.clone(),
            hand_force_w: [[0.0, 0.0, -10.0], [5.0, 0.0, 0.0]],
            keypoints_w: vec![[0.0, 0.0, 1.0]; 13],
            reference_keypoints_w: vec![[0.0, 0.0, 1.01]; 13],
            kp_err_m: 0.01,
            reference_root_pos: with_reference.then_some([0.0, 0.5, 0.78]),
            reference_root_quat_wxyz: with_reference.then_some([1.0, 0.0, 0.0, 0.0]),
            reference_q: with_reference.then(|| q.clone()),
            feet: None,
        })
        .collect()
}

#[test]
fn the_viewer_poses_robot_and_ghost_bodies_by_forward_kinematics() {
    let g1 = robot::load_bundled("g1_29dof").unwrap();
    let steps = trace(true);
    let scene = view_scene(&g1, &steps, Path::new("t.json"), &TraceContext::default()).unwrap();
    assert_eq!(scene.bodies.len(), g1.bodies.len());
    let shapes: usize = g1.bodies.iter().map(|b| b.shapes.len()).sum();
    assert_eq!(
        scene.bodies.iter().map(|b| b.shapes.len()).sum::<usize>(),
        shapes
    );
    assert!(scene.bodies.iter().flat_map(|b| &b.shapes).any(|s| s.sole));
    let mut poses = Vec::new();
    let root = nalgebra::Isometry3::translation(0.3, 0.0, 0.78);
    forward_kinematics(&g1, &root, &steps[3].q, &mut poses);
    let last = g1.bodies.len() - 1;
    let p = poses[last].translation.vector;
    let got = &scene.robot_poses[3][7 * last..7 * last + 3];
    assert!(
        (got[0] - p.x).abs() < 1e-4 && (got[1] - p.y).abs() < 1e-4 && (got[2] - p.z).abs() < 1e-4,
        "{got:?} vs {p:?}"
    );
    let ghost = scene.reference_poses.as_ref().unwrap();
    assert_eq!(&ghost[0][..3], &[0.0, 0.5, 0.78]);
    // Re-anchoring moves the reference root onto the robot root.
    let anchor = scene.anchor.as_ref().unwrap()[2];
    assert!((anchor[0] - 0.2).abs() < 1e-9 && (anchor[1] + 0.5).abs() < 1e-9);
    assert_eq!(scene.kp_err_mm, vec![10.0; 5]);
}

#[test]
fn traces_without_reference_joints_still_view_and_wrong_robots_are_refused() {
    let g1 = robot::load_bundled("g1_29dof").unwrap();
    let scene = view_scene(
        &g1,
        &trace(false),
        Path::new("t.json"),
        &TraceContext::default(),
    )
    .unwrap();
    assert!(scene.reference_poses.is_none() && scene.anchor.is_none());
    let mut bad = trace(true);
    bad[1].q.pop();
    let err = view_scene(&g1, &bad, Path::new("t.json"), &TraceContext::default()).unwrap_err();
    assert!(matches!(err, ReportError::BadTrace { .. }));
    assert!(
        err.to_string().contains("step 1 has 28 joint angles"),
        "{err}"
    );
}

#[test]
fn a_missing_bundle_says_how_to_build_it() {
    let dir = tempfile::tempdir().unwrap();
    let err = WebBundle::at(dir.path()).unwrap_err();
    assert!(err.to_string().contains("npm ci --prefix web"), "{err}");
    let (_runs, dirs) = two_runs();
    let out = Command::new(BIN)
        .env("THORARENA_WEB_DIST", dir.path())
        .arg("report")
        .args(&dirs)
        .args(["--out", dir.path().join("r.html").to_str().unwrap()])
        .output()
        .unwrap();
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("npm run build --prefix web"));
}

#[test]
fn report_and_view_write_their_files_with_the_bundle_inlined() {
    let bundle = tempfile::tempdir().unwrap();
    std::fs::write(bundle.path().join("report.js"), "/* REPORT BUNDLE */").unwrap();
    std::fs::write(bundle.path().join("view.js"), "/* VIEW BUNDLE */").unwrap();
    let (dir, dirs) = two_runs();
    let html = dir.path().join("out/cmp.html");
    let out = Command::new(BIN)
        .env("THORARENA_WEB_DIST", bundle.path())
        .arg("report")
        .args(&dirs)
        .args(["--out", html.to_str().unwrap()])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let page = std::fs::read_to_string(&html).unwrap();
    assert!(page.contains("/* REPORT BUNDLE */") && page.contains("id=\"report-data\""));
    let md = std::fs::read_to_string(dir.path().join("out/cmp.md")).unwrap();
    assert!(md.contains("| Task | FATS: a (force) |"), "{md}");
    for csv in ["out/cmp-fats.csv", "out/cmp-diagnostics.csv"] {
        let text = std::fs::read_to_string(dir.path().join(csv)).unwrap();
        assert_eq!(parse_csv(&text)[0].len(), 5, "{csv}");
    }

    // A trace inside a run directory: the page names the policy and how the episode ended.
    let traces = dirs[0].join("traces");
    std::fs::create_dir_all(&traces).unwrap();
    let trace_path = traces.join("clean_table-clean_table_000-force.json");
    std::fs::write(&trace_path, serde_json::to_string(&trace(true)).unwrap()).unwrap();
    let view = dir.path().join("view.html");
    let out = Command::new(BIN)
        .env("THORARENA_WEB_DIST", bundle.path())
        .arg("view")
        .arg(&trace_path)
        .args(["--out", view.to_str().unwrap()])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let page = std::fs::read_to_string(&view).unwrap();
    assert!(page.contains("/* VIEW BUNDLE */") && page.contains("id=\"view-data\""));
    assert!(page.contains("<dt>policy</dt><dd>a</dd>"));
    assert!(page.contains("completed all 30 steps"));
    assert!(page.contains("max=\"4\""), "timeline over 5 steps");
}

#[test]
fn page_scripts_edited_after_the_bundle_was_built_are_reported_stale() {
    let web = tempfile::tempdir().unwrap();
    let (src, dist) = (web.path().join("src"), web.path().join("dist"));
    std::fs::create_dir_all(&src).unwrap();
    std::fs::create_dir_all(&dist).unwrap();
    let long_ago = std::time::SystemTime::UNIX_EPOCH + std::time::Duration::from_secs(1_000_000);
    for name in ["report.js", "view.js"] {
        let f = std::fs::File::create(dist.join(name)).unwrap();
        f.set_modified(long_ago).unwrap();
    }
    std::fs::write(src.join("view.js"), "// edited").unwrap();
    std::fs::write(src.join("view.css"), "/* not a script */").unwrap();
    let bundle = WebBundle::at(&dist).unwrap();
    assert_eq!(bundle.stale_sources(), [src.join("view.js")]);
}

#[test]
fn report_and_view_use_the_bundle_compiled_into_the_binary() {
    // No bundle directory anywhere: the pages must come from the binary alone.
    let (dir, dirs) = two_runs();
    let html = dir.path().join("embedded.html");
    let out = Command::new(BIN)
        .env_remove("THORARENA_WEB_DIST")
        .current_dir(dir.path())
        .arg("report")
        .args(&dirs)
        .args(["--out", html.to_str().unwrap()])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let page = std::fs::read_to_string(&html).unwrap();
    assert!(page.contains("Chart.js v4"), "Chart.js is inlined");
    assert!(
        page.contains("window.thorarenaReport"),
        "our page script is inlined"
    );

    let traces = dirs[0].join("traces");
    std::fs::create_dir_all(&traces).unwrap();
    let trace_path = traces.join("clean_table-clean_table_000-force.json");
    std::fs::write(&trace_path, serde_json::to_string(&trace(true)).unwrap()).unwrap();
    let view = dir.path().join("embedded-view.html");
    let out = Command::new(BIN)
        .env_remove("THORARENA_WEB_DIST")
        .current_dir(dir.path())
        .arg("view")
        .arg(&trace_path)
        .args(["--out", view.to_str().unwrap()])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let page = std::fs::read_to_string(&view).unwrap();
    assert!(
        page.contains("window.thorarenaView"),
        "our viewer script is inlined"
    );
    assert!(page.contains("Three.js Authors"), "three.js is inlined");
}
