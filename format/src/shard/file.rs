//! The parts of a shard file (see the layout in the [`crate::shard`] docs): its header, and
//! each cube's record with its trailer of raw-face checksums.

use std::io::Read;

use xxhash_rust::xxh3::xxh3_64;

use crate::bytes::{align8, le_u32, le_u64, zero_pad};
use crate::cube::{face_raw_size, EncodedCube, FACES};
use crate::header::{Header, HEADER_BYTES};
use crate::shard::spec::ShardSpec;
use crate::toc::{RecordHeader, RECORD_HEADER_BYTES};

pub use crate::SHARD_MAGIC;
/// The shard format version this crate writes and reads.
pub const SHARD_VERSION: u32 = 1;
/// Bytes of the shard header.
pub const SHARD_HEADER_BYTES: usize = 128;
/// Bytes of the raw-face checksums after each cube record.
pub const TRAILER_BYTES: usize = 56;
pub(crate) const SHARD_CHECKSUM_OFFSET: usize = 120;
pub(crate) const SHARD_COMPLETE: u32 = 1;

/// The shard header; see the module docs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct ShardHeader {
    pub(crate) flags: u32,
    pub(crate) spec: ShardSpec,
    pub(crate) cube_count: u64,
    pub(crate) shard_cubes: u64,
    pub(crate) prefix_size: u64,
    pub(crate) prefix_checksum: u64,
    pub(crate) file_size: u64,
}

impl ShardHeader {
    pub(crate) fn to_bytes(self) -> [u8; SHARD_HEADER_BYTES] {
        let mut b = [0u8; SHARD_HEADER_BYTES];
        b[0..8].copy_from_slice(&SHARD_MAGIC);
        b[8..12].copy_from_slice(&SHARD_VERSION.to_le_bytes());
        b[12..16].copy_from_slice(&self.flags.to_le_bytes());
        b[16..20].copy_from_slice(&self.spec.index().to_le_bytes());
        b[20..24].copy_from_slice(&self.spec.count().to_le_bytes());
        for (i, v) in [
            self.cube_count,
            self.shard_cubes,
            self.prefix_size,
            self.prefix_checksum,
            self.file_size,
        ]
        .iter()
        .enumerate()
        {
            b[24 + 8 * i..32 + 8 * i].copy_from_slice(&v.to_le_bytes());
        }
        let sum = xxh3_64(&b[..SHARD_CHECKSUM_OFFSET]);
        b[SHARD_CHECKSUM_OFFSET..].copy_from_slice(&sum.to_le_bytes());
        b
    }

    /// Parses and checks a shard header; `Err` says what is wrong.
    pub(crate) fn parse(b: &[u8; SHARD_HEADER_BYTES]) -> Result<Self, String> {
        if b[..8] != SHARD_MAGIC {
            return Err(format!(
                "it is not an OSLF shard (its first bytes are {:02x?}, not \"OSLFSHRD\")",
                &b[..8]
            ));
        }
        let version = le_u32(b, 8);
        if version != SHARD_VERSION {
            return Err(format!(
                "it is shard format version {version}; this oslf reads version {SHARD_VERSION}"
            ));
        }
        let stored = le_u64(b, SHARD_CHECKSUM_OFFSET);
        let computed = xxh3_64(&b[..SHARD_CHECKSUM_OFFSET]);
        if stored != computed {
            return Err(format!(
                "its shard header is damaged: checksum at byte offset {SHARD_CHECKSUM_OFFSET} is {stored:#018x}, computed {computed:#018x}"
            ));
        }
        let flags = le_u32(b, 12);
        if flags & !SHARD_COMPLETE != 0 {
            return Err(format!(
                "its shard header has unknown flag bits {:#x} (byte offset 12)",
                flags & !SHARD_COMPLETE
            ));
        }
        if let Some(at) = b[64..SHARD_CHECKSUM_OFFSET].iter().position(|&v| v != 0) {
            return Err(format!(
                "its shard header's reserved byte at offset {} is not zero",
                64 + at
            ));
        }
        let (index, count) = (le_u32(b, 16), le_u32(b, 20));
        let spec = ShardSpec::new(index, count).map_err(|_| {
            format!(
                "its shard header says shard {index}/{count} (byte offset 16), which is impossible"
            )
        })?;
        let h = ShardHeader {
            flags,
            spec,
            cube_count: le_u64(b, 24),
            shard_cubes: le_u64(b, 32),
            prefix_size: le_u64(b, 40),
            prefix_checksum: le_u64(b, 48),
            file_size: le_u64(b, 56),
        };
        let expected = u32::try_from(h.cube_count)
            .map(|t| u64::from(spec.cubes_of(t)))
            .map_err(|_| format!("its cube count {} is above 2³²−1", h.cube_count))?;
        if h.shard_cubes != expected {
            return Err(format!(
                "its shard header says it holds {} cubes (byte offset 32), but shard {spec} of {} cubes holds {expected}",
                h.shard_cubes, h.cube_count
            ));
        }
        if h.prefix_size < HEADER_BYTES as u64 || !h.prefix_size.is_multiple_of(8) {
            return Err(format!(
                "its prefix size {} (byte offset 40) is not a store's payload offset",
                h.prefix_size
            ));
        }
        Ok(h)
    }

    pub(crate) fn records_offset(&self) -> u64 {
        (SHARD_HEADER_BYTES as u64).saturating_add(self.prefix_size)
    }
}

pub(crate) fn record_header(cube: &EncodedCube) -> RecordHeader {
    RecordHeader {
        cube: cube.cube_index,
        faces: std::array::from_fn(|f| {
            (
                cube.frames[f].len() as u64,
                cube.raw_size,
                cube.checksums[f],
            )
        }),
    }
}

