//! The one `unitree_go` message a G1 deployment reads besides `unitree_hg`'s: the wireless
//! remote on `rt/wirelesscontroller` (`unitree_go::msg::dds_::WirelessController_`, sticks
//! and the 16-bit button word). unitree_sdk2's C++ bindings (e.g. PyPI `far-unitree-sdk`,
//! which holosoma's inference package drives the robot through) read the remote from this
//! topic, not from `rt/lowstate`'s `wireless_remote` bytes, so the bridge publishes both.

use super::cdr::{Message, Visit};

/// The remote's sticks (each axis in [-1, 1]) and buttons (the bits of
/// [`super::wireless_remote::BUTTONS`]).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct WirelessController {
    /// Left stick, x.
    pub lx: f32,
    /// Left stick, y.
    pub ly: f32,
    /// Right stick, x.
    pub rx: f32,
    /// Right stick, y.
    pub ry: f32,
    /// Buttons held, one bit each.
    pub keys: u16,
}

impl Message for WirelessController {
    const TYPE_NAME: &'static str = "unitree_go::msg::dds_::WirelessController_";
    fn walk(&mut self, v: &mut impl Visit) {
        v.begin_struct();
        for axis in [&mut self.lx, &mut self.ly, &mut self.rx, &mut self.ry] {
            v.f32(axis);
        }
        // A uint16 has the int16's size and alignment; the bits pass through unchanged.
        let mut keys = self.keys as i16;
        v.i16(&mut keys);
        self.keys = keys as u16;
        v.end_struct();
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::dds::cdr::{decode_cdr, encode, Layout};

    #[test]
    fn the_cdr_is_four_floats_and_the_button_word() {
        let message = WirelessController {
            lx: 0.5,
            ry: -1.0,
            keys: 0x0108, // select + A
            ..Default::default()
        };
        let bytes = encode(&message, Layout::Cdr);
        // Header, 18 bytes of fields, 2 of padding to a 4-byte multiple (counted in the
        // header's options).
        assert_eq!(bytes.len(), 4 + 4 * 4 + 2 + 2);
        assert_eq!(bytes[3], 2);
        assert_eq!(&bytes[4..8], &0.5f32.to_le_bytes());
        assert_eq!(&bytes[20..22], &[0x08, 0x01]);
        assert_eq!(decode_cdr::<WirelessController>(&bytes).unwrap(), message);
        let high_bit = WirelessController {
            keys: 0x8000,
            ..Default::default()
        };
        let back: WirelessController = decode_cdr(&encode(&high_bit, Layout::Cdr)).unwrap();
        assert_eq!(back.keys, 0x8000);
    }
}
