//! Teleoperation glitches: root positions that jump farther between two consecutive frames
//! than a human can move, and which of them can be repaired by trimming.
//!
//! Teleoperation recordings (TWIST2's PICO walks among them) can start or end with a few
//! frames captured before the tracker locked onto the operator: the root sits metres away
//! from where the motion continues. Imported as they are, a tracking policy is asked to
//! teleport and "falls" at step 0. The importers refuse such files unless the user asks for
//! the repair (`--trim-glitches`), and `data info` reports them in existing datasets.
//!
//! # The rule
//!
//! A *jump* at frame `k` (`k ≥ 1`) is a step `k-1 → k` whose root displacement implies a
//! speed above [`MAX_HUMAN_ROOT_SPEED_M_PER_S`]. With `W` = [`EDGE_GLITCH_WINDOW_S`] ×
//! fps frames (at least 1) and `T` frames:
//!
//! - *leading glitch frames* are frames `0 .. L`, where `L` is the last jump with `L ≤ W`
//!   (none: `L = 0`). Every frame before the last early jump is dropped, so two teleported
//!   frames at different places (jumps at 1 and 2) and two at the same place (a jump at 2
//!   only) both lose exactly frames 0 and 1;
//! - *trailing glitch frames* are frames `R .. T`, where `R` is the first jump after `L`
//!   with `T - R ≤ W` (none: `R = T`);
//! - any other jump (`L < k < R`) is *interior*: real motion lies on both sides of it, and
//!   cutting there would discard more than a start-up artefact, so it is never repaired.
//!
//! Trimming keeps frames `L .. R`, in which no jump remains. It is only offered when no
//! interior jump exists and at least two frames remain.
use crate::files::log_text::short_number;

/// Largest root speed between consecutive frames a human motion can have, m/s.
///
/// A sprinter's pelvis peaks at about 10–12 m/s and a walk stays within 1–3 m/s, while the
/// teleoperation glitches in TWIST2's walks move the root 1.4–3.2 m in one 30 fps frame
/// (40–100 m/s). 10 m/s sits a factor of 3 above walking and 4 below the smallest glitch;
/// a genuine sprint at its peak could come close, so the check errs towards accepting.
/// Measured as the 3-D displacement (a vertical teleport is as wrong as a horizontal one).
pub const MAX_HUMAN_ROOT_SPEED_M_PER_S: f64 = 10.0;

/// How close to the start or end of a motion a jump must lie to count as a leading or
/// trailing teleoperation glitch, s.
///
/// The glitches seen are the tracker's first one or two samples (33–67 ms at 30 fps);
/// 0.5 s leaves room for a slower lock-on while anything farther in is real motion, whose
/// loss the user must decide about rather than have it trimmed away.
pub const EDGE_GLITCH_WINDOW_S: f64 = 0.5;

/// One implausible root step between consecutive frames.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct RootJump {
    /// The later frame of the step: the jump is from frame `frame - 1` to `frame`.
    pub frame: usize,
    /// Root displacement over the step, world frame, m.
    pub distance_m: f64,
    /// `distance_m` × fps, m/s.
    pub speed_m_per_s: f64,
}

/// `v` to `decimals` places, or short when it is huge (a 1e30 m jump is not 31 digits).
fn fixed(v: f64, decimals: usize) -> String {
    if v.abs() < 1e6 {
        format!("{v:.decimals$}")
    } else {
        short_number(v)
    }
}

impl std::fmt::Display for RootJump {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "frame {}→{}: {} m ({} m/s)",
            self.frame - 1,
            self.frame,
            fixed(self.distance_m, 2),
            fixed(self.speed_m_per_s, 1)
        )
    }
}

/// What [`scan_root_glitches`] found in one root trajectory.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct GlitchScan {
    /// Every implausible step, in frame order.
    pub jumps: Vec<RootJump>,
    /// Frames at the start that trimming would drop (`0 .. leading_frames`).
    pub leading_frames: usize,
    /// Frames at the end that trimming would drop.
    pub trailing_frames: usize,
    /// Jumps with real motion on both sides: trimming cannot repair them.
    pub interior: Vec<RootJump>,
    /// Frames of the trajectory.
    pub frames: usize,
}

