//! `sweep run`: [`thorarena::campaign::sweep::run_sweep`] on the local pool, N tasks at a time,
//! with a progress bar over the sweep's episodes.

use super::SweepRunArgs;
use indicatif::{ProgressBar, ProgressStyle};
use thorarena::campaign::sweep::{
    run_sweep, LocalRun, RunFinished, RunObserver, RunProgress, RunStarting,
};

/// The bar, once the run says how many episodes it counts up to.
struct Bar(Option<ProgressBar>);

impl RunObserver for Bar {
    fn starting(&mut self, starting: &RunStarting) {
        eprintln!("{starting}");
        let bar = ProgressBar::new(starting.episodes as u64);
        bar.set_style(
            ProgressStyle::with_template(
                "{bar:40} {pos}/{len} episodes  {elapsed} elapsed, ~{eta} left  {msg}",
            )
            .expect("valid template"),
        );
        self.0 = Some(bar);
    }

    fn progress(&mut self, progress: &RunProgress) {
        if let Some(bar) = &self.0 {
            bar.set_position(progress.pool.episodes as u64);
            bar.set_message(progress.to_string());
        }
    }

    fn finished(&mut self, finished: &RunFinished) {
        if let Some(bar) = self.0.take() {
            bar.finish_and_clear();
        }
        eprintln!("{finished}");
    }
}

pub(super) fn run_all(args: &SweepRunArgs) -> anyhow::Result<()> {
    let run = LocalRun {
        exe: &std::env::current_exe()?,
        dir: &args.dir,
        jobs: args.jobs,
    };
    run_sweep(&run, &mut Bar(None))?;
    Ok(())
}
