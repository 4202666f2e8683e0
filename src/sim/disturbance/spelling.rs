//! How a disturbance is written in `--settings`, a sweep's `settings` or a leaderboard's
//! pushes: a kind, its main value, then `:key=value` fields in any order, each with a
//! default. No commas (lists of settings are comma-separated) and only file-name-safe
//! characters, so the canonical spelling is also the setting's name.

use super::{Disturbance, ForceEvent, Hands, ImpulseTarget, Impulses, Payload};

/// The spellings, with their defaults.
pub const SYNTAX: &str = "event:<N>[@<deg>][:hand=left|right|both][:up=<deg>][:start=<s>][:ramp=<s>][:hold=<s>][:release=<s>] (defaults: @0, right, up=0, start=2, ramp=0.5, hold=1, release=ramp); impulse:<N>[-<N>][:on=torso|hands][:dur=<s>][:every=<s>[-<s>]][:seed=<n>] (defaults: torso, dur=0.1, every=3-6, seed=0); payload:<kg>[:hand=left|right|both] (default: both)";

/// Largest force of an event or an impulse, N (as a constant push's bound).
const MAX_FORCE_N: f64 = 1000.0;
/// Largest time of any field, s.
const MAX_TIME_S: f64 = 3600.0;
/// Shortest gap between impulses, s (a gap of zero would draw pulses without end).
const MIN_INTERVAL_S: f64 = 0.05;
/// Longest impulse, s.
const MAX_IMPULSE_S: f64 = 10.0;

/// See [`Disturbance::parse`].
pub fn parse(s: &str) -> Option<Result<Disturbance, String>> {
    let (kind, rest) = s.split_once(':')?;
    let parse_kind = match kind {
        "event" => event,
        "impulse" => impulse,
        "payload" => payload,
        _ => return None,
    };
    let mut parts = rest.split(':');
    let main = parts.next().unwrap_or_default();
    let mut fields = Vec::new();
    for part in parts {
        let Some((key, value)) = part.split_once('=') else {
            return Some(Err(format!("`{part}` is no key=value field")));
        };
        if fields.iter().any(|(k, _)| *k == key) {
            return Some(Err(format!("`{key}` is given twice")));
        }
        fields.push((key, value));
    }
    Some(parse_kind(main, &fields))
}

/// See [`Disturbance::name`].
pub fn name(d: &Disturbance) -> String {
    match d {
        Disturbance::Event(e) => format!(
            "event:{}@{}:hand={}:up={}:start={}:ramp={}:hold={}:release={}",
            e.force_n,
            e.heading_deg,
            e.hands.word(),
            e.up_deg,
            e.start_s,
            e.ramp_s,
            e.hold_s,
            e.release_s
        ),
        Disturbance::Impulses(i) => format!(
            "impulse:{}-{}:on={}:dur={}:every={}-{}:seed={}",
            i.force_n[0],
            i.force_n[1],
            match i.target {
                ImpulseTarget::Torso => "torso",
                _ => "hands",
            },
            i.duration_s,
            i.interval_s[0],
            i.interval_s[1],
            i.seed
        ),
        Disturbance::Payload(p) => format!("payload:{}:hand={}", p.mass_kg, p.hands.word()),
    }
}

type Fields<'a> = [(&'a str, &'a str)];

/// The most characters a number takes in a setting's name (`0.000001`, `1234.5678901`):
/// a name is a file name and a table's label, never three hundred zeros. Every setting's
/// numbers are held to it (`eval::Setting` too).
pub const MAX_NUMBER_CHARS: usize = 12;

/// Whether a setting's name writes `x` in at most [`MAX_NUMBER_CHARS`] characters.
pub fn fits_name(x: f64) -> bool {
    format!("{x}").len() <= MAX_NUMBER_CHARS
}

/// A number within `lo..=hi`, named `what` in the refusal, that the setting's name can
/// write back in at most [`MAX_NUMBER_CHARS`] characters.
fn number(what: &str, value: &str, lo: f64, hi: f64) -> Result<f64, String> {
    let x = value
        .parse::<f64>()
        .ok()
        .filter(|x| x.is_finite() && (lo..=hi).contains(x))
        .ok_or_else(|| format!("{what} `{value}` is not a number from {lo} to {hi}"))?;
    if !fits_name(x) {
        return Err(format!(
            "{what} `{value}` has more digits than a setting's name carries (at most {MAX_NUMBER_CHARS} characters, e.g. 0.000001): round it"
        ));
    }
    Ok(x)
}

/// A range `a-b` (or one value `a`) within `lo..=hi`, `a ≤ b`.
fn range(what: &str, value: &str, lo: f64, hi: f64) -> Result<[f64; 2], String> {
    let (a, b) = value.split_once('-').unwrap_or((value, value));
    let (a, b) = (number(what, a, lo, hi)?, number(what, b, lo, hi)?);
    if a > b {
        return Err(format!(
            "{what} `{value}`: its first value exceeds its second"
        ));
    }
    Ok([a, b])
}

fn hands(value: &str) -> Result<Hands, String> {
    match value {
        "left" => Ok(Hands::Left),
        "right" => Ok(Hands::Right),
        "both" => Ok(Hands::Both),
        other => Err(format!("hand `{other}` is not left, right or both")),
    }
}

/// Each field through `read` (which refuses a key it does not know), in order.
fn read_fields(
    fields: &Fields,
    mut read: impl FnMut(&str, &str) -> Result<(), String>,
) -> Result<(), String> {
    fields.iter().try_for_each(|(key, value)| read(key, value))
}

