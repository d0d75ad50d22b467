//! Writing a store: streaming, crash-safe, resumable.
//!
//! [`StoreWriter::create`] writes `<path>.partial` beside the target: the header (with the
//! COMPLETE flag clear), metadata, sample points and sample maps, then syncs. Cubes are
//! appended as records (see the crate docs); the file is synced every
//! [`SYNC_EVERY_CUBES`] cubes or [`SYNC_EVERY_BYTES`] bytes. [`StoreWriter::finish`] writes the
//! table of contents, patches the header, syncs, renames the partial file over `path` and
//! syncs the directory. A crash at any moment leaves either no store or a complete one under
//! the final name; [`StoreWriter::resume`] continues from the partial file.

use std::fs::{File, OpenOptions};
use std::io::{BufWriter, Read, Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};

use crate::bytes::align8;
use crate::cube::{face_raw_size, EncodedCube, FACES};
use crate::error::io_at;
use crate::header::{
    Header, Section, FILTER_OFFSET, FINISH_FIELDS, FLAGS_FIELD, FLAG_COMPLETE, FLAG_DISTANCE,
    FLAG_ENV_CUBE, HEADER_BYTES, SECTION_CHECKSUMS,
};
use crate::meta::{
    decode_meta, encode_meta, encode_points, validate_points, SamplePoint, StoreMeta,
    SAMPLE_POINT_BYTES,
};
use crate::sample_map::{encode_maps, SampleMaps};
use crate::toc::{FaceEntry, RecordHeader, RECORD_HEADER_BYTES, TOC_CUBE_BYTES};
use crate::{Error, Filter, VERSION};
use xxhash_rust::xxh3::{xxh3_64, Xxh3};

/// Sync the partial file at least every this many cubes.
pub const SYNC_EVERY_CUBES: u32 = 64;
/// Sync the partial file at least every this many bytes.
pub const SYNC_EVERY_BYTES: u64 = 64 << 20;

/// What [`StoreWriter::finish`] wrote.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct StoreSummary {
    /// Size of the store in bytes.
    pub file_size: u64,
    /// Compressed bytes of all cube faces.
    pub cube_bytes: u64,
    /// Raw (encoded, uncompressed) bytes of all cube faces.
    pub raw_cube_bytes: u64,
    /// Cube-map texels stored (cubes × 6 × res²).
    pub texels: u64,
    /// Cubes stored.
    pub cubes: u32,
    /// Sample points stored.
    pub sample_points: u64,
}

/// Appends cubes to a partial store; see the module docs.
pub struct StoreWriter {
    path: PathBuf,
    partial: PathBuf,
    file: BufWriter<File>,
    header: Header,
    /// RGB9E5 mantissa bits of the store (the metadata's); appended cubes must match.
    mantissa_bits: u32,
    /// The TOC entries so far (192 bytes per cube).
    toc: Vec<u8>,
    pos: u64,
    next: u32,
    total: u32,
    cube_bytes: u64,
    unsynced_cubes: u32,
    unsynced_bytes: u64,
    /// Set after an I/O error: the file's state is unknown, so nothing more is written.
    failed: bool,
}

/// `<path>.partial`, beside `path`.
pub fn partial_path(path: &Path) -> PathBuf {
    let mut name = path
        .file_name()
        .map(|n| n.to_os_string())
        .unwrap_or_default();
    name.push(".partial");
    path.with_file_name(name)
}

/// Everything before the cube payload, as `create()` writes it.
struct Prefix {
    header: Header,
    meta: Vec<u8>,
    points: Vec<u8>,
    maps: Vec<u8>,
    total: u32,
}

