//! Networks in process, batched and on the workers: one tract call for a batch of
//! environments gives each environment bit for bit its batch-one action, and an
//! evaluation whose policy acts on the workers (each worker's copy, its own slots)
//! records exactly what the same policy acting on the coordinator records, for any
//! number of workers and slots. With the published TWIST2 network, and the BeyondMimic
//! family's (wbc-mjlab's tracker, holosoma's dance policy with its `time_step` input),
//! which run [`thorarena::policy::beyondmimic::INFERENCE_BATCH`] rows per call (eight;
//! every count from 2 to 16 rounds alike, one row differently, by less than 1e-5);
//! skipped, saying so, when `../shared/reference` is absent.

use std::sync::Arc;
use thorarena::eval::runner::{run_eval, EvalPlan};
use thorarena::eval::{schedule, EpisodeRecord};
use thorarena::policy::beyondmimic::INFERENCE_BATCH;
use thorarena::policy::{ActOutcome, BeyondMimicPolicy, Observation, Policy, Twist2Policy};
use thorarena::sim::motion::Sequence;
use thorarena::sim::profile::{bundled_profile_path, load_profile, Profile};
use thorarena::sim::robot::RobotModel;

mod common;
mod prereq;
use common::{g1, sample_sequence};

fn twist2(test: &str, profile: &Profile) -> Option<Twist2Policy> {
    let onnx = prereq::reference(test, "twist2/twist2_1017_25k.onnx")?;
    Some(Twist2Policy::load(&onnx, profile.action_offset_rad.clone()).unwrap())
}

fn twist2_profile(robot: &RobotModel) -> Profile {
    load_profile(&bundled_profile_path("twist2"), robot).unwrap()
}

#[test]
fn a_row_of_a_fixed_size_batch_answers_the_same_wherever_it_sits_and_whatever_its_neighbours() {
    const TEST: &str = "batched_inference::batch_rows";
    let robot = g1();
    let Some(policy) = twist2(TEST, &twist2_profile(&robot)) else {
        return;
    };
    let width = thorarena::policy::twist2::OBS_LEN;
    // A call shape of several rows: where the kernel's row tiling could matter.
    let batch = 4;
    let row = |r: usize| input_row(width, r);
    // Row 0 at each position of the batch, among different neighbours (zeros, as padding
    // is, or other rows).
    let mut answers = Vec::new();
    for position in 0..batch {
        for neighbours in [None, Some(1), Some(5)] {
            let inputs: Vec<f32> = (0..batch)
                .flat_map(|p| match (p == position, neighbours) {
                    (true, _) => row(0),
                    (false, None) => vec![0.0; width],
                    (false, Some(k)) => row(k + p),
                })
                .collect();
            let out = policy.infer_batch(&inputs, batch).unwrap();
            answers.push(out[position * 29..(position + 1) * 29].to_vec());
        }
    }
    for (i, a) in answers.iter().enumerate() {
        assert!(a == &answers[0], "placement {i} answers differently");
    }
    // Against batch one (another tract kernel) the rounding differs: by how much.
    let alone = policy.infer(&row(0)).unwrap();
    let max_diff = largest_difference(&alone, &answers[0]);
    eprintln!("batch {batch} against batch one: largest difference {max_diff:e}");
    assert!(max_diff < 1e-5, "{max_diff:e}");
}

/// wbc-mjlab's tracker (a single `[rows, 132]` input), through the plans the TWIST2 policy
/// uses: a row answers bit for bit the same in calls of 2 to 16 rows (tract runs one
/// kernel for all of them, so the BeyondMimic family's row count is a cost, not a
/// result), and within 1e-5 of a call of one row (another kernel).
#[test]
fn every_call_shape_of_several_rows_rounds_alike_and_one_row_within_1e_5() {
    const TEST: &str = "batched_inference::call_shapes";
    let Some(onnx) = prereq::reference(TEST, "wbc-mjlab/wbc_g1_policy.onnx") else {
        return;
    };
    let width = 132;
    let (model, _) = thorarena::policy::network_kernels::load_onnx(&onnx).unwrap();
    let plans = thorarena::policy::BatchPlans::new(model, width, None).unwrap();
    let row = input_row(width, 0);
    let alone = plans.run(&row, 1).unwrap();
    let in_a_call = |rows: usize| {
        let mut inputs = row.clone();
        inputs.resize(rows * width, 0.0);
        plans.run(&inputs, rows).unwrap()[..alone.len()].to_vec()
    };
    let eight = in_a_call(INFERENCE_BATCH);
    for rows in [2, 3, 4, 8, 16] {
        assert!(
            in_a_call(rows) == eight,
            "{rows} rows per call round otherwise than {INFERENCE_BATCH}"
        );
    }
    let max_diff = largest_difference(&alone, &eight);
    eprintln!("wbc-mjlab, {INFERENCE_BATCH} rows against one: largest difference {max_diff:e}");
    assert!(max_diff < 1e-5, "{max_diff:e}");
}

