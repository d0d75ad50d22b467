//! Shards: a deterministic share of a store's cube maps, baked on its own machine and merged
//! into the store later ([`merge`]), byte for byte the store a single bake writes.
//!
//! Shard `I/N` holds the cubes `i` with `i % N == I` (interleaved: neighbouring sample points
//! cost about the same to trace, so every shard gets a fair share of the expensive ones, and
//! shards differ by at most one cube). Every shard recomputes the sample points and sample
//! maps (they are deterministic) and stores them, so shards need no coordination and any
//! one of them carries everything but the other shards' cubes.
//!
//! ## Shard file layout (shard format version 1)
//!
//! Little-endian, checksums xxh3-64 with seed 0, as in the store.
//!
//! | offset | type      | field |
//! |-------:|-----------|-------|
//! | 0      | `[u8; 8]` | magic [`SHARD_MAGIC`] = `"OSLFSHRD"` |
//! | 8      | `u32`     | shard format version = [`SHARD_VERSION`] (1) |
//! | 12     | `u32`     | flags: bit 0 COMPLETE (set by [`ShardWriter::finish`]); other bits 0 |
//! | 16     | `u32`     | shard index `I` |
//! | 20     | `u32`     | shard count `N` (`I < N`) |
//! | 24     | `u64`     | cube_count of the whole store |
//! | 32     | `u64`     | cubes in this shard (`i < cube_count` with `i % N == I`) |
//! | 40     | `u64`     | prefix size `P` |
//! | 48     | `u64`     | checksum of the prefix's `P` bytes |
//! | 56     | `u64`     | file size (0 until finished) |
//! | 64     | 56 bytes  | reserved, zero |
//! | 120    | `u64`     | checksum of bytes 0..120 |
//!
//! Then the *prefix*: the first `P` bytes of the (unfinished) store exactly as
//! [`crate::StoreWriter::create`] writes them — store header with the COMPLETE flag clear,
//! metadata, sample points, sample maps and their padding; `P` is the cube payload offset.
//! Then, for each cube of the shard in increasing index, the store's cube record (record
//! header, six frames, zero padding to a multiple of 8; see the crate docs) followed by a
//! 56-byte *trailer*: the six `u64` checksums of the raw faces (what the store's
//! decoded-faces checksum hashes) and a `u64` checksum of those 48 bytes.
//!
//! A shard is written to `<path>.partial` and renamed when finished, like a store;
//! [`ShardWriter::resume`] keeps its complete records after a kill. [`merge`] checks that the
//! shards form one complete set (same shard count, every index once, identical prefixes),
//! then writes the store through [`crate::StoreWriter`]: the prefix, the records in cube
//! order, the table of contents.

use std::fs::{File, OpenOptions};
use std::io::{BufReader, BufWriter, Read, Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};

use xxhash_rust::xxh3::xxh3_64;

use crate::bytes::{align8, le_u32, le_u64};
use crate::cube::{face_raw_size, EncodedCube, FACES};
use crate::error::io_at;
use crate::header::{Header, Section, HEADER_BYTES};
use crate::meta::{decode_meta, SamplePoint, StoreMeta};
use crate::sample_map::SampleMaps;
use crate::toc::{RecordHeader, RECORD_HEADER_BYTES};
use crate::writer::{partial_path, setting_differences, sync_partial, zero_pad, Prefix, SyncBatch};
use crate::{Error, Filter, StoreSummary, StoreWriter};

/// The first 8 bytes of every shard file.
pub const SHARD_MAGIC: [u8; 8] = *b"OSLFSHRD";
/// The shard format version this crate writes and reads.
pub const SHARD_VERSION: u32 = 1;
/// Bytes of the shard header.
pub const SHARD_HEADER_BYTES: usize = 128;
/// Bytes of the raw-face checksums after each cube record.
pub const TRAILER_BYTES: usize = 56;
const SHARD_CHECKSUM_OFFSET: usize = 120;
const SHARD_COMPLETE: u32 = 1;

