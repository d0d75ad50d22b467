//! The table of contents and the cube records of the payload section.

use crate::bytes::le_u32;
use crate::bytes::le_u64;
use crate::cube::FACES;
use xxhash_rust::xxh3::xxh3_64;

/// Where one compressed face lives.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub struct FaceEntry {
    /// Absolute byte offset of the zstd frame.
    pub offset: u64,
    /// Bytes of the frame.
    pub compressed_size: u64,
    /// Bytes it decompresses to (the store's face raw size).
    pub raw_size: u64,
    /// xxh3-64 (seed 0) of the compressed frame.
    pub checksum: u64,
}

/// Bytes of one TOC entry.
pub const TOC_ENTRY_BYTES: usize = 32;
/// Bytes of one cube's TOC entries.
pub const TOC_CUBE_BYTES: usize = TOC_ENTRY_BYTES * FACES;

/// Magic of a cube record header: `"OSCR"`.
pub const RECORD_MAGIC: u32 = u32::from_le_bytes(*b"OSCR");
/// Bytes of a cube record header.
pub const RECORD_HEADER_BYTES: usize = 160;
/// Byte offset of the record header's checksum (it covers bytes `0..152`).
const RECORD_CHECKSUM_OFFSET: usize = 152;

impl FaceEntry {
    pub(crate) fn to_bytes(self) -> [u8; TOC_ENTRY_BYTES] {
        let mut b = [0u8; TOC_ENTRY_BYTES];
        for (i, v) in [
            self.offset,
            self.compressed_size,
            self.raw_size,
            self.checksum,
        ]
        .iter()
        .enumerate()
        {
            b[8 * i..8 * i + 8].copy_from_slice(&v.to_le_bytes());
        }
        b
    }

    /// Parses the entry at `off` of `b` (zeros past the end; callers check sizes first).
    pub(crate) fn parse(b: &[u8], off: usize) -> FaceEntry {
        FaceEntry {
            offset: le_u64(b, off),
            compressed_size: le_u64(b, off.saturating_add(8)),
            raw_size: le_u64(b, off.saturating_add(16)),
            checksum: le_u64(b, off.saturating_add(24)),
        }
    }
}

/// A cube record header: magic, cube index, per face (compressed size, raw size, checksum),
/// checksum of the preceding 152 bytes. The six frames follow it back to back.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct RecordHeader {
    pub cube: u32,
    /// (compressed size, raw size, checksum) per face.
    pub faces: [(u64, u64, u64); FACES],
}

impl RecordHeader {
    pub(crate) fn to_bytes(self) -> [u8; RECORD_HEADER_BYTES] {
        let mut b = [0u8; RECORD_HEADER_BYTES];
        b[0..4].copy_from_slice(&RECORD_MAGIC.to_le_bytes());
        b[4..8].copy_from_slice(&self.cube.to_le_bytes());
        for (f, (c, r, s)) in self.faces.iter().enumerate() {
            let o = 8 + 24 * f;
            b[o..o + 8].copy_from_slice(&c.to_le_bytes());
            b[o + 8..o + 16].copy_from_slice(&r.to_le_bytes());
            b[o + 16..o + 24].copy_from_slice(&s.to_le_bytes());
        }
        let sum = xxh3_64(&b[..RECORD_CHECKSUM_OFFSET]);
        b[RECORD_CHECKSUM_OFFSET..].copy_from_slice(&sum.to_le_bytes());
        b
    }

    /// Parses a record header; `Err` says what is wrong (bad length, magic or checksum).
    pub(crate) fn parse(b: &[u8]) -> Result<RecordHeader, String> {
        let Some(b) = b.get(..RECORD_HEADER_BYTES) else {
            return Err(format!(
                "record header needs {RECORD_HEADER_BYTES} bytes, {} available",
                b.len()
            ));
        };
        let magic = le_u32(b, 0);
        if magic != RECORD_MAGIC {
            return Err(format!("bad record magic {magic:#010x}"));
        }
        let stored = le_u64(b, RECORD_CHECKSUM_OFFSET);
        let computed = xxh3_64(&b[..RECORD_CHECKSUM_OFFSET]);
        if stored != computed {
            return Err(format!(
                "record checksum mismatch: stored {stored:#018x}, computed {computed:#018x}"
            ));
        }
        let faces = std::array::from_fn(|f| {
            let o = 8 + 24 * f;
            (le_u64(b, o), le_u64(b, o + 8), le_u64(b, o + 16))
        });
        Ok(RecordHeader {
            cube: le_u32(b, 4),
            faces,
        })
    }
}