impl Prefix {
    fn build(
        meta: &StoreMeta,
        points: &[SamplePoint],
        maps: &SampleMaps,
        filter: Filter,
    ) -> Result<Self, Error> {
        let meta_bytes = encode_meta(meta, VERSION);
        // Validate by decoding what was encoded (same checks as the reader).
        let meta_offset = HEADER_BYTES as u64;
        let decoded = decode_meta(&meta_bytes, meta_offset, VERSION)?;
        if decoded != *meta {
            return Err(Error::InvalidMetadata {
                offset: meta_offset,
                detail: "metadata does not survive encoding (counts above u32::MAX?)".into(),
            });
        }
        validate_points(points, meta)?;
        let sample_count = points.len() as u64;
        let total = sample_count
            .checked_add(u64::from(meta.has_env_cube))
            .and_then(|t| u32::try_from(t).ok())
            .ok_or(Error::Limit {
                what: "cube count",
                value: sample_count,
                max: u64::from(u32::MAX) - 1,
            })?;
        let (index_width, map_bytes) = encode_maps(
            maps,
            meta.patches.len(),
            meta.bake.sample_map_resolution,
            sample_count,
        )?;
        let point_bytes = encode_points(points);
        debug_assert_eq!(point_bytes.len(), points.len() * SAMPLE_POINT_BYTES);
        let sect = |offset: u64, size: usize| Section {
            offset,
            size: size as u64,
        };
        let m = sect(meta_offset, meta_bytes.len());
        let p = sect(align8(m.end()).unwrap_or(u64::MAX), point_bytes.len());
        let s = sect(align8(p.end()).unwrap_or(u64::MAX), map_bytes.len());
        let payload = sect(align8(s.end()).unwrap_or(u64::MAX), 0);
        let mut flags = 0;
        if meta.bake.distance_channel {
            flags |= FLAG_DISTANCE;
        }
        if meta.has_env_cube {
            flags |= FLAG_ENV_CUBE;
        }
        let header = Header {
            version: VERSION,
            flags,
            encoding: meta.bake.encoding,
            filter,
            index_width,
            cube_resolution: meta.bake.cube_resolution,
            sample_map_resolution: meta.bake.sample_map_resolution,
            sample_count,
            cube_count: u64::from(total),
            patch_count: meta.patches.len() as u64,
            object_count: meta.objects.len() as u64,
            meta: m,
            points: p,
            maps: s,
            payload,
            toc: Section::default(),
            file_size: 0,
            meta_checksum: xxh3_64(&meta_bytes),
            points_checksum: xxh3_64(&point_bytes),
            maps_checksum: xxh3_64(&map_bytes),
        };
        Ok(Prefix {
            header,
            meta: meta_bytes,
            points: point_bytes,
            maps: map_bytes,
            total,
        })
    }

    /// The sections in file order with their names.
    fn sections(&self) -> [(&'static str, Section, &[u8]); 3] {
        [
            ("metadata", self.header.meta, &self.meta),
            ("sample points", self.header.points, &self.points),
            ("sample maps", self.header.maps, &self.maps),
        ]
    }
}

fn zero_pad(pos: u64) -> usize {
    (align8(pos).unwrap_or(pos) - pos) as usize
}

impl StoreWriter {
    /// Starts a new store: validates the inputs (metadata, every sample point, every
    /// sample-map index `< points.len()`), writes `<path>.partial` (replacing any old one)
    /// up to the cube payload and syncs it.
    ///
    /// The store records [`Filter::for_store`] of its encoding and mantissa bits, the filter
    /// [`crate::encode_cube`] uses.
    pub fn create(
        path: &Path,
        meta: &StoreMeta,
        points: &[SamplePoint],
        maps: &SampleMaps,
    ) -> Result<Self, Error> {
        let filter = Filter::for_store(meta.bake.encoding, meta.bake.mantissa_bits);
        Self::create_with_filter(path, meta, points, maps, filter)
    }

    /// [`StoreWriter::create`] recording face filter `filter`: every appended cube must be
    /// encoded with it ([`crate::cube::encode_cube_with_filter`]). [`StoreWriter::resume`]
    /// continues only partial files that use [`Filter::for_store`].
    pub fn create_with_filter(
        path: &Path,
        meta: &StoreMeta,
        points: &[SamplePoint],
        maps: &SampleMaps,
        filter: Filter,
    ) -> Result<Self, Error> {
        let prefix = Prefix::build(meta, points, maps, filter)?;
        let partial = partial_path(path);
        let file = File::create(&partial).map_err(io_at(&partial, "create"))?;
        let mut w = BufWriter::with_capacity(1 << 20, file);
        let io = io_at(&partial, "write");
        let mut write = || -> std::io::Result<()> {
            w.write_all(&prefix.header.to_bytes())?;
            for (_, s, bytes) in prefix.sections() {
                w.write_all(bytes)?;
                w.write_all(&[0u8; 8][..zero_pad(s.end())])?;
            }
            w.flush()?;
            w.get_ref().sync_data()
        };
        write().map_err(io)?;
        Ok(StoreWriter {
            path: path.to_path_buf(),
            partial,
            file: w,
            pos: prefix.header.payload.offset,
            header: prefix.header,
            mantissa_bits: meta.bake.mantissa_bits,
            toc: Vec::new(),
            next: 0,
            total: prefix.total,
            cube_bytes: 0,
            unsynced_cubes: 0,
            unsynced_bytes: 0,
            failed: false,
        })
    }

