//! `sweep plan` in one call: the spec read, its datasets resolved against the spec's own
//! directory and opened, the plan expanded, every cell's evaluation loaded as `eval`
//! loads it, and the plan written. Checking the cells before anything is written means a
//! sweep that plans never fails hours later on a request `eval` refuses.

use super::{DatasetInfo, Plan, SweepError, SweepSpec};
use crate::eval::EvalSpec;
use std::collections::HashSet;
use std::path::{Path, PathBuf};

/// A plan placed in its sweep directory.
#[derive(Debug)]
pub struct PlannedSweep {
    /// The plan.
    pub plan: Plan,
    /// The sweep directory, as given.
    pub dir: PathBuf,
    /// Written now; `false`: the directory already held this very plan.
    pub written: bool,
}

/// Plans the sweep of spec file `spec` into sweep directory `dir`: writes its plan, or
/// finds that very plan there already. A directory holding another plan is refused.
pub fn plan_sweep(spec: &Path, dir: &Path) -> Result<PlannedSweep, SweepError> {
    let spec_path = std::fs::canonicalize(spec).map_err(|source| SweepError::SpecMissing {
        path: spec.to_path_buf(),
        source,
    })?;
    let sweep_spec = SweepSpec::load(&spec_path)?;
    let base = spec_path.parent().unwrap_or(Path::new("/"));
    let robot = crate::policy::registry::robot(&sweep_spec.robot).map_err(SweepError::SpecRobot)?;
    let mut datasets = Vec::new();
    for name in &sweep_spec.datasets {
        let dataset = std::fs::canonicalize(base.join(name)).map_err(|source| {
            SweepError::DatasetMissing {
                name: name.clone(),
                base: base.to_path_buf(),
                source,
            }
        })?;
        let info =
            DatasetInfo::read(dataset, &robot).map_err(|source| SweepError::DatasetUnreadable {
                name: name.clone(),
                source,
            })?;
        if info.sequences.is_empty() {
            return Err(SweepError::DatasetEmpty { name: name.clone() });
        }
        datasets.push(info);
    }
    let plan = Plan::expand(&sweep_spec, &spec_path, &datasets)?;
    check_cells_load(&plan)?;
    let written = plan.place(dir)?;
    Ok(PlannedSweep {
        plan,
        dir: dir.to_path_buf(),
        written,
    })
}

/// Checks every cell's evaluation before anything is written: its request loads as
/// `eval` loads one (profile and keypoint set exist for the robot, the setting parses,
/// the dataset and selection are usable), and each network file loads.
pub fn check_cells_load(plan: &Plan) -> Result<(), SweepError> {
    let mut checked: HashSet<String> = HashSet::new();
    for task in plan.tasks.iter().filter(|t| t.shard.0 == 0) {
        let cell = &plan.cells[task.cell];
        // Loading the dataset, profile and keypoints once per combination keeps planning
        // a sweep of thousands of cells fast.
        // The latency rule too: a budget an in-process policy cannot honour is refused.
        let key = format!(
            "{}|{}|{}|{}|{:?}|{:?}",
            cell.policy.policy,
            cell.policy.profile,
            cell.policy.keypoints,
            cell.dataset.display(),
            cell.engine,
            cell.latency
        );
        if !checked.insert(key) {
            continue;
        }
        let request = task.request_for("plan-check");
        let spec = EvalSpec::load(&request).map_err(|source| SweepError::CellRequest {
            cell: cell.index,
            policy: cell.policy.name.clone(),
            source: Box::new(source),
        })?;
        if cell.policy.policy.in_process() && checked.insert(format!("policy|{}", request.policy)) {
            request
                .policy
                .load(&spec.robot, &spec.profile)
                .map_err(|source| SweepError::PolicyLoad {
                    policy: cell.policy.name.clone(),
                    source: Box::new(source),
                })?;
        }
    }
    Ok(())
}

impl std::fmt::Display for PlannedSweep {
    /// The line `sweep plan` prints: planned now, or found already there.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let plan = &self.plan;
        let simulated_s = plan.simulated_s();
        let size = format!(
            "{} cells, {} tasks, {} episodes, {simulated_s:.0} simulated s ({:.2} h)",
            plan.cells.len(),
            plan.tasks.len(),
            plan.episodes(),
            simulated_s / 3600.0
        );
        if self.written {
            write!(f, "planned {size} into {}", self.dir.display())
        } else {
            write!(
                f,
                "{} already holds this plan: nothing to do ({size})",
                self.dir.display()
            )
        }
    }
}
