//! `sweep plan`: [`thorarena::sweep::plan_sweep`] (the spec expanded, each cell's
//! evaluation loaded as `eval` loads it, the plan written).

use super::PlanArgs;

pub(super) fn plan(args: &PlanArgs) -> anyhow::Result<()> {
    println!("{}", thorarena::sweep::plan_sweep(&args.spec, &args.out)?);
    Ok(())
}
