//! A run directory is read back as what it is (docs/guarantees.md, "What ThorArena guarantees"): every
//! record is checked against its header, so a bad record is an error naming the file and
//! line — never a panic in `report`, `merge` or `eval --resume`, never a score that moved
//! silently — and a run holding less than its plan is reported as partial, cell by cell.
//!
//! Every reader is called in process, as the commands call it: `report`'s
//! `report::load_runs`, `merge`'s `pipeline::merge`, `eval --resume`'s
//! `pipeline::evaluate`.

use std::path::{Path, PathBuf};
use thorarena::eval::pipeline::{self, EvalObserver, EvalOptions, Starting};
use thorarena::eval::results::RunDir;
use thorarena::eval::{EvalRequest, EvalSpec};
use thorarena::policy::HoldPolicy;
use thorarena::report::{comparison_markdown, comparison_notes, comparison_warnings, load_runs};
use thorarena::sim::motion::DatasetWriter;

mod common;
use common::{g1, sample_sequence};

/// The error's message with its causes, as the command line prints it.
fn chain(e: &dyn std::error::Error) -> String {
    let mut text = e.to_string();
    let mut cause = e.source();
    while let Some(c) = cause {
        text += &format!(": {c}");
        cause = c.source();
    }
    text
}

/// `eval --policy hold --dataset DS --out RUN` (with `--resume`), in process; whether
/// the resume dropped a line cut short.
fn eval_hold(ds: &Path, run: &Path, resume: bool) -> Result<bool, String> {
    struct Torn(bool);
    impl EvalObserver for Torn {
        fn starting(&mut self, s: &Starting) {
            self.0 = s.started.torn_tail_dropped;
        }
    }
    let spec = EvalSpec::load(&EvalRequest {
        policy: thorarena::policy::registry::PolicySource::parse("hold").unwrap(),
        dataset: Some(ds.to_path_buf()),
        ..EvalRequest::default()
    })
    .map_err(|e| chain(&e))?;
    let mut torn = Torn(false);
    let options = EvalOptions {
        resume,
        ..EvalOptions::default()
    };
    pipeline::evaluate(
        &spec,
        &mut HoldPolicy,
        &RunDir::new(run),
        options,
        &mut torn,
    )
    .map_err(|e| chain(&e))?;
    Ok(torn.0)
}

/// `report RUN`'s reading of the run.
fn report_error(run: &Path) -> String {
    chain(&load_runs(&[run.to_path_buf()]).expect_err("report refuses the run"))
}

/// A finished `hold` run of a two-task dataset (4 episodes: 2 sequences × force,
/// no-force) in `<tmp>/run`, and the dataset path.
fn finished_run(tmp: &Path) -> (PathBuf, PathBuf) {
    let robot = g1();
    let ds = tmp.join("ds");
    let mut w = DatasetWriter::create(&ds, &robot).unwrap();
    for (task, id) in [("clean_table", "a"), ("liftup_water", "b")] {
        let mut s = sample_sequence(&robot, id);
        s.task = task.into();
        w.add(&s).unwrap();
    }
    w.finish().unwrap();
    eval_hold(&ds, &tmp.join("run"), false).unwrap();
    (tmp.join("run"), ds)
}

fn lines(run: &Path) -> Vec<serde_json::Value> {
    std::fs::read_to_string(run.join("episodes.jsonl"))
        .unwrap()
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect()
}

fn write_lines(run: &Path, records: &[serde_json::Value]) {
    let text: String = records.iter().map(|r| format!("{r}\n")).collect();
    std::fs::write(run.join("episodes.jsonl"), text).unwrap();
}

/// Every reader of a run refuses `run` with a message containing `expected` and the line.
fn every_reader_refuses(tmp: &Path, run: &Path, line: usize, expected: &str) {
    let at = format!("episodes.jsonl line {line}");
    let report = report_error(run);
    let merge = chain(
        &pipeline::merge(&[RunDir::new(run)], &RunDir::new(tmp.join("merged")), &g1())
            .expect_err("merge refuses the run"),
    );
    let dataset = RunDir::new(run).read_header().unwrap().dataset;
    let resumed = eval_hold(Path::new(&dataset), run, true).expect_err("resume refuses the run");
    for (what, e) in [("report", report), ("merge", merge), ("resume", resumed)] {
        assert!(
            e.contains(&at) && e.contains(expected),
            "{what}: expected `{at}` and `{expected}` in: {e}"
        );
    }
}

