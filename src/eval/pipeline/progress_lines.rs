//! Runs' progress as lines of text for a terminal or a log (the leaderboard's, `data
//! check`'s rollouts): a run's sanity check and episode count, one line per tenth of its
//! episodes, and the notes of its opening (advice, the policy process's news). Lines, not
//! a bar: a leaderboard runs for hours, often with its output in a file.

use super::{EvalObserver, Starting};
use crate::eval::episode::EpisodeTrace;
use crate::eval::EpisodeRecord;

/// Hands each line of the runs' progress to `say`.
pub struct ProgressLines<'a> {
    say: &'a mut dyn FnMut(&str),
    /// Episodes the current run has to run.
    to_run: usize,
    /// Of them, done.
    done: usize,
}

impl<'a> ProgressLines<'a> {
    /// Progress said through `say`.
    pub fn new(say: &'a mut dyn FnMut(&str)) -> Self {
        Self {
            say,
            to_run: 0,
            done: 0,
        }
    }
}

impl EvalObserver for ProgressLines<'_> {
    fn starting(&mut self, s: &Starting) {
        self.to_run = s.to_run;
        self.done = 0;
        if let Some(sanity) = &s.header.sanity {
            (self.say)(&format!("  sanity check: {}", sanity.label()));
        }
        let kept = s.started.kept.len();
        (self.say)(&format!(
            "  {} episodes to run ({kept} already done)",
            s.to_run
        ));
    }

    fn note(&mut self, text: &str) {
        (self.say)(text);
    }

    fn episode(&mut self, _: &EpisodeRecord, _: Option<&EpisodeTrace>) {
        self.done += 1;
        let step = (self.to_run / 10).max(1);
        if self.done.is_multiple_of(step) || self.done == self.to_run {
            (self.say)(&format!("  {}/{} episodes", self.done, self.to_run));
        }
    }
}
