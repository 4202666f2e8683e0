//! Names that come from outside (a policy process's self-declared name, `--task`, task and
//! sequence ids of a manifest) and become file or directory names. Each is checked before
//! it touches a path, so no input can write outside the directory it was meant for.
//!
//! Beside them, the text cells of every CSV the library writes (`csv_text`): a cell a
//! spreadsheet would read as a formula is written with a leading `'`; and a user's number
//! echoed in a message (`short_number`): `1e300`, never three hundred digits.

/// `x` as a message echoes it, in a few characters: exponent form outside 0.001 to 10⁶.
pub fn short_number(x: f64) -> String {
    let a = x.abs();
    if a != 0.0 && a.is_finite() && !(1e-3..1e6).contains(&a) {
        format!("{x:e}")
    } else {
        format!("{x}")
    }
}

/// A name that cannot be used as one path component.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error(
    "{what} `{value}` cannot become a file name: {why} (use letters, digits and `._+:=@-`, \
     at most {MAX_LEN} characters, not starting with `.`)"
)]
pub struct NameError {
    /// What the name is (`task`, `policy name`, …).
    pub what: String,
    /// The name as given (control characters escaped).
    pub value: String,
    /// Which rule it breaks.
    pub why: &'static str,
}

/// Longest accepted name, in bytes.
pub const MAX_LEN: usize = 128;

/// Checks that `value` is a plain file name: not empty, at most [`MAX_LEN`] bytes, only
/// ASCII letters, digits and `._+:=@-`, not starting with `.` (so neither `.`, `..` nor a
/// hidden file). Separators, whitespace and control characters are refused.
pub fn check_name(what: &str, value: &str) -> Result<(), NameError> {
    let why = if value.is_empty() {
        Some("it is empty")
    } else if value.len() > MAX_LEN {
        Some("it is too long")
    } else if value.contains('/') || value.contains('\\') {
        Some("it contains a path separator")
    } else if value.starts_with('.') {
        Some("it starts with `.`")
    } else if !value
        .chars()
        .all(|c| c.is_ascii_alphanumeric() || "._+:=@-".contains(c))
    {
        Some("it contains a character outside the plain set")
    } else {
        None
    };
    match why {
        None => Ok(()),
        Some(why) => Err(NameError {
            what: what.to_string(),
            value: value.escape_debug().to_string(),
            why,
        }),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn plain_names_pass_and_hostile_ones_are_refused() {
        for ok in [
            "clean_table",
            "clean_table_000",
            "push-30",
            "coef-0.5",
            "twist2:v2",
            "a",
        ] {
            assert_eq!(check_name("task", ok), Ok(()), "{ok}");
        }
        for (bad, why) in [
            ("", "empty"),
            ("..", "starts with `.`"),
            (".hidden", "starts with `.`"),
            ("../../x", "path separator"),
            ("/etc/passwd", "path separator"),
            ("a\\b", "path separator"),
            ("a b", "plain set"),
            ("tab\there", "plain set"),
            ("nul\0", "plain set"),
            ("ünïcode", "plain set"),
        ] {
            let e = check_name("task", bad).unwrap_err();
            assert!(e.why.contains(why), "{bad:?}: {}", e.why);
            assert!(e.to_string().starts_with("task `"), "{e}");
        }
        assert!(check_name("task", &"x".repeat(MAX_LEN + 1)).is_err());
    }
}

/// Text cells of the CSV files ThorArena writes (`episodes.csv`, a report's `-fats.csv`,
/// a sweep's `results.csv`, `crosscheck.csv`), safe to open in a spreadsheet: a cell that
/// begins with `=`, `+`, `-`, `@`, a tab or a carriage return would be read as a formula
/// (`=HYPERLINK(…)` as a policy name, `=1+2` as a sequence id: both are plain names), so it
/// is written with a leading `'`, which spreadsheets show as text and this module's
/// reader removes again. Numbers are written as numbers and never pass through here.
pub mod csv_text {
    use serde::{Deserialize, Deserializer, Serializer};

    /// Whether a spreadsheet would read `text` as a formula.
    fn formula_like(text: &str) -> bool {
        text.starts_with(['=', '+', '-', '@', '\t', '\r'])
    }

    /// `text` as a cell: with a leading `'` when it would read as a formula.
    pub fn cell(text: &str) -> std::borrow::Cow<'_, str> {
        if formula_like(text) {
            format!("'{text}").into()
        } else {
            text.into()
        }
    }

    /// For `#[serde(with = "crate::files::names::csv_text")]` on a `String` field.
    pub fn serialize<S: Serializer>(text: &str, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(&cell(text))
    }

    /// Reads a cell [`serialize`] wrote.
    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<String, D::Error> {
        let text = String::deserialize(d)?;
        Ok(match text.strip_prefix('\'') {
            Some(rest) if formula_like(rest) => rest.to_string(),
            _ => text,
        })
    }
}
