//! One evaluation run on the terminal: its progress bar and first lines, its tables
//! printed, and a policy failure turned into the exit status.

use super::flags::as_flags;
use std::path::Path;
use thorarena::eval::episode::EpisodeTrace;
use thorarena::eval::pipeline::{EvalObserver, EvalOptions, Evaluated, Starting};
use thorarena::eval::results::RunDir;
use thorarena::eval::{EpisodeRecord, EvalSpec};
use thorarena::policy::Policy;

/// The progress of a run on the terminal: what it starts with, a bar over its episodes.
pub(super) struct Progress {
    bar: indicatif::ProgressBar,
    policy: String,
    /// Environment slots and workers.
    slots: (usize, usize),
    run: RunDir,
    /// `--resume` was asked for.
    resume: bool,
}

impl Progress {
    /// The bar of `policy`'s run of `spec` into `run`.
    pub fn new(policy: &str, spec: &EvalSpec, run: &RunDir, resume: bool) -> Self {
        let bar = indicatif::ProgressBar::new(0);
        bar.set_style(
            indicatif::ProgressStyle::with_template(
                "{bar:40} {pos}/{len} episodes  {elapsed} elapsed, ~{eta} left  {msg}",
            )
            .expect("valid template"),
        );
        Self {
            bar,
            policy: policy.to_string(),
            slots: (spec.envs, spec.workers),
            run: RunDir::new(run.path()),
            resume,
        }
    }

    /// Clears the bar.
    pub fn finish(&self) {
        self.bar.finish_and_clear()
    }
}

impl EvalObserver for Progress {
    fn starting(&mut self, s: &Starting) {
        for line in s.news(&self.policy, self.slots, &self.run, self.resume) {
            eprintln!("{}", as_flags(&line));
        }
        self.bar.set_length(s.to_run as u64);
    }

    fn episode(&mut self, r: &EpisodeRecord, _trace: Option<&EpisodeTrace>) {
        self.bar
            .set_message(format!("{}/{} ({})", r.task, r.sequence_id, r.setting));
        self.bar.inc(1);
    }
}

/// Prints a written run: its tables on stdout, its files and traces on stderr.
pub(super) fn print_evaluated(done: &Evaluated, spec: &EvalSpec, run: &RunDir) {
    println!("{}", done.tables);
    for line in done.written_news(spec, run) {
        eprintln!("{line}");
    }
}

/// Runs the benchmark for one connected policy into `out` and prints its tables; a run
/// whose policy failed is an error (after its results are written).
pub(super) fn evaluate(
    resume: bool,
    spec: &EvalSpec,
    policy: &mut dyn Policy,
    out: &Path,
) -> anyhow::Result<()> {
    let run = RunDir::new(out);
    let mut progress = Progress::new(policy.name(), spec, &run, resume);
    let options = EvalOptions {
        resume,
        trace_first_s: None,
    };
    let result = thorarena::eval::pipeline::evaluate(spec, policy, &run, options, &mut progress);
    progress.finish();
    let done = result?;
    print_evaluated(&done, spec, &run);
    Ok(done.check_policy(out)?)
}