    /// Reopens `<path>.partial` after an interruption: checks that its header, metadata,
    /// sample points and maps are exactly what [`StoreWriter::create`] would write for these
    /// inputs ([`Error::ResumeMismatch`] naming what differs), keeps every complete cube record
    /// whose record and frame checksums are valid, truncates the rest and continues.
    /// [`Error::NoPartial`] if there is no partial file.
    pub fn resume(
        path: &Path,
        meta: &StoreMeta,
        points: &[SamplePoint],
        maps: &SampleMaps,
    ) -> Result<Self, Error> {
        let partial = partial_path(path);
        let filter = Filter::for_store(meta.bake.encoding, meta.bake.mantissa_bits);
        let prefix = Prefix::build(meta, points, maps, filter)?;
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
        let payload_offset = prefix.header.payload.offset;
        if file_len < payload_offset {
            return Err(mismatch(format!(
                "the partial file has {file_len} bytes, less than the {payload_offset} bytes of its fixed sections (killed during create?)"
            )));
        }
        let mut rd = std::io::BufReader::with_capacity(1 << 20, &mut file);
        let read_err = io_at(&partial, "read");
        let mut got = [0u8; HEADER_BYTES];
        rd.read_exact(&mut got).map_err(read_err)?;
        // finish() may have patched the header before a crash: compare without those fields.
        // The section checksums are left out too: the sections themselves are compared next,
        // which says precisely what differs.
        let mut want = prefix.header.to_bytes();
        let normalise = |b: &mut [u8; HEADER_BYTES]| {
            b[FINISH_FIELDS].fill(0);
            b[SECTION_CHECKSUMS].fill(0);
            b[FLAGS_FIELD.start] &= !(FLAG_COMPLETE as u8);
            b[248..].fill(0);
        };
        normalise(&mut got);
        normalise(&mut want);
        if got != want {
            let at = got.iter().zip(&want).position(|(a, b)| a != b).unwrap_or(0);
            if (8..12).contains(&at) {
                return Err(mismatch(format!(
                    "the partial file is format version {}, this writer writes version {VERSION}",
                    u32::from_le_bytes([got[8], got[9], got[10], got[11]])
                )));
            }
            if (FILTER_OFFSET..FILTER_OFFSET + 4).contains(&at) {
                return Err(mismatch(format!(
                    "the partial file uses face filter id {}, this bake filter {} (id {}), the filter of {} with mantissa_bits {} (different mantissa_bits?)",
                    u32::from_le_bytes([
                        got[FILTER_OFFSET],
                        got[FILTER_OFFSET + 1],
                        got[FILTER_OFFSET + 2],
                        got[FILTER_OFFSET + 3]
                    ]),
                    filter,
                    filter.id(),
                    meta.bake.encoding,
                    meta.bake.mantissa_bits
                )));
            }
            return Err(mismatch(format!(
                "header differs at byte {at} (encoding, resolutions, counts or section sizes changed)"
            )));
        }
        let mut pos = HEADER_BYTES as u64;
        let mut buf = Vec::new();
        for (name, s, bytes) in prefix.sections() {
            let len = s.end() - pos + zero_pad(s.end()) as u64;
            buf.resize(len as usize, 0);
            rd.read_exact(&mut buf).map_err(io_at(&partial, "read"))?;
            let start = (s.offset - pos) as usize;
            let got = buf.get(start..start + bytes.len()).unwrap_or(&[]);
            if got != bytes {
                let at = got.iter().zip(bytes).position(|(a, b)| a != b).unwrap_or(0);
                // The same header (version included) means the same metadata layout.
                let partial_bits = (name == "metadata")
                    .then(|| decode_meta(got, s.offset, VERSION).ok())
                    .flatten()
                    .map(|m| m.bake.mantissa_bits)
                    .filter(|b| *b != meta.bake.mantissa_bits);
                let detail = match (name, partial_bits) {
                    ("metadata", Some(bits)) => format!(
                        "metadata differ: the partial file was baked with mantissa_bits {bits}, this bake has {}",
                        meta.bake.mantissa_bits
                    ),
                    ("sample points", _) => format!(
                        "sample points differ (point {}, byte {})",
                        at / SAMPLE_POINT_BYTES,
                        s.offset + at as u64
                    ),
                    _ => format!("{name} differ at byte {}", s.offset + at as u64),
                };
                return Err(mismatch(detail));
            }
            pos = s.end() + zero_pad(s.end()) as u64;
        }

        // Recover complete cube records.
        let raw = face_raw_size(
            prefix.header.encoding,
            prefix.header.cube_resolution,
            prefix.header.has_distance(),
        )?;
        let bound = zstd::zstd_safe::compress_bound(usize::try_from(raw).unwrap_or(usize::MAX));
        let mut toc = Vec::new();
        let mut next = 0u32;
        let mut cube_bytes = 0u64;
        let mut chunk = vec![0u8; 1 << 16];
        'records: while next < prefix.total {
            let mut rec = [0u8; RECORD_HEADER_BYTES];
            if pos + RECORD_HEADER_BYTES as u64 > file_len || rd.read_exact(&mut rec).is_err() {
                break;
            }
            let Ok(h) = RecordHeader::parse(&rec) else {
                break;
            };
            if h.cube != next {
                break;
            }
            let mut off = pos + RECORD_HEADER_BYTES as u64;
            let mut entries = [FaceEntry::default(); FACES];
            for (face, (c, r, sum)) in h.faces.iter().enumerate() {
                let end = off.checked_add(*c);
                if *r != raw || *c == 0 || *c > bound as u64 || end.is_none_or(|e| e > file_len) {
                    break 'records;
                }
                let mut hasher = Xxh3::new();
                let mut left = *c;
                while left > 0 {
                    let n = left.min(chunk.len() as u64) as usize;
                    let Some(part) = chunk.get_mut(..n) else {
                        break 'records;
                    };
                    if rd.read_exact(part).is_err() {
                        break 'records;
                    }
                    hasher.update(part);
                    left -= n as u64;
                }
                if hasher.digest() != *sum {
                    break 'records;
                }
                entries[face] = FaceEntry {
                    offset: off,
                    compressed_size: *c,
                    raw_size: *r,
                    checksum: *sum,
                };
                off += *c;
            }
            let pad = zero_pad(off);
            let mut padding = [0u8; 8];
            if off + pad as u64 > file_len || rd.read_exact(&mut padding[..pad]).is_err() {
                break;
            }
            for e in entries {
                toc.extend_from_slice(&e.to_bytes());
                cube_bytes += e.compressed_size;
            }
            pos = off + pad as u64;
            next += 1;
        }
        drop(rd);

