//! A scripted wireless remote: button presses at given times, carried in `rt/lowstate`'s
//! `wireless_remote` and on `rt/wirelesscontroller`, as the G1 carries its handheld
//! remote's, so deployment scripts that wait for "start", then "A" (or a chord such as
//! holosoma's "select+A"), get through their start-up unattended.
//!
//! The buttons are the bits of the little-endian 16-bit word in bytes 2–3, in the order of
//! unitree_rl_gym's `deploy/deploy_real/common/remote_controller.py` (bit 0 R1, 1 L1,
//! 2 start, 3 select, 4 R2, 5 L2, 6 F1, 7 F2, 8 A, 9 B, 10 X, 11 Y, 12 up, 13 right,
//! 14 down, 15 left); unitree_sdk2_python's `utils/joystick.py` reads the same bits.

use std::time::Duration;

/// How long a scripted press holds its button down.
pub const PRESS: Duration = Duration::from_millis(200);

/// The buttons, by name, in bit order.
pub const BUTTONS: [&str; 16] = [
    "R1", "L1", "start", "select", "R2", "L2", "F1", "F2", "A", "B", "X", "Y", "up", "right",
    "down", "left",
];

/// A bad `--remote` script.
#[derive(Debug, thiserror::Error, PartialEq, Eq)]
pub enum RemoteError {
    /// A press is not `BUTTON@SECONDS` (e.g. `start@1s`, `A@2.5`, `select+A@4s`).
    #[error("remote press `{0}`: give BUTTON@SECONDS or BUTTON+BUTTON@SECONDS, e.g. start@1s")]
    Malformed(String),
    /// An unknown button.
    #[error("remote press `{press}`: no button `{button}` (buttons: {})", BUTTONS.join(", "))]
    UnknownButton {
        /// The press as written.
        press: String,
        /// The button named.
        button: String,
    },
}

/// The bit of button `name` (case-insensitive) in the remote's 16-bit word.
pub fn button_bit(name: &str) -> Option<u16> {
    BUTTONS
        .iter()
        .position(|b| b.eq_ignore_ascii_case(name.trim()))
        .map(|bit| 1u16 << bit)
}

/// The bits of `chord`: one button, or several joined by `+` (`select+A`), held together.
pub fn chord_bits(chord: &str) -> Option<u16> {
    chord
        .split('+')
        .try_fold(0u16, |bits, name| Some(bits | button_bit(name)?))
}

/// Presses at times since the bridge started publishing.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct RemoteScript {
    presses: Vec<(Duration, u16)>,
}

/// `BUTTON@SECONDS,…`, as a command line gives it ([`RemoteScript::parse`]).
impl std::str::FromStr for RemoteScript {
    type Err = RemoteError;

    fn from_str(text: &str) -> Result<Self, RemoteError> {
        Self::parse(text)
    }
}
impl RemoteScript {
    /// `start@1s,A@2s,select+A@3s`: comma-separated presses, each a button (or a chord of
    /// buttons joined by `+`) and the time, s (the `s` is optional).
    pub fn parse(text: &str) -> Result<Self, RemoteError> {
        let mut presses = Vec::new();
        for press in text.split(',').map(str::trim).filter(|p| !p.is_empty()) {
            let malformed = || RemoteError::Malformed(press.to_string());
            let (button, at) = press.split_once('@').ok_or_else(malformed)?;
            let seconds: f64 = at
                .trim()
                .trim_end_matches('s')
                .parse()
                .map_err(|_| malformed())?;
            let at = Duration::try_from_secs_f64(seconds).map_err(|_| malformed())?;
            let bit = chord_bits(button).ok_or_else(|| RemoteError::UnknownButton {
                press: press.to_string(),
                button: button
                    .split('+')
                    .find(|name| button_bit(name).is_none())
                    .unwrap_or(button)
                    .trim()
                    .to_string(),
            })?;
            presses.push((at, bit));
        }
        presses.sort();
        Ok(Self { presses })
    }

    /// Whether the script ever holds all the buttons of `bits` down together.
    pub fn presses(&self, bits: u16) -> bool {
        bits != 0 && self.presses.iter().any(|(_, b)| b & bits == bits)
    }

    /// When `bits` are first all held down together, after the bridge starts.
    pub fn first_press(&self, bits: u16) -> Option<Duration> {
        self.presses
            .iter()
            .filter(|(_, b)| bits != 0 && b & bits == bits)
            .map(|(at, _)| *at)
            .min()
    }

    /// The buttons held down `since` the bridge started publishing.
    pub fn buttons_at(&self, since: Duration) -> u16 {
        self.presses
            .iter()
            .filter(|(at, _)| since >= *at && since < *at + PRESS)
            .fold(0, |held, (_, bit)| held | bit)
    }

    /// Writes the held buttons into a `wireless_remote` field.
    pub fn write(&self, since: Duration, wireless_remote: &mut [u8; 40]) {
        let [low, high] = self.buttons_at(since).to_le_bytes();
        wireless_remote[2] = low;
        wireless_remote[3] = high;
    }

    /// The remote as `rt/wirelesscontroller` carries it: the held buttons, sticks centred.
    pub fn controller(&self, since: Duration) -> super::WirelessController {
        super::WirelessController {
            keys: self.buttons_at(since),
            ..Default::default()
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn presses_set_their_bits_for_a_moment() {
        let script = RemoteScript::parse("start@1s, A@2").unwrap();
        let mut remote = [0u8; 40];
        script.write(Duration::from_millis(1050), &mut remote);
        assert_eq!((remote[2], remote[3]), (0x04, 0x00));
        script.write(Duration::from_millis(2100), &mut remote);
        assert_eq!((remote[2], remote[3]), (0x00, 0x01));
        script.write(Duration::from_millis(1500), &mut remote);
        assert_eq!((remote[2], remote[3]), (0, 0));
        assert_eq!(script.buttons_at(Duration::from_millis(999)), 0);
        assert_eq!(script.controller(Duration::from_millis(2100)).keys, 0x0100);
    }

    #[test]
    fn a_chord_holds_its_buttons_together() {
        // holosoma's "start the motion clip": select (bit 3) + A (bit 8) = 264.
        assert_eq!(chord_bits("select+A"), Some(264));
        let script = RemoteScript::parse("A@1s,select+A@2s").unwrap();
        assert_eq!(script.buttons_at(Duration::from_millis(2100)), 264);
        assert!(script.presses(264));
        assert!(script.presses(button_bit("A").unwrap()));
        assert!(!RemoteScript::parse("A@1s").unwrap().presses(264));
        assert!(matches!(
            RemoteScript::parse("select+Q@1s"),
            Err(RemoteError::UnknownButton { button, .. }) if button == "Q"
        ));
        assert_eq!(chord_bits("select+"), None);
    }

    #[test]
    fn bad_scripts_are_errors_naming_the_press() {
        assert!(matches!(
            RemoteScript::parse("start"),
            Err(RemoteError::Malformed(p)) if p == "start"
        ));
        assert!(matches!(
            RemoteScript::parse("Z@1s"),
            Err(RemoteError::UnknownButton { button, .. }) if button == "Z"
        ));
        assert!(RemoteScript::parse("A@-1").is_err());
        assert!(RemoteScript::parse("A@nan").is_err());
        assert_eq!(RemoteScript::parse("").unwrap(), RemoteScript::default());
    }
}
