//! `sweep plan`: a spec expanded, each cell's evaluation loaded as `eval` loads it, written.

use super::PlanArgs;
use anyhow::{bail, Context};
use std::path::Path;
use thorarena::evaluation::EvalSpec;
use thorarena::registry::PolicyArg;
use thorarena::sweep::{DatasetInfo, Plan, SweepSpec};
pub(super) fn plan(args: &PlanArgs) -> anyhow::Result<()> {
    let spec_path = std::fs::canonicalize(&args.spec)
        .with_context(|| format!("reading the sweep spec {}", args.spec.display()))?;
    let spec = SweepSpec::load(&spec_path)?;
    let base = spec_path.parent().unwrap_or(Path::new("/"));
    let robot = thorarena::registry::robot(&spec.robot).context("`robot` of the sweep spec")?;
    let mut datasets = Vec::new();
    for d in &spec.datasets {
        let dir = std::fs::canonicalize(base.join(d)).with_context(|| {
            format!(
                "`datasets`: {d} (relative to {}) does not exist",
                base.display()
            )
        })?;
        let info = DatasetInfo::read(dir, &robot).with_context(|| format!("`datasets`: {d}"))?;
        if info.sequences.is_empty() {
            bail!("`datasets`: {d} holds no sequence");
        }
        datasets.push(info);
    }
    let plan = Plan::expand(&spec, &spec_path, &datasets)?;
    validate(&plan)?;

    if plan.place(&args.out)? {
        println!(
            "planned {} into {}",
            plan_summary(&plan),
            args.out.display()
        );
    } else {
        println!(
            "{} already holds this plan: nothing to do ({})",
            args.out.display(),
            plan_summary(&plan)
        );
    }
    Ok(())
}

pub(super) fn plan_summary(plan: &Plan) -> String {
    let s = plan.simulated_s();
    format!(
        "{} cells, {} tasks, {} episodes, {:.0} simulated s ({:.2} h)",
        plan.cells.len(),
        plan.tasks.len(),
        plan.episodes(),
        s,
        s / 3600.0
    )
}

/// Checks every cell's evaluation before anything is written: its request loads as
/// `eval` loads one (profile and keypoint set exist for the robot, the setting parses,
/// the dataset and selection are usable), and each network file loads.
pub(super) fn validate(plan: &Plan) -> anyhow::Result<()> {
    use std::collections::HashSet;
    let mut checked: HashSet<String> = HashSet::new();
    for task in plan.tasks.iter().filter(|t| t.shard.0 == 0) {
        let cell = &plan.cells[task.cell];
        let in_cell = || format!("cell {} (policy `{}`)", cell.index, cell.policy.name);
        if thorarena::evaluation::Setting::parse(&cell.setting).is_none() {
            bail!(
                "cell {}: setting `{}` is not force, no-force, a number or push:<N>",
                cell.index,
                cell.setting
            );
        }
        // Loading the dataset, profile and keypoints once per combination keeps planning
        // a sweep of thousands of cells fast.
        let key = format!(
            "{}|{}|{}|{}|{:?}",
            cell.policy.policy,
            cell.policy.profile,
            cell.policy.keypoints,
            cell.dataset.display(),
            cell.engine
        );
        if !checked.insert(key) {
            continue;
        }
        let request = task.request_for("plan-check");
        let spec = EvalSpec::load(&request).with_context(in_cell)?;
        if cell.policy.command.is_none() && checked.insert(format!("policy|{}", request.policy)) {
            let arg = PolicyArg::parse(&request.policy).with_context(in_cell)?;
            arg.load(&spec.robot, &spec.profile)
                .with_context(|| format!("policy `{}`", cell.policy.name))?;
        }
    }
    Ok(())
}
