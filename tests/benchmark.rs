//! The evaluation through the library, in process (no binary): a checked `EvalSpec` run
//! into a `RunDir` by `pipeline::evaluate`, resumed after a kill, sharded and merged by
//! `pipeline::merge`, and two runs compared by `results::crosscheck` — each giving the
//! same files as one uninterrupted run.

use std::path::Path;
use thorarena::eval::pipeline::{self, BenchmarkError, EvalObserver, EvalOptions, Starting};
use thorarena::eval::results::crosscheck::{compare_runs, write_crosscheck, SeriesLog};
use thorarena::eval::results::{MergeError, ResultsError, RunDir};
use thorarena::eval::{EpisodeRecord, EvalRequest, EvalSpec, SpecError};
use thorarena::policy::HoldPolicy;
use thorarena::sim::motion::SequenceSelection;

/// Two sample sequences of two tasks under force and no force: four `hold` episodes.
fn request() -> EvalRequest {
    EvalRequest {
        policy: thorarena::policy::registry::PolicySource::parse("hold").unwrap(),
        dataset: Some(concat!(env!("CARGO_MANIFEST_DIR"), "/data/sample").into()),
        selection: SequenceSelection {
            tasks: Vec::new(),
            sequences: vec![
                "clean_table/clean_table_000".into(),
                "push_chair/push_chair_000".into(),
            ],
        },
        workers: Some(2),
        ..EvalRequest::default()
    }
}

/// Counts what an evaluation reports.
#[derive(Default)]
struct Counted {
    to_run: usize,
    kept: usize,
    torn: bool,
    episodes: usize,
}

impl EvalObserver for Counted {
    fn starting(&mut self, s: &Starting) {
        self.to_run = s.to_run;
        self.kept = s.started.kept.len();
        self.torn = s.started.torn_tail_dropped;
    }
    fn episode(&mut self, _: &EpisodeRecord, _: Option<&thorarena::eval::episode::EpisodeTrace>) {
        self.episodes += 1;
    }
}

fn run_into(spec: &EvalSpec, dir: &Path, resume: bool) -> (pipeline::Evaluated, Counted) {
    let mut counted = Counted::default();
    let options = EvalOptions {
        resume,
        ..EvalOptions::default()
    };
    let done = pipeline::evaluate(
        spec,
        &mut HoldPolicy,
        &RunDir::new(dir),
        options,
        &mut counted,
    )
    .unwrap();
    (done, counted)
}

fn read(path: impl AsRef<Path>) -> String {
    std::fs::read_to_string(path).unwrap()
}

/// The records of a run's `episodes.jsonl`, in key order (the file holds them in the
/// order episodes finished).
fn records(dir: &Path) -> Vec<EpisodeRecord> {
    let mut r: Vec<EpisodeRecord> = read(dir.join("episodes.jsonl"))
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    r.sort_by_key(EpisodeRecord::key);
    r
}

/// `value` as its file holds it (NaN, an undefined diagnostic, written as `null`), so two
/// summaries compare equal when their files do.
fn as_written<T: serde::Serialize>(value: &T) -> serde_json::Value {
    serde_json::to_value(value).unwrap()
}

/// The same run: records by key, the scores (the policy's measured latency aside: it is
/// the machine's), every other file byte for byte (no dump on failure: a record is
/// kilobytes).
fn assert_same_run(a: &Path, b: &Path, files: &[&str], what: &str) {
    assert!(records(a) == records(b), "{what}: other records");
    let scores = |dir: &Path| {
        let mut s = RunDir::new(dir).read_summary().unwrap();
        s.policy_io = None;
        s
    };
    let (sa, sb) = (scores(a), scores(b));
    let (ja, jb) = (
        serde_json::to_value(&sa).unwrap(),
        serde_json::to_value(&sb).unwrap(),
    );
    let differ: Vec<&String> = ja
        .as_object()
        .unwrap()
        .iter()
        .filter(|(k, v)| jb.get(k.as_str()) != Some(v))
        .map(|(k, _)| k)
        .collect();
    // Compared as written: an undefined diagnostic (NaN, FATS Std of a one-episode task)
    // is `null` in `summary.json`, and NaN is equal to nothing in memory.
    assert!(ja == jb, "{what}: other scores (in {differ:?})");
    for file in files {
        assert!(
            read(a.join(file)) == read(b.join(file)),
            "{what}: {file} differs"
        );
    }
}

