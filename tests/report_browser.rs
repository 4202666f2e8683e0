//! `thorarena report` and `thorarena view` in a real browser: headless Chromium opens a
//! report comparing two runs of the sample dataset (`balance` in process, `hold` through
//! the policy server) and the 3D replay of one traced episode, from disk with the network
//! cut off. Checked: no console error or exception, no request leaves the file, every
//! plot's canvas exists and holds paint and data, the tables have their rows, the viewer
//! draws the robot (its pixels differ from the empty scene), and moving the timeline —
//! or pressing Play — moves it. In the report and the sweep's report (two policies × two
//! latency rules × two force coefficients), as Chart.js drew them: each policy has one colour in every chart of
//! both pages, every chart's legend names each of its policies in that colour, the scatter's
//! legend maps each setting to its marker, the sweep's curves map their latency rule to a
//! line style in their legend, and the sweep's title names its axes.
//! Screenshots of the last run stay in `<target>/browser-tests/` for CI artifacts.
//!
//! The pages use the front-end bundle compiled into the binary. Needs `chromium` (Debian's
//! package), node, and the test driver's playwright-core (`npm ci --prefix web`); without
//! them the test is recorded as skipped (a failure in CI).

use serde_json::Value;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

mod prereq;

const ROOT: &str = env!("CARGO_MANIFEST_DIR");
const BIN: &str = env!("CARGO_BIN_EXE_thorarena");

/// The browser, or why the test cannot run.
fn prerequisites() -> Result<PathBuf, String> {
    let chromium = std::env::var_os("THORARENA_CHROMIUM")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from("/usr/bin/chromium"));
    if !chromium.is_file() {
        return Err(format!(
            "no browser at {} (apt-get install chromium, or set THORARENA_CHROMIUM)",
            chromium.display()
        ));
    }
    let node = Command::new("node").arg("--version").output();
    if !node.is_ok_and(|o| o.status.success()) {
        return Err("node is not on PATH".into());
    }
    if !Path::new(ROOT)
        .join("web/node_modules/playwright-core")
        .is_dir()
    {
        return Err("web/node_modules/playwright-core is missing (npm ci --prefix web)".into());
    }
    Ok(chromium)
}