impl GlitchScan {
    /// No implausible step at all.
    pub fn is_clean(&self) -> bool {
        self.jumps.is_empty()
    }

    /// Trimming the leading and trailing glitch frames leaves a glitch-free motion of at
    /// least two frames.
    pub fn is_trimmable(&self) -> bool {
        self.interior.is_empty() && self.kept_frames() >= 2
    }

    /// Frames left after trimming.
    pub fn kept_frames(&self) -> usize {
        self.frames
            .saturating_sub(self.leading_frames + self.trailing_frames)
    }

    /// One line for people: "none", or the jumps and what trimming would do.
    pub fn summary(&self) -> String {
        if self.is_clean() {
            return "none".into();
        }
        let jumps: Vec<String> = self.jumps.iter().map(|j| j.to_string()).collect();
        let verdict = if self.is_trimmable() {
            format!(
                "leading {} and trailing {} glitch frame(s)",
                self.leading_frames, self.trailing_frames
            )
        } else if self.interior.is_empty() {
            format!(
                "fewer than 2 of {} frames would remain after trimming",
                self.frames
            )
        } else {
            let at: Vec<String> = self.interior.iter().map(|j| j.frame.to_string()).collect();
            format!("interior jump(s) at frame {}", at.join(", "))
        };
        format!("{}; {verdict}", jumps.join(", "))
    }
}

/// The implausible root steps of a trajectory sampled at `fps`, classified by the module's
/// rule. Non-finite positions produce no jumps (sequence validation rejects them).
pub fn scan_root_glitches(root_pos_m: &[[f64; 3]], fps: f64) -> GlitchScan {
    let frames = root_pos_m.len();
    let jumps: Vec<RootJump> = root_pos_m
        .windows(2)
        .enumerate()
        .filter_map(|(i, w)| {
            let d = w[1]
                .iter()
                .zip(&w[0])
                .map(|(a, b)| (a - b) * (a - b))
                .sum::<f64>()
                .sqrt();
            let speed = d * fps;
            (speed > MAX_HUMAN_ROOT_SPEED_M_PER_S).then_some(RootJump {
                frame: i + 1,
                distance_m: d,
                speed_m_per_s: speed,
            })
        })
        .collect();
    // At least one frame, so a 1 Hz motion can still lose its first sample.
    let window = ((EDGE_GLITCH_WINDOW_S * fps).floor() as usize).max(1);
    let first_kept = jumps
        .iter()
        .map(|j| j.frame)
        .filter(|&k| k <= window)
        .max()
        .unwrap_or(0);
    let end_kept = jumps
        .iter()
        .map(|j| j.frame)
        .filter(|&k| k > first_kept && frames - k <= window)
        .min()
        .unwrap_or(frames);
    let interior = jumps
        .iter()
        .filter(|j| j.frame > first_kept && j.frame < end_kept)
        .copied()
        .collect();
    GlitchScan {
        jumps,
        leading_frames: first_kept,
        trailing_frames: frames - end_kept,
        interior,
        frames,
    }
}

/// What `--trim-glitches` cut from an imported motion, as its provenance records it under
/// [`TrimmedGlitches::KEY`]: read back typed, never by string keys.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct TrimmedGlitches {
    /// Frames dropped at the start: frame 0 of the sequence is this source frame.
    pub leading: usize,
    /// Frames dropped at the end.
    pub trailing: usize,
    /// Frames of the source motion.
    pub source_frames: usize,
    /// The jumps found, in source frames.
    pub root_jumps: Vec<RootJump>,
    /// How to read the frame numbers.
    pub note: String,
}

impl TrimmedGlitches {
    /// Its key in a sequence's provenance.
    pub const KEY: &'static str = "trimmed_glitch_frames";

    /// The record of a scan whose edge glitches were trimmed.
    pub fn of(scan: &GlitchScan) -> Self {
        Self {
            leading: scan.leading_frames,
            trailing: scan.trailing_frames,
            source_frames: scan.frames,
            root_jumps: scan.jumps.clone(),
            note: "frame 0 of this sequence is source frame `leading`; forces are resampled on the source clock".into(),
        }
    }

