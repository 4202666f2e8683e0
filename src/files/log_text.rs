//! Text that came from a policy or a file, made safe to store and to print: a policy's
//! output can be a 100 MB line or hold terminal escape sequences (`ESC ]0;…` retitles
//! the terminal, `ESC [2J` clears it), and `sweep status` prints it back.

use std::io::{Read, Seek, SeekFrom};
use std::path::Path;

/// Most bytes kept of one log line (longer lines are cut, marked `…`).
pub const LOG_LINE_MAX_BYTES: usize = 4 * 1024;
/// Most bytes of a log tail in all (whole lines, the last ones).
pub const LOG_TAIL_MAX_BYTES: usize = 16 * 1024;
/// Bytes read from the end of a log to find its last lines: the tail can hold no more.
const LOG_READ_MAX_BYTES: u64 = 64 * 1024;

/// `s` with every control character (C0, DEL, C1) written as an escape (`\n`, `\u{1b}`),
/// so printing it cannot move the cursor, retitle or clear a terminal.
pub fn printable(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for c in s.chars() {
        if c.is_control() {
            out.extend(c.escape_default());
        } else {
            out.push(c);
        }
    }
    out
}

/// `s` as [`printable`] makes it, but for its line breaks and tabs, which a message of
/// several lines keeps: what the terminal shows of an error quoting outside names.
pub fn printable_lines(s: &str) -> String {
    s.split('\n')
        .map(|line| {
            line.split('\t')
                .map(printable)
                .collect::<Vec<_>>()
                .join("\t")
        })
        .collect::<Vec<_>>()
        .join("\n")
}

/// `v` as a message shows it: as Rust writes it when that is short (`0.25`, `1000`), to
/// six decimals when it is of a moderate size (`3.141593`), else in exponent form (`1e308`,
/// not its three hundred digits).
pub fn short_number(v: f64) -> String {
    let trimmed = |digits: &str| {
        digits
            .trim_end_matches('0')
            .trim_end_matches('.')
            .to_string()
    };
    let text = format!("{v}");
    if text.len() <= 12 {
        text
    } else if (1e-3..1e6).contains(&v.abs()) {
        trimmed(&format!("{v:.6}"))
    } else {
        let text = format!("{v:.6e}");
        let (mantissa, exponent) = text.split_once('e').unwrap_or((&text, "0"));
        format!("{}e{exponent}", trimmed(mantissa))
    }
}

/// The error and its causes joined by `: `, each cause once: a typed error names its
/// cause in its own message (`{path}: {source}`), which walking the chain (as anyhow's
/// `{:#}` does) would print a second time ("it is a directory, not a file: it is a
/// directory, not a file").
pub fn causes_once(e: &(dyn std::error::Error + 'static)) -> String {
    let mut text = String::new();
    let mut cause = Some(e);
    while let Some(c) = cause {
        let said = c.to_string();
        if !text.contains(&said) {
            if !text.is_empty() {
                text += ": ";
            }
            text += &said;
        }
        cause = c.source();
    }
    text
}

/// `s` cut to at most `max` bytes on a character boundary, `…` marking a cut.
pub fn truncated(s: &str, max: usize) -> String {
    if s.len() <= max {
        return s.to_string();
    }
    let mut end = max.saturating_sub('…'.len_utf8());
    while !s.is_char_boundary(end) {
        end -= 1;
    }
    format!("{}…", &s[..end])
}

/// Creates (or empties) the log file of a process a run starts — a task's policy, a
/// leaderboard's policy process — its directory first; [`log_tail`] quotes it back when
/// the process fails.
pub fn create_log(path: &std::path::Path) -> std::io::Result<std::fs::File> {
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir)?;
    }
    crate::files::no_follow::create(path)
}

/// The last `n` non-empty lines of a log file, each printable and at most
/// [`LOG_LINE_MAX_BYTES`], together at most [`LOG_TAIL_MAX_BYTES`]; only the file's last
/// 64 KiB are read, however large it is. A line rewritten with `\r` (a progress bar)
/// counts as its last state.
pub fn log_tail(path: &Path, n: usize) -> Vec<String> {
    let Ok(mut f) = std::fs::File::open(path) else {
        return Vec::new();
    };
    let len = f.metadata().map_or(0, |m| m.len());
    let start = len.saturating_sub(LOG_READ_MAX_BYTES);
    let mut bytes = Vec::new();
    if f.seek(SeekFrom::Start(start)).is_err()
        || f.take(LOG_READ_MAX_BYTES).read_to_end(&mut bytes).is_err()
    {
        return Vec::new();
    }
    let text = String::from_utf8_lossy(&bytes);
    let mut lines: Vec<String> = text
        .split('\n')
        .map(|l| l.rsplit('\r').next().unwrap_or("").trim_end())
        .filter(|l| !l.is_empty())
        .map(|l| truncated(&printable(l), LOG_LINE_MAX_BYTES))
        .collect();
    lines.drain(..lines.len().saturating_sub(n));
    let mut total = 0;
    let keep = lines
        .iter()
        .rev()
        .take_while(|l| {
            total += l.len();
            total <= LOG_TAIL_MAX_BYTES
        })
        .count();
    lines.split_off(lines.len() - keep)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn control_characters_are_escaped_and_text_kept() {
        assert_eq!(printable("a\u{1b}]0;t\u{7}b\n"), "a\\u{1b}]0;t\\u{7}b\\n");
        assert_eq!(printable("é ok"), "é ok");
    }

    #[test]
    fn numbers_are_shown_short() {
        for (v, shown) in [
            (0.25, "0.25"),
            (1000.0, "1000"),
            (std::f64::consts::PI, "3.141593"),
            (1e308, "1e308"),
            (-1.5e-300, "-1.5e-300"),
            (1e30, "1e30"),
        ] {
            assert_eq!(short_number(v), shown);
        }
    }

    #[test]
    fn cuts_respect_characters() {
        assert_eq!(truncated("abc", 3), "abc");
        let cut = truncated(&"é".repeat(10), 8);
        assert!(cut.len() <= 8 && cut.ends_with('…'), "{cut}");
    }
}
