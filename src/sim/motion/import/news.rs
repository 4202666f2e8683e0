//! What an import says while it works, as text for whoever shows it: per motion file the
//! glitch frames trimmed and where its soles stood, then the sequence it became.

use super::ImportObserver;
use crate::sim::motion::{GroundCheck, Sequence, TrimmedGlitches};
use std::path::Path;

/// An import's news as lines handed to `say`: each file's name, what its conversion
/// found (indented), and the sequence it became.
pub struct ImportLines<'a> {
    /// Where the lines go.
    pub say: &'a mut dyn FnMut(&str),
}

impl ImportObserver for ImportLines<'_> {
    fn reading(&mut self, input: &Path) {
        (self.say)(&format!("{}:", input.display()));
    }

    fn converted(&mut self, _input: &Path, seq: &Sequence, ground: Option<&GroundCheck>) {
        for line in converted_lines(seq, ground) {
            (self.say)(&format!("  {line}"));
        }
    }

    fn imported(&mut self, input: &Path, seq: &Sequence) {
        (self.say)(&imported_line(input, seq));
    }
}

/// The lines about a converted motion: glitch frames trimmed, frames a force log does
/// not cover, the ground check.
pub fn converted_lines(seq: &Sequence, ground: Option<&GroundCheck>) -> Vec<String> {
    let mut lines = Vec::new();
    if let Some(trim) = TrimmedGlitches::in_provenance(&seq.provenance) {
        lines.push(format!("trimmed glitch frames: {}", trim.summary()));
    }
    for (side, key) in [
        ("left", "left_force_frames_outside_log"),
        ("right", "right_force_frames_outside_log"),
    ] {
        if let Some(outside) = seq.provenance.get(key).and_then(|v| v.as_u64()) {
            lines.push(format!(
                "note: the {side} force log covers {} of the motion's {} frames; the other {outside} replay no force (check `option.force_offset` if the log should cover them)",
                (seq.n_frames() as u64).saturating_sub(outside),
                seq.n_frames()
            ));
        }
    }
    if let Some(g) = ground {
        lines.push(format!(
            "ground check: median lowest sole point {:+.1} mm, lowest {:+.1} mm",
            1e3 * g.offset_m,
            1e3 * g.min_m
        ));
    }
    lines
}

/// The line of a motion file written into the dataset as `seq`.
pub fn imported_line(input: &Path, seq: &Sequence) -> String {
    format!(
        "imported {} → {}/{} ({} frames at {} fps, {:.1} s{})",
        input.display(),
        seq.task,
        seq.sequence_id,
        seq.n_frames(),
        fps_text(seq.fps),
        seq.duration_s(),
        if seq.forces_recorded {
            ", with force logs"
        } else {
            ", no force logs"
        }
    )
}

/// A frame rate as people write it: `30`, `29.97`, `59.94`.
pub fn fps_text(fps: f64) -> String {
    let text = format!("{fps:.2}");
    text.trim_end_matches('0').trim_end_matches('.').to_string()
}

#[cfg(test)]
mod tests {
    #[test]
    fn frame_rates_read_as_written() {
        assert_eq!(super::fps_text(30.0), "30");
        assert_eq!(super::fps_text(29.97), "29.97");
        assert_eq!(super::fps_text(59.5), "59.5");
    }
}
