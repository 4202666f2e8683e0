//! `sweep task`: one task ([`thorarena::sweep::run_engine_task`]), its index given or
//! taken from the cluster engine's environment (a Slurm array, a Kubernetes Indexed Job).

use super::TaskArgs;
use thorarena::sweep::{run_engine_task, EngineTask};

pub(super) fn task(args: &TaskArgs) -> anyhow::Result<()> {
    let ended = run_engine_task(&EngineTask {
        exe: &std::env::current_exe()?,
        dir: &args.dir,
        index: args.index,
        workers: args.workers,
    })?;
    println!("{ended}");
    Ok(())
}
