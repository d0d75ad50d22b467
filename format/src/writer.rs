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
use std::io::{BufReader, BufWriter, Read, Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};

use crate::bytes::align8;
use crate::cube::{face_raw_size, EncodedCube, FACES};
use crate::error::io_at;
use crate::header::{
    Header, Section, DECODED_CHECKSUM_FIELD, FINISH_FIELDS, FLAGS_FIELD, FLAG_COMPLETE,
    FLAG_DISTANCE, FLAG_ENV_CUBE, HEADER_BYTES, SECTION_CHECKSUMS,
};
use crate::meta::{
    decode_meta, encode_meta, encode_points, validate_points, ObjectInfo, SamplePoint, StoreMeta,
    SAMPLE_POINT_BYTES,
};
use crate::sample_map::{encode_maps, SampleMaps};
use crate::toc::{FaceEntry, RecordHeader, RECORD_HEADER_BYTES, TOC_CUBE_BYTES};
use crate::{Error, Filter, MAGIC, VERSION};
use xxhash_rust::xxh3::{xxh3_64, Xxh3};

/// Sync the partial file at least every this many cubes.
pub const SYNC_EVERY_CUBES: u32 = 64;
/// Sync the partial file at least every this many bytes.
pub const SYNC_EVERY_BYTES: u64 = 64 << 20;

/// What was appended to a partial file since it was last synced; both the store writer and
/// the shard writer sync after [`SYNC_EVERY_CUBES`] cubes or [`SYNC_EVERY_BYTES`] bytes.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct SyncBatch {
    cubes: u32,
    bytes: u64,
}

impl SyncBatch {
    /// Counts one appended cube of `bytes`; true when the file is due a sync.
    pub(crate) fn add(&mut self, bytes: u64) -> bool {
        self.cubes += 1;
        self.bytes += bytes;
        self.cubes >= SYNC_EVERY_CUBES || self.bytes >= SYNC_EVERY_BYTES
    }
}

/// Flushes and syncs a partial file; on failure the writer is marked `failed` (a later
/// append must not write after a hole).
pub(crate) fn sync_partial(
    file: &mut BufWriter<File>,
    partial: &Path,
    batch: &mut SyncBatch,
    failed: &mut bool,
) -> Result<(), Error> {
    if let Err(e) = file.flush().and_then(|()| file.get_ref().sync_data()) {
        *failed = true;
        return Err(io_at(partial, "sync")(e));
    }
    *batch = SyncBatch::default();
    Ok(())
}

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
    /// Hash of the raw faces' checksums so far: the header's decoded-faces checksum.
    decoded: Xxh3,
    unsynced: SyncBatch,
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
pub(crate) struct Prefix {
    pub(crate) header: Header,
    pub(crate) meta: Vec<u8>,
    pub(crate) points: Vec<u8>,
    pub(crate) maps: Vec<u8>,
    pub(crate) total: u32,
}

impl Prefix {
    pub(crate) fn build(
        meta: &StoreMeta,
        points: &[SamplePoint],
        maps: &SampleMaps,
        filter: Filter,
    ) -> Result<Self, Error> {
        Self::build_version(meta, points, maps, filter, VERSION)
    }

