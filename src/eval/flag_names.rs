//! The terminal's spelling of the library's field names. The library names what a user
//! set by its field in backticks — a field of the evaluation's request as
//! `request.envs`, `request.io.budget_s`, another option of a command as `option.out` —
//! which a request file or a library caller reads as it is; on the terminal (the binary
//! passes every line it prints through [`as_flags`]) those names become the flags that
//! set them. The flags are named after the fields (the last part, without its unit
//! suffix, dashed: `request.physics_dt_s` is `--physics-dt`), so no table has to follow
//! each new option; a `request.` name is only written as a flag when `EvalRequest` has
//! that field, which keeps file names such as `request.json` and anything else in
//! backticks (a sweep spec's keys, a user's values) as they are.

use crate::eval::EvalRequest;
use std::sync::OnceLock;

/// Unit suffixes of field names that their flags leave out.
const UNIT_SUFFIXES: [&str; 4] = ["_s", "_m", "_rad", "_hz"];

/// `text` with every field the library names in backticks written as its flag.
pub fn as_flags(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    let mut rest = text;
    while let Some(open) = rest.find('`') {
        out.push_str(&rest[..open]);
        let after = &rest[open + 1..];
        let quoted = after
            .find('`')
            .map(|close| (&after[..close], &after[close + 1..]));
        match quoted.and_then(|(name, tail)| Some((flag_of(name)?, tail))) {
            Some((flag, tail)) => {
                out.push_str(&flag);
                rest = tail;
            }
            // Not a field: the backtick stays, and the search goes on after it.
            None => {
                out.push('`');
                rest = after;
            }
        }
    }
    out.push_str(rest);
    out
}

/// The flag of field `name` (`option.per_task` → `--per-task`), if it names one.
fn flag_of(name: &str) -> Option<String> {
    let path = match name.strip_prefix("request.") {
        Some(path) if is_request_field(path) => path,
        Some(_) => return None,
        None => name.strip_prefix("option.")?,
    };
    let field = path.rsplit('.').next()?;
    if field.is_empty() || !field.bytes().all(|b| b.is_ascii_lowercase() || b == b'_') {
        return None;
    }
    let field = UNIT_SUFFIXES
        .iter()
        .find_map(|unit| field.strip_suffix(unit))
        .unwrap_or(field);
    Some(format!("--{}", field.replace('_', "-")))
}

/// Whether `path` (`io.budget_s`) is a field of an evaluation request as a request file
/// holds it.
fn is_request_field(path: &str) -> bool {
    static FIELDS: OnceLock<serde_json::Value> = OnceLock::new();
    let fields = FIELDS.get_or_init(|| {
        serde_json::to_value(EvalRequest::default()).expect("an EvalRequest serialises")
    });
    path.split('.')
        .try_fold(fields, |value, key| value.get(key))
        .is_some()
}

#[cfg(test)]
mod tests {
    use super::as_flags;

    #[test]
    fn fields_become_flags_and_nothing_else_changes() {
        for (text, shown) in [
            ("`request.io.budget_s` 2ms", "--budget 2ms"),
            (
                "`request.termination.max_torso_tilt_error_rad`",
                "--max-torso-tilt-error",
            ),
            (
                "a `request.json` and `option.per_task`",
                "a `request.json` and --per-task",
            ),
            (
                "`request.nonsense` `option.Out`",
                "`request.nonsense` `option.Out`",
            ),
            ("a stray ` and `sweep run`", "a stray ` and `sweep run`"),
        ] {
            assert_eq!(as_flags(text), shown, "{text}");
        }
    }
}