fn run(cmd: &mut Command, what: &str) -> std::process::Output {
    let out = cmd.output().unwrap_or_else(|e| panic!("{what}: {e}"));
    assert!(
        out.status.success(),
        "{what} failed:\n{}\n{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    out
}

fn eval_args(policy: &str, out: &Path) -> Vec<String> {
    [
        "eval",
        "--dataset",
        &format!("{ROOT}/data/sample"),
        "--policy",
        policy,
        "--settings",
        "force,no-force",
        "--out",
        out.to_str().unwrap(),
    ]
    .map(String::from)
    .to_vec()
}

/// `balance` in process with a trace of one clean_table episode, and `hold` as a separate
/// process behind the policy server (so the report has latency to plot).
fn make_runs(dir: &Path) -> (PathBuf, PathBuf, PathBuf) {
    let balance = dir.join("balance");
    run(
        Command::new(BIN)
            .args(eval_args("balance", &balance))
            .args(["--trace", "clean_table/clean_table_000"]),
        "eval balance",
    );
    let hold = dir.join("hold");
    let session = format!("browser-{}", std::process::id());
    let server = Command::new(BIN)
        .args(eval_args(&format!("ipc:{session}"), &hold))
        .args(["--connect-timeout", "120"])
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let client = Command::new(BIN)
        .args(["client", "--session", &session, "--policy", "hold"])
        .args(["--connect-timeout", "120"])
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    for (child, what) in [(server, "eval over ipc"), (client, "client hold")] {
        let out = child.wait_with_output().unwrap();
        assert!(
            out.status.success(),
            "{what}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
    }
    let trace = balance.join("traces/clean_table-clean_table_000-force.json");
    (balance, hold, trace)
}

/// An eight-cell sweep (balance and hold as policy processes — a budget times a process's
/// round trip —, without and with force, in lock step and with a
/// 5 ms budget under measured latency) collected into its report.
fn make_sweep(dir: &Path) -> PathBuf {
    let spec = dir.join("sweep.toml");
    std::fs::write(
        &spec,
        format!(
            "datasets = [\"{ROOT}/data/sample\"]\nsettings = [\"no-force\", \"force\"]\n[[policy]]\nname = \"hold\"\ncommand = \"{{thorarena}} client --session {{session}} --policy hold\"\nconnect_timeout_s = 30\n[[policy]]\nname = \"balance\"\ncommand = \"{{thorarena}} client --session {{session}} --policy balance\"\nconnect_timeout_s = 30\n[[latency]]\nname = \"lock-step\"\n[[latency]]\nname = \"5ms\"\nbudget = \"5ms\"\nmode = \"measured\"\n"
        ),
    )
    .unwrap();
    let sweep = dir.join("sweep");
    for args in [
        vec![
            "sweep",
            "plan",
            spec.to_str().unwrap(),
            "--out",
            sweep.to_str().unwrap(),
        ],
        vec!["sweep", "run", sweep.to_str().unwrap()],
        vec!["sweep", "collect", sweep.to_str().unwrap()],
    ] {
        run(
            Command::new(BIN)
                .env_remove("THORARENA_WEB_DIST")
                .args(&args),
            args[1],
        );
    }
    sweep.join("report.html")
}

/// Checks the charts of the report pages `pages` (name, facts) as drawn: one colour per
/// policy across all of them, and legends that say which colour is which policy.
fn check_chart_styles(pages: &[(&str, &Value)], context: &str) {
    use std::collections::{BTreeMap, BTreeSet};
    let mut colours: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
    // (page, chart, policy, legend) to check once the colours are known to be one each.
    let mut legends: Vec<(&str, &str, String, &Vec<Value>)> = Vec::new();
    for (page, facts) in pages {
        let charts = facts["charts"]
            .as_object()
            .unwrap_or_else(|| panic!("{page}: the page exposes no charts; {context}"));
        for id in facts["declared_plots"].as_array().unwrap() {
            let id = id.as_str().unwrap();
            let chart = &charts
                .get(id)
                .unwrap_or_else(|| panic!("{page}: no chart #{id}; {context}"));
            let legend = chart["legend"].as_array().unwrap();
            let mut policies: BTreeSet<&str> = BTreeSet::new();
            for d in chart["datasets"].as_array().unwrap() {
                let policy = d["policy"]
                    .as_str()
                    .unwrap_or_else(|| panic!("{page} #{id}: a dataset without policy: {d}"));
                let colour = d["border_color"]
                    .as_str()
                    .unwrap_or_else(|| panic!("{page} #{id}: a dataset without colour: {d}"))
                    .to_ascii_lowercase();
                colours
                    .entry(policy.to_string())
                    .or_default()
                    .insert(colour);
                policies.insert(policy);
            }
            for policy in policies {
                legends.push((page, id, policy.to_string(), legend));
            }
        }
    }
    for (policy, set) in &colours {
        assert_eq!(
            set.len(),
            1,
            "policy {policy} is drawn in several colours {set:?}; {context}"
        );
    }
    let distinct: BTreeSet<&String> = colours.values().flatten().collect();
    assert_eq!(
        distinct.len(),
        colours.len(),
        "two policies share a colour: {colours:?}"
    );
    for policy in ["balance", "hold"] {
        assert!(colours.contains_key(policy), "{policy} is in no chart");
    }
    for (page, id, policy, legend) in legends {
        let colour = colours[&policy].first().unwrap();
        assert!(
            legend
                .iter()
                .any(|e| e["text"].as_str().is_some_and(|t| t.contains(&policy))
                    && e["stroke_style"]
                        .as_str()
                        .map(str::to_ascii_lowercase)
                        .as_ref()
                        == Some(colour)),
            "{page} #{id}: no legend entry names {policy} in its colour {colour}: {legend:?}"
        );
    }
}

/// The scatter's legend maps each setting to the marker its points are drawn with, and
/// settings have different markers.
fn check_scatter_markers(page: &str, facts: &Value, settings: &[&str], context: &str) {
    let chart = &facts["charts"]["scatter-tracking-survival"];
    let legend = chart["legend"].as_array().cloned().unwrap_or_default();
    let mut markers = std::collections::BTreeSet::new();
    for setting in settings {
        let styles: std::collections::BTreeSet<String> = chart["datasets"]
            .as_array()
            .unwrap()
            .iter()
            .filter(|d| {
                d["label"]
                    .as_str()
                    .is_some_and(|l| l.ends_with(&format!(" — {setting}")))
            })
            .map(|d| d["point_style"].as_str().unwrap_or("?").to_string())
            .collect();
        assert_eq!(
            styles.len(),
            1,
            "{page}: the points of {setting} have markers {styles:?}; {context}"
        );
        let style = styles.into_iter().next().unwrap();
        assert!(
            legend
                .iter()
                .any(|e| e["text"].as_str().is_some_and(|t| t.contains(setting)
                    && !t.contains("balance")
                    && !t.contains("hold"))
                    && e["point_style"].as_str() == Some(style.as_str())),
            "{page}: no legend entry maps marker {style} to setting {setting}: {legend:?}"
        );
        markers.insert(style);
    }
    assert_eq!(
        markers.len(),
        settings.len(),
        "{page}: settings share a marker"
    );
}

fn differing(v: &Value) -> (u64, u64) {
    (
        v["differing"].as_u64().unwrap_or(0),
        v["total"].as_u64().unwrap_or(0),
    )
}

#[test]
fn report_and_viewer_render_in_headless_chromium() {
    let chromium = match prerequisites() {
        Ok(c) => c,
        Err(reason) => {
            return prereq::skip(
                "report_browser::report_and_viewer_render_in_headless_chromium",
                &reason,
            );
        }
    };
    let shots = Path::new(env!("CARGO_TARGET_TMPDIR"))
        .parent()
        .expect("target dir")
        .join("browser-tests");
    let _ = std::fs::remove_dir_all(&shots);
    std::fs::create_dir_all(&shots).unwrap();
    let runs = tempfile::tempdir().unwrap();
    let (balance, hold, trace) = make_runs(runs.path());
    let report = shots.join("report.html");
    let view = shots.join("view.html");
    run(
        Command::new(BIN)
            // The bundle compiled into the binary, not a directory.
            .env_remove("THORARENA_WEB_DIST")
            .arg("report")
            .args([&balance, &hold])
            .arg("--out")
            .arg(&report),
        "report",
    );
    run(
        Command::new(BIN)
            .env_remove("THORARENA_WEB_DIST")
            .arg("view")
            .arg(&trace)
            .arg("--out")
            .arg(&view),
        "view",
    );
    let sweep_report = make_sweep(runs.path());
    let out = run(
        Command::new("node")
            .arg(Path::new(ROOT).join("web/tests/browser.mjs"))
            .arg("--report")
            .arg(&report)
            .arg("--sweep-report")
            .arg(&sweep_report)
            .arg("--view")
            .arg(&view)
            .arg("--shots")
            .arg(&shots)
            .arg("--chromium")
            .arg(&chromium),
        "the browser driver",
    );
    let facts: Value = serde_json::from_slice(&out.stdout).expect("driver prints JSON");
    std::fs::write(
        shots.join("facts.json"),
        serde_json::to_string_pretty(&facts).unwrap(),
    )
    .unwrap();
    let context = format!("browser facts (also in {}):\n{facts:#}", shots.display());

    let r = &facts["report"];
    for key in ["console_errors", "page_errors", "blocked_requests"] {
        assert_eq!(r[key], serde_json::json!([]), "report {key}; {context}");
    }
    assert_eq!(r["ready"], true, "{context}");
    let declared: Vec<&str> = r["declared_plots"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_str().unwrap())
        .collect();
    for id in [
        "radar-force",
        "radar-no-force",
        "scatter-tracking-survival",
        "kp-regimes-force",
        "kp-regimes-no-force",
        "latency-percentiles",
        "latency-faults",
    ] {
        assert!(declared.contains(&id), "plot {id} missing; {context}");
    }
    for plot in r["plots"].as_array().unwrap() {
        let id = plot["id"].as_str().unwrap();
        assert_eq!(plot["exists"], true, "#{id}; {context}");
        assert_eq!(plot["tag"], "canvas", "#{id}; {context}");
        assert!(
            plot["painted_pixels"].as_u64().unwrap_or(0) > 2000,
            "#{id} is blank; {context}"
        );
        assert!(
            r["points"][id].as_u64().unwrap_or(0) > 0,
            "#{id} plots no data; {context}"
        );
    }
    // Each plot also as an SVG file beside the page.
    for id in &declared {
        let svg = shots.join("report-figures").join(format!("{id}.svg"));
        assert!(svg.is_file(), "{} not written", svg.display());
    }
    // 12 episodes × 2 settings × 2 runs in the scatter plot.
    assert_eq!(r["points"]["scatter-tracking-survival"], 48, "{context}");
    assert_eq!(r["tables"]["fats-table"], 7, "six tasks and the average");
    assert_eq!(
        r["tables"]["diagnostics-table"], 11,
        "the paper's ten rows and Global KP"
    );
    assert_eq!(r["tables"]["policy-io-table"], 2);
    assert_eq!(
        r["warning_box"], 0,
        "same dataset, profile and rules; {context}"
    );

    // The sweep's report: its curves drawn with data, before the cells' comparison.
    let s = &facts["sweep_report"];
    for key in ["console_errors", "page_errors", "blocked_requests"] {
        assert_eq!(
            s[key],
            serde_json::json!([]),
            "sweep report {key}; {context}"
        );
    }
    for id in ["sweep-fats-vs-coefficient", "sweep-survival-vs-coefficient"] {
        let plot = s["plots"]
            .as_array()
            .unwrap()
            .iter()
            .find(|p| p["id"] == id)
            .unwrap_or_else(|| panic!("sweep plot {id} missing; {context}"));
        assert!(
            plot["painted_pixels"].as_u64().unwrap_or(0) > 2000,
            "#{id} is blank; {context}"
        );
        assert_eq!(
            s["points"][id], 8,
            "two policies and two latency rules, no force and force; {context}"
        );
        let datasets = s["charts"][id]["datasets"]
            .as_array()
            .cloned()
            .unwrap_or_default();
        assert_eq!(
            datasets.len(),
            4,
            "one line per policy and latency rule; {context}"
        );
        // The second axis is a line style, and the legend says which.
        let legend = s["charts"][id]["legend"]
            .as_array()
            .cloned()
            .unwrap_or_default();
        let mut dashes = std::collections::BTreeSet::new();
        for rule in ["lock-step", "5ms"] {
            let of_rule: std::collections::BTreeSet<String> = datasets
                .iter()
                .filter(|d| {
                    d["label"]
                        .as_str()
                        .is_some_and(|l| l.ends_with(&format!(" · {rule}")))
                })
                .map(|d| d["border_dash"].to_string())
                .collect();
            assert_eq!(
                of_rule.len(),
                1,
                "#{id} {rule}: dashes {of_rule:?}; {context}"
            );
            let dash = of_rule.into_iter().next().unwrap();
            let dash_value: Value = serde_json::from_str(&dash).unwrap();
            assert!(
                legend
                    .iter()
                    .any(|e| e["text"] == rule && e["line_dash"] == dash_value),
                "#{id}: no legend entry maps line style {dash} to {rule}: {legend:?}"
            );
            dashes.insert(dash);
        }
        assert_eq!(dashes.len(), 2, "#{id}: latency rules share a line style");
    }
    assert_eq!(
        s["title"], "sweep: 2 policies × 2 latency rules × 2 force coefficients",
        "{context}"
    );
    assert!(shots.join("sweep-report.png").is_file());
    for id in s["declared_plots"].as_array().unwrap() {
        let svg = sweep_report
            .with_file_name("report-figures")
            .join(format!("{}.svg", id.as_str().unwrap()));
        assert!(svg.is_file(), "{} not written", svg.display());
    }
    // One colour per policy across every chart of both pages; legends map colour →
    // policy and, in the scatter, marker → setting.
    check_chart_styles(&[("report", r), ("sweep report", s)], &context);
    for (page, facts) in [("report", r), ("sweep report", s)] {
        check_scatter_markers(page, facts, &["force", "no-force"], &context);
    }

    let v = &facts["view"];
    for key in ["console_errors", "page_errors", "blocked_requests"] {
        assert_eq!(v[key], serde_json::json!([]), "view {key}; {context}");
    }
    assert_eq!(v["ready"], true, "{context}");
    assert_eq!(v["bodies"], 30, "{context}");
    assert_eq!(v["ghost"], true, "the trace carries the reference joints");
    let (robot, total) = differing(&v["robot_vs_empty"]);
    assert!(
        total > 0 && robot * 200 > total,
        "the robot covers under 0.5 % of the scene; {context}"
    );
    let (moved, total) = differing(&v["robot_start_vs_later"]);
    assert!(
        total > 0 && moved * 1000 > total,
        "the timeline did not move the robot; {context}"
    );
    assert_eq!(v["step_after_fill"], v["later_step"], "{context}");
    assert!(
        v["step_after_play"].as_u64().unwrap_or(0) > 0,
        "Play did not advance; {context}"
    );
    assert!(
        v["plot"]["painted_pixels"].as_u64().unwrap_or(0) > 2000,
        "{context}"
    );
    // The feet: both of the G1's, their slip speed and load plotted over the whole trace.
    assert_eq!(
        v["feet"], 2,
        "the trace carries both feet's contacts; {context}"
    );
    assert!(
        v["foot_plot"]["painted_pixels"].as_u64().unwrap_or(0) > 2000,
        "the foot slip plot is blank; {context}"
    );
    let datasets = v["foot_plot_datasets"]
        .as_array()
        .cloned()
        .unwrap_or_default();
    assert_eq!(datasets.len(), 4, "slip and load per foot; {context}");
    let steps = v["steps"].as_u64().unwrap();
    for d in &datasets {
        assert_eq!(d["points"].as_u64(), Some(steps), "{d}; {context}");
    }
    assert!(
        datasets
            .iter()
            .any(|d| d["label"].as_str().unwrap().contains("normal force")
                && d["max"].as_f64().unwrap_or(0.0) > 100.0),
        "a foot carried the robot's weight: {datasets:?}; {context}"
    );
    for png in [
        "report.png",
        "view-start.png",
        "view-later.png",
        "view-empty.png",
        "view-robot-start.png",
        "view-robot-later.png",
    ] {
        assert!(shots.join(png).is_file(), "{png} not written");
    }
    eprintln!("screenshots in {}", shots.display());
}
