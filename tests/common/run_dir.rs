//! A run directory written as `eval` writes it (through the same writers), from a
//! header and records a test makes up: shared by the report tests.
#![allow(dead_code)]

use std::path::Path;
use thorarena::eval::metrics::RegimeThresholds;
use thorarena::eval::results::{
    write_header, write_record, write_results, PlannedSequence, PolicyIoReport, RunHeader,
    RESULTS_VERSION,
};
use thorarena::eval::{EpisodeRecord, LatencySummary, PolicyIoRules, Setting, TerminationRule};

/// A run of `policy` planning clean_table and push_chair, two sequences each of 30
/// steps, under `force` and `no-force`.
pub fn header(policy: &str) -> RunHeader {
    RunHeader {
        results_version: RESULTS_VERSION,
        version: "0.1.0".into(),
        policy: policy.into(),
        profile: "default".into(),
        profile_mismatch_ok: false,
        declared_profile: None,
        control_dt_s: 0.02,
        physics_dt_s: 0.005,
        engine: thorarena::sim::physics::Engine::Rapier,
        dataset: "data/sample".into(),
        dataset_sha256: "ab".repeat(32),
        keypoints: "default".into(),
        termination: TerminationRule::default(),
        settings: vec![
            Setting::parse("force").unwrap(),
            Setting::parse("no-force").unwrap(),
        ],
        sequences: ["clean_table", "push_chair"]
            .iter()
            .flat_map(|task| {
                ["000", "001"].map(|id| PlannedSequence {
                    task: task.to_string(),
                    sequence_id: format!("{task}_{id}"),
                    steps_ref: 30,
                })
            })
            .collect(),
        subset: None,
        shard: None,
        io: PolicyIoRules::default(),
        sanity: None,
        network_kernels: None,
        policy_parameters: Default::default(),
        identity: None,
        outside_training: Default::default(),
    }
}

/// Writes a run directory as `eval` would, through the same writers, keeping the records
/// the header plans (a shard's) under the header's policy name.
pub fn write_run(dir: &Path, header: &RunHeader, records: &[EpisodeRecord], transport: bool) {
    std::fs::create_dir_all(dir).unwrap();
    write_header(dir, header).unwrap();
    let planned: Vec<_> = header
        .planned_jobs()
        .into_iter()
        .map(|job| header.job_key(job))
        .collect();
    let records: Vec<EpisodeRecord> = records
        .iter()
        .filter(|r| planned.contains(&r.key()))
        .map(|r| EpisodeRecord {
            policy: header.policy.clone(),
            ..r.clone()
        })
        .collect();
    let mut file = std::fs::File::create(dir.join("episodes.jsonl")).unwrap();
    for r in &records {
        write_record(&mut file, r).unwrap();
    }
    let th = RegimeThresholds::from_forces(&[0.0, 10.0, 20.0]);
    let thresholds = [
        ("clean_table".to_string(), th),
        ("push_chair".to_string(), th),
    ]
    .into_iter()
    .collect();
    let io = PolicyIoReport {
        latency: LatencySummary {
            count: 120,
            mean_us: 3.0,
            p50_us: 2.0,
            p90_us: 4.0,
            p99_us: 9.0,
            p999_us: 40.0,
            max_us: 90.0,
        },
        transport: transport.then(|| {
            serde_json::from_value(serde_json::json!({"round_trips": 120,
            "deadline_misses": 2, "late_replies": 1, "policy_failures": 0, "reconnections": 0}))
            .unwrap()
        }),
        deadline_misses: if transport { 2 } else { 0 },
        invalid_actions: 0,
        resumed_episodes: 0,
    };
    let summary = write_results(dir, header, &records, thresholds, Some(io)).unwrap();
    thorarena::report::write_run_tables(dir, &summary).unwrap();
}