    /// [`Prefix::build`] in the layout of format `version` (4 or [`VERSION`]: a version-4
    /// layout, for continuing older partial files, cannot hold mesh objects).
    pub(crate) fn build_version(
        meta: &StoreMeta,
        points: &[SamplePoint],
        maps: &SampleMaps,
        filter: Filter,
        version: u32,
    ) -> Result<Self, Error> {
        let meta_offset = HEADER_BYTES as u64;
        if version < 5 {
            if let Some(i) = meta.objects.iter().position(|o| o.mesh.is_some()) {
                return Err(Error::InvalidMetadata {
                    offset: meta_offset,
                    detail: format!(
                        "object {i} is a triangle mesh, which format version {version} cannot hold"
                    ),
                });
            }
        }
        let meta_bytes = encode_meta(meta, version);
        // Validate by decoding what was encoded (same checks as the reader).
        let decoded = decode_meta(&meta_bytes, meta_offset, version)?;
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
            meta.map_count(),
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
            version,
            flags,
            encoding: meta.bake.encoding,
            filter,
            index_width,
            cube_resolution: meta.bake.cube_resolution,
            sample_map_resolution: meta.bake.sample_map_resolution,
            sample_count,
            cube_count: u64::from(total),
            patch_count: meta.map_count() as u64,
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
            decoded_checksum: 0,
        };
        Ok(Prefix {
            header,
            meta: meta_bytes,
            points: point_bytes,
            maps: map_bytes,
            total,
        })
    }

    /// The bytes `create()` writes before the first cube: header, sections and padding
    /// (`header.payload.offset` bytes).
    pub(crate) fn to_bytes(&self) -> Vec<u8> {
        let mut b = Vec::with_capacity(usize::try_from(self.header.payload.offset).unwrap_or(0));
        b.extend_from_slice(&self.header.to_bytes());
        for (_, s, bytes) in self.sections() {
            b.extend_from_slice(bytes);
            b.extend_from_slice(&[0u8; 8][..zero_pad(s.end())]);
        }
        b
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

pub(crate) fn zero_pad(pos: u64) -> usize {
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
            unsynced: SyncBatch::default(),
            decoded: Xxh3::new(),
            failed: false,
        })
    }

    /// Starts a new store from the bytes `create()` would write before the first cube
    /// (`prefix`, already validated by the caller, whose header is `header`): the merge of
    /// shards ([`crate::shard::merge`]) copies them from a shard file.
    pub(crate) fn create_from_prefix(
        path: &Path,
        prefix: &[u8],
        header: Header,
        mantissa_bits: u32,
    ) -> Result<Self, Error> {
        let total = u32::try_from(header.cube_count).map_err(|_| Error::Limit {
            what: "cube count",
            value: header.cube_count,
            max: u64::from(u32::MAX) - 1,
        })?;
        let partial = partial_path(path);
        let file = File::create(&partial).map_err(io_at(&partial, "create"))?;
        let mut w = BufWriter::with_capacity(1 << 20, file);
        w.write_all(prefix)
            .and_then(|()| w.flush())
            .and_then(|()| w.get_ref().sync_data())
            .map_err(io_at(&partial, "write"))?;
        Ok(StoreWriter {
            path: path.to_path_buf(),
            partial,
            file: w,
            pos: header.payload.offset,
            header,
            mantissa_bits,
            toc: Vec::new(),
            next: 0,
            total,
            cube_bytes: 0,
            unsynced: SyncBatch::default(),
            decoded: Xxh3::new(),
            failed: false,
        })
    }

    /// Reopens `<path>.partial` after an interruption: checks that its header, metadata,
    /// sample points and maps are exactly what [`StoreWriter::create`] would write for these
    /// inputs, keeps every complete cube record whose record and frame checksums are valid
    /// (and whose frames decode), truncates the rest and continues.
    ///
    /// Errors: [`Error::NoPartial`] if there is no partial file;
    /// [`Error::PartialNeverCreated`] if `create()` was interrupted before its fixed sections
    /// were all written (the file is shorter than them, or its header is all zero): it holds
    /// no finished cube maps, so create the store again; [`Error::ResumeMismatch`] if it was
    /// started with different settings (naming each bake parameter, count or object that
    /// differs, the partial's value and this bake's), is damaged, or is not a partial store of
    /// format version 2 to [`VERSION`]. Partial files of versions 2 to 4 are continued and
    /// finished as version 4 (version 2's layout differs from version 4's only in the header's
    /// decoded-faces checksum, which `finish()` writes; version 3's only in the version number,
    /// version 4 adding the BC6H encoding), so they cannot take mesh objects, whose object
    /// records need version 5; version-5 partial files are finished as version 5.
    pub fn resume(
        path: &Path,
        meta: &StoreMeta,
        points: &[SamplePoint],
        maps: &SampleMaps,
    ) -> Result<Self, Error> {
        let partial = partial_path(path);
        let filter = Filter::for_store(meta.bake.encoding, meta.bake.mantissa_bits);
        // Validate the inputs before touching the partial file.
        let mut prefix = Prefix::build(meta, points, maps, filter)?;
        let mut file = open_partial(&partial)?;
        let file_len = file.metadata().map_err(io_at(&partial, "stat"))?.len();
        let mut rd = PartialReader {
            partial: &partial,
            rd: BufReader::with_capacity(1 << 20, &mut file),
            file_len,
        };
        let (got, old) = rd.header()?;
        if old.version < 5 {
            // Versions 2 to 4 share version 4's metadata layout: continue as version 4.
            prefix = Prefix::build_version(meta, points, maps, filter, 4).map_err(|e| {
                rd.mismatch(format!(
                    "it is format version {}, which this bake cannot continue ({e})",
                    old.version
                ))
            })?;
        }
        let old_meta_bytes = rd.metadata(&old, &prefix.header, meta)?;
        rd.compare_header_and_metadata(got, &old_meta_bytes, &prefix)?;
        drop(old_meta_bytes);
        let pos = rd.sections(&prefix, meta)?;
        let recovered = rd.recover_cubes(&prefix, meta, pos)?;
        drop(rd);
        restore_partial(&mut file, &partial, recovered.pos, &prefix.header)?;
        Ok(StoreWriter {
            path: path.to_path_buf(),
            partial,
            file: BufWriter::with_capacity(1 << 20, file),
            header: prefix.header,
            mantissa_bits: meta.bake.mantissa_bits,
            toc: recovered.toc,
            pos: recovered.pos,
            next: recovered.next,
            total: prefix.total,
            cube_bytes: recovered.cube_bytes,
            decoded: recovered.decoded,
            unsynced: SyncBatch::default(),
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
        for sum in cube.raw_checksums {
            self.decoded.update(&sum.to_le_bytes());
        }
        self.next += 1;
        if self.unsynced.add(written) {
            self.sync()?;
        }
        Ok(())
    }

    /// Flushes and syncs the partial file, so the cubes appended so far survive a kill.
    pub fn sync(&mut self) -> Result<(), Error> {
        self.check_usable()?;
        sync_partial(
            &mut self.file,
            &self.partial,
            &mut self.unsynced,
            &mut self.failed,
        )
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
        self.header.decoded_checksum = self.decoded.digest();
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

/// Opens the partial file `partial` for reading and writing; [`Error::NoPartial`] if there is
/// none.
fn open_partial(partial: &Path) -> Result<File, Error> {
    match OpenOptions::new().read(true).write(true).open(partial) {
        Ok(f) => Ok(f),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
            Err(Error::NoPartial(partial.to_path_buf()))
        }
        Err(e) => Err(io_at(partial, "open")(e)),
    }
}

/// The end of the errors that find a partial file's fixed sections differ from this bake's
/// although every setting is the same.
const SAME_SETTINGS: &str =
    "although every setting is the same (written by another version of oslf?)";

/// A partial file read front to back by [`StoreWriter::resume`], and the errors it reports.
struct PartialReader<'a> {
    partial: &'a Path,
    rd: BufReader<&'a mut File>,
    file_len: u64,
}

/// The complete cube records found in a partial file, and where the next one goes.
struct Recovered {
    /// Their TOC entries.
    toc: Vec<u8>,
    /// How many there are.
    next: u32,
    /// Their compressed bytes.
    cube_bytes: u64,
    /// Hash of their raw faces' checksums.
    decoded: Xxh3,
    /// The end of the last one.
    pos: u64,
}

impl PartialReader<'_> {
    /// [`Error::ResumeMismatch`] saying `what` differs or is damaged.
    fn mismatch(&self, what: String) -> Error {
        Error::ResumeMismatch {
            path: self.partial.to_path_buf(),
            what,
        }
    }

    /// [`Error::PartialNeverCreated`] with `detail`.
    fn never_created(&self, detail: String) -> Error {
        Error::PartialNeverCreated {
            path: self.partial.to_path_buf(),
            detail,
        }
    }

    /// Reads exactly `buf.len()` bytes.
    fn read(&mut self, buf: &mut [u8]) -> Result<(), Error> {
        self.rd.read_exact(buf).map_err(io_at(self.partial, "read"))
    }

    /// Reads the header, its bytes and parsed: refuses a file whose fixed sections `create()`
    /// never finished and a header that is not a resumable partial's.
    fn header(&mut self) -> Result<([u8; HEADER_BYTES], Header), Error> {
        let file_len = self.file_len;
        if file_len < HEADER_BYTES as u64 {
            return Err(self.never_created(format!(
                "it has {file_len} bytes, less than its {HEADER_BYTES}-byte header"
            )));
        }
        let mut got = [0u8; HEADER_BYTES];
        self.read(&mut got)?;
        if got.iter().all(|b| *b == 0) {
            return Err(self.never_created("its header is all zero bytes".into()));
        }
        let old = parse_partial_header(&got).map_err(|what| self.mismatch(what))?;
        // create() writes the fixed sections front to back, then syncs, before any cube.
        let fixed_end = old.payload.offset;
        if file_len < fixed_end {
            return Err(self.never_created(format!(
                "it has {file_len} bytes, less than the {fixed_end} bytes of its header, metadata, sample points and sample maps"
            )));
        }
        Ok((got, old))
    }

    /// Reads the metadata section (of header `old`), checks its checksum and compares its
    /// settings with this bake's (`new_header`, `meta`); returns its bytes.
    fn metadata(
        &mut self,
        old: &Header,
        new_header: &Header,
        meta: &StoreMeta,
    ) -> Result<Vec<u8>, Error> {
        // Decode the partial's metadata and compare the settings field by field.
        let mut old_meta_bytes = vec![0u8; usize::try_from(old.meta.size).unwrap_or(0)];
        self.read(&mut old_meta_bytes)?;
        let computed = xxh3_64(&old_meta_bytes);
        if computed != old.meta_checksum {
            return Err(self.mismatch(format!(
                "its metadata section (byte offset {}) is damaged: checksum {computed:#018x}, its header says {:#018x}",
                old.meta.offset, old.meta_checksum
            )));
        }
        let old_meta = decode_meta(&old_meta_bytes, old.meta.offset, old.version)
            .map_err(|e| self.mismatch(format!("its metadata section is damaged: {e}")))?;
        let differences = setting_differences(old, &old_meta, new_header, meta, "this bake");
        if !differences.is_empty() {
            return Err(Error::ResumeSettings {
                path: self.partial.to_path_buf(),
                differences,
            });
        }
        Ok(old_meta_bytes)
    }

    /// Compares the header bytes `got` and metadata bytes with those `create()` writes for
    /// this bake (`prefix`), leaving out what `finish()` patches.
    fn compare_header_and_metadata(
        &self,
        mut got: [u8; HEADER_BYTES],
        old_meta_bytes: &[u8],
        prefix: &Prefix,
    ) -> Result<(), Error> {
        // finish() may have patched the header before a crash: compare without those fields.
        // The section checksums are left out too: the sections themselves are compared next.
        // A version-2 or version-3 partial file is continued as version 4, the layout it
        // shares.
        let mut want = prefix.header.to_bytes();
        got[8..12].copy_from_slice(&prefix.header.version.to_le_bytes());
        let normalise = |b: &mut [u8; HEADER_BYTES]| {
            b[FINISH_FIELDS].fill(0);
            b[SECTION_CHECKSUMS].fill(0);
            b[DECODED_CHECKSUM_FIELD].fill(0);
            b[FLAGS_FIELD.start] &= !(FLAG_COMPLETE as u8);
            b[248..].fill(0);
        };
        normalise(&mut got);
        normalise(&mut want);
        if got != want {
            let at = got.iter().zip(&want).position(|(a, b)| a != b).unwrap_or(0);
            return Err(self.mismatch(format!(
                "its header differs from this bake's at byte {at} {SAME_SETTINGS}"
            )));
        }
        if old_meta_bytes != prefix.meta {
            return Err(self.mismatch(format!(
                "its metadata bytes differ from this bake's {SAME_SETTINGS}"
            )));
        }
        Ok(())
    }

    /// Compares the sample points and maps (read after the metadata) and their padding with
    /// this bake's (`prefix`); returns the payload's offset.
    fn sections(&mut self, prefix: &Prefix, meta: &StoreMeta) -> Result<u64, Error> {
        let mut pos = prefix.header.meta.end();
        let mut buf = Vec::new();
        // The metadata was compared above; then the sample points and maps.
        for (name, s, bytes) in prefix.sections().into_iter().skip(1) {
            // The padding before this section, then the section.
            let len = s.end() - pos;
            buf.resize(len as usize, 0);
            self.read(&mut buf)?;
            let start = (s.offset - pos) as usize;
            let got = buf.get(start..start + bytes.len()).unwrap_or(&[]);
            if got != bytes {
                let at = got.iter().zip(bytes).position(|(a, b)| a != b).unwrap_or(0);
                let which = match name {
                    "sample points" => format!("point {}", at / SAMPLE_POINT_BYTES),
                    _ => {
                        let per_patch = (bytes.len() / meta.map_count().max(1)).max(1);
                        format!("map {}", at / per_patch)
                    }
                };
                return Err(self.mismatch(format!(
                    "its {name} differ from this bake's ({which}, byte offset {}) {SAME_SETTINGS}",
                    s.offset + at as u64
                )));
            }
            pos = s.end();
        }
        // The padding before the payload.
        let pad = zero_pad(pos);
        let mut padding = [0u8; 8];
        self.read(&mut padding[..pad])?;
        pos += pad as u64;
        debug_assert_eq!(pos, prefix.header.payload.offset);
        Ok(pos)
    }

    /// Reads the cube records from `pos` (the payload's offset) on and keeps the complete ones,
    /// up to the first torn or damaged record.
    fn recover_cubes(
        &mut self,
        prefix: &Prefix,
        meta: &StoreMeta,
        mut pos: u64,
    ) -> Result<Recovered, Error> {
        // Recover complete cube records: valid record headers and frame checksums, frames that
        // decode to their raw size (the decoded-faces checksum is rebuilt from them).
        let mut faces = FaceDecoder::new(&prefix.header, meta.bake.mantissa_bits, self.partial)?;
        let mut decoded = Xxh3::new();
        let mut toc = Vec::new();
        let mut next = 0u32;
        let mut cube_bytes = 0u64;
        while next < prefix.total {
            let Some((entries, raw_sums, end)) = self.record(&mut faces, pos, next) else {
                break;
            };
            for e in entries {
                toc.extend_from_slice(&e.to_bytes());
                cube_bytes += e.compressed_size;
            }
            for s in raw_sums {
                decoded.update(&s.to_le_bytes());
            }
            pos = end;
            next += 1;
        }
        Ok(Recovered {
            toc,
            next,
            cube_bytes,
            decoded,
            pos,
        })
    }

    /// Reads the record of cube `cube` at `pos`: its TOC entries, its raw faces' checksums and
    /// where it ends (after its padding); `None` if it is torn, damaged or of another cube.
    fn record(
        &mut self,
        faces: &mut FaceDecoder,
        pos: u64,
        cube: u32,
    ) -> Option<([FaceEntry; FACES], [u64; FACES], u64)> {
        let file_len = self.file_len;
        let rd = &mut self.rd;
        let mut rec = [0u8; RECORD_HEADER_BYTES];
        if pos + RECORD_HEADER_BYTES as u64 > file_len || rd.read_exact(&mut rec).is_err() {
            return None;
        }
        let r = RecordHeader::parse(&rec).ok()?;
        if r.cube != cube {
            return None;
        }
        let mut off = pos + RECORD_HEADER_BYTES as u64;
        let mut entries = [FaceEntry::default(); FACES];
        let mut raw_sums = [0u64; FACES];
        for (face, (c, r, sum)) in r.faces.iter().enumerate() {
            let end = off.checked_add(*c);
            if *r != faces.raw
                || *c == 0
                || *c > faces.bound as u64
                || end.is_none_or(|e| e > file_len)
            {
                return None;
            }
            raw_sums[face] = faces.read_face(rd, *c as usize, *sum)?;
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
            return None;
        }
        Some((entries, raw_sums, off + pad as u64))
    }
}

