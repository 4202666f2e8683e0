//! `sweep status`: tasks by state, failure reasons, the not-done set.

use super::*;

/// Tasks by state: (done, failed with reasons, started, not started).
pub(super) struct Census {
    pub(super) done: Vec<usize>,
    pub(super) failed: Vec<FailedRecord>,
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
            TaskState::Failed(f) => c.failed.push(f),
            TaskState::Started => c.started.push(t.index),
            TaskState::NotStarted => c.not_started.push(t.index),
        }
    }
    Ok(c)
}

impl Census {
    pub(super) fn not_done(&self) -> Vec<usize> {
        let mut v: Vec<usize> = self.failed.iter().map(|f| f.task).collect();
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
    for f in &c.failed {
        let cell = &plan.cells[plan.tasks[f.task].cell];
        println!(
            "failed: task {} (cell {}, policy `{}`, setting `{}`): {}",
            f.task, cell.index, cell.policy.name, cell.setting, f.reason
        );
        for l in &f.log_tail {
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