#[test]
fn a_bad_record_is_an_error_naming_file_and_line_for_every_reader() {
    let tmp = tempfile::tempdir().unwrap();
    let (run, _) = finished_run(tmp.path());
    let good = lines(&run);
    assert_eq!(good.len(), 4);
    type Edit = fn(&mut Vec<serde_json::Value>);
    let cases: [(&str, usize, &str, Edit); 7] = [
        ("unequal series", 2, "one value per recorded step", |r| {
            r[1]["series"]["power_w"].as_array_mut().unwrap().pop();
        }),
        ("duplicate", 5, "recorded twice", |r| {
            let first = r[0].clone();
            r.push(first);
        }),
        ("unknown task", 1, "not in the run's dataset", |r| {
            r[0]["task"] = "ghost_task".into();
        }),
        (
            "unknown setting",
            3,
            "a setting this run does not have",
            |r| {
                r[2]["setting"] = "coef-0.5".into();
            },
        ),
        ("absurd steps_ref", 1, "steps_ref 1000000000", |r| {
            r[0]["series"]["steps_ref"] = 1_000_000_000u64.into();
        }),
        ("empty series", 4, "no termination says why", |r| {
            for c in [
                "kp_err_m",
                "kp_err_upper_m",
                "kp_err_lower_m",
                "total_force_n",
                "power_w",
                "root_drift_m",
                "kp_err_global_m",
            ] {
                r[3]["series"][c] = serde_json::json!([]);
            }
            r[3]["termination"] = serde_json::Value::Null;
        }),
        ("negative error", 2, "kp_err_m[0] is -1", |r| {
            r[1]["series"]["kp_err_m"][0] = (-1.0).into();
        }),
    ];
    for (name, line, expected, edit) in cases {
        let mut records = good.clone();
        edit(&mut records);
        write_lines(&run, &records);
        eprintln!("case: {name}");
        every_reader_refuses(tmp.path(), &run, line, expected);
        // A refused resume leaves the records as they were.
        assert_eq!(lines(&run), records, "{name}: the run was changed");
    }
    // Non-finite values cannot be JSON numbers: `null` where a number belongs is a parse
    // error naming the line.
    let mut records = good.clone();
    records[2]["series"]["kp_err_m"][0] = serde_json::Value::Null;
    write_lines(&run, &records);
    every_reader_refuses(tmp.path(), &run, 3, "invalid type: null");
}

#[test]
fn a_run_of_another_results_version_is_refused_plainly() {
    let tmp = tempfile::tempdir().unwrap();
    let (run, _) = finished_run(tmp.path());
    let path = run.join("run.json");
    let mut h: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
    h.as_object_mut().unwrap().remove("results_version");
    std::fs::write(&path, h.to_string()).unwrap();
    let e = report_error(&run);
    assert!(
        e.contains("results version 0") && e.contains("reads version 2"),
        "{e}"
    );
    h["results_version"] = (u64::from(u32::MAX) + 3).into();
    std::fs::write(&path, h.to_string()).unwrap();
    let e = report_error(&run);
    assert!(e.contains("results version 4294967298"), "{e}");
}

#[test]
fn a_partial_run_is_reported_as_partial_cell_by_cell() {
    let tmp = tempfile::tempdir().unwrap();
    let (run, _) = finished_run(tmp.path());
    let text = std::fs::read_to_string(run.join("episodes.jsonl")).unwrap();
    // Killed mid-write: the last record is cut in half, and one episode never ran.
    let all: Vec<&str> = text.lines().collect();
    let cut = format!("{}\n{}\n{}", all[0], all[1], &all[3][..all[3].len() / 2]);
    std::fs::write(run.join("episodes.jsonl"), cut).unwrap();
    let runs = load_runs(std::slice::from_ref(&run)).unwrap();
    let warnings = comparison_warnings(&runs);
    let e: Vec<&str> = warnings.iter().map(|w| w.message.as_str()).collect();
    let e = e.join("\n");
    assert!(
        e.contains("partial run: 2 of 4 planned episodes missing") && e.contains("cut short"),
        "{e}"
    );
    let md = comparison_markdown(&runs, &warnings, &comparison_notes(&runs));
    let html = thorarena::report::report_html(&runs, "");
    for page in [&md, &html] {
        assert!(page.contains("partial run"), "not said on the page");
        assert!(
            page.contains("no-force/clean_table: 0 of 1 present"),
            "no present / expected per cell"
        );
    }
    // The run's own tables, rewritten by resuming it, are complete again.
    let ds = tmp.path().join("ds");
    let torn_dropped = eval_hold(&ds, &run, true).unwrap();
    assert!(torn_dropped, "the line cut short is dropped");
    assert_eq!(lines(&run).len(), 4);
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(run.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["complete"], true);
    assert!(!std::fs::read_to_string(run.join("tables.md"))
        .unwrap()
        .contains("partial run"));
}

/// A trace lost after its episode was recorded (a full disk fails the trace's write, not
/// the record's; or the file was removed): `--resume` runs that episode again, says so,
/// and writes the trace; nothing else runs again.
#[test]
fn a_resume_writes_a_lost_trace_again() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("run");
    let sample = concat!(env!("CARGO_MANIFEST_DIR"), "/data/sample");
    let eval = |resume: bool| {
        let mut cmd = std::process::Command::new(env!("CARGO_BIN_EXE_thorarena"));
        cmd.args(["eval", "--dataset", sample, "--policy", "hold"])
            .args([
                "--settings",
                "no-force",
                "--trace",
                "push_chair/push_chair_000",
            ])
            .arg("--out")
            .arg(&out);
        if resume {
            cmd.arg("--resume");
        }
        let o = cmd.output().unwrap();
        let stderr = String::from_utf8_lossy(&o.stderr).into_owned();
        assert!(o.status.success(), "{stderr}");
        stderr
    };
    eval(false);
    let trace = out.join("traces/push_chair-push_chair_000-no-force.json");
    let written = std::fs::read(&trace).unwrap();
    let records = lines(&out).len();
    std::fs::remove_file(&trace).unwrap();
    let said = eval(true);
    assert!(
        said.contains("1 finished episode run again, its trace missing from")
            && said.contains("push_chair/push_chair_000 no-force")
            && said.contains(&format!("1 episodes to run ({} already done)", records - 1)),
        "{said}"
    );
    assert_eq!(
        std::fs::read(&trace).unwrap(),
        written,
        "the trace written again differs"
    );
    assert_eq!(lines(&out).len(), records);
}