/// Checks and decodes the face frames of a partial file's cube records, reusing its buffers.
struct FaceDecoder<'h> {
    header: &'h Header,
    mantissa_bits: u32,
    /// Bytes of a raw face, as records state it and as a length.
    raw: u64,
    raw_len: usize,
    /// The largest frame a raw face compresses to.
    bound: usize,
    /// Bytes of a filtered face, as a frame decompresses to.
    filtered_len: usize,
    dctx: zstd::bulk::Decompressor<'static>,
    frame: Vec<u8>,
    filtered: Vec<u8>,
    raw_face: Vec<u8>,
}

impl<'h> FaceDecoder<'h> {
    /// A decoder for the faces of a store with header `h` and `mantissa_bits`.
    fn new(h: &'h Header, mantissa_bits: u32, partial: &Path) -> Result<Self, Error> {
        let raw = face_raw_size(h.encoding, h.cube_resolution, h.has_distance())?;
        let raw_len = usize::try_from(raw).unwrap_or(usize::MAX);
        let bound = zstd::zstd_safe::compress_bound(raw_len);
        let filtered_len = crate::filter::filtered_face_size(
            h.filter,
            h.encoding,
            h.cube_resolution,
            h.has_distance(),
            mantissa_bits,
        )
        .unwrap_or(usize::MAX);
        let dctx = zstd::bulk::Decompressor::new()
            .map_err(|e| Error::io(partial.display().to_string(), e))?;
        Ok(FaceDecoder {
            header: h,
            mantissa_bits,
            raw,
            raw_len,
            bound,
            filtered_len,
            dctx,
            frame: Vec::new(),
            filtered: Vec::new(),
            raw_face: Vec::new(),
        })
    }