#[test]
fn a_run_resumed_after_a_kill_ends_as_the_uninterrupted_run() {
    let tmp = tempfile::tempdir().unwrap();
    let spec = EvalSpec::load(&request()).unwrap();
    assert_eq!((spec.sequences.len(), spec.settings.len()), (2, 2));
    let whole = tmp.path().join("whole");
    let (done, counted) = run_into(&spec, &whole, false);
    assert_eq!((counted.to_run, counted.episodes), (4, 4));
    assert!(!done.policy_failed() && done.summary.complete);
    assert_eq!(done.tables, read(whole.join("tables.md")));

    // Killed after two episodes, in the middle of writing the third.
    let killed = tmp.path().join("killed");
    std::fs::create_dir_all(&killed).unwrap();
    std::fs::copy(whole.join("run.json"), killed.join("run.json")).unwrap();
    let text = read(whole.join("episodes.jsonl"));
    let lines: Vec<&str> = text.lines().collect();
    let torn = format!(
        "{}\n{}\n{}",
        lines[0],
        lines[1],
        &lines[2][..lines[2].len() / 2]
    );
    std::fs::write(killed.join("episodes.jsonl"), torn).unwrap();
    let (resumed, counted) = run_into(&spec, &killed, true);
    assert_eq!((counted.kept, counted.to_run, counted.episodes), (2, 2, 2));
    assert!(counted.torn, "the torn line is reported dropped");
    assert_same_run(
        &killed,
        &whole,
        &["run.json", "episodes.csv"],
        "the resumed run",
    );
    assert_eq!(
        as_written(&resumed.summary.settings),
        as_written(&done.summary.settings)
    );

    // Resuming it under another configuration is a typed error naming what differs,
    // and leaves the run as it was.
    let other = EvalSpec::load(&EvalRequest {
        settings: vec!["no-force".parse().unwrap()],
        ..request()
    })
    .unwrap();
    let e = pipeline::evaluate(
        &other,
        &mut HoldPolicy,
        &RunDir::new(&killed),
        EvalOptions {
            resume: true,
            ..EvalOptions::default()
        },
        &mut (),
    )
    .unwrap_err();
    match e {
        BenchmarkError::ResumedOther(ResultsError::OtherConfiguration { differences, .. }) => {
            assert_eq!(differences, ["settings"])
        }
        e => panic!("not the resume refusal: {e}"),
    }
    assert!(
        records(&killed) == records(&whole),
        "the refused resume changed the run"
    );
}

#[test]
fn shards_merge_into_the_unsharded_run() {
    let tmp = tempfile::tempdir().unwrap();
    let whole = tmp.path().join("whole");
    run_into(&EvalSpec::load(&request()).unwrap(), &whole, false);
    let shards: Vec<RunDir> = (0..3)
        .map(|i| {
            let spec = EvalSpec::load(&EvalRequest {
                shard: Some((i, 3)),
                ..request()
            })
            .unwrap();
            let dir = tmp.path().join(format!("shard{i}"));
            run_into(&spec, &dir, false);
            RunDir::new(dir)
        })
        .collect();
    let robot = thorarena::policy::registry::robot("g1_29dof").unwrap();
    let merged_dir = tmp.path().join("merged");
    let merged = pipeline::merge(&shards, &RunDir::new(&merged_dir), &robot).unwrap();
    assert_eq!(merged.summary.episodes, 4);
    assert_same_run(
        &merged_dir,
        &whole,
        &["run.json", "episodes.csv"],
        "the merge",
    );
    // Without one shard, the merge names what no shard holds.
    let e = pipeline::merge(&shards[..2], &RunDir::new(tmp.path().join("m2")), &robot).unwrap_err();
    match e {
        BenchmarkError::Results(ResultsError::Merge(MergeError::Missing { missing })) => {
            assert_eq!(missing.len(), 1, "{missing:?}");
            assert!(missing[0].to_string().contains('/'));
        }
        e => panic!("not the missing-episodes refusal: {e}"),
    }
    // A run of another evaluation is not a shard.
    let other = EvalSpec::load(&EvalRequest {
        settings: vec!["force".parse().unwrap()],
        ..request()
    })
    .unwrap();
    let stranger = tmp.path().join("stranger");
    run_into(&other, &stranger, false);
    let e = pipeline::merge(
        &[shards[0].clone(), RunDir::new(&stranger)],
        &RunDir::new(tmp.path().join("m3")),
        &robot,
    )
    .unwrap_err();
    assert!(
        matches!(
            e,
            BenchmarkError::Results(ResultsError::Merge(MergeError::NotAShard { .. }))
        ),
        "{e}"
    );
}