/// Which share of the cubes a shard holds: `index` of `count`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ShardSpec {
    index: u32,
    count: u32,
}

impl ShardSpec {
    /// The shard's index `I`.
    pub fn index(&self) -> u32 {
        self.index
    }

    /// The number of shards `N`.
    pub fn count(&self) -> u32 {
        self.count
    }

    /// Shard `index` of `count`; [`Error::InvalidShardSpec`] unless `index < count`.
    pub fn new(index: u32, count: u32) -> Result<Self, Error> {
        if count == 0 || index >= count {
            return Err(Error::InvalidShardSpec(format!("{index}/{count}")));
        }
        Ok(ShardSpec { index, count })
    }

    /// How many of a store's `total` cubes this shard holds.
    pub fn cubes_of(&self, total: u32) -> u32 {
        if self.index >= total {
            0
        } else {
            (total - 1 - self.index) / self.count + 1
        }
    }

    /// The store's index of this shard's `k`-th cube (`k < cubes_of(total)`).
    pub fn cube(&self, k: u32) -> u32 {
        let i = u64::from(self.index) + u64::from(k) * u64::from(self.count);
        u32::try_from(i).unwrap_or(u32::MAX)
    }
}

impl std::fmt::Display for ShardSpec {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}/{}", self.index, self.count)
    }
}

impl std::str::FromStr for ShardSpec {
    type Err = Error;
    /// Parses `I/N`.
    fn from_str(s: &str) -> Result<Self, Error> {
        let bad = || Error::InvalidShardSpec(s.to_string());
        let (i, n) = s.split_once('/').ok_or_else(bad)?;
        let i = i.trim().parse().map_err(|_| bad())?;
        let n = n.trim().parse().map_err(|_| bad())?;
        ShardSpec::new(i, n).map_err(|_| bad())
    }
}

/// The shard header; see the module docs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct ShardHeader {
    flags: u32,
    spec: ShardSpec,
    cube_count: u64,
    shard_cubes: u64,
    prefix_size: u64,
    prefix_checksum: u64,
    file_size: u64,
}

impl ShardHeader {
    fn to_bytes(self) -> [u8; SHARD_HEADER_BYTES] {
        let mut b = [0u8; SHARD_HEADER_BYTES];
        b[0..8].copy_from_slice(&SHARD_MAGIC);
        b[8..12].copy_from_slice(&SHARD_VERSION.to_le_bytes());
        b[12..16].copy_from_slice(&self.flags.to_le_bytes());
        b[16..20].copy_from_slice(&self.spec.index.to_le_bytes());
        b[20..24].copy_from_slice(&self.spec.count.to_le_bytes());
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
    fn parse(b: &[u8; SHARD_HEADER_BYTES]) -> Result<Self, String> {
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

    fn records_offset(&self) -> u64 {
        (SHARD_HEADER_BYTES as u64).saturating_add(self.prefix_size)
    }
}

/// What [`ShardWriter::finish`] wrote.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ShardSummary {
    /// Size of the shard file in bytes.
    pub file_size: u64,
    /// Cubes in the shard.
    pub cubes: u32,
    /// Compressed bytes of the shard's cube faces.
    pub cube_bytes: u64,
    /// Bytes of the store prefix (header, metadata, sample points, sample maps) it carries.
    pub prefix_bytes: u64,
}

/// Appends one shard's cubes to a shard file; see the module docs.
pub struct ShardWriter {
    path: PathBuf,
    partial: PathBuf,
    file: BufWriter<File>,
    header: ShardHeader,
    store: Header,
    mantissa_bits: u32,
    pos: u64,
    next: u32,
    total: u32,
    cube_bytes: u64,
    unsynced: SyncBatch,
    failed: bool,
}

impl ShardWriter {
    /// Starts shard `spec` of the store these inputs make: writes `<path>.partial` (replacing
    /// any old one) with the shard header and the store prefix, and syncs it.
    pub fn create(
        path: &Path,
        spec: ShardSpec,
        meta: &StoreMeta,
        points: &[SamplePoint],
        maps: &SampleMaps,
    ) -> Result<Self, Error> {
        let prefix = build_prefix(meta, points, maps)?;
        let bytes = prefix.to_bytes();
        let header = ShardHeader {
            flags: 0,
            spec,
            cube_count: u64::from(prefix.total),
            shard_cubes: u64::from(spec.cubes_of(prefix.total)),
            prefix_size: bytes.len() as u64,
            prefix_checksum: xxh3_64(&bytes),
            file_size: 0,
        };
        let partial = partial_path(path);
        let file = File::create(&partial).map_err(io_at(&partial, "create"))?;
        let mut w = BufWriter::with_capacity(1 << 20, file);
        w.write_all(&header.to_bytes())
            .and_then(|()| w.write_all(&bytes))
            .and_then(|()| w.flush())
            .and_then(|()| w.get_ref().sync_data())
            .map_err(io_at(&partial, "write"))?;
        Ok(ShardWriter {
            path: path.to_path_buf(),
            partial,
            file: w,
            pos: header.records_offset(),
            header,
            store: prefix.header,
            mantissa_bits: meta.bake.mantissa_bits,
            next: 0,
            total: spec.cubes_of(prefix.total),
            cube_bytes: 0,
            unsynced: SyncBatch::default(),
            failed: false,
        })
    }

