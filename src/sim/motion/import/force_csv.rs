//! Hand-force logs from force/torque sensors (CSV).
//!
//! Columns: time (s), fx, fy, fz (N) and optionally tx, ty, tz (N·m, ignored: the benchmark
//! applies forces at a point). A header such as `time,fx,fy,fz` or `timestamp,...` is
//! optional and recognised by its first row not being numbers. Sensors log at 100–1000 Hz
//! on their own clock, so [`ForceLog::resample`] brings a log onto the motion's frames.

use std::io::BufReader;
use std::path::Path;

use super::ImportError;

/// A recorded hand force over time, sensor frame.
#[derive(Debug, Clone, PartialEq)]
pub struct ForceLog {
    /// Sample times, s, strictly increasing (any origin, e.g. Unix time).
    pub time_s: Vec<f64>,
    /// Force at each sample, N, sensor frame.
    pub force_n: Vec<[f64; 3]>,
}

/// Reads a force log. Errors name the line as `row N` / `row N, column M` (1-based file
/// lines, header included, so an editor finds them); a sample beyond
/// [`super::bounds::MAX_HAND_FORCE_N`] is refused.
pub fn read_force_csv(path: &Path) -> Result<ForceLog, ImportError> {
    let bad = |field: String, reason: String| ImportError::BadField {
        path: path.to_path_buf(),
        field,
        reason,
    };
    let file = crate::files::bounded_read::open(path, "force log", super::MAX_IMPORT_BYTES)
        .map_err(|source| ImportError::Io {
            path: path.to_path_buf(),
            source,
        })?;
    // Headers are detected by hand; `flexible` lets a bad row reach our own message.
    let mut reader = csv::ReaderBuilder::new()
        .has_headers(false)
        .flexible(true)
        .trim(csv::Trim::All)
        .from_reader(BufReader::new(file));

    let mut log = ForceLog {
        time_s: Vec::new(),
        force_n: Vec::new(),
    };
    let mut record = csv::ByteRecord::new();
    let mut index = 0u64;
    let mut first = true;
    while let Some(line) = super::next_csv_row(&mut reader, &mut record, &mut index, path)? {
        let row = format!("row {line}");
        let parsed: Vec<Option<f64>> = record.iter().map(parse_number).collect();
        if std::mem::take(&mut first) && parsed.iter().any(Option::is_none) {
            // A header: it must at least have the four required columns.
            if record.len() < 4 {
                return Err(bad(
                    row,
                    format!("header has {} columns, need 4", record.len()),
                ));
            }
            continue;
        }
        if record.len() != 4 && record.len() != 7 {
            return Err(bad(
                row,
                format!(
                    "{} columns, expected 4 (t,fx,fy,fz) or 7 (+tx,ty,tz)",
                    record.len()
                ),
            ));
        }
        let mut values = [0.0f64; 4];
        for (col, slot) in values.iter_mut().enumerate() {
            *slot = parsed[col].filter(|v| v.is_finite()).ok_or_else(|| {
                let raw = String::from_utf8_lossy(&record[col]).into_owned();
                bad(
                    format!("{row}, column {}", col + 1),
                    format!("not a finite number: {raw:?}"),
                )
            })?;
        }
        if let Some(&prev) = log.time_s.last() {
            if values[0] <= prev {
                return Err(bad(
                    format!("{row}, column 1"),
                    format!("time {} s does not increase (previous {prev} s)", values[0]),
                ));
            }
        }
        let force_n = [values[1], values[2], values[3]];
        if let Some(why) = super::bounds::hand_force_problem(&force_n) {
            return Err(bad(format!("{row}, columns 2 to 4 (fx, fy, fz)"), why));
        }
        log.time_s.push(values[0]);
        log.force_n.push(force_n);
    }
    if log.time_s.is_empty() {
        return Err(ImportError::Format {
            path: path.to_path_buf(),
            format: "force CSV",
            reason: "no data rows".into(),
        });
    }
    Ok(log)
}

fn parse_number(raw: &[u8]) -> Option<f64> {
    std::str::from_utf8(raw).ok()?.parse().ok()
}

impl ForceLog {
    /// The force at each of `times_s` (motion clock) shifted by `offset_s` (log time = motion time + offset),
    /// linearly interpolated; zero outside the recorded span. Returns the values and the number of samples that fell outside.
    ///
    /// Zero, not the edge value, outside the span: a log that starts late or ends early
    /// means nobody was pushing then, and holding the last reading would invent a force.
    /// The count lets callers warn about a misaligned offset.
    pub fn resample(&self, times_s: &[f64], offset_s: f64) -> (Vec<[f64; 3]>, usize) {
        let mut outside = 0;
        let values = times_s
            .iter()
            .map(|&t| match self.at(t + offset_s) {
                Some(f) => f,
                None => {
                    outside += 1;
                    [0.0; 3]
                }
            })
            .collect();
        (values, outside)
    }

    /// The interpolated force at log time `t`, or None outside `[first, last]` (or NaN).
    fn at(&self, t: f64) -> Option<[f64; 3]> {
        let (&first, &last) = (self.time_s.first()?, self.time_s.last()?);
        if !(t >= first && t <= last) {
            return None;
        }
        // First sample strictly after t; at least 1 since t >= first (for a sorted log).
        let hi = self.time_s.partition_point(|&s| s <= t);
        if hi >= self.time_s.len() {
            return self.force_n.last().copied();
        }
        let lo = hi.checked_sub(1)?;
        let (t0, t1) = (self.time_s[lo], self.time_s[hi]);
        let (f0, f1) = (self.force_n.get(lo)?, self.force_n.get(hi)?);
        let w = (t - t0) / (t1 - t0);
        Some([0, 1, 2].map(|k| f0[k] + w * (f1[k] - f0[k])))
    }
}
