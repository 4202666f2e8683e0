//! `sweep collect`: [`thorarena::report::collect_sweep`] — shards merged into cells,
//! `results.csv`, and the report with the sweep's curves.

use super::CollectArgs;
use thorarena::report::{collect_sweep, SweepCollect};

pub(super) fn collect(args: &CollectArgs) -> anyhow::Result<()> {
    let request = SweepCollect {
        dir: &args.dir,
        partial: args.partial,
        mixed_engines: args.mixed_engines,
    };
    let collected = collect_sweep(&request, &mut |note| eprintln!("{note}"))?;
    eprintln!("{collected}");
    Ok(())
}
