//! A dataset check for people (Markdown) and for programs (JSON), and the two files
//! `data check --out` writes.

use super::{CheckSummary, DatasetCheck};
use std::fmt::Write;
use std::path::{Path, PathBuf};

/// The Markdown file of a check in its output directory.
pub const CHECK_MARKDOWN: &str = "check.md";
/// The JSON file of a check in its output directory.
pub const CHECK_JSON: &str = "check.json";

/// A check did not pass its gate (`data check --max-outside`).
#[derive(Debug, thiserror::Error)]
pub enum CheckGateError {
    /// The gate is no share.
    #[error("`option.max_outside` is a share from 0 to 1, got {}", crate::files::names::short_number(*.0))]
    Share(f64),
    /// Tasks above it.
    #[error("stance frames with the CoP outside the support above `option.max_outside` {max_share}: {tasks}")]
    Over {
        /// The gate.
        max_share: f64,
        /// Each task over it, with its share.
        tasks: String,
    },
}

impl CheckGateError {
    /// Refuses a gate that is no share from 0 to 1 (NaN, −1, 2, 1e300), so a command can
    /// refuse it before the check runs or writes anything.
    pub fn check_share(max_share: f64) -> Result<(), Self> {
        if (0.0..=1.0).contains(&max_share) {
            Ok(())
        } else {
            Err(Self::Share(max_share))
        }
    }
}

/// Writing a check's files failed.
#[derive(Debug, thiserror::Error)]
#[error("writing {path}: {source}")]
pub struct CheckWriteError {
    /// The file.
    pub path: PathBuf,
    /// What failed.
    pub source: std::io::Error,
}

fn pct(x: f64) -> String {
    format!("{:.1} %", 100.0 * x)
}

fn balance_table(s: &mut String, rows: &[&CheckSummary], name: &str) {
    let _ = writeln!(
        s,
        "| {name} | frames | stance | outside > tol (force / none) | p95 outside, mm (force / none) | pulling (force / none) | friction p95 (force) | over μ (force) | CoM–CoP p95, mm (force) |"
    );
    let _ = writeln!(s, "|---|---:|---:|---:|---:|---:|---:|---:|---:|");
    for r in rows {
        let (w, o) = (&r.with_force, &r.without_force);
        let label = r.sequence_id.as_deref().unwrap_or(&r.task);
        let _ = writeln!(
            s,
            "| {label} | {} | {} | {} / {} | {:.0} / {:.0} | {} / {} | {:.2} | {} | {:.0} |",
            r.frames,
            w.stance_frames,
            pct(w.outside_share),
            pct(o.outside_share),
            w.outside_p95_mm,
            o.outside_p95_mm,
            pct(w.pulling_share),
            pct(o.pulling_share),
            w.friction_ratio_p95,
            pct(w.friction_over_share),
            w.com_cop_p95_mm,
        );
    }
}