/// Bytes of a cube's record in a shard: record header, frames, padding, trailer. Records
/// start 8-aligned, so the padding depends only on the record's own length.
pub(crate) fn record_len(cube: &EncodedCube) -> u64 {
    let body = RECORD_HEADER_BYTES as u64 + cube.compressed_bytes();
    align8(body).unwrap_or(body) + TRAILER_BYTES as u64
}

pub(crate) fn trailer(raw_checksums: &[u64; FACES]) -> [u8; TRAILER_BYTES] {
    let mut t = [0u8; TRAILER_BYTES];
    for (f, s) in raw_checksums.iter().enumerate() {
        t[8 * f..8 * f + 8].copy_from_slice(&s.to_le_bytes());
    }
    let sum = xxh3_64(&t[..48]);
    t[48..].copy_from_slice(&sum.to_le_bytes());
    t
}

/// Reads the record of cube `expected` at `pos` (the reader's position) of a shard of the
/// store whose header is `h`: checks the record header, every frame's checksum, the padding
/// and the trailer. Returns the cube and the bytes read; `Err` says what is wrong, with the
/// byte offset.
pub(crate) fn read_record(
    rd: &mut impl Read,
    pos: u64,
    file_len: u64,
    expected: u32,
    h: &Header,
) -> Result<(EncodedCube, u64), String> {
    let raw = face_raw_size(h.encoding, h.cube_resolution, h.has_distance())
        .map_err(|e| e.to_string())?;
    let bound = zstd::zstd_safe::compress_bound(usize::try_from(raw).unwrap_or(usize::MAX)) as u64;
    let truncated = |what: &str, at: u64| {
        format!("the file ends inside {what} of cube {expected} (byte offset {at})")
    };
    if pos + RECORD_HEADER_BYTES as u64 > file_len {
        return Err(truncated("the record header", pos));
    }
    let mut rec = [0u8; RECORD_HEADER_BYTES];
    rd.read_exact(&mut rec)
        .map_err(|e| format!("cannot read cube {expected} at byte offset {pos}: {e}"))?;
    let r = RecordHeader::parse(&rec)
        .map_err(|e| format!("cube {expected}: record header at byte offset {pos}: {e}"))?;
    if r.cube != expected {
        return Err(format!(
            "the record at byte offset {pos} is cube {}, but cube {expected} belongs there",
            r.cube
        ));
    }
    let mut off = pos + RECORD_HEADER_BYTES as u64;
    let mut frames: [Vec<u8>; FACES] = Default::default();
    for (face, (c, r, sum)) in r.faces.iter().enumerate() {
        if *r != raw || *c == 0 || *c > bound {
            return Err(format!(
                "cube {expected}, face {face} (record at byte offset {pos}): {c} compressed bytes of {r} raw bytes, but faces of this store have {raw} raw bytes and at most {bound} compressed"
            ));
        }
        if off + c > file_len {
            return Err(truncated("a frame", off));
        }
        let mut frame = vec![0u8; *c as usize];
        rd.read_exact(&mut frame)
            .map_err(|e| format!("cannot read cube {expected} at byte offset {off}: {e}"))?;
        let computed = xxh3_64(&frame);
        if computed != *sum {
            return Err(format!(
                "cube {expected}, face {face}: frame checksum mismatch at byte offset {off}: stored {sum:#018x}, computed {computed:#018x}"
            ));
        }
        frames[face] = frame;
        off += c;
    }
    let pad = zero_pad(off);
    let mut rest = [0u8; 8 + TRAILER_BYTES];
    let rest = &mut rest[..pad + TRAILER_BYTES];
    if off + rest.len() as u64 > file_len {
        return Err(truncated("the trailer", off));
    }
    rd.read_exact(rest)
        .map_err(|e| format!("cannot read cube {expected} at byte offset {off}: {e}"))?;
    if let Some(at) = rest[..pad].iter().position(|&v| v != 0) {
        return Err(format!(
            "padding byte at byte offset {} (after cube {expected}) is not zero",
            off + at as u64
        ));
    }
    let t = &rest[pad..];
    let stored = le_u64(t, 48);
    let computed = xxh3_64(&t[..48]);
    if stored != computed {
        return Err(format!(
            "cube {expected}: raw-face checksums at byte offset {} are damaged (checksum {stored:#018x}, computed {computed:#018x})",
            off + pad as u64
        ));
    }
    let len = off + rest.len() as u64 - pos;
    let cube = EncodedCube {
        cube_index: expected,
        encoding: h.encoding,
        filter: h.filter,
        resolution: h.cube_resolution,
        distance: h.distance_plane(),
        mantissa_bits: 0, // set by the caller, which knows the metadata
        raw_size: raw,
        checksums: std::array::from_fn(|f| r.faces[f].2),
        raw_checksums: std::array::from_fn(|f| le_u64(t, 8 * f)),
        frames,
    };
    Ok((cube, len))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shard::ShardSpec;

    #[test]
    fn the_shard_header_round_trips_and_detects_damage() {
        let h = ShardHeader {
            flags: SHARD_COMPLETE,
            spec: ShardSpec::new(2, 5).unwrap(),
            cube_count: 25,
            shard_cubes: 5,
            prefix_size: 4096,
            prefix_checksum: 7,
            file_size: 9000,
        };
        let mut b = h.to_bytes();
        assert_eq!(ShardHeader::parse(&b).unwrap(), h);
        b[40] ^= 1;
        assert!(ShardHeader::parse(&b).unwrap_err().contains("checksum"));
        let wrong = ShardHeader {
            shard_cubes: 6,
            ..h
        };
        let e = ShardHeader::parse(&wrong.to_bytes()).unwrap_err();
        assert!(e.contains("holds 5"), "{e}");
    }
}
