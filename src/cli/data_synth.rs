//! `thorarena data synth`: writes the synthetic six-task dataset.

use super::data::SynthArgs;
use anyhow::{bail, Context};
use std::path::Path;
use thorarena::motion::describe;
use thorarena::motion::synth::{synthesize, SynthOptions};
use thorarena::motion::{DatasetWriter, Manifest, MANIFEST};

/// Most sequences per task `data synth` writes (a million sequences would be ~100 GB).
const MAX_PER_TASK: usize = 100_000;

pub(super) fn run(args: &SynthArgs) -> anyhow::Result<()> {
    if !(1..=MAX_PER_TASK).contains(&args.per_task) {
        bail!(
            "--per-task {}: give 1 to {MAX_PER_TASK} sequences per task",
            args.per_task
        );
    }
    let robot = thorarena::registry::robot(&args.robot)?;
    if args.out.join(MANIFEST).exists() {
        if !args.force {
            bail!(
                "{} already holds a dataset; pass --force to replace it",
                args.out.display()
            );
        }
        remove_dataset(&args.out)?;
    }
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("creating {}", args.out.display()))?;
    let opts = SynthOptions {
        per_task: args.per_task,
        seed: args.seed,
        fps: 50.0,
        tasks: args.tasks.clone(),
    };
    let started = std::time::Instant::now();
    let seqs = synthesize(&robot, &opts, |done, total| {
        if done % args.per_task.max(1) == 0 || done == total {
            eprintln!(
                "synth: {done}/{total} sequences ({:.1} s)",
                started.elapsed().as_secs_f64()
            );
        }
    })?;
    let mut writer = DatasetWriter::create(&args.out, &robot)?;
    for s in &seqs {
        writer.add(s)?;
    }
    let ds = writer.finish()?;
    print!("{}", describe(&ds, &seqs, &robot));
    eprintln!(
        "{}: {} sequences in {:.1} s",
        ds.dir.display(),
        ds.len(),
        started.elapsed().as_secs_f64()
    );
    Ok(())
}

/// Removes a dataset's manifest and the sequence files it lists (nothing else in `dir`).
fn remove_dataset(dir: &Path) -> anyhow::Result<()> {
    let path = dir.join(MANIFEST);
    let text =
        std::fs::read_to_string(&path).with_context(|| format!("reading {}", path.display()))?;
    let manifest: Manifest =
        serde_json::from_str(&text).with_context(|| format!("parsing {}", path.display()))?;
    for e in &manifest.sequences {
        if Path::new(&e.file).is_absolute() || e.file.split('/').any(|c| c == "..") {
            bail!(
                "{}: refusing to delete `{}` outside the dataset",
                path.display(),
                e.file
            );
        }
        let f = dir.join(&e.file);
        if f.exists() {
            std::fs::remove_file(&f).with_context(|| format!("removing {}", f.display()))?;
        }
    }
    std::fs::remove_file(&path).with_context(|| format!("removing {}", path.display()))?;
    Ok(())
}
