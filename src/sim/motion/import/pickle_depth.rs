//! A walk over a pickle's opcodes that bounds how deeply its containers nest, before any
//! value is built.
//!
//! `serde-pickle` builds and drops values recursively, so a few kilobytes of nested lists
//! (`[[[…]]]`, 10 000 levels in 20 KB) overflow the stack and abort the process. Motion
//! pickles nest a handful of levels (a dict of numpy arrays, each a small tuple), so the
//! importer refuses anything deeper than [`MAX_NESTING`] from this walk alone. The walk
//! tracks, for every entry of the pickle machine's stack, how deep the value it will
//! become nests; it builds no values and recurses nowhere. Opcodes follow Python's
//! `pickletools` (protocols 0–5); an unknown opcode ends the walk with an error, so the
//! walk can never fall out of step with the stream it vouches for.

/// Deepest container nesting a motion pickle may have (real ones have about 5).
pub const MAX_NESTING: u32 = 100;

#[derive(Clone, Copy)]
enum Entry {
    Mark,
    Value(u32),
}

/// How an opcode's argument is encoded.
enum Arg {
    None,
    Fixed(usize),
    /// Up to and including a newline; `n` lines.
    Lines(usize),
    /// A little-endian length of this many bytes, then that many bytes.
    Counted(usize),
}

/// What an opcode does to the stack, for nesting purposes.
enum Effect {
    /// Pushes a leaf (or an empty container).
    Push,
    /// Pushes a mark.
    Mark,
    /// No change.
    Nothing,
    /// Pops one.
    Pop,
    /// Pops to the mark.
    PopMark,
    /// Duplicates the top.
    Dup,
    /// Pops `n` values and pushes one containing them.
    Combine(usize),
    /// Pops to the mark and pushes one containing what was popped.
    CombineMark,
    /// Pops `n` values into the container now on top.
    Into(usize),
    /// Pops to the mark into the container below the mark.
    IntoMark,
    /// Stores the top in the memo.
    Put,
    /// Pushes a memo entry.
    Get,
    /// The end of the pickle.
    Stop,
}

fn opcode(op: u8) -> Option<(Arg, Effect)> {
    use Arg::*;
    use Effect::*;
    Some(match op {
        b'N' | 0x88 | 0x89 | b'}' | b']' | b')' | 0x8f | 0x97 => (None, Push),
        b'(' => (None, Mark),
        b'.' => (None, Stop),
        b'0' => (None, Pop),
        b'1' => (None, PopMark),
        b'2' => (None, Dup),
        b'I' | b'L' | b'F' | b'S' | b'V' | b'P' => (Lines(1), Push),
        b'g' => (Lines(1), Get),
        b'p' => (Lines(1), Put),
        b'c' => (Lines(2), Push),
        b'i' => (Lines(2), CombineMark),
        b'J' => (Fixed(4), Push),
        b'K' => (Fixed(1), Push),
        b'M' => (Fixed(2), Push),
        b'G' => (Fixed(8), Push),
        0x82 => (Fixed(1), Push),
        0x83 => (Fixed(2), Push),
        0x84 => (Fixed(4), Push),
        0x8a | b'U' | 0x8c | b'C' => (Counted(1), Push),
        0x8b | b'T' | b'X' | b'B' => (Counted(4), Push),
        0x8d | 0x8e | 0x96 => (Counted(8), Push),
        b'h' => (Fixed(1), Get),
        b'j' => (Fixed(4), Get),
        b'q' => (Fixed(1), Put),
        b'r' => (Fixed(4), Put),
        0x94 => (None, Put),
        0x80 => (Fixed(1), Nothing),
        0x95 => (Fixed(8), Nothing),
        0x98 => (None, Nothing),
        b'a' => (None, Into(1)),
        b's' => (None, Into(2)),
        b'b' => (None, Into(1)),
        b'e' | b'u' | 0x90 => (None, IntoMark),
        b'l' | b'd' | b't' | b'o' | 0x91 => (None, CombineMark),
        0x85 => (None, Combine(1)),
        0x86 | b'R' | 0x81 | 0x93 => (None, Combine(2)),
        0x87 | 0x92 => (None, Combine(3)),
        b'Q' => (None, Combine(1)),
        _ => return Option::None,
    })
}

