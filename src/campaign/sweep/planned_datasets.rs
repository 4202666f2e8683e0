//! The datasets a plan names, as they are now. A run is scored against the references on
//! disk when it is collected, so a dataset changed since planning would score runs
//! against other references: `collect` refuses it (as `merge` and `eval --resume` refuse
//! theirs), and `status` says which ones changed and counts their tasks not done.

use super::{Plan, SweepError};
use crate::sim::motion::{Dataset, Sequence};
use crate::sim::robot::RobotModel;
use std::collections::{BTreeMap, BTreeSet};
use std::path::PathBuf;

/// Characters of a content hash an error quotes: enough to tell two apart.
const HASH_QUOTED_CHARS: usize = 12;

/// Each dataset of `plan`, loaded, after checking it is the one planned.
pub fn planned_sequences(
    plan: &Plan,
    robot: &RobotModel,
) -> Result<BTreeMap<PathBuf, Vec<Sequence>>, SweepError> {
    let mut datasets: BTreeMap<PathBuf, Vec<Sequence>> = BTreeMap::new();
    for cell in &plan.cells {
        if datasets.contains_key(&cell.dataset) {
            continue;
        }
        let ds = Dataset::open(&cell.dataset, robot).map_err(|source| SweepError::CellDataset {
            cell: cell.index,
            source,
        })?;
        let now = ds.content_hash();
        if now != cell.dataset_sha256 {
            let planned = &cell.dataset_sha256;
            return Err(SweepError::DatasetChanged {
                dataset: cell.dataset.clone(),
                planned: planned[..planned.len().min(HASH_QUOTED_CHARS)].to_string(),
                now: now[..HASH_QUOTED_CHARS].to_string(),
            });
        }
        datasets.insert(cell.dataset.clone(), ds.load_all()?);
    }
    Ok(datasets)
}

/// The planned datasets that are no longer what was planned — changed content, or gone —
/// each with why. None when the plan's robot does not resolve (nothing can be checked).
pub fn changed_datasets(plan: &Plan) -> BTreeMap<PathBuf, String> {
    let mut changed = BTreeMap::new();
    let Ok(robot) = crate::policy::registry::robot(&plan.robot) else {
        return changed;
    };
    let mut seen = BTreeSet::new();
    for cell in &plan.cells {
        if !seen.insert(cell.dataset.clone()) {
            continue;
        }
        match Dataset::open(&cell.dataset, &robot) {
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