    /// Reopens `<path>.partial` after an interruption: checks that it is shard `spec` and
    /// that its prefix is exactly what [`ShardWriter::create`] writes for these inputs, keeps
    /// every complete cube record (valid record header, frame checksums and trailer),
    /// truncates the rest and continues.
    ///
    /// Errors as [`StoreWriter::resume`]: [`Error::NoPartial`], [`Error::PartialNeverCreated`]
    /// (start over with `create`), [`Error::ResumeMismatch`] naming what differs.
    pub fn resume(
        path: &Path,
        spec: ShardSpec,
        meta: &StoreMeta,
        points: &[SamplePoint],
        maps: &SampleMaps,
    ) -> Result<Self, Error> {
        let partial = partial_path(path);
        let prefix = build_prefix(meta, points, maps)?;
        let bytes = prefix.to_bytes();
        let mut file = match OpenOptions::new().read(true).write(true).open(&partial) {
            Ok(f) => f,
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
                return Err(Error::NoPartial(partial))
            }
            Err(e) => return Err(io_at(&partial, "open")(e)),
        };
        let file_len = file.metadata().map_err(io_at(&partial, "stat"))?.len();
        let mismatch = |what: String| Error::ResumeMismatch {
            path: partial.clone(),
            what,
        };
        let never_created = |detail: String| Error::PartialNeverCreated {
            path: partial.clone(),
            detail,
        };
        if file_len < SHARD_HEADER_BYTES as u64 {
            return Err(never_created(format!(
                "it has {file_len} bytes, less than its {SHARD_HEADER_BYTES}-byte shard header"
            )));
        }
        let mut rd = BufReader::with_capacity(1 << 20, &mut file);
        let mut got = [0u8; SHARD_HEADER_BYTES];
        rd.read_exact(&mut got).map_err(io_at(&partial, "read"))?;
        if got.iter().all(|b| *b == 0) {
            return Err(never_created("its shard header is all zero bytes".into()));
        }
        let old = ShardHeader::parse(&got).map_err(&mismatch)?;
        if old.spec != spec {
            return Err(mismatch(format!(
                "it is shard {}, and this bake is shard {spec}",
                old.spec
            )));
        }
        let records = old.records_offset();
        if file_len < records {
            return Err(never_created(format!(
                "it has {file_len} bytes, less than the {records} bytes of its headers, metadata, sample points and sample maps"
            )));
        }
        // Bounded by the file's length, checked above.
        let mut old_prefix = vec![0u8; old.prefix_size as usize];
        rd.read_exact(&mut old_prefix)
            .map_err(io_at(&partial, "read"))?;
        if old_prefix != bytes {
            return Err(mismatch(describe_difference(
                &old_prefix,
                &bytes,
                "this bake",
            )));
        }
        drop(old_prefix);