/// Checks that the pickle in `bytes` nests no deeper than `limit`. The error says where
/// and why; a stream this walk cannot follow (an unknown opcode, a cut argument, a stack
/// underflow) is an error too, since decoding it would fail anyway.
pub fn check_nesting(bytes: &[u8], limit: u32) -> Result<(), String> {
    let mut walk = Walk::default();
    let mut pos = 0usize;
    while pos < bytes.len() {
        let at = pos;
        let op = bytes[pos];
        pos += 1;
        let Some((arg, effect)) = opcode(op) else {
            return Err(format!("unknown pickle opcode 0x{op:02x} at byte {at}"));
        };
        let arg_bytes = read_arg(bytes, &mut pos, &arg, at)?;
        let Some(depth) = walk.apply(effect, op, &arg, arg_bytes, at)? else {
            return Ok(());
        };
        if depth > limit {
            return Err(format!(
                "containers nest more than {limit} levels deep (at byte {at}); a motion pickle nests a few"
            ));
        }
    }
    Err("the pickle has no STOP opcode".into())
}

fn cut(at: usize) -> String {
    format!("the pickle ends inside the argument of the opcode at byte {at}")
}

fn underflow(at: usize) -> String {
    format!("the opcode at byte {at} takes more than the stack holds")
}

/// Skips the argument of the opcode at byte `at`, which starts at `*pos`, and moves `*pos`
/// past it. Returns the argument's bytes for fixed and line arguments (memo ids are read
/// from them); a counted argument (a string or bytes) is skipped unread.
fn read_arg<'a>(
    bytes: &'a [u8],
    pos: &mut usize,
    arg: &Arg,
    at: usize,
) -> Result<&'a [u8], String> {
    match *arg {
        Arg::None => Ok(&[]),
        Arg::Fixed(n) => {
            let arg_bytes = bytes.get(*pos..*pos + n).ok_or_else(|| cut(at))?;
            *pos += n;
            Ok(arg_bytes)
        }
        Arg::Lines(n) => {
            let start = *pos;
            for _ in 0..n {
                let nl = bytes[*pos..]
                    .iter()
                    .position(|&b| b == b'\n')
                    .ok_or_else(|| cut(at))?;
                *pos += nl + 1;
            }
            Ok(&bytes[start..*pos])
        }
        Arg::Counted(n) => {
            let len_bytes = bytes.get(*pos..*pos + n).ok_or_else(|| cut(at))?;
            let mut len = [0u8; 8];
            len[..n].copy_from_slice(len_bytes);
            let len = usize::try_from(u64::from_le_bytes(len)).map_err(|_| cut(at))?;
            *pos += n;
            if len > bytes.len() - *pos {
                return Err(cut(at));
            }
            *pos += len;
            Ok(&[])
        }
    }
}

/// The pickle machine's stack and memo, holding nesting depths instead of values.
#[derive(Default)]
struct Walk {
    stack: Vec<Entry>,
    /// Depths in order of storing (MEMOIZE); ids are small.
    memo: Vec<u32>,
    /// Depths stored by explicit id (PUT).
    memo_by_id: std::collections::HashMap<u64, u32>,
}

impl Walk {
    /// Applies the `effect` of opcode `op` (at byte `at`, with argument `arg_bytes`).
    /// Returns the depth of the value it made or touched (0 for none), or `None` at STOP.
    fn apply(
        &mut self,
        effect: Effect,
        op: u8,
        arg: &Arg,
        arg_bytes: &[u8],
        at: usize,
    ) -> Result<Option<u32>, String> {
        let depth = match effect {
            Effect::Push => {
                self.stack.push(Entry::Value(1));
                1
            }
            Effect::Mark => {
                self.stack.push(Entry::Mark);
                0
            }
            Effect::Nothing => 0,
            Effect::Stop => return Ok(None),
            Effect::Pop => {
                match self.stack.pop() {
                    Some(_) => {}
                    None => return Err(underflow(at)),
                }
                0
            }
            Effect::PopMark => {
                self.pop_mark(at)?;
                0
            }
            Effect::Dup => {
                let top = *self.stack.last().ok_or_else(|| underflow(at))?;
                self.stack.push(top);
                0
            }
            Effect::Combine(n) => {
                let deepest = self.pop_values(n, at)?;
                self.stack.push(Entry::Value(deepest + 1));
                deepest + 1
            }
            Effect::CombineMark => {
                let d = self.pop_mark(at)? + 1;
                self.stack.push(Entry::Value(d));
                d
            }
            Effect::Into(n) => {
                let deepest = self.pop_values(n, at)?;
                self.add_to_top(deepest, at)?
            }
            Effect::IntoMark => {
                let d = self.pop_mark(at)?;
                self.add_to_top(d, at)?
            }
            Effect::Put => {
                let Some(Entry::Value(d)) = self.stack.last() else {
                    return Err(underflow(at));
                };
                match arg {
                    Arg::None => self.memo.push(*d),
                    _ => {
                        self.memo_by_id.insert(memo_id(op, arg_bytes), *d);
                    }
                }
                0
            }
            Effect::Get => {
                let id = memo_id(op, arg_bytes);
                // MEMOIZE numbers entries from 0 in order; PUT names them explicitly.
                let d = self
                    .memo_by_id
                    .get(&id)
                    .copied()
                    .or_else(|| {
                        usize::try_from(id)
                            .ok()
                            .and_then(|i| self.memo.get(i).copied())
                    })
                    .unwrap_or(1);
                self.stack.push(Entry::Value(d));
                d
            }
        };
        Ok(Some(depth))
    }

