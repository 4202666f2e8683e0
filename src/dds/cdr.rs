//! Plain CDR for fixed-size messages of bytes, 16- and 32-bit integers and floats: the
//! encoding DDS puts on the wire (XCDR1 and, for such final types, XCDR2 lay them out
//! alike), and the C struct layout Unitree's checksum is computed over.
//!
//! Both are one walk over the fields in declaration order, each aligned to its size; they
//! differ only at struct boundaries: a C struct starts and ends at its alignment (4 here:
//! every struct holds a 32-bit field), CDR pads nowhere but before a field.

use super::DecodeError;

/// One walk over a message's fields, in declaration order: a writer reads each field, a
/// reader sets it. A message type lists its fields once (`Message::walk`) for both.
pub trait Visit {
    /// A struct starts.
    fn begin_struct(&mut self);
    /// A struct ends.
    fn end_struct(&mut self);
    /// A byte.
    fn u8(&mut self, v: &mut u8);
    /// A 16-bit signed integer.
    fn i16(&mut self, v: &mut i16);
    /// A 32-bit unsigned integer.
    fn u32(&mut self, v: &mut u32);
    /// A 32-bit float.
    fn f32(&mut self, v: &mut f32);
}

/// A message whose fields a [`Visit`] walks.
pub trait Message: Default {
    /// The DDS type name.
    const TYPE_NAME: &'static str;
    /// Visits every field, in declaration order.
    fn walk(&mut self, v: &mut impl Visit);
}

/// `message` in `layout`.
pub fn encode<M: Message + Clone>(message: &M, layout: Layout) -> Vec<u8> {
    let mut w = Writer::new(layout);
    message.clone().walk(&mut w);
    w.finish()
}

/// A message from its CDR payload (with the encapsulation header).
pub fn decode_cdr<M: Message>(payload: &[u8]) -> Result<M, DecodeError> {
    let mut r = Reader::cdr(payload, M::TYPE_NAME)?;
    let mut m = M::default();
    m.walk(&mut r);
    r.finish()?;
    Ok(m)
}

/// A message from CDR data without the encapsulation header, which said `kind`.
pub fn decode_cdr_body<M: Message>(body: &[u8], kind: u16) -> Result<M, DecodeError> {
    let mut r = Reader::cdr_body(body, kind, M::TYPE_NAME)?;
    let mut m = M::default();
    m.walk(&mut r);
    r.finish()?;
    Ok(m)
}

/// A message from its C struct bytes.
pub fn decode_c<M: Message>(bytes: &[u8]) -> Result<M, DecodeError> {
    let mut r = Reader::c_struct(bytes, M::TYPE_NAME);
    let mut m = M::default();
    m.walk(&mut r);
    r.finish()?;
    Ok(m)
}

impl Visit for Writer {
    fn begin_struct(&mut self) {
        self.struct_boundary();
    }
    fn end_struct(&mut self) {
        self.struct_boundary();
    }
    fn u8(&mut self, v: &mut u8) {
        self.put_u8(*v);
    }
    fn i16(&mut self, v: &mut i16) {
        self.put_i16(*v);
    }
    fn u32(&mut self, v: &mut u32) {
        self.put_u32(*v);
    }
    fn f32(&mut self, v: &mut f32) {
        self.put_f32(*v);
    }
}

impl Visit for Reader<'_> {
    fn begin_struct(&mut self) {
        self.struct_boundary();
    }
    fn end_struct(&mut self) {
        self.struct_boundary();
    }
    fn u8(&mut self, v: &mut u8) {
        *v = self.get_u8();
    }
    fn i16(&mut self, v: &mut i16) {
        *v = self.get_i16();
    }
    fn u32(&mut self, v: &mut u32) {
        *v = self.get_u32();
    }
    fn f32(&mut self, v: &mut f32) {
        *v = self.get_f32();
    }
}

/// Encapsulation identifiers (RTPS serialized payload header, big-endian on the wire).
pub mod encapsulation {
    /// XCDR1, big-endian.
    pub const CDR_BE: u16 = 0x0000;
    /// XCDR1, little-endian: what the bridge writes.
    pub const CDR_LE: u16 = 0x0001;
    /// XCDR2 plain (final types), big-endian.
    pub const CDR2_BE: u16 = 0x0006;
    /// XCDR2 plain (final types), little-endian.
    pub const CDR2_LE: u16 = 0x0007;
}

/// Where the bytes go: the wire, or the C struct.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Layout {
    /// CDR after the 4-byte encapsulation header; alignment counts from the data's start.
    Cdr,
    /// The C struct, little-endian, structs aligned to 4.
    C,
}

/// Writes fields little-endian, aligned as `layout` wants.
#[derive(Debug)]
pub struct Writer {
    layout: Layout,
    bytes: Vec<u8>,
    /// Where alignment counts from (after the encapsulation header for CDR).
    origin: usize,
}

impl Writer {
    /// An empty message: for CDR, the XCDR1 little-endian encapsulation header first.
    pub fn new(layout: Layout) -> Self {
        let bytes = match layout {
            Layout::Cdr => {
                let mut b = encapsulation::CDR_LE.to_be_bytes().to_vec();
                b.extend([0, 0]); // options
                b
            }
            Layout::C => Vec::new(),
        };
        Self {
            layout,
            origin: bytes.len(),
            bytes,
        }
    }