    /// Reads a frame of `size` bytes from `rd` and checks it against `checksum` and that it
    /// decodes; returns its raw face's checksum, `None` if it is unreadable or damaged.
    fn read_face(&mut self, rd: &mut impl Read, size: usize, checksum: u64) -> Option<u64> {
        let h = self.header;
        self.frame.resize(size, 0);
        if rd.read_exact(&mut self.frame).is_err() || xxh3_64(&self.frame) != checksum {
            return None;
        }
        self.filtered.resize(self.filtered_len, 0);
        self.raw_face.resize(self.raw_len, 0);
        let decodes = self
            .dctx
            .decompress_to_buffer(&self.frame, &mut self.filtered)
            .is_ok_and(|n| n == self.filtered_len)
            && crate::filter::unfilter_face_quantized(
                h.filter,
                h.encoding,
                h.cube_resolution,
                h.has_distance(),
                self.mantissa_bits,
                &self.filtered,
                &mut self.raw_face,
            )
            .is_ok();
        if !decodes {
            return None;
        }
        Some(xxh3_64(&self.raw_face))
    }
}

/// Drops the partial file's tail from `pos` on, writes `header` (the partial header) back,
/// syncs, and leaves the file at `pos`.
fn restore_partial(
    file: &mut File,
    partial: &Path,
    pos: u64,
    header: &Header,
) -> Result<(), Error> {
    // Drop the torn tail (or a TOC from an interrupted finish) and restore the partial
    // header.
    let wr = io_at(partial, "truncate");
    file.set_len(pos).map_err(wr)?;
    file.seek(SeekFrom::Start(0))
        .map_err(io_at(partial, "seek"))?;
    file.write_all(&header.to_bytes())
        .map_err(io_at(partial, "write"))?;
    file.seek(SeekFrom::Start(pos))
        .map_err(io_at(partial, "seek"))?;
    file.sync_all().map_err(io_at(partial, "sync"))?;
    Ok(())
}

