//! Equivalent axis values refused: `settings = ["force", "1"]`, a dataset spelled twice
//! (`../ds/short`, `../ds/./short`), two identical `[[engine]]` tables would each be a
//! cell, running the same episodes twice and plotting them as two points. Values are
//! compared as parsed — settings by what they apply, datasets by their canonical
//! directory, engines by engine, model file and step — and a duplicate is an error naming
//! both spellings.

use super::plan::DatasetInfo;
use super::spec::{resolve, SweepSpec};
use super::SweepError;

use std::path::Path;

/// `Err` naming the first pair of equivalent values of an axis.
pub(super) fn refuse_equivalent(
    spec: &SweepSpec,
    spec_path: &Path,
    datasets: &[DatasetInfo],
) -> Result<(), SweepError> {
    let invalid = |message: String| SweepError::Invalid {
        path: spec_path.to_path_buf(),
        message,
    };
    // Settings by the load they put on the robot, as `eval --settings` compares them.
    let settings = &spec.settings;
    if let Some((a, b)) = first_pair(settings, |a, b| a.setting.same_load(&b.setting)) {
        let s = &settings[a].setting;
        return Err(invalid(format!(
            "`settings`: `{}` and `{}` are the same setting (force replay coefficient {}, push {} N{}): give it once",
            settings[a].spelled,
            settings[b].spelled,
            s.coefficient,
            s.push_n,
            s.push_heading_deg
                .map_or(String::new(), |d| format!(" at {d}°"))
        )));
    }
    let dirs: Vec<&Path> = datasets.iter().map(|d| d.dir.as_path()).collect();
    if let Some((a, b)) = first_pair(&dirs, |a, b| a == b) {
        return Err(invalid(format!(
            "`datasets`: `{}` and `{}` are the same directory ({}): give it once",
            spec.datasets[a],
            spec.datasets[b],
            dirs[a].display()
        )));
    }
    let base = spec_path.parent().unwrap_or(Path::new("/"));
    let engines: Vec<_> = spec
        .engines
        .iter()
        .map(|e| {
            let mjcf = e.mjcf.as_deref().map(|m| {
                let p = resolve(base, m);
                std::fs::canonicalize(&p).unwrap_or(p)
            });
            (e.engine.clone(), mjcf, e.physics_dt_s)
        })
        .collect();
    if let Some((a, b)) = first_pair(&engines, |a, b| a == b) {
        return Err(invalid(format!(
            "`[[engine]] #{}` and `[[engine]] #{}` are the same engine ({}): give it once",
            a + 1,
            b + 1,
            spec.engines[a].label()
        )));
    }
    let labels: Vec<String> = spec.engines.iter().map(|e| e.label()).collect();
    if let Some((a, b)) = first_pair(&labels, |a, b| a == b) {
        return Err(invalid(format!(
            "`[[engine]] #{}` and `[[engine]] #{}` have one label `{}`: give them distinct `name`s",
            a + 1,
            b + 1,
            labels[a]
        )));
    }
    Ok(())
}

/// The first `(i, j)`, `i < j`, of values that are `same`.
fn first_pair<T>(values: &[T], same: impl Fn(&T, &T) -> bool) -> Option<(usize, usize)> {
    (0..values.len()).find_map(|j| {
        (0..j)
            .find(|&i| same(&values[i], &values[j]))
            .map(|i| (i, j))
    })
}
