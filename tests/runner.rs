//! The evaluation runner: every (sequence, setting) runs once, results are identical for
//! any number of workers, slots and pipeline depths, the force and no-force settings differ only through the replay,
//! and every record streams out.

use thorarena::eval::results::summarize;
use thorarena::eval::runner::{run_eval, EvalPlan};
use thorarena::eval::schedule;
use thorarena::eval::task_thresholds;
use thorarena::policy::HoldPolicy;
use thorarena::sim::motion::Sequence;
use thorarena::sim::profile::{bundled_profile_path, load_profile};

mod common;
use common::{g1, runner_spec, sample_sequence};

fn sequences() -> Vec<Sequence> {
    let robot = g1();
    let mut out = Vec::new();
    for (task, n) in [("clean_table", 2), ("push_chair", 2)] {
        for i in 0..n {
            let mut s = sample_sequence(&robot, &format!("{task}_{i}"));
            s.task = task.into();
            // Forces that push hard enough to matter: 40 N·(i+1) along sensor x.
            for f in s.force_sensor[0].iter_mut() {
                f[0] = 40.0 * (i + 1) as f64;
            }
            out.push(s);
        }
    }
    out
}

#[test]
fn results_are_identical_for_any_number_of_workers() {
    let robot = g1();
    let profile = load_profile(&bundled_profile_path("default"), &robot).unwrap();
    let seqs = sequences();
    let mut outputs = Vec::new();
    // (workers, slots, pipeline depth): depth 2 steps one half of the slots while the
    // policy answers for the other.
    let configurations = [
        (1, 1, 1),
        (2, 2, 1),
        (3, 5, 1),
        (2, 8, 1),
        (2, 2, 2),
        (1, 3, 2),
        (3, 5, 2),
        (2, 8, 2),
    ];
    for (workers, envs, pipeline_depth) in configurations {
        let spec = runner_spec(
            &robot,
            &profile,
            &seqs,
            &["force", "no-force"],
            (workers, envs, pipeline_depth),
        );
        let plan = EvalPlan::of(&spec, None);
        let mut streamed = 0;
        let jobs = schedule(seqs.len(), spec.settings.len(), None);
        let records = run_eval(&plan, &seqs, &jobs, &mut HoldPolicy, &mut |_, _| {
            streamed += 1;
        })
        .records;
        assert_eq!(streamed, 8);
        assert_eq!(records.len(), 8);
        let summary = summarize(&records, &task_thresholds(&seqs, profile.control_dt_s));
        outputs.push(format!("{records:?}{summary:?}"));
    }
    assert_eq!(outputs.len(), configurations.len());
    for (i, out) in outputs.iter().enumerate().skip(1) {
        assert_eq!(
            &outputs[0], out,
            "configuration {:?} differs from one worker, one slot",
            configurations[i]
        );
    }
}

#[test]
fn force_and_no_force_differ_only_by_the_replay() {
    let robot = g1();
    let profile = load_profile(&bundled_profile_path("default"), &robot).unwrap();
    let seqs = sequences();
    let spec = runner_spec(
        &robot,
        &profile,
        &seqs,
        &["force", "no-force", "0"],
        (2, 2, 1),
    );
    let plan = EvalPlan::of(&spec, None);
    let jobs = schedule(seqs.len(), spec.settings.len(), None);
    let records = run_eval(&plan, &seqs, &jobs, &mut HoldPolicy, &mut |_, _| {}).records;
    let by = |setting: &str, id: &str| {
        records
            .iter()
            .find(|r| r.setting == setting && r.sequence_id == id)
            .unwrap()
            .clone()
    };
    for s in &seqs {
        let (f, n, z) = (
            by("force", &s.sequence_id),
            by("no-force", &s.sequence_id),
            by("coef-0", &s.sequence_id),
        );
        assert_eq!(n.series, z.series, "coefficient 0 is the no-force setting");
        assert_ne!(
            f.series.kp_err_m, n.series.kp_err_m,
            "a 40–80 N push changes tracking"
        );
        // The push may end the force episode early; up to there the recorded forces (and so
        // the regimes) are the same in both settings.
        let steps = f
            .series
            .total_force_n
            .len()
            .min(n.series.total_force_n.len());
        assert_eq!(
            f.series.total_force_n[..steps],
            n.series.total_force_n[..steps],
            "regimes come from the recorded force either way"
        );
    }
}

#[test]
fn the_balance_baseline_keeps_the_standing_sample_tasks_upright_without_force() {
    use thorarena::policy::{BalanceGains, BalancePolicy};
    use thorarena::sim::motion::Dataset;
    let robot = g1();
    let profile = load_profile(&bundled_profile_path("default"), &robot).unwrap();
    let ds = Dataset::open(
        std::path::Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/data/sample")),
        &robot,
    )
    .unwrap();
    let standing: Vec<Sequence> = ds
        .load_all()
        .unwrap()
        .into_iter()
        .filter(|s| ["clean_table", "liftup_water", "liftdown_water"].contains(&s.task.as_str()))
        .collect();
    assert_eq!(standing.len(), 6);
    let spec = runner_spec(&robot, &profile, &standing, &["no-force"], (2, 3, 1));
    let plan = EvalPlan::of(&spec, None);
    let pose = profile.action_offset_rad.clone();
    let mut balance = BalancePolicy::new(&robot, pose.clone(), BalanceGains::default()).unwrap();
    let jobs = schedule(standing.len(), 1, None);
    let records = run_eval(&plan, &standing, &jobs, &mut balance, &mut |_, _| {}).records;
    for r in &records {
        assert_eq!(r.termination, None, "{} fell", r.sequence_id);
        assert_eq!(r.series.kp_err_m.len(), r.series.steps_ref);
    }
    // And plain open-loop replay does not: the feedback is what keeps it up.
    let mut replay = thorarena::policy::ReplayPolicy::new(pose.clone());
    let replayed = run_eval(&plan, &standing, &jobs, &mut replay, &mut |_, _| {}).records;
    assert!(replayed.iter().any(|r| r.termination.is_some()));
}