    fn align(&mut self, n: usize) {
        while !(self.bytes.len() - self.origin).is_multiple_of(n) {
            self.bytes.push(0);
        }
    }

    /// A struct starts or ends: in C, at its alignment of 4 (every struct here holds a
    /// 32-bit field); CDR pads nowhere but before a field.
    fn struct_boundary(&mut self) {
        if self.layout == Layout::C {
            self.align(4);
        }
    }

    /// A byte.
    fn put_u8(&mut self, v: u8) {
        self.bytes.push(v);
    }

    /// A 16-bit signed integer.
    fn put_i16(&mut self, v: i16) {
        self.align(2);
        self.bytes.extend(v.to_le_bytes());
    }

    /// A 32-bit unsigned integer.
    fn put_u32(&mut self, v: u32) {
        self.align(4);
        self.bytes.extend(v.to_le_bytes());
    }

    /// A 32-bit float.
    fn put_f32(&mut self, v: f32) {
        self.align(4);
        self.bytes.extend(v.to_le_bytes());
    }

    /// The message. CDR payloads are padded to a multiple of 4, the padding counted in
    /// the header's options as RTPS wants.
    pub fn finish(mut self) -> Vec<u8> {
        if self.layout == Layout::Cdr {
            let padding = (4 - self.bytes.len() % 4) % 4;
            self.bytes.extend(std::iter::repeat_n(0, padding));
            self.bytes[3] = padding as u8;
        }
        self.bytes
    }
}

/// Reads fields in either byte order, aligned as `layout` wants.
#[derive(Debug)]
pub struct Reader<'a> {
    layout: Layout,
    bytes: &'a [u8],
    at: usize,
    origin: usize,
    big_endian: bool,
    message: &'static str,
    /// Set when a read ran past the end; every later read gives 0.
    short: bool,
}

impl<'a> Reader<'a> {
    /// A CDR payload with its encapsulation header (XCDR1 or plain XCDR2, either byte
    /// order) of message type `message`.
    pub fn cdr(bytes: &'a [u8], message: &'static str) -> Result<Self, DecodeError> {
        if bytes.len() < 4 {
            return Err(DecodeError::Truncated {
                message,
                got: bytes.len(),
                need: 4,
            });
        }
        let kind = u16::from_be_bytes([bytes[0], bytes[1]]);
        let mut r = Self::cdr_body(bytes, kind, message)?;
        (r.at, r.origin) = (4, 4);
        Ok(r)
    }

    /// CDR data without its encapsulation header, which said `kind` (a DDS library that
    /// parsed the header hands over the rest).
    pub fn cdr_body(
        bytes: &'a [u8],
        kind: u16,
        message: &'static str,
    ) -> Result<Self, DecodeError> {
        use encapsulation::*;
        let big_endian = match kind {
            CDR_LE | CDR2_LE => false,
            CDR_BE | CDR2_BE => true,
            _ => return Err(DecodeError::Encapsulation { message, kind }),
        };
        Ok(Self {
            layout: Layout::Cdr,
            bytes,
            at: 0,
            origin: 0,
            big_endian,
            message,
            short: false,
        })
    }

    /// A little-endian C struct of message type `message`.
    pub fn c_struct(bytes: &'a [u8], message: &'static str) -> Self {
        Self {
            layout: Layout::C,
            bytes,
            at: 0,
            origin: 0,
            big_endian: false,
            message,
            short: false,
        }
    }

    fn align(&mut self, n: usize) {
        let rem = (self.at - self.origin) % n;
        if rem != 0 {
            self.at += n - rem;
        }
    }

    fn take<const N: usize>(&mut self) -> [u8; N] {
        let mut out = [0u8; N];
        match self.bytes.get(self.at..self.at + N) {
            Some(b) if !self.short => out.copy_from_slice(b),
            _ => self.short = true,
        }
        self.at += N;
        if self.big_endian {
            out.reverse();
        }
        out
    }

    /// A struct starts or ends: in C, at its alignment of 4 (every struct here holds a
    /// 32-bit field); CDR pads nowhere but before a field.
    fn struct_boundary(&mut self) {
        if self.layout == Layout::C {
            self.align(4);
        }
    }

    /// A byte.
    fn get_u8(&mut self) -> u8 {
        self.take::<1>()[0]
    }

    /// A 16-bit signed integer.
    fn get_i16(&mut self) -> i16 {
        self.align(2);
        i16::from_le_bytes(self.take())
    }

    /// A 32-bit unsigned integer.
    fn get_u32(&mut self) -> u32 {
        self.align(4);
        u32::from_le_bytes(self.take())
    }

    /// A 32-bit float.
    fn get_f32(&mut self) -> f32 {
        self.align(4);
        f32::from_le_bytes(self.take())
    }

    /// Done: an error if any read ran past the end.
    pub fn finish(self) -> Result<(), DecodeError> {
        if self.short {
            Err(DecodeError::Truncated {
                message: self.message,
                got: self.bytes.len(),
                need: self.at,
            })
        } else {
            Ok(())
        }
    }
}