impl DatasetCheck {
    /// The per-task tables (balance, kinematics, force levels, style) as Markdown; with
    /// `per_sequence`, a balance table per task follows with one row per sequence.
    pub fn markdown(&self, per_sequence: bool) -> String {
        let mut s = String::new();
        let o = &self.options;
        let _ = writeln!(
            s,
            "# Data check: {}\n\ndataset sha256 {}, robot {}; low-pass {} Hz (zero phase), contact within {} mm of the ground, outside tolerance {} mm, friction μ = {}\n",
            self.dataset,
            &self.dataset_sha256[..16.min(self.dataset_sha256.len())],
            self.robot,
            o.cutoff_hz,
            1e3 * o.contact_height_m,
            1e3 * o.outside_tolerance_m,
            o.friction
        );
        let _ = writeln!(
            s,
            "## Balance: the ground's centre of pressure against the support\n"
        );
        balance_table(&mut s, &self.tasks.iter().collect::<Vec<_>>(), "task");
        let _ = writeln!(s, "\n## Kinematics\n");
        let _ = writeln!(
            s,
            "| task | contact share | pelvis outside BoS, mean mm | root jerk, mean m/s³ | skate p95, m/s | penetration max, mm | limit margin, rad |"
        );
        let _ = writeln!(s, "|---|---:|---:|---:|---:|---:|---:|");
        for t in &self.tasks {
            let k = &t.kinematics;
            let _ = writeln!(
                s,
                "| {} | {} | {:.1} | {:.1} | {:.3} | {:.1} | {:.3} |",
                t.task,
                pct(k.contact_share),
                k.pelvis_outside_mean_mm,
                k.root_jerk_mean_m_s3,
                k.skate_p95_m_s,
                k.penetration_max_mm,
                k.limit_margin_rad
            );
        }
        let _ = writeln!(s, "\n## Recorded hand forces\n");
        let _ = writeln!(
            s,
            "| task | loaded share | mean while loaded, N | p95 while loaded, N | peak, N | both hands: mean while loaded, N | both hands: peak, N |"
        );
        let _ = writeln!(s, "|---|---:|---:|---:|---:|---:|---:|");
        for t in &self.tasks {
            let f = &t.forces;
            let _ = writeln!(
                s,
                "| {} | {} | {:.1} | {:.1} | {:.1} | {:.1} | {:.1} |",
                t.task,
                pct(f.loaded_share),
                f.loaded_mean_n,
                f.loaded_p95_n,
                f.peak_n,
                f.both_loaded_mean_n,
                f.both_peak_n
            );
        }
        s.push_str(&super::style::markdown(&self.styles));
        if let Some(tracker) = &self.tracker {
            let tasks: Vec<&str> = self.tasks.iter().map(|t| t.task.as_str()).collect();
            s.push_str(&tracker.markdown(&tasks));
        }
        if per_sequence {
            for t in &self.tasks {
                let _ = writeln!(s, "\n## {} by sequence\n", t.task);
                let rows: Vec<&CheckSummary> =
                    self.sequences.iter().filter(|q| q.task == t.task).collect();
                balance_table(&mut s, &rows, "sequence");
            }
        }
        s
    }

    /// Tasks whose share of stance frames outside, with force or without, is above
    /// `max_share`.
    pub fn tasks_over(&self, max_share: f64) -> Vec<&CheckSummary> {
        self.tasks
            .iter()
            .filter(|t| t.worst_outside_share() > max_share)
            .collect()
    }

    /// Passes when no task's share of stance frames outside (with force or without) is
    /// above `max_share` (0 to 1); else the error names each task over it.
    pub fn gate(&self, max_share: f64) -> Result<(), CheckGateError> {
        CheckGateError::check_share(max_share)?;
        let over: Vec<String> = self
            .tasks_over(max_share)
            .iter()
            .map(|t| format!("{} {:.1} %", t.task, 100.0 * t.worst_outside_share()))
            .collect();
        if over.is_empty() {
            Ok(())
        } else {
            Err(CheckGateError::Over {
                max_share,
                tasks: over.join(", "),
            })
        }
    }

    /// Writes [`CHECK_MARKDOWN`] (with the per-sequence tables) and [`CHECK_JSON`] into
    /// `dir` (created if missing), each whole or not at all.
    pub fn write(&self, dir: &Path) -> Result<(), CheckWriteError> {
        let fail = |path: PathBuf| move |source| CheckWriteError { path, source };
        std::fs::create_dir_all(dir).map_err(fail(dir.to_path_buf()))?;
        let json = serde_json::to_string_pretty(self).expect("a check serialises");
        for (name, text) in [(CHECK_MARKDOWN, self.markdown(true)), (CHECK_JSON, json)] {
            let path = dir.join(name);
            crate::files::atomic_file::write(&path, text).map_err(fail(path.clone()))?;
        }
        Ok(())
    }
}