/// Parses the header of a partial file for [`StoreWriter::resume`]: an OSLF header of a
/// resumable version (2 to [`VERSION`]) whose fixed sections lie in the order and at the
/// places `create()` puts them. The error says what is wrong with it.
fn parse_partial_header(bytes: &[u8; HEADER_BYTES]) -> Result<Header, String> {
    if bytes[..8] != MAGIC {
        return Err(format!(
            "it is not an OSLF store (its first bytes are {:02x?}, not \"OSLFSTOR\")",
            &bytes[..8]
        ));
    }
    let version = u32::from_le_bytes([bytes[8], bytes[9], bytes[10], bytes[11]]);
    if !(2..=VERSION).contains(&version) {
        return Err(format!(
            "it is format version {version}, and this writer continues only versions 2 to {VERSION}"
        ));
    }
    let h = Header::parse(bytes).map_err(|e| format!("its header is damaged: {e}"))?;
    let after = |s: Section| align8(s.end());
    let in_order = h.meta.offset == HEADER_BYTES as u64
        && Some(h.points.offset) == after(h.meta)
        && Some(h.maps.offset) == after(h.points)
        && Some(h.payload.offset) == after(h.maps);
    if !in_order {
        return Err(
            "its header is damaged: the sections are not where the writer puts them".into(),
        );
    }
    Ok(h)
}