        let total = spec.cubes_of(prefix.total);
        let mut pos = records;
        let mut next = 0u32;
        let mut cube_bytes = 0u64;
        while next < total {
            match read_record(&mut rd, pos, file_len, spec.cube(next), &prefix.header) {
                Ok((cube, len)) => {
                    cube_bytes += cube.compressed_bytes();
                    pos += len;
                    next += 1;
                }
                Err(_) => break,
            }
        }
        drop(rd);
        let header = ShardHeader {
            flags: 0,
            file_size: 0,
            ..old
        };
        let wr = io_at(&partial, "truncate");
        file.set_len(pos).map_err(wr)?;
        file.seek(SeekFrom::Start(0))
            .and_then(|_| file.write_all(&header.to_bytes()))
            .and_then(|()| file.seek(SeekFrom::Start(pos)))
            .and_then(|_| file.sync_all())
            .map_err(io_at(&partial, "write"))?;
        Ok(ShardWriter {
            path: path.to_path_buf(),
            partial,
            file: BufWriter::with_capacity(1 << 20, file),
            header,
            store: prefix.header,
            mantissa_bits: meta.bake.mantissa_bits,
            pos,
            next,
            total,
            cube_bytes,
            unsynced: SyncBatch::default(),
            failed: false,
        })
    }

    /// Which shard this is.
    pub fn spec(&self) -> ShardSpec {
        self.header.spec
    }

    /// How many of the shard's cubes are already in.
    pub fn appended(&self) -> u32 {
        self.next
    }

    /// How many cubes the finished shard holds.
    pub fn shard_cubes(&self) -> u32 {
        self.total
    }

    /// How many cubes the merged store holds.
    pub fn store_cubes(&self) -> u32 {
        self.header.cube_count as u32
    }

    /// The partial file's path.
    pub fn partial_path(&self) -> &Path {
        &self.partial
    }

    /// Appends the shard's next cube (store index `spec().cube(appended())`).
    pub fn append(&mut self, cube: EncodedCube) -> Result<(), Error> {
        if self.failed {
            return Err(Error::io(
                format!("{}", self.partial.display()),
                std::io::Error::other("an earlier write failed; resume the shard to continue"),
            ));
        }
        let spec = self.header.spec;
        if self.next >= self.total || cube.cube_index != spec.cube(self.next) {
            return Err(Error::ShardCubeOrder {
                shard: spec.to_string(),
                expected: if self.next < self.total {
                    spec.cube(self.next).to_string()
                } else {
                    "none (the shard is full)".into()
                },
                got: cube.cube_index,
            });
        }
        check_cube_params(&cube, &self.store, self.mantissa_bits)?;
        let record = record_header(&cube);
        let len = record_len(&cube);
        // Records start 8-aligned.
        let pad = zero_pad(RECORD_HEADER_BYTES as u64 + cube.compressed_bytes());
        let trailer = trailer(&cube.raw_checksums);
        let result = (|| -> std::io::Result<()> {
            self.file.write_all(&record.to_bytes())?;
            for frame in &cube.frames {
                self.file.write_all(frame)?;
            }
            self.file.write_all(&[0u8; 8][..pad])?;
            self.file.write_all(&trailer)
        })();
        if let Err(e) = result {
            self.failed = true;
            return Err(io_at(&self.partial, "write")(e));
        }
        self.pos += len;
        self.cube_bytes += cube.compressed_bytes();
        self.next += 1;
        if self.unsynced.add(len) {
            sync_partial(
                &mut self.file,
                &self.partial,
                &mut self.unsynced,
                &mut self.failed,
            )?;
        }
        Ok(())
    }