    /// Pops `n` values; returns the deepest.
    fn pop_values(&mut self, n: usize, at: usize) -> Result<u32, String> {
        let mut deepest = 0;
        for _ in 0..n {
            match self.stack.pop() {
                Some(Entry::Value(d)) => deepest = deepest.max(d),
                _ => return Err(underflow(at)),
            }
        }
        Ok(deepest)
    }

    /// Pops down to and including the top mark; returns the deepest value popped.
    fn pop_mark(&mut self, at: usize) -> Result<u32, String> {
        let mut deepest = 0;
        loop {
            match self.stack.pop() {
                Some(Entry::Mark) => return Ok(deepest),
                Some(Entry::Value(d)) => deepest = deepest.max(d),
                None => return Err(underflow(at)),
            }
        }
    }

    /// Puts a value `child` levels deep into the container on top; returns its new depth.
    fn add_to_top(&mut self, child: u32, at: usize) -> Result<u32, String> {
        match self.stack.last_mut() {
            Some(Entry::Value(d)) => {
                *d = (*d).max(child + 1);
                Ok(*d)
            }
            _ => Err(underflow(at)),
        }
    }
}

/// The memo key of a PUT/GET opcode's argument (text digits for protocol 0, else
/// little-endian).
fn memo_id(op: u8, arg: &[u8]) -> u64 {
    if op == b'p' || op == b'g' {
        std::str::from_utf8(arg)
            .ok()
            .and_then(|s| s.trim().parse().ok())
            .unwrap_or(u64::MAX)
    } else {
        let mut b = [0u8; 8];
        b[..arg.len()].copy_from_slice(arg);
        u64::from_le_bytes(b)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `[[…[]…]]` nested `n` deep, as protocol 2 writes it (EMPTY_LIST, then APPENDs).
    fn nested(n: usize) -> Vec<u8> {
        let mut p = vec![0x80, 2];
        p.extend(std::iter::repeat_n(b']', n));
        p.extend(std::iter::repeat_n(b'a', n - 1));
        p.push(b'.');
        p
    }

    #[test]
    fn shallow_pickles_pass_and_deep_ones_are_refused() {
        assert_eq!(check_nesting(&nested(5), MAX_NESTING), Ok(()));
        assert_eq!(check_nesting(&nested(100), MAX_NESTING), Ok(()));
        let e = check_nesting(&nested(10_000), MAX_NESTING).unwrap_err();
        assert!(e.contains("more than 100 levels"), "{e}");
    }

    #[test]
    fn tuples_and_marks_count_as_levels() {
        // MARK MARK … 1 TUPLE TUPLE … : tuples in tuples.
        let n = 200;
        let mut p = vec![b'('; n];
        p.push(b'N');
        p.extend(std::iter::repeat_n(b't', n));
        p.push(b'.');
        assert!(check_nesting(&p, MAX_NESTING).is_err());
    }

    #[test]
    fn streams_the_walk_cannot_follow_are_errors_not_panics() {
        for bad in [
            &b"\x80\x02]"[..],            // no STOP
            b"\x80\x02X\xff\xff\xff\xff", // a length past the end
            b"a.",                        // APPEND on an empty stack
            b"\xff.",                     // unknown opcode
            b"\x80",                      // PROTO cut short
        ] {
            assert!(check_nesting(bad, MAX_NESTING).is_err(), "{bad:?}");
        }
    }
}