        // Drop the torn tail (or a TOC from an interrupted finish) and restore the partial
        // header.
        let wr = io_at(&partial, "truncate");
        file.set_len(pos).map_err(wr)?;
        file.seek(SeekFrom::Start(0))
            .map_err(io_at(&partial, "seek"))?;
        file.write_all(&prefix.header.to_bytes())
            .map_err(io_at(&partial, "write"))?;
        file.seek(SeekFrom::Start(pos))
            .map_err(io_at(&partial, "seek"))?;
        file.sync_all().map_err(io_at(&partial, "sync"))?;
        Ok(StoreWriter {
            path: path.to_path_buf(),
            partial,
            file: BufWriter::with_capacity(1 << 20, file),
            header: prefix.header,
            mantissa_bits: meta.bake.mantissa_bits,
            toc,
            pos,
            next,
            total: prefix.total,
            cube_bytes,
            unsynced_cubes: 0,
            unsynced_bytes: 0,
            failed: false,
        })
    }

    /// How many cubes are already in (cubes are appended strictly in index order).
    pub fn next_cube(&self) -> u32 {
        self.next
    }

    /// Cubes the finished store holds: sample points, plus the environment cube if any.
    pub fn total_cubes(&self) -> u32 {
        self.total
    }

    /// The path of the partial file.
    pub fn partial_path(&self) -> &Path {
        &self.partial
    }

    fn check_usable(&self) -> Result<(), Error> {
        if self.failed {
            return Err(Error::io(
                format!("{}", self.partial.display()),
                std::io::Error::other("an earlier write failed; resume the store to continue"),
            ));
        }
        Ok(())
    }