    /// Marks the shard complete, syncs, renames the partial file over the target path and
    /// syncs the directory. [`Error::Incomplete`] unless every cube of the shard was appended.
    pub fn finish(mut self) -> Result<ShardSummary, Error> {
        if self.next != self.total {
            return Err(Error::Incomplete {
                present: self.next,
                total: self.total,
            });
        }
        self.header.flags |= SHARD_COMPLETE;
        self.header.file_size = self.pos;
        let header = self.header.to_bytes();
        let file = &mut self.file;
        (|| -> std::io::Result<()> {
            file.flush()?;
            file.get_ref().sync_data()?;
            let f = file.get_mut();
            f.seek(SeekFrom::Start(0))?;
            f.write_all(&header)?;
            f.sync_all()
        })()
        .map_err(io_at(&self.partial, "finish"))?;
        std::fs::rename(&self.partial, &self.path).map_err(io_at(&self.path, "rename"))?;
        sync_dir(&self.path)?;
        Ok(ShardSummary {
            file_size: self.pos,
            cubes: self.total,
            cube_bytes: self.cube_bytes,
            prefix_bytes: self.header.prefix_size,
        })
    }
}

fn build_prefix(
    meta: &StoreMeta,
    points: &[SamplePoint],
    maps: &SampleMaps,
) -> Result<Prefix, Error> {
    let filter = Filter::for_store(meta.bake.encoding, meta.bake.mantissa_bits);
    Prefix::build(meta, points, maps, filter)
}

fn sync_dir(path: &Path) -> Result<(), Error> {
    let dir = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    };
    File::open(&dir)
        .and_then(|d| d.sync_all())
        .map_err(io_at(&dir, "sync directory"))
}

fn check_cube_params(cube: &EncodedCube, h: &Header, mantissa_bits: u32) -> Result<(), Error> {
    if cube.encoding != h.encoding
        || cube.filter != h.filter
        || cube.resolution != h.cube_resolution
        || cube.distance_channel != h.has_distance()
        || cube.mantissa_bits != mantissa_bits
    {
        return Err(Error::CubeParamsMismatch {
            cube: cube.cube_index,
            detail: format!(
                "cube: {} filter {} {}² distance={} mantissa_bits={}, store: {} filter {} {}² distance={} mantissa_bits={}",
                cube.encoding,
                cube.filter,
                cube.resolution,
                cube.distance_channel,
                cube.mantissa_bits,
                h.encoding,
                h.filter,
                h.cube_resolution,
                h.has_distance(),
                mantissa_bits
            ),
        });
    }
    Ok(())
}