#[test]
fn two_runs_of_one_engine_crosscheck_as_identical() {
    let tmp = tempfile::tempdir().unwrap();
    let spec = EvalSpec::load(&request()).unwrap();
    let runs = [tmp.path().join("a"), tmp.path().join("b")].map(RunDir::new);
    let mut series = Vec::new();
    for run in &runs {
        let mut log = SeriesLog::open(run, false).unwrap();
        struct Keep<'a>(&'a mut SeriesLog);
        impl EvalObserver for Keep<'_> {
            fn episode(
                &mut self,
                r: &EpisodeRecord,
                trace: Option<&thorarena::eval::episode::EpisodeTrace>,
            ) {
                let trace = trace.expect("a trace of the first seconds");
                let q = trace.steps.iter().map(|s| s.q.clone()).collect();
                self.0
                    .append(r.key(), q, trace.foot_slip_m.clone())
                    .unwrap();
            }
        }
        let options = EvalOptions {
            resume: false,
            trace_first_s: Some(0.5),
        };
        pipeline::evaluate(&spec, &mut HoldPolicy, run, options, &mut Keep(&mut log)).unwrap();
        series.push(log);
    }
    let check = compare_runs([&runs[0], &runs[1]], [&series[0], &series[1]], 200).unwrap();
    assert_eq!((check.pairs.len(), check.without_series), (4, 0));
    for s in &check.settings {
        for c in [&s.survival, &s.kp_mm, &s.fats] {
            assert_eq!((c.diff, c.ci95), (0.0, [0.0, 0.0]), "{}", s.setting);
        }
        assert_eq!(s.joint_divergence_rad.mean, 0.0);
    }
    let [json, csv] = write_crosscheck(
        tmp.path(),
        [runs[0].path(), runs[1].path()],
        &check,
        200,
        0.5,
    )
    .unwrap();
    let rows = read(csv);
    assert_eq!(rows.lines().count(), 5, "a header and a row per episode");
    assert!(rows.starts_with("task,sequence_id,setting,survival_rapier,"));
    let file: serde_json::Value = serde_json::from_str(&read(json)).unwrap();
    assert_eq!(file["episodes"].as_array().unwrap().len(), 4);
    assert_eq!(file["bootstrap_resamples"], 200);
}

#[test]
fn a_spec_is_checked_before_anything_runs() {
    for (request, says) in [
        (
            EvalRequest {
                workers: Some(0),
                ..request()
            },
            "`request.workers` must be at least 1",
        ),
        (
            EvalRequest {
                settings: vec!["force".parse().unwrap(), "1".parse().unwrap()],
                ..request()
            },
            "same load on the robot",
        ),
        (
            EvalRequest {
                profile: Some("twist".into()),
                ..request()
            },
            "did you mean `twist2`?",
        ),
        (
            EvalRequest {
                trace: vec!["clean_table/nope".into()],
                ..request()
            },
            "`request.trace`: no sequence `clean_table/nope`",
        ),
    ] {
        let e = EvalSpec::load(&request).unwrap_err();
        assert!(matches!(e, SpecError::Invalid(_)), "{e:?}");
        assert!(e.to_string().contains(says), "{e}");
    }
}