    /// Appends cube [`StoreWriter::next_cube`].
    pub fn append(&mut self, cube: EncodedCube) -> Result<(), Error> {
        self.check_usable()?;
        let index = cube.cube_index;
        if index >= self.total {
            return Err(Error::CubeOutOfRange {
                cube: index,
                count: self.total,
            });
        }
        if index != self.next {
            return Err(Error::CubeOutOfOrder {
                expected: self.next,
                got: index,
            });
        }
        let h = &self.header;
        if cube.encoding != h.encoding
            || cube.filter != h.filter
            || cube.resolution != h.cube_resolution
            || cube.distance_channel != h.has_distance()
            || cube.mantissa_bits != self.mantissa_bits
        {
            return Err(Error::CubeParamsMismatch {
                cube: index,
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
                    self.mantissa_bits
                ),
            });
        }
        let faces = std::array::from_fn(|f| {
            (
                cube.frames[f].len() as u64,
                cube.raw_size,
                cube.checksums[f],
            )
        });
        let record = RecordHeader { cube: index, faces };
        let mut off = self.pos + RECORD_HEADER_BYTES as u64;
        let mut entries = Vec::with_capacity(TOC_CUBE_BYTES);
        for (f, frame) in cube.frames.iter().enumerate() {
            let e = FaceEntry {
                offset: off,
                compressed_size: frame.len() as u64,
                raw_size: cube.raw_size,
                checksum: cube.checksums[f],
            };
            entries.extend_from_slice(&e.to_bytes());
            off += frame.len() as u64;
        }
        let pad = zero_pad(off);
        let result = (|| -> std::io::Result<()> {
            self.file.write_all(&record.to_bytes())?;
            for frame in &cube.frames {
                self.file.write_all(frame)?;
            }
            self.file.write_all(&[0u8; 8][..pad])
        })();
        if let Err(e) = result {
            self.failed = true;
            return Err(io_at(&self.partial, "write")(e));
        }
        let written = off + pad as u64 - self.pos;
        self.pos += written;
        self.toc.extend_from_slice(&entries);
        self.cube_bytes += cube.compressed_bytes();
        self.next += 1;
        self.unsynced_cubes += 1;
        self.unsynced_bytes += written;
        if self.unsynced_cubes >= SYNC_EVERY_CUBES || self.unsynced_bytes >= SYNC_EVERY_BYTES {
            self.sync()?;
        }
        Ok(())
    }

    /// Flushes and syncs the partial file, so the cubes appended so far survive a kill.
    pub fn sync(&mut self) -> Result<(), Error> {
        self.check_usable()?;
        let r = self
            .file
            .flush()
            .and_then(|()| self.file.get_ref().sync_data());
        if let Err(e) = r {
            self.failed = true;
            return Err(io_at(&self.partial, "sync")(e));
        }
        self.unsynced_cubes = 0;
        self.unsynced_bytes = 0;
        Ok(())
    }

    /// Writes the table of contents, patches the header, syncs, renames the partial file over
    /// the target path and syncs the directory. Fails with [`Error::Incomplete`] unless every
    /// cube was appended.
    pub fn finish(mut self) -> Result<StoreSummary, Error> {
        self.check_usable()?;
        if self.next != self.total {
            return Err(Error::Incomplete {
                present: self.next,
                total: self.total,
            });
        }
        let payload_size = self.pos - self.header.payload.offset;
        let toc_sum = xxh3_64(&self.toc);
        let toc_size = self.toc.len() as u64 + 8;
        let toc_offset = self.pos;
        let file_size = toc_offset + toc_size;
        self.header.payload.size = payload_size;
        self.header.toc = Section {
            offset: toc_offset,
            size: toc_size,
        };
        self.header.file_size = file_size;
        self.header.flags |= FLAG_COMPLETE;
        let partial = self.partial.clone();
        let header_bytes = self.header.to_bytes();
        let toc = std::mem::take(&mut self.toc);
        let file = &mut self.file;
        let result = (|| -> std::io::Result<()> {
            file.write_all(&toc)?;
            file.write_all(&toc_sum.to_le_bytes())?;
            file.flush()?;
            file.get_ref().sync_data()?;
            let f = file.get_mut();
            f.seek(SeekFrom::Start(0))?;
            f.write_all(&header_bytes)?;
            f.sync_all()
        })();
        result.map_err(io_at(&partial, "finish"))?;
        std::fs::rename(&partial, &self.path).map_err(io_at(&self.path, "rename"))?;
        let dir = match self.path.parent() {
            Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
            _ => PathBuf::from("."),
        };
        File::open(&dir)
            .and_then(|d| d.sync_all())
            .map_err(io_at(&dir, "sync directory"))?;
        let res = u64::from(self.header.cube_resolution);
        Ok(StoreSummary {
            file_size,
            cube_bytes: self.cube_bytes,
            raw_cube_bytes: u64::from(self.total) * FACES as u64 * raw_of(&self.header),
            texels: u64::from(self.total) * FACES as u64 * res * res,
            cubes: self.total,
            sample_points: self.header.sample_count,
        })
    }
}

fn raw_of(h: &Header) -> u64 {
    face_raw_size(h.encoding, h.cube_resolution, h.has_distance()).unwrap_or(0)
}
