//! A run directory is read back as what it is (README, "What ThorArena guarantees"): every
//! record is checked against its header, so a bad record is an error naming the file and
//! line — never a panic in `report`, `merge` or `eval --resume`, never a score that moved
//! silently — and a run holding less than its plan is reported as partial, cell by cell.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use thorarena::motion::DatasetWriter;

mod common;
use common::{g1, sample_sequence};

const BIN: &str = env!("CARGO_BIN_EXE_thorarena");

fn thorarena(cwd: &Path, args: &[&str]) -> Output {
    Command::new(BIN)
        .current_dir(cwd)
        .args(args)
        .output()
        .expect("thorarena runs")
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

fn failure(o: &Output) -> String {
    let e = stderr(o);
    assert!(
        !o.status.success(),
        "expected an error; stderr: {e}; stdout: {}",
        String::from_utf8_lossy(&o.stdout)
    );
    assert!(!e.contains("panicked"), "a panic: {e}");
    e
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
    let o = thorarena(
        tmp,
        &[
            "eval",
            "--dataset",
            ds.to_str().unwrap(),
            "--policy",
            "hold",
            "--out",
            "run",
        ],
    );
    assert!(o.status.success(), "{}", stderr(&o));
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
    let r = run.to_str().unwrap();
    let at = format!("episodes.jsonl line {line}");
    let report = failure(&thorarena(tmp, &["report", r, "--out", "r.html"]));
    let merge = failure(&thorarena(tmp, &["merge", r, "--out", "merged"]));
    let mut resume = vec!["eval", "--policy", "hold", "--out", r, "--resume"];
    let dataset = serde_json::from_str::<serde_json::Value>(
        &std::fs::read_to_string(run.join("run.json")).unwrap(),
    )
    .unwrap()["dataset"]
        .as_str()
        .unwrap()
        .to_string();
    resume.extend(["--dataset", &dataset]);
    let resumed = failure(&thorarena(tmp, &resume));
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
    let e = failure(&thorarena(
        tmp.path(),
        &["report", run.to_str().unwrap(), "--out", "r.html"],
    ));
    assert!(
        e.contains("results version 0") && e.contains("reads version 2"),
        "{e}"
    );
    h["results_version"] = (u64::from(u32::MAX) + 3).into();
    std::fs::write(&path, h.to_string()).unwrap();
    let e = failure(&thorarena(
        tmp.path(),
        &["report", run.to_str().unwrap(), "--out", "r.html"],
    ));
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
    let o = thorarena(
        tmp.path(),
        &["report", run.to_str().unwrap(), "--out", "r.html"],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let e = stderr(&o);
    assert!(
        e.contains("partial run: 2 of 4 planned episodes missing") && e.contains("cut short"),
        "{e}"
    );
    let md = std::fs::read_to_string(tmp.path().join("r.md")).unwrap();
    let html = std::fs::read_to_string(tmp.path().join("r.html")).unwrap();
    for page in [&md, &html] {
        assert!(page.contains("partial run"), "not said on the page");
        assert!(
            page.contains("no-force/clean_table: 0 of 1 present"),
            "no present / expected per cell"
        );
    }
    // The run's own tables, rewritten by resuming it, are complete again.
    let ds = tmp.path().join("ds");
    let o = thorarena(
        tmp.path(),
        &[
            "eval",
            "--dataset",
            ds.to_str().unwrap(),
            "--policy",
            "hold",
            "--out",
            "run",
            "--resume",
        ],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stderr(&o).contains("cut short; it is dropped"));
    assert_eq!(lines(&run).len(), 4);
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(run.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["complete"], true);
    assert!(!std::fs::read_to_string(run.join("tables.md"))
        .unwrap()
        .contains("partial run"));
}
