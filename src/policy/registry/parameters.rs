//! The parameters a family's policy takes after its file's `@`
//! (`softmimic:F.onnx@stiffness=200`): each family declares them in its registry entry —
//! name, unit, the range accepted, what it is — and an argument is held to that
//! declaration where it is parsed. An unknown key, a key given twice, a value that is no
//! finite number or lies outside its range, or a parameter on a family that declares none
//! is refused there, before anything runs: a parameter accepted and ignored would label a
//! run (or a sweep's cell) with a value that changed nothing.

use super::did_you_mean;

/// One parameter a family's policy takes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Parameter {
    /// Its key after `@` (`stiffness`).
    pub name: &'static str,
    /// Its unit (`N/m`).
    pub unit: &'static str,
    /// Values accepted, inclusive (for a network: the range it was trained on).
    pub range: (f64, f64),
    /// What it is and its default, in a few words (help and errors).
    pub what: &'static str,
}

/// Parameter values as an argument gives them, each checked against its declaration, in
/// the order given.
pub type ParameterValues = Vec<(&'static str, f64)>;

/// `text` (what follows the file's `@`: `KEY=VALUE,…`) read against `declared`, the
/// parameters of family `family`; `Err` says what is wrong and what the family takes.
pub fn parse_parameters(
    family: &str,
    declared: &'static [Parameter],
    text: &str,
) -> Result<ParameterValues, String> {
    if declared.is_empty() {
        return Err(format!(
            "`{family}` takes no parameters, but `@{text}` gives some"
        ));
    }
    let takes = || {
        declared
            .iter()
            .map(|p| {
                format!(
                    "{}=<{}> ({} to {}; {})",
                    p.name, p.unit, p.range.0, p.range.1, p.what
                )
            })
            .collect::<Vec<_>>()
            .join(", ")
    };
    let mut values = ParameterValues::new();
    for item in text.split(',') {
        let Some((key, value)) = item.split_once('=') else {
            return Err(format!(
                "`{item}` is not KEY=VALUE: `{family}` takes {}",
                takes()
            ));
        };
        let key = key.trim();
        let Some(p) = declared.iter().find(|p| p.name == key) else {
            let hint = did_you_mean(key, declared.iter().map(|p| p.name));
            return Err(format!(
                "`{family}` has no parameter `{key}`{hint}: it takes {}",
                takes()
            ));
        };
        if values.iter().any(|(name, _)| *name == p.name) {
            return Err(format!(
                "parameter `{key}` is given twice in `@{text}`: give it once"
            ));
        }
        let v: f64 = value
            .trim()
            .parse()
            .ok()
            .filter(|v: &f64| v.is_finite())
            .ok_or_else(|| format!("parameter `{key}`: `{value}` is not a finite number"))?;
        if !(p.range.0..=p.range.1).contains(&v) {
            return Err(format!(
                "parameter `{key}` = {} {} is outside {} to {} {} ({})",
                crate::files::log_text::short_number(v),
                p.unit,
                p.range.0,
                p.range.1,
                p.unit,
                p.what
            ));
        }
        values.push((p.name, v));
    }
    Ok(values)
}

#[cfg(test)]
mod tests {
    use super::*;

    const STIFFNESS: [Parameter; 1] = [Parameter {
        name: "stiffness",
        unit: "N/m",
        range: (10.0, 1000.0),
        what: "default 60",
    }];

    #[test]
    fn declared_parameters_parse_in_range() {
        assert_eq!(
            parse_parameters("softmimic", &STIFFNESS, "stiffness=200").unwrap(),
            vec![("stiffness", 200.0)]
        );
    }

    #[test]
    fn everything_else_is_refused_with_what_the_family_takes() {
        for (declared, text, says) in [
            (&[][..], "stiffness=5", "`falcon` takes no parameters"),
            (
                &STIFFNESS[..],
                "stifness=5",
                "has no parameter `stifness` (did you mean `stiffness`",
            ),
            (
                &STIFFNESS[..],
                "x=1",
                "it takes stiffness=<N/m> (10 to 1000",
            ),
            (&STIFFNESS[..], "stiffness=100,stiffness=200", "given twice"),
            (&STIFFNESS[..], "stiffness=1e300", "outside 10 to 1000"),
            (&STIFFNESS[..], "stiffness=NaN", "not a finite number"),
            (&STIFFNESS[..], "stiffness=-5", "outside"),
            (&STIFFNESS[..], "stiffness", "not KEY=VALUE"),
        ] {
            let e = parse_parameters("falcon", declared, text).unwrap_err();
            assert!(e.contains(says), "{text}: {e}");
        }
    }
}
