//! Little-endian byte cursors for the metadata section and headers.

use crate::Error;

/// Appends little-endian values to a buffer.
#[derive(Default)]
pub(crate) struct ByteWriter {
    buf: Vec<u8>,
}

impl ByteWriter {
    pub(crate) fn u32(&mut self, v: u32) {
        self.buf.extend_from_slice(&v.to_le_bytes());
    }
    pub(crate) fn i32(&mut self, v: i32) {
        self.buf.extend_from_slice(&v.to_le_bytes());
    }
    pub(crate) fn u64(&mut self, v: u64) {
        self.buf.extend_from_slice(&v.to_le_bytes());
    }
    pub(crate) fn f32(&mut self, v: f32) {
        self.buf.extend_from_slice(&v.to_le_bytes());
    }
    pub(crate) fn bytes(&mut self, v: &[u8]) {
        self.buf.extend_from_slice(v);
    }
    pub(crate) fn into_inner(self) -> Vec<u8> {
        self.buf
    }
}

/// Reads little-endian values from an untrusted section; every read is bounds-checked and
/// fails with [`Error::InvalidMetadata`] naming the absolute file offset.
pub(crate) struct ByteReader<'a> {
    bytes: &'a [u8],
    pos: usize,
    base: u64,
    section: &'static str,
}

impl<'a> ByteReader<'a> {
    pub(crate) fn new(bytes: &'a [u8], base: u64, section: &'static str) -> Self {
        ByteReader {
            bytes,
            pos: 0,
            base,
            section,
        }
    }

    /// Absolute file offset of the next byte.
    pub(crate) fn offset(&self) -> u64 {
        self.base.saturating_add(self.pos as u64)
    }

    pub(crate) fn remaining(&self) -> usize {
        self.bytes.len().saturating_sub(self.pos)
    }

    pub(crate) fn take(&mut self, n: usize) -> Result<&'a [u8], Error> {
        let end = self.pos.checked_add(n);
        match end.and_then(|end| self.bytes.get(self.pos..end)) {
            Some(s) => {
                self.pos += n;
                Ok(s)
            }
            None => Err(Error::InvalidMetadata {
                offset: self.offset(),
                detail: format!(
                    "{} section ends early: {n} more bytes needed, {} remain",
                    self.section,
                    self.remaining()
                ),
            }),
        }
    }

    fn array<const N: usize>(&mut self) -> Result<[u8; N], Error> {
        let mut a = [0u8; N];
        a.copy_from_slice(self.take(N)?);
        Ok(a)
    }

    pub(crate) fn u32(&mut self) -> Result<u32, Error> {
        Ok(u32::from_le_bytes(self.array()?))
    }
    pub(crate) fn i32(&mut self) -> Result<i32, Error> {
        Ok(i32::from_le_bytes(self.array()?))
    }
    pub(crate) fn u64(&mut self) -> Result<u64, Error> {
        Ok(u64::from_le_bytes(self.array()?))
    }
    /// An `f32`, finite or not (callers check).
    pub(crate) fn f32(&mut self) -> Result<f32, Error> {
        Ok(f32::from_le_bytes(self.array()?))
    }

    /// A finite `f32`; `what` names the field in the error.
    pub(crate) fn finite_f32(&mut self, what: &str) -> Result<f32, Error> {
        let at = self.offset();
        let v = f32::from_le_bytes(self.array()?);
        if v.is_finite() {
            Ok(v)
        } else {
            Err(Error::InvalidMetadata {
                offset: at,
                detail: format!("{what}: {v} is not finite"),
            })
        }
    }

    /// A `u32` that must be 0 or 1.
    pub(crate) fn bool(&mut self, what: &str) -> Result<bool, Error> {
        let at = self.offset();
        match self.u32()? {
            0 => Ok(false),
            1 => Ok(true),
            v => Err(Error::InvalidMetadata {
                offset: at,
                detail: format!("{what}: {v} is not 0 or 1"),
            }),
        }
    }
}

/// Reads a little-endian `u32` at `off` of a slice already known to be long enough; returns 0
/// past the end instead of panicking.
pub(crate) fn le_u32(b: &[u8], off: usize) -> u32 {
    let mut a = [0u8; 4];
    if let Some(s) = off.checked_add(4).and_then(|end| b.get(off..end)) {
        a.copy_from_slice(s);
    }
    u32::from_le_bytes(a)
}

/// Reads a little-endian `u64` at `off` (0 past the end, never panics).
pub(crate) fn le_u64(b: &[u8], off: usize) -> u64 {
    let mut a = [0u8; 8];
    if let Some(s) = off.checked_add(8).and_then(|end| b.get(off..end)) {
        a.copy_from_slice(s);
    }
    u64::from_le_bytes(a)
}

/// Rounds up to a multiple of 8 (`None` on overflow).
pub(crate) fn align8(v: u64) -> Option<u64> {
    v.checked_add(7).map(|v| v & !7)
}

/// The zero bytes that pad `pos` to a multiple of 8.
pub(crate) fn zero_pad(pos: u64) -> usize {
    (align8(pos).unwrap_or(pos) - pos) as usize
}
