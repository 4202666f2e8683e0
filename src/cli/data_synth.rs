//! `thorarena data synth`: writes the synthetic six-task dataset.

use super::data::SynthArgs;
use super::flags::as_flags;
use anyhow::bail;
use thorarena::motion::describe;
use thorarena::motion::synth::{write_synthetic, SynthOptions, SynthWriteError};

pub(super) fn run(args: &SynthArgs) -> anyhow::Result<()> {
    thorarena::results::check_dataset_dir(&args.out)?;
    let robot = thorarena::registry::robot(&args.robot)?;
    let opts = SynthOptions {
        per_task: args.per_task,
        seed: args.seed,
        fps: 50.0,
        tasks: args.tasks.clone(),
    };
    let started = std::time::Instant::now();
    let written = write_synthetic(&args.out, &robot, &opts, args.force, |done, total| {
        if done % args.per_task.max(1) == 0 || done == total {
            eprintln!(
                "synth: {done}/{total} sequences ({:.1} s)",
                started.elapsed().as_secs_f64()
            );
        }
    });
    let (ds, seqs) = match written {
        Err(e @ SynthWriteError::Exists(_)) => bail!("{e}: pass --force"),
        written => written?,
    };
    print!("{}", as_flags(&describe(&ds, &seqs, &robot)));
    eprintln!(
        "{}: {} sequences in {:.1} s",
        ds.dir.display(),
        ds.len(),
        started.elapsed().as_secs_f64()
    );
    Ok(())
}
