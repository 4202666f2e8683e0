//! What `sweep status` says about a sweep directory: tasks by state, a task done only
//! when its run counts and its dataset is still the one planned, why the others are not,
//! failure reasons with their log tails, and the not-done set as Slurm's array syntax.
//! Records are policy output and files anyone may edit: they are shown bounded, with
//! control characters escaped.

use super::{changed_datasets, compact_ranges, printable, truncated, CheckedCensus, Plan};
use super::{SweepError, LOG_LINE_MAX_BYTES, LOG_TAIL_MAX_BYTES};
use std::collections::BTreeMap;
use std::fmt::{self, Display, Formatter};
use std::path::{Path, PathBuf};

/// A sweep directory's tasks as `status` reports them.
#[derive(Debug)]
pub struct SweepStatus {
    /// The sweep directory, as given.
    pub dir: PathBuf,
    /// Its plan.
    pub plan: Plan,
    /// Its tasks, each done task's run checked.
    pub checked: CheckedCensus,
    /// Planned datasets changed or gone since planning, with why.
    pub changed: BTreeMap<PathBuf, String>,
}

impl SweepStatus {
    /// Reads the state of every task of sweep directory `dir`.
    pub fn read(dir: &Path) -> Result<Self, SweepError> {
        let plan = Plan::load(dir)?;
        let checked = CheckedCensus::of(dir, &plan)?;
        let changed = changed_datasets(&plan);
        Ok(Self {
            dir: dir.to_path_buf(),
            plan,
            checked,
            changed,
        })
    }

    /// The last line: the tasks not done as a Slurm array expression (the field that
    /// takes it named `option.array`), or none.
    pub fn not_done_line(&self) -> String {
        let not_done = self.checked.not_done();
        if not_done.is_empty() {
            "not done: none".to_string()
        } else {
            format!("not done (`option.array`): {}", compact_ranges(&not_done))
        }
    }

    /// Tasks marked done on a dataset changed since planning: `collect` refuses their
    /// cells, so they are not counted done either.
    fn done_on_changed(&self) -> usize {
        let plan = &self.plan;
        self.checked
            .census
            .done
            .iter()
            .filter(|&&i| {
                self.changed
                    .contains_key(&plan.cells[plan.tasks[i].cell].dataset)
            })
            .count()
    }

    /// `task I (cell C, policy `P`, setting `S`)`, its names printable.
    fn task_said(&self, i: usize) -> String {
        let cell = &self.plan.cells[self.plan.tasks[i].cell];
        format!(
            "task {i} (cell {}, policy `{}`, setting `{}`)",
            cell.index,
            printable(&cell.policy.name),
            printable(&cell.setting.spelling())
        )
    }
}

/// A record's text bounded and escaped for the terminal.
fn bounded(text: &str) -> String {
    truncated(&printable(text), LOG_LINE_MAX_BYTES)
}

impl Display for SweepStatus {
    /// Every line but [`SweepStatus::not_done_line`], each ending in a newline.
    fn fmt(&self, f: &mut Formatter<'_>) -> fmt::Result {
        let (c, not_counted) = (&self.checked.census, &self.checked.not_counted);
        for (dataset, why) in &self.changed {
            writeln!(
                f,
                "dataset {} {why}: `sweep collect` refuses its cells, and their tasks are not counted done; restore it, or plan a new sweep",
                dataset.display()
            )?;
        }
        let on_changed = self.done_on_changed();
        write!(
            f,
            "{}: {} tasks — {} done, {} failed, {} started (running or interrupted), {} not started",
            self.dir.display(),
            self.plan.tasks.len(),
            c.done.len() - on_changed,
            c.failed.len(),
            c.started.len(),
            c.not_started.len()
        )?;
        if !not_counted.is_empty() {
            write!(
                f,
                ", {} marked done whose run does not count",
                not_counted.len()
            )?;
        }
        if on_changed != 0 {
            write!(
                f,
                ", {on_changed} marked done on a dataset changed since planning"
            )?;
        }
        writeln!(f)?;
        for (i, problem) in not_counted {
            writeln!(
                f,
                "not counted: {}: {}; `sweep run` runs what is missing, or says why it cannot",
                self.task_said(*i),
                bounded(problem.why())
            )?;
        }
        for (i, failed) in &c.failed {
            writeln!(
                f,
                "failed: {}: {}",
                self.task_said(*i),
                bounded(&failed.reason)
            )?;
            let mut budget = LOG_TAIL_MAX_BYTES;
            for line in &failed.log_tail {
                let line = bounded(line);
                let Some(left) = budget.checked_sub(line.len()) else {
                    writeln!(f, "    … (log tail cut at {LOG_TAIL_MAX_BYTES} bytes)")?;
                    break;
                };
                budget = left;
                writeln!(f, "    {line}")?;
            }
        }
        Ok(())
    }
}
