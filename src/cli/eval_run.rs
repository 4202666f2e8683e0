//! One evaluation run from the terminal: its progress bar and first lines, its tables
//! printed, and a policy failure turned into the exit status.

use anyhow::bail;
use std::path::Path;
use thorarena::benchmark::{EvalObserver, EvalOptions, Starting};
use thorarena::episode::EpisodeTrace;
use thorarena::evaluation::{EpisodeRecord, EvalSpec};
use thorarena::policy::Policy;
use thorarena::results::{RunDir, RUN_FILES, TRACES_DIR};

/// Hands the trace of every episode's first seconds to a caller (`crosscheck`).
pub(super) struct FirstSeconds<'a> {
    /// How many seconds of each episode.
    pub seconds: f64,
    /// Called once per episode run, with its record, those steps and the feet's slip
    /// over the whole episode.
    pub sink: &'a mut dyn FnMut(&EpisodeRecord, &EpisodeTrace),
}

/// The progress of a run on the terminal: what it starts with, a bar over its episodes.
struct Progress<'a, 'f> {
    bar: indicatif::ProgressBar,
    policy: String,
    spec: &'a EvalSpec,
    run: &'a RunDir,
    /// `--resume` was asked for.
    resume: bool,
    first_seconds: Option<FirstSeconds<'f>>,
}

impl EvalObserver for Progress<'_, '_> {
    fn starting(&mut self, s: &Starting) {
        let dir = s.header.dataset.as_str();
        if self.resume && !s.started.resumed {
            eprintln!(
                "--resume: nothing to resume in {}, starting afresh",
                self.run.path().display()
            );
        }
        if s.started.torn_tail_dropped {
            eprintln!(
                "--resume: {} ended in a line cut short; it is dropped",
                self.run.episodes_file().display()
            );
        }
        let part = s
            .header
            .subset
            .as_ref()
            .map(|sub| format!(" (part of it: {})", sub.describe(s.header.sequences.len())))
            .unwrap_or_default();
        eprintln!(
            "evaluating `{}` on {dir}{part}: {} episodes to run ({} already done), {} environment slots on {} workers",
            self.policy,
            s.to_run,
            s.started.kept.len(),
            self.spec.envs,
            self.spec.workers
        );
        if let Some(sanity) = &s.header.sanity {
            eprintln!("sanity check: {}", sanity.label());
        }
        self.bar.set_length(s.to_run as u64);
    }

    fn episode(&mut self, r: &EpisodeRecord, trace: Option<&EpisodeTrace>) {
        if let (Some(trace), Some(f)) = (trace, self.first_seconds.as_mut()) {
            (f.sink)(r, trace);
        }
        self.bar
            .set_message(format!("{}/{} ({})", r.task, r.sequence_id, r.setting));
        self.bar.inc(1);
    }
}

/// Runs the benchmark for one connected policy into `out` and prints its tables; a run
/// whose policy failed is an error (after its results are written).
pub(super) fn evaluate(
    resume: bool,
    spec: &EvalSpec,
    policy: &mut dyn Policy,
    out: &Path,
    first_seconds: Option<FirstSeconds>,
) -> anyhow::Result<()> {
    let run = RunDir::new(out);
    let bar = indicatif::ProgressBar::new(0);
    bar.set_style(
        indicatif::ProgressStyle::with_template(
            "{bar:40} {pos}/{len} episodes  {elapsed} elapsed, ~{eta} left  {msg}",
        )
        .expect("valid template"),
    );
    let options = EvalOptions {
        resume,
        trace_first_s: first_seconds.as_ref().map(|f| f.seconds),
    };
    let mut progress = Progress {
        bar,
        policy: policy.name().to_string(),
        spec,
        run: &run,
        resume,
        first_seconds,
    };
    let result = thorarena::benchmark::evaluate(spec, policy, &run, options, &mut progress);
    progress.bar.finish_and_clear();
    let done = result.map_err(|e| match e {
        thorarena::benchmark::BenchmarkError::Results(
            e @ thorarena::results::ResultsError::OtherConfiguration { .. },
        ) => anyhow::anyhow!("--resume: {e}; use another --out, or --overwrite"),
        e => e.into(),
    })?;
    println!("{}", done.tables);
    eprintln!(
        "wrote {}/{{{}}}",
        out.display(),
        RUN_FILES
            .iter()
            .filter(|f| **f != TRACES_DIR)
            .copied()
            .collect::<Vec<_>>()
            .join(", ")
    );
    if !spec.trace.is_empty() {
        eprintln!(
            "traces of {} in {}/<task>-<sequence>-<setting>.json: look at one with `thorarena view FILE`",
            spec.trace.join(", "),
            run.traces_dir().display()
        );
    }
    // The records of episodes a failed policy cut short say `policy_failed`, and the exit
    // status must say it too (sweeps and scripts go by it).
    if done.policy_failed() {
        bail!(
            "the policy failed: {} episodes ended `policy_failed`, {} did not run (finished ones are in {}; `--resume` with a working policy runs both again)",
            done.cut_short,
            done.not_run,
            out.display()
        );
    }
    Ok(())
}
