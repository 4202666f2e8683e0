//! `sweep status`: tasks by state (done only when the run counts), failure reasons, the
//! not-done set.

use super::StatusArgs;
use thorarena::sweep::CheckedCensus;
use thorarena::sweep::{
    compact_ranges, printable, truncated, Plan, LOG_LINE_MAX_BYTES, LOG_TAIL_MAX_BYTES,
};
pub(super) fn status(args: &StatusArgs) -> anyhow::Result<()> {
    let plan = Plan::load(&args.dir)?;
    // A task is done when its run counts, not merely when its done.json is there.
    let checked = CheckedCensus::of(&args.dir, &plan)?;
    let (c, not_counted) = (&checked.census, &checked.not_counted);
    // A dataset changed since planning: `collect` refuses its cells, so their done tasks
    // are not done either (they would be scored against other references).
    let changed = changed_datasets(&plan);
    for (dataset, why) in &changed {
        println!(
            "dataset {} {why}: `sweep collect` refuses its cells, and their tasks are not counted done; restore it, or plan a new sweep",
            dataset.display()
        );
    }
    let on_changed = c
        .done
        .iter()
        .filter(|&&i| changed.contains_key(&plan.cells[plan.tasks[i].cell].dataset))
        .count();
    println!(
        "{}: {} tasks — {} done, {} failed, {} started (running or interrupted), {} not started{}{}",
        args.dir.display(),
        plan.tasks.len(),
        c.done.len() - on_changed,
        c.failed.len(),
        c.started.len(),
        c.not_started.len(),
        if not_counted.is_empty() {
            String::new()
        } else {
            format!(
                ", {} marked done whose run does not count",
                not_counted.len()
            )
        },
        if on_changed == 0 {
            String::new()
        } else {
            format!(", {on_changed} marked done on a dataset changed since planning")
        }
    );
    // Records are policy output and files anyone may edit: printed bounded, with
    // control characters escaped.
    for (i, problem) in not_counted {
        let cell = &plan.cells[plan.tasks[*i].cell];
        println!(
            "not counted: task {i} (cell {}, policy `{}`, setting `{}`): {}; `sweep run` runs what is missing, or says why it cannot",
            cell.index,
            printable(&cell.policy.name),
            printable(&cell.setting),
            truncated(&printable(problem.why()), LOG_LINE_MAX_BYTES)
        );
    }
    for (i, f) in &c.failed {
        let cell = &plan.cells[plan.tasks[*i].cell];
        println!(
            "failed: task {i} (cell {}, policy `{}`, setting `{}`): {}",
            cell.index,
            printable(&cell.policy.name),
            printable(&cell.setting),
            truncated(&printable(&f.reason), LOG_LINE_MAX_BYTES)
        );
        let mut budget = LOG_TAIL_MAX_BYTES;
        for l in &f.log_tail {
            let l = truncated(&printable(l), LOG_LINE_MAX_BYTES);
            let Some(left) = budget.checked_sub(l.len()) else {
                println!("    … (log tail cut at {LOG_TAIL_MAX_BYTES} bytes)");
                break;
            };
            budget = left;
            println!("    {l}");
        }
    }
    let not_done = checked.not_done();
    if not_done.is_empty() {
        println!("not done: none");
    } else {
        println!("not done (--array): {}", compact_ranges(&not_done));
    }
    Ok(())
}

/// The planned datasets that are no longer what was planned: changed content, or gone.
fn changed_datasets(plan: &Plan) -> std::collections::BTreeMap<std::path::PathBuf, String> {
    let mut changed = std::collections::BTreeMap::new();
    let Ok(robot) = thorarena::registry::robot(&plan.robot) else {
        return changed;
    };
    let mut seen = std::collections::BTreeSet::new();
    for cell in &plan.cells {
        if !seen.insert(cell.dataset.clone()) {
            continue;
        }
        match thorarena::motion::Dataset::open(&cell.dataset, &robot) {
            Ok(ds) if ds.content_hash() == cell.dataset_sha256 => {}
            Ok(_) => {
                changed.insert(
                    cell.dataset.clone(),
                    "changed since the sweep was planned (its content hash differs)".to_string(),
                );
            }
            Err(e) => {
                changed.insert(cell.dataset.clone(), format!("cannot be read ({e})"));
            }
        }
    }
    changed
}
