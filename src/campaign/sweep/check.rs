//! A plan checked as a whole when it is read back: `plan.json` crosses a boundary (a
//! shared file system, an editor), and every command indexes cells and tasks by the
//! numbers in it. A plan that loads holds what it claims: cells and tasks numbered
//! 0..n in order, every task's cell in range, every cell's shards present exactly once,
//! and every task's `eval` arguments exactly those its cell gives — so an edited argument
//! cannot run another policy under the cell's label.

use super::plan::{shard_episodes, task_request, Plan};

impl Plan {
    /// The first inconsistency of the plan, as a sentence naming the task or cell.
    pub(super) fn check(&self) -> Result<(), String> {
        if self.cells.is_empty() {
            return Err("`cells` is empty".into());
        }
        if self.tasks.is_empty() {
            return Err("`tasks` is empty".into());
        }
        for (i, c) in self.cells.iter().enumerate() {
            if c.index != i {
                return Err(format!("cells[{i}] says it is cell {}", c.index));
            }
            if c.shards == 0 || c.shards > c.episodes {
                return Err(format!(
                    "cell {i}: {} shards of {} episodes (1 to the episodes)",
                    c.shards, c.episodes
                ));
            }
        }
        // As many tasks as shards (which also bounds what is allocated below by the
        // tasks actually listed, however large a damaged count claims to be).
        let shards = self
            .cells
            .iter()
            .try_fold(0usize, |sum, c| sum.checked_add(c.shards));
        if shards != Some(self.tasks.len()) {
            return Err(format!(
                "the cells have {} shards in all, the plan {} tasks",
                shards.map_or("too many".into(), |s| s.to_string()),
                self.tasks.len()
            ));
        }
        // Each cell's shards, each seen once: duplicates and gaps both fail.
        let mut seen: Vec<Vec<bool>> = self.cells.iter().map(|c| vec![false; c.shards]).collect();
        for (i, t) in self.tasks.iter().enumerate() {
            if t.index != i {
                return Err(format!("tasks[{i}] says it is task {}", t.index));
            }
            let Some(cell) = self.cells.get(t.cell) else {
                return Err(format!(
                    "task {i}: cell {} (the plan has cells 0..{})",
                    t.cell,
                    self.cells.len()
                ));
            };
            let (s, n) = t.shard;
            if n != cell.shards || s >= n {
                return Err(format!(
                    "task {i}: shard {s}/{n} of cell {} (which has {} shards)",
                    t.cell, cell.shards
                ));
            }
            if std::mem::replace(&mut seen[t.cell][s], true) {
                return Err(format!(
                    "task {i}: shard {s}/{n} of cell {} is planned twice",
                    t.cell
                ));
            }
            let episodes = shard_episodes(cell.episodes, t.shard);
            if t.episodes != episodes {
                return Err(format!(
                    "task {i}: {} episodes, its shard of cell {} has {episodes}",
                    t.episodes, t.cell
                ));
            }
            if task_request(&self.robot, cell, t.shard).as_ref() != Ok(&t.request) {
                return Err(format!(
                    "task {i}: its evaluation is not that of cell {} (policy `{}`, setting `{}`)",
                    t.cell,
                    cell.policy.name,
                    cell.setting.spelling()
                ));
            }
        }
        if let Some(c) = seen.iter().position(|s| s.iter().any(|&x| !x)) {
            return Err(format!("cell {c}: a shard has no task"));
        }
        Ok(())
    }
}