fn record_header(cube: &EncodedCube) -> RecordHeader {
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
fn record_len(cube: &EncodedCube) -> u64 {
    let body = RECORD_HEADER_BYTES as u64 + cube.compressed_bytes();
    align8(body).unwrap_or(body) + TRAILER_BYTES as u64
}

fn trailer(raw_checksums: &[u64; FACES]) -> [u8; TRAILER_BYTES] {
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
fn read_record(
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
        distance_channel: h.has_distance(),
        mantissa_bits: 0, // set by the caller, which knows the metadata
        raw_size: raw,
        checksums: std::array::from_fn(|f| r.faces[f].2),
        raw_checksums: std::array::from_fn(|f| le_u64(t, 8 * f)),
        frames,
    };
    Ok((cube, len))
}

/// What differs between two store prefixes (`old`, and `new` of `new_label`): the settings
/// (as `StoreWriter::resume` names them), else the section that differs.
fn describe_difference(old: &[u8], new: &[u8], new_label: &str) -> String {
    let parse = |b: &[u8]| -> Option<(Header, StoreMeta)> {
        let h = Header::parse(b).ok()?;
        let start = usize::try_from(h.meta.offset).ok()?;
        let end = usize::try_from(h.meta.end()).ok()?;
        let meta = decode_meta(b.get(start..end)?, h.meta.offset, h.version).ok()?;
        Some((h, meta))
    };
    let (Some((oh, om)), Some((nh, nm))) = (parse(old), parse(new)) else {
        return "its store header or metadata is damaged".into();
    };
    let d = setting_differences(&oh, &om, &nh, &nm, new_label);
    if !d.is_empty() {
        return format!("it was baked with different settings: {}", d.join(", "));
    }
    let differs = |s: Section, t: Section| {
        let get = |b: &[u8], s: Section| -> Option<Vec<u8>> {
            b.get(usize::try_from(s.offset).ok()?..usize::try_from(s.end()).ok()?)
                .map(<[u8]>::to_vec)
        };
        get(old, s) != get(new, t)
    };
    let section = if oh.points_checksum != nh.points_checksum || differs(oh.points, nh.points) {
        "sample points"
    } else if oh.maps_checksum != nh.maps_checksum || differs(oh.maps, nh.maps) {
        "sample maps"
    } else {
        "store headers"
    };
    format!(
        "its {section} differ from {new_label}'s although every setting is the same (baked by another version of oslf?)"
    )
}

/// An open shard file, checked up to its first record.
struct OpenShard {
    path: PathBuf,
    header: ShardHeader,
    reader: BufReader<File>,
    pos: u64,
    file_len: u64,
}

fn open_shard(path: &Path) -> Result<OpenShard, Error> {
    let bad = |detail: String| Error::InvalidShard {
        path: path.to_path_buf(),
        detail,
    };
    let file = File::open(path).map_err(io_at(path, "open"))?;
    let file_len = file.metadata().map_err(io_at(path, "stat"))?.len();
    // Small buffers: the merge holds every shard open at once.
    let mut reader = BufReader::with_capacity(64 << 10, file);
    let mut b = [0u8; SHARD_HEADER_BYTES];
    if file_len < SHARD_HEADER_BYTES as u64 {
        return Err(bad(format!(
            "it has {file_len} bytes, less than a {SHARD_HEADER_BYTES}-byte shard header"
        )));
    }
    reader.read_exact(&mut b).map_err(io_at(path, "read"))?;
    let header = ShardHeader::parse(&b).map_err(bad)?;
    if header.flags & SHARD_COMPLETE == 0 {
        return Err(Error::UnfinishedShard {
            path: path.to_path_buf(),
            shard: header.spec,
        });
    }
    if header.file_size != file_len {
        return Err(bad(format!(
            "shard {} has {file_len} bytes, but its header says {} (truncated or appended to?)",
            header.spec, header.file_size
        )));
    }
    if header.records_offset() > file_len {
        return Err(bad(format!(
            "shard {} ends at byte {file_len}, inside its store prefix (bytes {}..{})",
            header.spec,
            SHARD_HEADER_BYTES,
            header.records_offset()
        )));
    }
    Ok(OpenShard {
        path: path.to_path_buf(),
        header,
        reader,
        pos: SHARD_HEADER_BYTES as u64,
        file_len,
    })
}

/// Reads a shard's store prefix and checks it against the shard header's checksum.
fn read_prefix(s: &mut OpenShard) -> Result<Vec<u8>, Error> {
    let size = usize::try_from(s.header.prefix_size).unwrap_or(usize::MAX);
    let mut b = vec![0u8; size];
    s.reader
        .read_exact(&mut b)
        .map_err(io_at(&s.path, "read"))?;
    s.pos += s.header.prefix_size;
    let computed = xxh3_64(&b);
    if computed != s.header.prefix_checksum {
        return Err(Error::InvalidShard {
            path: s.path.clone(),
            detail: format!(
                "its store prefix (bytes {}..{}) is damaged: checksum {computed:#018x}, its shard header says {:#018x}",
                SHARD_HEADER_BYTES,
                s.header.records_offset(),
                s.header.prefix_checksum
            ),
        });
    }
    Ok(b)
}

/// Checks that `prefix` is what `create()` writes before the first cube of a store: a
/// store header (COMPLETE clear) of the current version, sections in order ending at the
/// payload offset `prefix.len()`, valid section checksums and metadata. Returns the header
/// and the metadata.
fn check_prefix(prefix: &[u8]) -> Result<(Header, StoreMeta), String> {
    let h = Header::parse(prefix).map_err(|e| format!("its store header is damaged: {e}"))?;
    if h.version != crate::VERSION || h.is_complete() {
        return Err(format!(
            "its store header is not an unfinished store of format version {} (version {}, flags {:#x})",
            crate::VERSION,
            h.version,
            h.flags
        ));
    }
    let after = |s: Section| align8(s.end());
    let in_order = h.meta.offset == HEADER_BYTES as u64
        && Some(h.points.offset) == after(h.meta)
        && Some(h.maps.offset) == after(h.points)
        && Some(h.payload.offset) == after(h.maps)
        && h.payload.offset == prefix.len() as u64;
    if !in_order {
        return Err("its store header's sections are not where the writer puts them".into());
    }
    for (name, s, sum) in [
        ("metadata", h.meta, h.meta_checksum),
        ("sample points", h.points, h.points_checksum),
        ("sample maps", h.maps, h.maps_checksum),
    ] {
        let bytes = &prefix[s.offset as usize..s.end() as usize];
        let computed = xxh3_64(bytes);
        if computed != sum {
            return Err(format!(
                "its {name} section (byte offset {} of the store prefix) is damaged: checksum {computed:#018x}, the store header says {sum:#018x}",
                s.offset
            ));
        }
    }
    let meta = decode_meta(
        &prefix[h.meta.offset as usize..h.meta.end() as usize],
        h.meta.offset,
        h.version,
    )
    .map_err(|e| format!("its metadata is damaged: {e}"))?;
    Ok((h, meta))
}

/// Merges a complete set of shard files into the store at `output`, byte-identical to the
/// store a single bake of the same scene and settings writes. Checks first that the shards
/// are finished, undamaged, baked for the same shard count, each index exactly once, and
/// from the same scene, settings and seed (naming what differs); then writes
/// `<output>.partial`, syncs it and renames it over `output` ([`StoreWriter::finish`]).
/// Every frame checksum and raw-face checksum record is checked on the way; a failure
/// removes the partial file.
pub fn merge(shards: &[PathBuf], output: &Path) -> Result<StoreSummary, Error> {
    if shards.is_empty() {
        return Err(Error::ShardSet("no shard files given".into()));
    }
    let mut open = shards
        .iter()
        .map(|p| open_shard(p))
        .collect::<Result<Vec<_>, _>>()?;

    // One shard count, every index once.
    let count = open[0].header.spec.count;
    if let Some(other) = open.iter().find(|s| s.header.spec.count != count) {
        return Err(Error::ShardSet(format!(
            "the shards were baked for different shard counts: {} is shard {}, {} is shard {}",
            open[0].path.display(),
            open[0].header.spec,
            other.path.display(),
            other.header.spec
        )));
    }
    let mut by_index: std::collections::BTreeMap<u32, Vec<&Path>> = Default::default();
    for s in &open {
        by_index
            .entry(s.header.spec.index)
            .or_default()
            .push(&s.path);
    }
    let mut problems = Vec::new();
    let missing_count = count as usize - by_index.len();
    if missing_count > 0 {
        // Name the first few (N may be large).
        const NAMED: usize = 20;
        let mut missing: Vec<String> = (0..count)
            .filter(|i| !by_index.contains_key(i))
            .take(NAMED)
            .map(|i| i.to_string())
            .collect();
        if missing_count > NAMED {
            missing.push(format!("… ({missing_count} in all)"));
        }
        problems.push(format!(
            "shard{} {} of {count} {} missing",
            if missing_count > 1 { "s" } else { "" },
            missing.join(", "),
            if missing_count > 1 { "are" } else { "is" }
        ));
    }
    for (i, paths) in &by_index {
        if paths.len() > 1 {
            let names: Vec<String> = paths.iter().map(|p| p.display().to_string()).collect();
            problems.push(format!(
                "shard {i}/{count} is given {} times ({})",
                paths.len(),
                names.join(", ")
            ));
        }
    }
    if !problems.is_empty() {
        return Err(Error::ShardSet(problems.join("; ")));
    }
    open.sort_by_key(|s| s.header.spec.index);

    // The same store prefix (scene, settings, seed, sample points, sample maps) in all.
    let prefix = read_prefix(&mut open[0])?;
    let (header, meta) = check_prefix(&prefix).map_err(|detail| Error::InvalidShard {
        path: open[0].path.clone(),
        detail,
    })?;
    for i in 1..open.len() {
        let same = open[i].header.prefix_size == open[0].header.prefix_size
            && open[i].header.prefix_checksum == open[0].header.prefix_checksum;
        if same {
            // Skip (and check) the prefix: its checksum equals the first shard's.
            read_prefix(&mut open[i])?;
            continue;
        }
        let other = read_prefix(&mut open[i])?;
        let label = format!("shard {} ({})", open[0].header.spec, open[0].path.display());
        let what = describe_difference(&other, &prefix, &label);
        return Err(Error::ShardSet(format!(
            "shard {} ({}) does not belong with the others: {what}",
            open[i].header.spec,
            open[i].path.display()
        )));
    }
    for s in &open {
        if s.header.cube_count != header.cube_count {
            return Err(Error::InvalidShard {
                path: s.path.clone(),
                detail: format!(
                    "its shard header says the store has {} cubes, its store header {}",
                    s.header.cube_count, header.cube_count
                ),
            });
        }
    }

    let mut writer =
        StoreWriter::create_from_prefix(output, &prefix, header.clone(), meta.bake.mantissa_bits)?;
    let partial = writer.partial_path().to_path_buf();
    let result = (|| -> Result<StoreSummary, Error> {
        for i in 0..writer.total_cubes() {
            let s = &mut open[(i % count) as usize];
            let (mut cube, len) = read_record(&mut s.reader, s.pos, s.file_len, i, &header)
                .map_err(|detail| Error::InvalidShard {
                    path: s.path.clone(),
                    detail,
                })?;
            cube.mantissa_bits = meta.bake.mantissa_bits;
            s.pos += len;
            writer.append(cube)?;
        }
        for s in &open {
            if s.pos != s.file_len {
                return Err(Error::InvalidShard {
                    path: s.path.clone(),
                    detail: format!(
                        "it has {} bytes after its last cube (byte offset {})",
                        s.file_len - s.pos,
                        s.pos
                    ),
                });
            }
        }
        writer.finish()
    })();
    if result.is_err() {
        let _ = std::fs::remove_file(&partial);
    }
    result
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shards_partition_the_cubes() {
        for total in [0u32, 1, 2, 25, 100] {
            for count in [1u32, 2, 3, 7, 30, 200] {
                let mut seen = vec![0u32; total as usize];
                for index in 0..count {
                    let spec = ShardSpec::new(index, count).unwrap();
                    let n = spec.cubes_of(total);
                    for k in 0..n {
                        let i = spec.cube(k);
                        assert_eq!(i % count, index);
                        seen[i as usize] += 1;
                    }
                    assert!(n <= total.div_ceil(count));
                }
                assert!(
                    seen.iter().all(|&n| n == 1),
                    "{total} cubes, {count} shards"
                );
            }
        }
    }

    #[test]
    fn shard_specs_parse_and_refuse() {
        let s: ShardSpec = "3/8".parse().unwrap();
        assert_eq!((s.index(), s.count()), (3, 8));
        assert_eq!(s.to_string(), "3/8");
        for bad in ["8/8", "0/0", "1", "a/2", "1/b", "-1/2", ""] {
            let e = bad.parse::<ShardSpec>().unwrap_err().to_string();
            assert!(e.contains(&format!("{bad:?}")), "{e}");
        }
    }

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
