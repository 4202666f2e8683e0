//! What `data import`, `data info` and `eval` compute, called through the library as
//! those commands call it, for tests about the results rather than the command line
//! (`tests/cli.rs` and the other binary tests keep the end-to-end checks).
#![allow(dead_code)]

use std::path::{Path, PathBuf};
use thorarena::eval::pipeline::{self, EvalOptions};
use thorarena::eval::results::RunDir;
use thorarena::eval::{EngineChoice, EvalRequest, EvalSpec};
use thorarena::policy::registry::PolicyChoice;
use thorarena::sim::motion::import::{import_batch, ImportBatch, ImportObserver, SourceFormat};
use thorarena::sim::motion::{describe, Dataset, GroundCheck, Sequence, TrimmedGlitches};

/// What an import reports, a line per trimmed input.
#[derive(Default)]
struct TrimLog(Vec<String>);

impl ImportObserver for TrimLog {
    fn converted(&mut self, _: &Path, seq: &Sequence, _: Option<&GroundCheck>) {
        if let Some(trim) = TrimmedGlitches::in_provenance(&seq.provenance) {
            self.0
                .push(format!("trimmed glitch frames: {}", trim.summary()));
        }
    }
}

/// `data import --format F FILES --out OUT --task walk` with `--trim-glitches` and
/// `--ground-correct` as given: the trim lines on success, the error's text otherwise.
pub fn import(
    format: SourceFormat,
    files: &[&Path],
    out: &Path,
    trim_glitches: bool,
    ground_correct: bool,
) -> Result<String, String> {
    let batch = ImportBatch {
        inputs: files.iter().map(|f| f.to_path_buf()).collect(),
        format,
        task: "walk".into(),
        force_logs: None,
        force_offset_s: 0.0,
        force_sign: 1.0,
        renormalize_quaternions: false,
        trim_glitches,
        ground_correct,
    };
    let mut log = TrimLog::default();
    import_batch(out, &crate::common::g1(), &batch, &mut log)
        .map(|_| log.0.join("\n"))
        .map_err(|e| e.to_string())
}

/// What `data info DIR` prints.
pub fn data_info(dir: &Path) -> String {
    let robot = crate::common::g1();
    let ds = Dataset::open(dir, &robot).unwrap();
    let seqs = ds.load_all().unwrap();
    describe(&ds, &seqs, &robot)
}

/// `eval --dataset D --policy P [--profile PROFILE] --settings S --out OUT` in process;
/// returns the run.
pub fn eval(
    dataset: &Path,
    policy: &str,
    profile: Option<&str>,
    settings: &[&str],
    out: &Path,
) -> PathBuf {
    eval_on(
        EngineChoice::Rapier,
        dataset,
        policy,
        profile,
        settings,
        out,
    )
}

/// [`eval`] on `engine` (`--engine`, the generated MJCF for MuJoCo).
pub fn eval_on(
    engine: EngineChoice,
    dataset: &Path,
    policy: &str,
    profile: Option<&str>,
    settings: &[&str],
    out: &Path,
) -> PathBuf {
    let request = EvalRequest {
        policy: thorarena::policy::registry::PolicySource::parse(policy).unwrap(),
        dataset: Some(dataset.to_path_buf()),
        profile: profile.map(String::from),
        settings: settings.iter().map(|s| s.parse().unwrap()).collect(),
        engine,
        ..EvalRequest::default()
    };
    evaluate(&request, out).unwrap()
}

/// `eval` of a whole request into `out`, in process: the run, or the error's text (a
/// policy refused by its sanity check, …).
pub fn evaluate(request: &EvalRequest, out: &Path) -> Result<PathBuf, String> {
    let spec = EvalSpec::load(request).map_err(|e| e.to_string())?;
    let PolicyChoice::InProcess(mut policy) = spec
        .policy
        .as_ref()
        .expect("a policy argument")
        .load(&spec.robot, &spec.profile)
        .map_err(|e| e.to_string())?
    else {
        panic!("{} is not an in-process policy", request.policy);
    };
    pipeline::evaluate(
        &spec,
        policy.as_mut(),
        &RunDir::new(out),
        EvalOptions::default(),
        &mut (),
    )
    .map_err(|e| e.to_string())?;
    Ok(out.to_path_buf())
}