    /// The record in `provenance`, if the import trimmed anything (an unreadable record is
    /// reported as absent rather than guessed at).
    pub fn in_provenance(provenance: &serde_json::Value) -> Option<Self> {
        serde_json::from_value(provenance.get(Self::KEY)?.clone()).ok()
    }

    /// "2 leading, 0 trailing of 45 (root jumps 0→1 3.20 m, 1→2 2.90 m)".
    pub fn summary(&self) -> String {
        let jumps: Vec<String> = self
            .root_jumps
            .iter()
            .map(|j| {
                format!(
                    "{}→{} {:.2} m",
                    j.frame.saturating_sub(1),
                    j.frame,
                    j.distance_m
                )
            })
            .collect();
        format!(
            "{} leading, {} trailing of {} (root jumps {})",
            self.leading,
            self.trailing,
            self.source_frames,
            jumps.join(", ")
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 30 fps walk along +x at 1.2 m/s, 60 frames.
    fn walk() -> Vec<[f64; 3]> {
        (0..60)
            .map(|k| [1.2 * k as f64 / 30.0, 0.0, 0.78])
            .collect()
    }

    #[test]
    fn a_clean_walk_has_no_jumps() {
        let s = scan_root_glitches(&walk(), 30.0);
        assert!(s.is_clean() && s.is_trimmable());
        assert_eq!(
            (s.leading_frames, s.trailing_frames, s.kept_frames()),
            (0, 0, 60)
        );
        assert_eq!(s.summary(), "none");
    }

    #[test]
    fn two_teleported_leading_frames_are_both_dropped() {
        // At two different places: jumps 0→1 and 1→2.
        let mut p = walk();
        p[0] = [2.5, 1.0, 0.8];
        p[1] = [-1.0, 2.0, 0.8];
        let s = scan_root_glitches(&p, 30.0);
        let frames: Vec<usize> = s.jumps.iter().map(|j| j.frame).collect();
        assert_eq!(frames, [1, 2]);
        assert_eq!((s.leading_frames, s.trailing_frames), (2, 0));
        assert!(s.is_trimmable());
        // At the same place: only the jump 1→2, still two frames to drop.
        let mut p = walk();
        p[0] = [3.0, 0.0, 0.8];
        p[1] = [3.0, 0.0, 0.8];
        let s = scan_root_glitches(&p, 30.0);
        assert_eq!(s.jumps.len(), 1);
        assert_eq!((s.leading_frames, s.trailing_frames), (2, 0));
    }

    #[test]
    fn a_trailing_glitch_frame_is_dropped() {
        let mut p = walk();
        p[59] = [0.0, -2.0, 0.8];
        let s = scan_root_glitches(&p, 30.0);
        assert_eq!((s.leading_frames, s.trailing_frames), (0, 1));
        assert!(s.is_trimmable() && s.interior.is_empty());
        assert_eq!(s.kept_frames(), 59);
    }

    #[test]
    fn an_interior_jump_is_not_trimmable() {
        let mut p = walk();
        p[30] = [5.0, 0.0, 0.8];
        let s = scan_root_glitches(&p, 30.0);
        let interior: Vec<usize> = s.interior.iter().map(|j| j.frame).collect();
        assert_eq!(interior, [30, 31]);
        assert!(!s.is_trimmable());
        assert!(s.summary().contains("interior jump(s) at frame 30, 31"));
    }

    #[test]
    fn jump_sizes_and_speeds_are_reported() {
        let mut p = walk();
        p[0] = [p[1][0] - 2.0, 0.0, 0.78];
        let s = scan_root_glitches(&p, 30.0);
        let j = s.jumps[0];
        assert_eq!(j.frame, 1);
        assert!((j.distance_m - 2.0).abs() < 1e-12);
        assert!((j.speed_m_per_s - 60.0).abs() < 1e-9);
        assert_eq!(j.to_string(), "frame 0→1: 2.00 m (60.0 m/s)");
    }
}
