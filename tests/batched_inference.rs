//! Networks in process, batched and on the workers: one tract call for a batch of
//! environments gives each environment bit for bit its batch-one action, and an
//! evaluation whose policy acts on the workers (each worker's copy, its own slots)
//! records exactly what the same policy acting on the coordinator records, for any
//! number of workers and slots. With the published TWIST2 network, and the BeyondMimic
//! family's (wbc-mjlab's tracker, holosoma's dance policy with its `time_step` input),
//! which run [`thorarena::policy::beyondmimic::INFERENCE_BATCH`] rows per call (one
//! today; these tests passed at four too); skipped, saying so, when `../shared/reference`
//! is absent.

use std::sync::Arc;
use thorarena::evaluation::{schedule, EpisodeRecord, PolicyIoRules, Setting, TerminationRule};
use thorarena::motion::Sequence;
use thorarena::policy::beyondmimic::INFERENCE_BATCH;
use thorarena::policy::{ActOutcome, BeyondMimicPolicy, Observation, Policy, Twist2Policy};
use thorarena::profile::{bundled_profile_path, load_profile, Profile};
use thorarena::robot::RobotModel;
use thorarena::runner::{run_eval, EvalPlan};

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
    // Rows of distinct, deterministic inputs in the range observations take.
    let row = |r: usize| -> Vec<f32> {
        (0..width)
            .map(|i| (((i * 7919 + r * 104_729) % 2001) as f32 / 1000.0 - 1.0) * 2.0)
            .collect()
    };
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
    let max_diff = alone
        .iter()
        .zip(&answers[0])
        .map(|(a, b)| (a - b).abs())
        .fold(0.0f32, f32::max);
    eprintln!("batch {batch} against batch one: largest difference {max_diff:e}");
    assert!(max_diff < 1e-5, "{max_diff:e}");
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
    let plan = EvalPlan {
        robot,
        profile,
        keypoints: "default",
        termination: TerminationRule::default(),
        settings: vec![
            Setting::parse("force").unwrap(),
            Setting::parse("no-force").unwrap(),
        ],
        workers,
        envs,
        pipeline_depth: 1,
        io: PolicyIoRules::default(),
        trace: Vec::new(),
        trace_first_s: None,
        engine: Default::default(),
    };
    let jobs = schedule(seqs.len(), plan.settings.len(), None);
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

/// A BeyondMimic network acting for 1 to 5 slots per worker — at four rows per call: one
/// padded call, a full one, a full one and a padded one — records what it records acting
/// for one slot at a time on the coordinator.
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
        &[(1, 4), (2, 5), (1, 5)],
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
