//! `sweep status`: tasks by state, failure reasons, the not-done set.

use super::*;

/// Tasks by state: (done, failed with reasons, started, not started). A record's
/// task is the directory it lies in (`task_state` refuses one claiming another).
pub(super) struct Census {
    pub(super) done: Vec<usize>,
    pub(super) failed: Vec<(usize, FailedRecord)>,
    pub(super) started: Vec<usize>,
    pub(super) not_started: Vec<usize>,
}

pub(super) fn census(dir: &Path, plan: &Plan) -> anyhow::Result<Census> {
    let mut c = Census {
        done: Vec::new(),
        failed: Vec::new(),
        started: Vec::new(),
        not_started: Vec::new(),
    };
    for t in &plan.tasks {
        match task_state(dir, t.index)? {
            TaskState::Done(_) => c.done.push(t.index),
            TaskState::Failed(f) => c.failed.push((t.index, f)),
            TaskState::Started => c.started.push(t.index),
            TaskState::NotStarted => c.not_started.push(t.index),
        }
    }
    Ok(c)
}

impl Census {
    pub(super) fn not_done(&self) -> Vec<usize> {
        let mut v: Vec<usize> = self.failed.iter().map(|(i, _)| *i).collect();
        v.extend(&self.started);
        v.extend(&self.not_started);
        v.sort_unstable();
        v
    }
}

pub(super) fn status(args: &StatusArgs) -> anyhow::Result<()> {
    let plan = Plan::load(&args.dir)?;
    let c = census(&args.dir, &plan)?;
    println!(
        "{}: {} tasks — {} done, {} failed, {} started (running or interrupted), {} not started",
        args.dir.display(),
        plan.tasks.len(),
        c.done.len(),
        c.failed.len(),
        c.started.len(),
        c.not_started.len()
    );
    // Records are policy output and files anyone may edit: printed bounded, with
    // control characters escaped.
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
    let not_done = c.not_done();
    if not_done.is_empty() {
        println!("not done: none");
    } else {
        println!("not done (--array): {}", compact_ranges(&not_done));
    }
    Ok(())
}