fn event(main: &str, fields: &Fields) -> Result<Disturbance, String> {
    let (n, deg) = main.split_once('@').unwrap_or((main, "0"));
    let mut e = ForceEvent {
        force_n: number("force", n, 0.0, MAX_FORCE_N)?,
        heading_deg: number("heading", deg, -360.0, 360.0)?,
        up_deg: 0.0,
        hands: Hands::Right,
        start_s: 2.0,
        ramp_s: 0.5,
        hold_s: 1.0,
        release_s: f64::NAN,
    };
    let time = |what: &str, v: &str| number(what, v, 0.0, MAX_TIME_S);
    read_fields(fields, |key, v| {
        match key {
            "hand" => e.hands = hands(v)?,
            "up" => e.up_deg = number("up", v, -90.0, 90.0)?,
            "start" => e.start_s = time("start", v)?,
            "ramp" => e.ramp_s = time("ramp", v)?,
            "hold" => e.hold_s = time("hold", v)?,
            "release" => e.release_s = time("release", v)?,
            _ => return Err(format!("`{key}` is no field of an event")),
        }
        Ok(())
    })?;
    if e.release_s.is_nan() {
        e.release_s = e.ramp_s;
    }
    Ok(Disturbance::Event(e))
}

fn impulse(main: &str, fields: &Fields) -> Result<Disturbance, String> {
    let mut i = Impulses {
        force_n: range("force", main, 0.0, MAX_FORCE_N)?,
        duration_s: 0.1,
        interval_s: [3.0, 6.0],
        target: ImpulseTarget::Torso,
        seed: 0,
    };
    read_fields(fields, |key, v| {
        match key {
            "on" => {
                i.target = match v {
                    "torso" => ImpulseTarget::Torso,
                    "hands" => ImpulseTarget::Hands,
                    other => return Err(format!("on `{other}` is not torso or hands")),
                }
            }
            "dur" => i.duration_s = number("dur", v, 0.001, MAX_IMPULSE_S)?,
            "every" => i.interval_s = range("every", v, MIN_INTERVAL_S, MAX_TIME_S)?,
            "seed" => {
                i.seed = v
                    .parse()
                    .map_err(|_| format!("seed `{v}` is not a whole number ≥ 0"))?
            }
            _ => return Err(format!("`{key}` is no field of impulses")),
        }
        Ok(())
    })?;
    Ok(Disturbance::Impulses(i))
}

fn payload(main: &str, fields: &Fields) -> Result<Disturbance, String> {
    let mass_kg = number("mass", main, 0.0, Payload::MAX_KG)?;
    if mass_kg == 0.0 {
        return Err("a payload of 0 kg is no payload: use no-force".into());
    }
    let mut p = Payload {
        mass_kg,
        hands: Hands::Both,
    };
    read_fields(fields, |key, v| {
        match key {
            "hand" => p.hands = hands(v)?,
            _ => return Err(format!("`{key}` is no field of a payload")),
        }
        Ok(())
    })?;
    Ok(Disturbance::Payload(p))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_canonical_name_parses_back_to_its_disturbance() {
        for s in [
            "event:30",
            "event:30@90:hand=both:up=-20:start=1:ramp=0:hold=2:release=0.25",
            "impulse:50-200",
            "impulse:80:on=hands:dur=0.2:every=2:seed=7",
            "payload:2.5",
            "payload:1:hand=left",
        ] {
            let d = parse(s).expect("a disturbance").expect(s);
            let n = name(&d);
            let again = parse(&n).expect("a disturbance").expect(&n);
            assert_eq!(d, again, "{s} → {n}");
            crate::files::names::check_name("setting", &n).expect(&n);
        }
    }

    #[test]
    fn defaults_are_those_written_in_the_syntax() {
        let Some(Ok(Disturbance::Event(e))) = parse("event:30") else {
            panic!()
        };
        assert_eq!(
            (
                e.heading_deg,
                e.hands,
                e.up_deg,
                e.start_s,
                e.ramp_s,
                e.hold_s,
                e.release_s
            ),
            (0.0, Hands::Right, 0.0, 2.0, 0.5, 1.0, 0.5)
        );
        let Some(Ok(Disturbance::Event(e))) = parse("event:30:ramp=2") else {
            panic!()
        };
        assert_eq!(e.release_s, 2.0, "release follows the ramp");
    }

    #[test]
    fn malformed_spellings_are_refused_with_their_reason() {
        for (s, why) in [
            ("event:abc", "force `abc`"),
            ("event:30:hand=middle", "hand `middle`"),
            ("event:30:hold", "no key=value"),
            ("event:30:hold=1:hold=2", "given twice"),
            ("event:30:dur=1", "no field of an event"),
            ("event:2000", "from 0 to 1000"),
            ("impulse:200-50", "exceeds its second"),
            ("impulse:50:every=0", "every `0`"),
            ("impulse:50:seed=-1", "seed `-1`"),
            ("payload:0", "0 kg"),
            ("payload:25", "from 0 to 20"),
            ("payload:nan", "mass `nan`"),
        ] {
            let e = parse(s).expect("a disturbance kind").unwrap_err();
            assert!(e.contains(why), "{s}: {e}");
        }
        assert!(parse("push:30").is_none());
        assert!(parse("force").is_none());
    }
}
