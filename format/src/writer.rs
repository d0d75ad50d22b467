//! Writing a store: streaming, crash-safe, resumable.
//!
//! [`StoreWriter::create`] writes `<path>.partial` beside the target: the header (with the
//! COMPLETE flag clear), metadata, sample points and sample maps, then syncs. Cubes are
//! appended as records (see `docs/format.md`); the file is synced every
//! [`SYNC_EVERY_CUBES`] cubes or [`SYNC_EVERY_BYTES`] bytes. [`StoreWriter::finish`] writes the
//! table of contents, patches the header, syncs, renames the partial file over `path` and
//! syncs the directory. A crash at any moment leaves either no store or a complete one under
//! the final name; [`StoreWriter::resume`] continues from the partial file.

use std::fs::File;
use std::io::{BufWriter, Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};

use crate::bytes::zero_pad;
use crate::cube::{face_raw_size, EncodedCube, FACES};
use crate::encoding::decode_face_texels;
use crate::error::io_at;
use crate::face_decoder::FaceDecoder;
use crate::header::{Header, Section, FLAG_COMPLETE, FLAG_IRRADIANCE};
use crate::irradiance::{Projection, IRRADIANCE_CUBE_BYTES};
use crate::meta::{SamplePoint, StoreMeta};
pub use crate::output_file::partial_path;
use crate::output_file::{open_partial, Open};
use crate::prefix::Prefix;
use crate::resume::{reopen, Reopened};
use crate::sample_map::SampleMaps;
use crate::toc::{FaceEntry, RecordHeader, RECORD_HEADER_BYTES, TOC_CUBE_BYTES, TOC_ENTRY_BYTES};
use crate::{Error, Filter};
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
        let file = open_partial(path, &partial, Open::Create)?;
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
        bake: &crate::BakeParams,
    ) -> Result<Self, Error> {
        let total = u32::try_from(header.cube_count).map_err(|_| Error::Limit {
            what: "cube count",
            value: header.cube_count,
            max: u64::from(u32::MAX) - 1,
        })?;
        let partial = partial_path(path);
        let file = open_partial(path, &partial, Open::Create)?;
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
            mantissa_bits: bake.mantissa_bits,
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
    /// format [`crate::VERSION`] (a partial file of a development version from before format
    /// 1.0 is refused: bake it again).
    pub fn resume(
        path: &Path,
        meta: &StoreMeta,
        points: &[SamplePoint],
        maps: &SampleMaps,
    ) -> Result<Self, Error> {
        let partial = partial_path(path);
        let filter = Filter::for_store(meta.bake.encoding, meta.bake.mantissa_bits);
        // Validate the inputs before touching the partial file.
        let prefix = Prefix::build(meta, points, maps, filter)?;
        let Reopened {
            file,
            prefix,
            recovered,
        } = reopen(path, &partial, meta, prefix)?;
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
        check_cube_params(&cube, &self.header, self.mantissa_bits)?;
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

    /// Removes the partial file while still holding its lock (so no other writer's file is
    /// removed), for a writer whose inputs turned out bad.
    pub fn discard(self) {
        let _ = std::fs::remove_file(&self.partial);
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
        let irradiance = self.project_cubes()?;
        let irradiance_section = Section {
            offset: self.pos,
            size: irradiance.len() as u64,
        };
        let irradiance_pad = zero_pad(irradiance_section.end());
        let toc_sum = xxh3_64(&self.toc);
        let toc_size = self.toc.len() as u64 + 8;
        let toc_offset = irradiance_section.end() + irradiance_pad as u64;
        let file_size = toc_offset + toc_size;
        self.header.payload.size = payload_size;
        self.header.toc = Section {
            offset: toc_offset,
            size: toc_size,
        };
        self.header.file_size = file_size;
        self.header.decoded_checksum = self.decoded.digest();
        // A merge of shards written by a format 1.0 build still writes format 1.1.
        self.header.version = crate::VERSION;
        self.header.irradiance = irradiance_section;
        self.header.irradiance_checksum = xxh3_64(&irradiance);
        self.header.flags |= FLAG_COMPLETE | FLAG_IRRADIANCE;
        let partial = self.partial.clone();
        let header_bytes = self.header.to_bytes();
        let toc = std::mem::take(&mut self.toc);
        let file = &mut self.file;
        let result = (|| -> std::io::Result<()> {
            file.write_all(&irradiance)?;
            file.write_all(&[0u8; 8][..irradiance_pad])?;
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

impl StoreWriter {
    /// The irradiance section: every cube's faces read back from the partial file as they are
    /// stored (frame checksums checked, decompressed, unfiltered, decoded) and projected onto
    /// the spherical harmonics ([`crate::irradiance`]). Reading back rather than projecting
    /// what `append` was given makes a fresh, a resumed and a merged store alike.
    fn project_cubes(&mut self) -> Result<Vec<u8>, Error> {
        let partial = self.partial.clone();
        self.file.flush().map_err(io_at(&partial, "write"))?;
        let file = File::open(&partial).map_err(io_at(&partial, "read back"))?;
        let mut rd = std::io::BufReader::with_capacity(1 << 20, file);
        let h = &self.header;
        let mut faces = FaceDecoder::new(h, self.mantissa_bits, &partial)?;
        let res = h.cube_resolution;
        let color_bytes = h.encoding.face_bytes(res).unwrap_or(usize::MAX);
        let mut texels = vec![[0.0f32; 3]; (res as usize) * (res as usize)];
        let mut out = Vec::with_capacity(self.total as usize * IRRADIANCE_CUBE_BYTES);
        for cube in 0..self.total {
            let mut projection = Projection::new(res);
            let first = FaceEntry::parse(&self.toc, cube as usize * TOC_CUBE_BYTES);
            rd.seek(SeekFrom::Start(first.offset))
                .map_err(io_at(&partial, "read back"))?;
            for face in 0..FACES {
                let e = FaceEntry::parse(
                    &self.toc,
                    cube as usize * TOC_CUBE_BYTES + face * TOC_ENTRY_BYTES,
                );
                let size = usize::try_from(e.compressed_size).unwrap_or(usize::MAX);
                if faces.read_face(&mut rd, size, e.checksum).is_none() {
                    return Err(Error::io(
                        partial.display().to_string(),
                        std::io::Error::other(format!(
                            "cube {cube}, face {face} (byte offset {}) no longer reads back as it was written",
                            e.offset
                        )),
                    ));
                }
                let color = faces.raw_face().get(..color_bytes).unwrap_or_default();
                decode_face_texels(h.encoding, res, color, &mut texels, cube, face)?;
                projection.face(face, &texels);
            }
            out.extend_from_slice(&crate::irradiance::to_bytes(&projection.finish(cube)?));
        }
        Ok(out)
    }
}

fn raw_of(h: &Header) -> u64 {
    face_raw_size(h.encoding, h.cube_resolution, h.has_distance()).unwrap_or(0)
}

/// A cube's encoding, filter, resolution, distance channel and mantissa bits are the store's.
pub(crate) fn check_cube_params(
    cube: &EncodedCube,
    h: &Header,
    mantissa_bits: u32,
) -> Result<(), Error> {
    if cube.encoding != h.encoding
        || cube.filter != h.filter
        || cube.resolution != h.cube_resolution
        || cube.distance != h.distance_plane()
        || cube.mantissa_bits != mantissa_bits
    {
        return Err(Error::CubeParamsMismatch {
            cube: cube.cube_index,
            detail: format!(
                "cube: {} filter {} {}² distance {} mantissa_bits={}, store: {} filter {} {}² distance {} mantissa_bits={}",
                cube.encoding,
                cube.filter,
                cube.resolution,
                cube.distance,
                cube.mantissa_bits,
                h.encoding,
                h.filter,
                h.cube_resolution,
                h.distance_plane(),
                mantissa_bits
            ),
        });
    }
    Ok(())
}
