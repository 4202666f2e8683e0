//! The checksum of Unitree's low-level messages.
//!
//! The robot and Unitree's SDKs (unitree_sdk2 `crc32_core`, unitree_sdk2_python
//! `unitree_sdk2py/utils/crc.py`) checksum a message's C struct — natural alignment,
//! little-endian — as 32-bit words, every word but the last (the `crc` field itself),
//! most significant bit first: CRC-32/MPEG-2 (polynomial 0x04C11DB7, initial value
//! 0xFFFFFFFF, no reflection, no final XOR) over each word's bytes in big-endian order.

/// CRC-32/MPEG-2 over `words`, each fed most significant byte first.
pub fn crc32_words(words: impl IntoIterator<Item = u32>) -> u32 {
    let mut crc = 0xFFFF_FFFFu32;
    for word in words {
        for byte in word.to_be_bytes() {
            crc = TABLE[((crc >> 24) as u8 ^ byte) as usize] ^ (crc << 8);
        }
    }
    crc
}

/// The checksum of a C struct's bytes (`c_bytes.len()` a multiple of 4, the last word
/// being the `crc` field, left out).
pub fn crc_of_c_struct(c_bytes: &[u8]) -> u32 {
    let words = c_bytes.len() / 4;
    crc32_words(
        c_bytes
            .chunks_exact(4)
            .take(words.saturating_sub(1))
            .map(|w| u32::from_le_bytes([w[0], w[1], w[2], w[3]])),
    )
}

const POLYNOMIAL: u32 = 0x04C1_1DB7;

/// Byte-wise table of the MSB-first CRC.
const TABLE: [u32; 256] = {
    let mut table = [0u32; 256];
    let mut i = 0;
    while i < 256 {
        let mut crc = (i as u32) << 24;
        let mut bit = 0;
        while bit < 8 {
            crc = if crc & 0x8000_0000 != 0 {
                (crc << 1) ^ POLYNOMIAL
            } else {
                crc << 1
            };
            bit += 1;
        }
        table[i] = crc;
        i += 1;
    }
    table
};

#[cfg(test)]
mod tests {
    use super::*;

    /// The SDK's own loop (`_crc_py` in unitree_sdk2py's crc.py), written bit by bit.
    fn bitwise(words: &[u32]) -> u32 {
        let mut crc = 0xFFFF_FFFFu32;
        for &current in words {
            let mut bit = 1u32 << 31;
            for _ in 0..32 {
                crc = if crc & 0x8000_0000 != 0 {
                    (crc << 1) ^ POLYNOMIAL
                } else {
                    crc << 1
                };
                if current & bit != 0 {
                    crc ^= POLYNOMIAL;
                }
                bit >>= 1;
            }
        }
        crc
    }

    #[test]
    fn the_table_gives_the_sdks_bitwise_crc() {
        let words: Vec<u32> = (0..300u32)
            .map(|i| i.wrapping_mul(2_654_435_761) ^ 0xA5A5_0F0F)
            .collect();
        for n in [0, 1, 2, 7, 300] {
            assert_eq!(
                crc32_words(words[..n].iter().copied()),
                bitwise(&words[..n])
            );
        }
    }

    #[test]
    fn the_check_value_of_crc32_mpeg2() {
        // "123456789" is the catalogue's check string; as big-endian words plus a
        // tail it is not word-aligned, so check the byte-level table on it directly.
        let mut crc = 0xFFFF_FFFFu32;
        for &byte in b"123456789" {
            crc = TABLE[((crc >> 24) as u8 ^ byte) as usize] ^ (crc << 8);
        }
        assert_eq!(crc, 0x0376_E6E7);
    }
}