/// How a setting compared by [`setting_differences`] reads from a store's header and
/// metadata, as its messages print it.
type ReadSetting = fn(&Header, &StoreMeta) -> String;

/// The settings [`setting_differences`] compares, in the order it names them: the name its
/// messages use and how to read the value.
const SETTINGS: [(&str, ReadSetting); 16] = [
    ("scene hash (the scene file's text)", |_, m| {
        let s: String = m.bake.scene_hash[..8]
            .iter()
            .map(|v| format!("{v:02x}"))
            .collect();
        format!("{s}…")
    }),
    ("seed", |_, m| m.bake.seed.to_string()),
    ("cube_resolution", |_, m| m.bake.cube_resolution.to_string()),
    ("sample count", |h, _| h.sample_count.to_string()),
    ("sample_map_resolution", |_, m| {
        m.bake.sample_map_resolution.to_string()
    }),
    ("samples_per_texel", |_, m| {
        m.bake.samples_per_texel.to_string()
    }),
    ("bounces", |_, m| m.bake.bounces.to_string()),
    ("epsilon", |_, m| m.bake.epsilon.to_string()),
    ("phi_samplemap", |_, m| {
        format!("{}°", m.bake.phi_samplemap_deg)
    }),
    ("encoding", |_, m| m.bake.encoding.to_string()),
    ("mantissa_bits", |_, m| m.bake.mantissa_bits.to_string()),
    ("face filter", |h, _| h.filter.to_string()),
    ("distance_channel", |_, m| {
        m.bake.distance_channel.to_string()
    }),
    ("zstd_level", |_, m| m.bake.zstd_level.to_string()),
    ("env_cube", |_, m| m.has_env_cube.to_string()),
    ("camera", |_, m| match &m.camera {
        Some(c) => format!(
            "position {:?}, target {:?}, up {:?}, vfov {}°",
            c.position, c.target, c.up, c.vfov_deg
        ),
        None => "none".into(),
    }),
];

