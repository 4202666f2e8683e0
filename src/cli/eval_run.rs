//! One evaluation run on the terminal: its progress bar and first lines, its tables
//! printed, and a policy failure turned into the exit status.

use super::flags::as_flags;
use thorarena::eval::episode::EpisodeTrace;
use thorarena::eval::pipeline::{EvalObserver, Evaluated, Evaluation, Starting};
use thorarena::eval::results::RunDir;
use thorarena::eval::{EpisodeRecord, EvalSpec};

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

    fn note(&mut self, text: &str) {
        self.bar.suspend(|| eprintln!("{}", as_flags(text)));
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

/// What opening a run says, on the terminal (its option names as flags).
pub(super) struct Notes;

impl EvalObserver for Notes {
    fn note(&mut self, text: &str) {
        eprintln!("{}", as_flags(text));
    }
}

/// Scores an opened run with its progress bar and prints its tables; a run whose policy
/// failed is an error (after its results are written).
pub(super) fn score(evaluation: &mut Evaluation) -> anyhow::Result<()> {
    let mut progress = Progress::new(
        evaluation.policy.name(),
        &evaluation.spec,
        &evaluation.run,
        evaluation.resume,
    );
    let result = evaluation.run(&mut progress);
    progress.finish();
    let done = result?;
    print_evaluated(&done, &evaluation.spec, &evaluation.run);
    Ok(done.check_policy(evaluation.run.path())?)
}
