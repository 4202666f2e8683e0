//! What a dataset holds, per task (`thorarena data info`): sequences, total duration,
//! force logs, percentiles of the total hand force, the smallest joint-limit margin, the
//! largest ground offset, and any teleoperation glitches left in the roots.

use super::{
    ground_check, scan_root_glitches, Dataset, GlitchScan, Sequence, MAX_HUMAN_ROOT_SPEED_M_PER_S,
};
use crate::eval::metrics::percentile;
use crate::sim::robot::RobotModel;

/// "1 sequence", "3 sequences".
pub fn plural(n: usize, noun: &str) -> String {
    if n == 1 {
        format!("1 {noun}")
    } else {
        format!("{n} {noun}s")
    }
}

/// The table `data info` prints.
pub fn describe(ds: &Dataset, seqs: &[Sequence], robot: &RobotModel) -> String {
    use std::fmt::Write;
    let mut s = String::new();
    let _ = writeln!(
        s,
        "dataset {} ({}, robot {}, content sha256 {})",
        ds.dir.display(),
        plural(seqs.len(), "sequence"),
        ds.manifest.robot,
        &ds.content_hash()[..16]
    );
    let _ = writeln!(
        s,
        "{:<16} {:>5} {:>10} {:>11} {:>9} {:>9} {:>9} {:>12}",
        "task", "seqs", "duration", "force logs", "F p33", "F p66", "F max", "limit margin"
    );
    let _ = writeln!(
        s,
        "{:<16} {:>5} {:>10} {:>11} {:>9} {:>9} {:>9} {:>12}",
        "", "", "s", "seqs", "N", "N", "N", "rad"
    );
    // Tasks in order of first appearance, each once (a manifest need not be grouped).
    let mut tasks: Vec<&str> = Vec::new();
    for q in seqs {
        if !tasks.contains(&q.task.as_str()) {
            tasks.push(q.task.as_str());
        }
    }
    for task in tasks {
        let group: Vec<&Sequence> = seqs.iter().filter(|q| q.task == task).collect();
        let duration: f64 = group.iter().map(|q| q.duration_s()).sum();
        let mut total: Vec<f64> = group.iter().flat_map(|q| total_hand_force(q)).collect();
        total.sort_by(f64::total_cmp);
        let margin = group
            .iter()
            .map(|q| joint_limit_margin(q, robot))
            .fold(f64::INFINITY, f64::min);
        // The largest per-sequence ground offset, signed.
        let ground = group
            .iter()
            .filter_map(|q| ground_check(robot, q))
            .map(|g| g.offset_m)
            .fold(0.0f64, |a, b| if b.abs() > a.abs() { b } else { a });
        let _ = writeln!(
            s,
            "{:<16} {:>5} {:>10.1} {:>11} {:>9.1} {:>9.1} {:>9.1} {:>12.3} {:>12.1}",
            task,
            group.len(),
            duration,
            group.iter().filter(|q| q.forces_recorded).count(),
            percentile(&total, 33.0),
            percentile(&total, 66.0),
            total.last().copied().unwrap_or(0.0),
            margin,
            1e3 * ground
        );
    }
    let logged = seqs.iter().filter(|q| q.forces_recorded).count();
    if logged < seqs.len() {
        let _ = writeln!(
            s,
            "{} of {} sequences have no force logs (imported without force logs; their forces are zero){}",
            seqs.len() - logged,
            seqs.len(),
            if logged == 0 {
                ": `eval` runs them under no-force only, unless `request.replay_without_force_logs`"
            } else {
                ": under a replay setting they run as if no-force"
            }
        );
    }
    // Datasets written before import checked for glitches (or by other tools) may hold
    // them, so they are looked for here rather than assumed absent.
    let glitched: Vec<(&Sequence, GlitchScan)> = seqs
        .iter()
        .map(|q| (q, scan_root_glitches(&q.root_pos, q.fps)))
        .filter(|(_, g)| !g.is_clean())
        .collect();
    let heading = format!(
        "root glitches (root speed above {MAX_HUMAN_ROOT_SPEED_M_PER_S} m/s between consecutive frames):"
    );
    if glitched.is_empty() {
        let _ = writeln!(s, "{heading} none");
    } else {
        let _ = writeln!(s, "{heading} {} sequence(s)", glitched.len());
        for (q, g) in glitched {
            let _ = writeln!(s, "  {}/{}: {}", q.task, q.sequence_id, g.summary());
        }
    }
    s
}

/// `|F_left| + |F_right|` per frame, N.
pub fn total_hand_force(seq: &Sequence) -> impl Iterator<Item = f64> + '_ {
    let norm = |f: &[f64; 3]| (f[0] * f[0] + f[1] * f[1] + f[2] * f[2]).sqrt();
    seq.force_sensor[0]
        .iter()
        .zip(&seq.force_sensor[1])
        .map(move |(l, r)| norm(l) + norm(r))
}

/// Smallest distance of any joint to its limits over the sequence (negative: outside), rad.
pub fn joint_limit_margin(seq: &Sequence, robot: &RobotModel) -> f64 {
    let limits: Vec<(f64, f64)> = seq
        .joint_names
        .iter()
        .map(|n| {
            robot
                .joint_index(n)
                .map_or((f64::NEG_INFINITY, f64::INFINITY), |j| {
                    (robot.joints[j].lower_rad, robot.joints[j].upper_rad)
                })
        })
        .collect();
    seq.joint_pos
        .iter()
        .flat_map(|row| {
            row.iter()
                .zip(&limits)
                .map(|(q, (lo, hi))| (q - lo).min(hi - q))
        })
        .fold(f64::INFINITY, f64::min)
}