/// How a field compared by [`setting_differences`] reads from an object.
type ReadObjectField = fn(&ObjectInfo) -> String;

/// The fields of an object [`setting_differences`] compares, named as its messages name them
/// after the object.
const OBJECT_FIELDS: [(&str, ReadObjectField); 4] = [
    ("name", |o| format!("{:?}", o.name)),
    ("transform", |o| format!("{:?}", o.transform)),
    ("colour", |o| format!("{:?}", o.base_color)),
    ("patches", |o| {
        format!(
            "{}..{}",
            o.first_patch,
            u64::from(o.first_patch) + u64::from(o.patch_count)
        )
    }),
];

/// What an object is made of, as [`setting_differences`] names it.
fn object_kind(o: &ObjectInfo) -> String {
    match &o.mesh {
        None => "Bézier patches".to_string(),
        Some(m) => format!(
            "triangle mesh ({} vertices, {} triangles, {}×{} atlas pages)",
            m.positions.len(),
            m.triangles.len(),
            m.atlas_grid,
            m.atlas_grid
        ),
    }
}

/// What differs between the settings a partial file was started with (`old`) and those of
/// the bake that wants to continue it (`new`): one `"name old (this bake: new)"` per bake
/// parameter, count, camera, object or patch. Empty if they agree.
pub(crate) fn setting_differences(
    old_header: &Header,
    old: &StoreMeta,
    new_header: &Header,
    new: &StoreMeta,
    new_label: &str,
) -> Vec<String> {
    let mut d = Vec::new();
    let mut diff = |name: &str, a: String, b: String| {
        if a != b {
            d.push(format!("{name} {a} ({new_label}: {b})"));
        }
    };
    for (name, read) in SETTINGS {
        diff(name, read(old_header, old), read(new_header, new));
    }
    let mut mesh_note = None;
    if old.objects.len() != new.objects.len() {
        diff(
            "object count",
            old.objects.len().to_string(),
            new.objects.len().to_string(),
        );
    } else if let Some((i, (x, y))) = old
        .objects
        .iter()
        .zip(&new.objects)
        .enumerate()
        .find(|(_, (x, y))| x != y)
    {
        let object = format!("object {i} ({:?})", y.name);
        for (field, read) in OBJECT_FIELDS {
            diff(&format!("{object} {field}"), read(x), read(y));
        }
        let (a, b) = (object_kind(x), object_kind(y));
        if a != b {
            diff(&format!("{object} kind"), a, b);
        } else if x.mesh != y.mesh {
            mesh_note = Some(format!("the vertices or triangles of {object}"));
        }
    }
    if old.patches.len() != new.patches.len() {
        diff(
            "patch count",
            old.patches.len().to_string(),
            new.patches.len().to_string(),
        );
    } else if let Some(i) = old
        .patches
        .iter()
        .zip(&new.patches)
        .position(|(x, y)| x != y)
    {
        d.push(format!("the control points of patch {i}"));
    }
    d.extend(mesh_note);
    d
}