/// Row `r` of distinct, deterministic network inputs, `width` floats in [-2, 2], the range
/// normalised observations take.
fn input_row(width: usize, r: usize) -> Vec<f32> {
    (0..width)
        .map(|i| (((i * 7919 + r * 104_729) % 2001) as f32 / 1000.0 - 1.0) * 2.0)
        .collect()
}

/// The largest absolute difference between two answers.
fn largest_difference(a: &[f32], b: &[f32]) -> f32 {
    a.iter()
        .zip(b)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0f32, f32::max)
}

/// The same policy without its worker copies: it acts on the coordinator.
struct OnCoordinator<P>(P);

impl<P: Policy> Policy for OnCoordinator<P> {
    fn name(&self) -> &str {
        self.0.name()
    }
    fn reference_offsets_s(&self) -> Vec<f64> {
        self.0.reference_offsets_s()
    }
    fn reset(&mut self, env: usize) {
        self.0.reset(env)
    }
    fn episode_ended(&mut self, env: usize, terminated: bool) {
        self.0.episode_ended(env, terminated)
    }
    fn act(&mut self, observations: &[Observation], actions: &mut [Vec<f64>]) -> ActOutcome {
        self.0.act(observations, actions)
    }
}

fn sequences(robot: &RobotModel) -> Vec<Sequence> {
    ["clean_table_0", "push_chair_0", "clean_table_1"]
        .iter()
        .map(|id| sample_sequence(robot, id))
        .collect()
}

fn records(
    robot: &RobotModel,
    profile: &Profile,
    seqs: &[Sequence],
    workers: usize,
    envs: usize,
    policy: &mut dyn Policy,
) -> Vec<EpisodeRecord> {
    let spec = common::runner_spec(
        robot,
        profile,
        seqs,
        &["force", "no-force"],
        (workers, envs, 1),
    );
    let plan = EvalPlan::of(&spec, None);
    let jobs = schedule(seqs.len(), spec.settings.len(), None);
    run_eval(&plan, seqs, &jobs, policy, &mut |_, _| {}).records
}

#[test]
fn acting_on_the_workers_records_what_acting_on_the_coordinator_records() {
    const TEST: &str = "batched_inference::workers_equal_coordinator";
    let robot = g1();
    let profile = twist2_profile(&robot);
    let Some(policy) = twist2(TEST, &profile) else {
        return;
    };
    assert!(
        policy.worker_copies(2).is_some(),
        "TWIST2 offers worker copies"
    );
    records_match_one_slot_on_the_coordinator(
        &robot,
        &profile,
        policy,
        &[(1, 1), (2, 2), (2, 5), (3, 4)],
        "TWIST2",
    );
}

/// `policy` on the workers, for each `(workers, slots)`, records what it records acting
/// for one slot at a time on the coordinator, over the three sample sequences.
fn records_match_one_slot_on_the_coordinator<P: Policy>(
    robot: &RobotModel,
    profile: &Profile,
    policy: P,
    layouts: &[(usize, usize)],
    what: &str,
) {
    let seqs = sequences(robot);
    let mut coordinator = OnCoordinator(policy);
    let want = records(robot, profile, &seqs, 1, 1, &mut coordinator);
    assert_eq!(want.len(), 6);
    let want = format!("{want:?}");
    let mut policy = coordinator.0;
    for &(workers, envs) in layouts {
        let got = records(robot, profile, &seqs, workers, envs, &mut policy);
        assert!(
            format!("{got:?}") == want,
            "{what}: {workers} workers, {envs} slots: the records differ from one slot on the coordinator"
        );
    }
}

/// A BeyondMimic network acting for four slots, five on two workers, and nine (two calls
/// of eight rows) — its six episodes in calls padded with zero rows — records what it
/// records acting for one slot at a time on the coordinator.
fn beyondmimic_records_do_not_depend_on_its_slots(test: &str, onnx: &str, profile: &str) {
    let robot = g1();
    let Some(path) = prereq::reference(test, onnx) else {
        return;
    };
    let profile = load_profile(&bundled_profile_path(profile), &robot).unwrap();
    let policy = BeyondMimicPolicy::load(&path, Arc::new(robot.clone()), &profile).unwrap();
    assert_eq!(
        policy.call_rows(),
        INFERENCE_BATCH,
        "{onnx} plans for {INFERENCE_BATCH} rows per call"
    );
    records_match_one_slot_on_the_coordinator(
        &robot,
        &profile,
        policy,
        &[(1, 4), (2, 5), (1, 9)],
        onnx,
    );
}

#[test]
fn wbc_mjlabs_records_do_not_depend_on_how_many_slots_share_a_call() {
    beyondmimic_records_do_not_depend_on_its_slots(
        "batched_inference::wbc_mjlab_slots",
        "wbc-mjlab/wbc_g1_policy.onnx",
        "wbc-mjlab",
    );
}

#[test]
fn holosomas_records_do_not_depend_on_how_many_slots_share_a_call() {
    beyondmimic_records_do_not_depend_on_its_slots(
        "batched_inference::holosoma_slots",
        "holosoma/fastsac_g1_29dof_dancing.onnx",
        "holosoma-wbt",
    );
}