#[test]
fn a_sweeps_cells_collect_from_their_shards_as_one_run_each() {
    use thorarena::campaign::sweep::{
        check_task_run, results_rows, CellResult, DatasetInfo, Plan, SweepSpec,
    };
    let tmp = tempfile::tempdir().unwrap();
    let sample =
        std::fs::canonicalize(concat!(env!("CARGO_MANIFEST_DIR"), "/data/sample")).unwrap();
    let spec_path = tmp.path().join("sweep.toml");
    std::fs::write(
        &spec_path,
        format!(
            "datasets = [{:?}]\nsettings = [\"no-force\", \"force\"]\nshards = 2\nsequences = [\"clean_table/clean_table_000\", \"push_chair/push_chair_000\"]\n[[policy]]\npolicy = \"hold\"\n",
            sample.display().to_string()
        ),
    )
    .unwrap();
    let spec = SweepSpec::load(&spec_path).unwrap();
    let robot = thorarena::policy::registry::robot("g1_29dof").unwrap();
    let info = DatasetInfo::read(sample.clone(), &robot).unwrap();
    let sequences = thorarena::sim::motion::Dataset::open(&sample, &robot)
        .unwrap()
        .load_all()
        .unwrap();
    let plan = Plan::expand(&spec, &spec_path, &[info]).unwrap();
    assert_eq!((plan.cells.len(), plan.tasks.len()), (2, 4));
    for t in &plan.tasks {
        // The task's own evaluation, as its `eval` runs it.
        let request = EvalRequest {
            workers: request().workers,
            ..t.request.clone()
        };
        assert_eq!(request.settings, [plan.cells[t.cell].setting.clone()]);
        let run = tmp.path().join(format!("task{}", t.index));
        run_into(&EvalSpec::load(&request).unwrap(), &run, false);
        let records = check_task_run(&plan, t, &RunDir::new(&run))
            .unwrap()
            .expect("the task's own complete run counts");
        assert_eq!(records.len(), t.episodes);
        // Another shard's run does not count, and the refusal reads as run.json does
        // (`[0,2]`), not as Rust's debug text (`Some((0, 2))`).
        if t.shard.0 == 0 {
            let sibling = &plan.tasks[t.index + 1];
            match check_task_run(&plan, sibling, &RunDir::new(&run)).unwrap() {
                Err(thorarena::campaign::sweep::RunProblem::NotThisTask(why)) => assert!(
                    why.contains("its shard is [0,2]") && why.contains("plans [1,2]"),
                    "{why}"
                ),
                other => panic!("task {}'s run counted for its sibling: {other:?}", t.index),
            }
        }
        // Another task's run does not count for this one.
        let other = &plan.tasks[(t.index + 2) % plan.tasks.len()];
        assert!(
            check_task_run(&plan, other, &RunDir::new(&run))
                .unwrap()
                .is_err(),
            "task {}'s run counted for task {}",
            t.index,
            other.index
        );
    }
    let results: Vec<Option<CellResult>> = plan
        .cells
        .iter()
        .map(|cell| {
            let shards: Vec<RunDir> = plan
                .tasks
                .iter()
                .filter(|t| t.cell == cell.index)
                .map(|t| RunDir::new(tmp.path().join(format!("task{}", t.index))))
                .collect();
            let out = RunDir::new(tmp.path().join(format!("cell{}", cell.index)));
            Some(CellResult::collect(&shards, &out, &sequences, cell.episodes).unwrap())
        })
        .collect();
    // Each cell scores as one unsharded run of its setting does.
    for (cell, result) in plan.cells.iter().zip(&results) {
        let result = result.as_ref().unwrap();
        assert!(
            result.complete && result.episodes == 2,
            "cell {}",
            cell.index
        );
        assert!(
            result.latency.is_none(),
            "two shards' latencies do not add up"
        );
        let whole = tmp.path().join(format!("whole{}", cell.index));
        let (done, _) = run_into(
            &EvalSpec::load(&EvalRequest {
                settings: vec![cell.setting.clone()],
                ..request()
            })
            .unwrap(),
            &whole,
            false,
        );
        assert_eq!(
            as_written(&result.summary.settings),
            as_written(&done.summary.settings)
        );
        assert_same_run(&result.dir, &whole, &["episodes.csv"], "a collected cell");
    }
    let rows = results_rows(&plan, &results);
    let csv = thorarena::campaign::sweep::results_csv(&plan, &results);
    assert_eq!(rows.len(), 2);
    assert_eq!(csv.lines().count(), 3, "a header and a row per cell");
    assert!(csv
        .lines()
        .next()
        .unwrap()
        .starts_with("cell,policy,dataset,setting,"));
}
