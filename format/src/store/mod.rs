//! Reading a store: [`Store`] validates everything structural on open, then serves zero-copy
//! views of the sample points and maps and checked, decompressed cube faces.

use std::borrow::Cow;
use std::path::Path;

use crate::bytes::align8;
use crate::cube::{face_raw_size, CubeImage, FACES};
use crate::encoding::{decode_distances, decode_face_texels};
use crate::error::io_at;
use crate::file_stamp::FileStamp;
use crate::filter::{unfilter_face_quantized, Filter};
use crate::header::{Header, Section, HEADER_BYTES};
use crate::irradiance::{CubeSh, Projection, IRRADIANCE_CUBE_BYTES};
use crate::meta::{decode_meta, validate_points, SamplePoint, StoreMeta, SAMPLE_POINT_BYTES};
use crate::sample_map::{validate_section, IndexWidth, MapData, SampleMapView, ENTRIES_PER_TEXEL};
use crate::toc::{FaceEntry, RecordHeader, RECORD_HEADER_BYTES, TOC_CUBE_BYTES, TOC_ENTRY_BYTES};
use crate::Error;

mod verify;
pub use verify::VerifyReport;
use xxhash_rust::xxh3::{xxh3_64, Xxh3};

/// 8-byte-aligned owned bytes (the zero-copy views of sample points and maps need the
/// alignment).
struct Aligned {
    words: Vec<u64>,
    len: usize,
}

impl Aligned {
    fn new(len: usize) -> Self {
        Self {
            words: vec![0u64; len.div_ceil(8)],
            len,
        }
    }

    fn bytes(&self) -> &[u8] {
        let all: &[u8] = bytemuck::cast_slice(&self.words);
        all.get(..self.len).unwrap_or(all)
    }

    fn bytes_mut(&mut self) -> &mut [u8] {
        let len = self.len;
        let all: &mut [u8] = bytemuck::cast_slice_mut(&mut self.words);
        &mut all[..len]
    }
}

/// The bytes of a store.
enum Backing {
    /// The whole store in memory ([`Store::from_bytes`]).
    Owned(Aligned),
    /// A file ([`Store::open`]): its fixed sections (header, metadata, sample points, sample
    /// maps: the bytes before the cube payload) and its table of contents are read into memory
    /// when it is opened; cube frames are read with positioned reads when needed. Nothing is
    /// memory-mapped, so a file changed or truncated while open (a `cp` over it) gives errors
    /// that name the offset, never a SIGBUS.
    File {
        file: std::fs::File,
        path: std::path::PathBuf,
        len: u64,
        prefix: Aligned,
        toc_offset: u64,
        toc: Vec<u8>,
    },
    /// A memory-mapped file ([`Store::open_mapped`]): every section and frame is served from
    /// the mapping. `file` stays open holding a shared advisory lock, so this project's writers
    /// refuse to write it in place while it is mapped.
    Mapped {
        map: memmap2::Mmap,
        file: std::fs::File,
        /// The file's size and modification time when it was mapped
        /// ([`Store::changed_since_open`]).
        opened: FileStamp,
    },
}

impl Backing {
    /// The bytes of `s`: borrowed where they are in memory, read from the file otherwise.
    /// Out-of-range sections of an in-memory store give an empty slice (callers validated the
    /// layout); a file that no longer holds them gives [`Error::ChangedOnDisk`].
    fn read(&self, s: Section) -> Result<Cow<'_, [u8]>, Error> {
        match self {
            Backing::Owned(a) => Ok(Cow::Borrowed(slice(a.bytes(), s))),
            Backing::Mapped { map, .. } => Ok(Cow::Borrowed(slice(map, s))),
            Backing::File {
                file,
                path,
                len,
                prefix,
                toc_offset,
                toc,
            } => {
                let end = s.offset.saturating_add(s.size);
                if end <= prefix.len as u64 {
                    return Ok(Cow::Borrowed(slice(prefix.bytes(), s)));
                }
                if s.offset >= *toc_offset && end <= toc_offset.saturating_add(toc.len() as u64) {
                    let local = Section {
                        offset: s.offset - toc_offset,
                        size: s.size,
                    };
                    return Ok(Cow::Borrowed(slice(toc, local)));
                }
                if end > *len {
                    return Ok(Cow::Borrowed(&[]));
                }
                let mut buf = vec![0u8; s.size as usize];
                read_exact_at(file, &mut buf, s.offset).map_err(|e| Error::ChangedOnDisk {
                    path: path.clone(),
                    offset: s.offset,
                    detail: e.to_string(),
                })?;
                Ok(Cow::Owned(buf))
            }
        }
    }

    fn len(&self) -> u64 {
        match self {
            Backing::Owned(a) => a.len as u64,
            Backing::File { len, .. } => *len,
            Backing::Mapped { map, .. } => map.len() as u64,
        }
    }

    /// The bytes from the start of the store that are in memory (at least the header, when
    /// the store has one).
    fn head(&self) -> &[u8] {
        match self {
            Backing::Owned(a) => a.bytes(),
            Backing::File { prefix, .. } => prefix.bytes(),
            Backing::Mapped { map, .. } => map,
        }
    }
}

/// `read_exact` at `offset` without moving a shared cursor (so reads from many threads need no
/// lock).
#[cfg(unix)]
fn read_exact_at(file: &std::fs::File, buf: &mut [u8], offset: u64) -> std::io::Result<()> {
    std::os::unix::fs::FileExt::read_exact_at(file, buf, offset)
}

/// `read_exact` at `offset` without moving a shared cursor (so reads from many threads need no
/// lock).
#[cfg(windows)]
fn read_exact_at(file: &std::fs::File, mut buf: &mut [u8], mut offset: u64) -> std::io::Result<()> {
    while !buf.is_empty() {
        match std::os::windows::fs::FileExt::seek_read(file, buf, offset) {
            Ok(0) => return Err(std::io::ErrorKind::UnexpectedEof.into()),
            Ok(n) => {
                buf = &mut buf[n..];
                offset += n as u64;
            }
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
            Err(e) => return Err(e),
        }
    }
    Ok(())
}

/// Per-thread zstd decompression context and filter scratch buffer, reused between reads.
#[derive(Default)]
struct Decoder {
    dctx: Option<zstd::bulk::Decompressor<'static>>,
    scratch: Vec<u8>,
}

/// Larger scratch buffers are freed after each read rather than kept per thread.
const MAX_KEPT_SCRATCH: usize = 64 << 20;

thread_local! {
    static DECODER: std::cell::RefCell<Decoder> = std::cell::RefCell::new(Decoder::default());
}

/// How [`Store::open_with`] reads a store's file.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum StoreAccess {
    /// [`Store::open`]: the fixed sections read into memory, frames by positioned reads; a
    /// file changed while open gives errors, never SIGBUS. The default.
    #[default]
    Positioned,
    /// [`Store::open_mapped`]: everything served from a memory map; see its risk.
    Mapped,
}

/// An open store. `Send + Sync`: share it between threads.
///
/// # A file that changes while open
///
/// [`Store::open`] keeps the fixed sections and the table of contents in memory and reads cube
/// frames from the file when asked. A file modified, truncated or overwritten while open (the
/// writer never does this: it replaces stores by rename) gives [`Error::ChangedOnDisk`] or a
/// checksum error naming the offset; it is not memory-mapped, so it cannot take the process
/// down with SIGBUS.
pub struct Store {
    backing: Backing,
    header: Header,
    meta: StoreMeta,
    face_raw_size: usize,
    /// The irradiance section, parsed and checked on open (format 1.1).
    irradiance: Option<Vec<CubeSh>>,
}

fn slice(bytes: &[u8], s: Section) -> &[u8] {
    let start = usize::try_from(s.offset).unwrap_or(usize::MAX);
    let end = usize::try_from(s.end()).unwrap_or(usize::MAX);
    bytes.get(start..end).unwrap_or(&[])
}

fn check_sum(section: &'static str, bytes: &[u8], offset: u64, stored: u64) -> Result<(), Error> {
    let computed = xxh3_64(bytes);
    if computed != stored {
        return Err(Error::ChecksumMismatch {
            section,
            offset,
            stored,
            computed,
        });
    }
    Ok(())
}

fn expect_size(section: &'static str, found: u64, expected: Option<u64>) -> Result<(), Error> {
    if expected != Some(found) {
        return Err(Error::SectionSize {
            section,
            found,
            expected: expected.unwrap_or(u64::MAX),
        });
    }
    Ok(())
}

fn check_little_endian() -> Result<(), Error> {
    if cfg!(target_endian = "big") {
        return Err(Error::BigEndianHost);
    }
    Ok(())
}

impl Store {
    /// Opens and validates a store. Its fixed sections and table of contents are read into
    /// memory; cube frames are read from the file when needed (see [`Store`], "A file that
    /// changes while open"). Little-endian hosts only ([`Error::BigEndianHost`] otherwise).
    pub fn open(path: &Path) -> Result<Self, Error> {
        check_little_endian()?;
        // Refuses a FIFO, device or directory before opening it (nothing can block).
        let (file, len) =
            oslf_util::input_file::open(path).map_err(crate::error::open_error(path))?;
        if len < HEADER_BYTES as u64 {
            return Err(Error::Truncated {
                section: "header",
                offset: 0,
                end: HEADER_BYTES as u64,
                file_size: len,
            });
        }
        let mut head = [0u8; HEADER_BYTES];
        read_exact_at(&file, &mut head, 0).map_err(io_at(path, "read"))?;
        let header = Header::parse(&head)?;
        if !header.is_complete() {
            return Err(Error::NotFinished);
        }
        header.check_layout(len)?;
        let read = |offset: u64, size: u64| -> Result<Vec<u8>, Error> {
            let mut buf = vec![0u8; size as usize];
            read_exact_at(&file, &mut buf, offset).map_err(io_at(path, "read"))?;
            Ok(buf)
        };
        let mut prefix = Aligned::new(header.payload.offset as usize);
        read_exact_at(&file, prefix.bytes_mut(), 0).map_err(io_at(path, "read"))?;
        let toc = read(header.toc.offset, header.toc.size)?;
        Self::parse(Backing::File {
            path: path.to_path_buf(),
            len,
            prefix,
            toc_offset: header.toc.offset,
            toc,
            file,
        })
    }

    /// Opens and validates a store through a memory map (memmap2): the same checks and errors
    /// as [`Store::open`], but no section is read into memory: the sample points and maps are
    /// served, zero-copy, from the page cache (a GPU upload reads them straight from the
    /// mapping), and cube frames are read from the mapping when needed.
    ///
    /// # The risk of a mapping
    ///
    /// A file **truncated or overwritten in place** while mapped (e.g. `cp other.oslf` over
    /// it, or a program writing into it) ends the process with SIGBUS on the next read of a
    /// page that is gone; [`Store::open`] reports the same as [`Error::ChangedOnDisk`]. A store
    /// **replaced by rename** (what every writer of this project does: `oslf bake`, `store
    /// merge`, `store convert`) is safe: the mapping keeps the old file. While mapped the
    /// store holds a shared advisory lock (`flock`), so this project's writers, which lock the
    /// file they write exclusively, refuse to write it in place ([`Error::Busy`]); other
    /// programs are not bound by the lock. Where the file system has no such locks the store is
    /// mapped without one. A file written in place without a truncation can serve pages of
    /// both versions, each valid by its checksums: [`Store::changed_since_open`] tells, after
    /// the reads, whether its size or modification time changed. Choose it for stores that only
    /// this project's tools replace.
    pub fn open_mapped(path: &Path) -> Result<Self, Error> {
        check_little_endian()?;
        // Only a regular file is opened, and never blocking (a FIFO is refused at once).
        let (file, _) =
            oslf_util::input_file::open(path).map_err(crate::error::open_error(path))?;
        let meta = file.metadata().map_err(io_at(path, "stat"))?;
        match file.try_lock_shared() {
            Ok(()) => {}
            Err(std::fs::TryLockError::WouldBlock) => {
                return Err(Error::Busy {
                    path: path.to_path_buf(),
                    partial: path.to_path_buf(),
                    holder: crate::output_file::holder(&meta)
                        .unwrap_or_else(|| "another process".into()),
                })
            }
            // No advisory locks on this file system: mapped without one (see above).
            Err(std::fs::TryLockError::Error(_)) => {}
        }
        if meta.len() < HEADER_BYTES as u64 {
            return Err(Error::Truncated {
                section: "header",
                offset: 0,
                end: HEADER_BYTES as u64,
                file_size: meta.len(),
            });
        }
        // SAFETY: the mapping is read-only and lives as long as `Backing::Mapped`, which owns
        // it. It is undefined behaviour only if the file changes while mapped; that is the
        // documented risk of this function (a truncation raises SIGBUS), which the shared lock
        // keeps this project's own writers from causing.
        let map = unsafe { memmap2::Mmap::map(&file) }.map_err(io_at(path, "map"))?;
        let opened = FileStamp::of(path, &meta);
        Self::parse(Backing::Mapped { map, file, opened })
    }

    /// [`Store::open`] or [`Store::open_mapped`], as `access` says.
    pub fn open_with(path: &Path, access: StoreAccess) -> Result<Self, Error> {
        match access {
            StoreAccess::Positioned => Self::open(path),
            StoreAccess::Mapped => Self::open_mapped(path),
        }
    }

    /// For a memory-mapped store ([`Store::open_mapped`]): a description of the change if its
    /// file was written in place since it was mapped (its size or modification time is not
    /// what it was), in which case what was read from the mapping may be of neither version.
    /// `None` when nothing is seen to have changed, and always for the other backings, which
    /// read into memory or fail on a short read. What this cannot see: a writer that keeps the
    /// size and sets the modification time back; a truncation raises SIGBUS before it can be
    /// checked. A store replaced by rename is not a change: the mapping keeps the old file.
    pub fn changed_since_open(&self) -> Option<String> {
        match &self.backing {
            Backing::Mapped { file, opened, .. } => opened.changed(file),
            _ => None,
        }
    }

    /// How this store reads its file.
    pub fn access(&self) -> Option<StoreAccess> {
        match self.backing {
            Backing::Owned(_) => None,
            Backing::File { .. } => Some(StoreAccess::Positioned),
            Backing::Mapped { .. } => Some(StoreAccess::Mapped),
        }
    }

    /// Validates a store held in memory (copied into an 8-byte-aligned buffer). Same checks
    /// as [`Store::open`].
    pub fn from_bytes(bytes: &[u8]) -> Result<Self, Error> {
        check_little_endian()?;
        let mut owned = Aligned::new(bytes.len());
        owned.bytes_mut().copy_from_slice(bytes);
        Self::parse(Backing::Owned(owned))
    }

    fn parse(backing: Backing) -> Result<Self, Error> {
        let file_size = backing.len();
        let header = Header::parse(backing.head())?;
        if !header.is_complete() {
            return Err(Error::NotFinished);
        }
        header.check_layout(file_size)?;
        let h = &header;

        // Metadata.
        let meta_bytes = backing.read(h.meta)?;
        let meta_bytes = &meta_bytes[..];
        check_sum("metadata", meta_bytes, h.meta.offset, h.meta_checksum)?;
        let meta = decode_meta(meta_bytes, h.meta.offset, h.version)?;
        check_against_meta(h, &meta)?;
        check_counts(h)?;

        // Sample points.
        expect_size(
            "sample points",
            h.points.size,
            h.sample_count.checked_mul(SAMPLE_POINT_BYTES as u64),
        )?;
        let point_bytes = backing.read(h.points)?;
        let point_bytes = &point_bytes[..];
        check_sum(
            "sample points",
            point_bytes,
            h.points.offset,
            h.points_checksum,
        )?;
        let points: &[SamplePoint] =
            bytemuck::try_cast_slice(point_bytes).map_err(|_| Error::Misaligned {
                section: "sample points",
                offset: h.points.offset,
            })?;
        validate_points(points, &meta)?;

        // Sample maps.
        let res = u64::from(h.sample_map_resolution);
        let maps_size = res
            .checked_mul(res)
            .and_then(|v| v.checked_mul(ENTRIES_PER_TEXEL as u64))
            .and_then(|v| v.checked_mul(h.index_width.bytes() as u64))
            .and_then(|v| v.checked_mul(h.patch_count));
        expect_size("sample maps", h.maps.size, maps_size)?;
        let map_bytes = backing.read(h.maps)?;
        let map_bytes = &map_bytes[..];
        check_sum("sample maps", map_bytes, h.maps.offset, h.maps_checksum)?;
        let data = map_data(map_bytes, h.index_width, h.maps.offset)?;
        validate_section(data, h.sample_map_resolution, h.sample_count)?;

        // Table of contents.
        let raw = face_raw_size(h.encoding, h.cube_resolution, h.has_distance())?;
        let face_raw = usize::try_from(raw).map_err(|_| Error::Limit {
            what: "face raw size",
            value: raw,
            max: usize::MAX as u64,
        })?;
        expect_size(
            "table of contents",
            h.toc.size,
            h.cube_count
                .checked_mul(TOC_CUBE_BYTES as u64)
                .and_then(|v| v.checked_add(8)),
        )?;
        let toc = backing.read(h.toc)?;
        let toc = &toc[..];
        let entries_len = toc.len().saturating_sub(8);
        let (entries, trailer) = toc.split_at(entries_len);
        let mut stored = [0u8; 8];
        stored.copy_from_slice(trailer.get(..8).unwrap_or(&[0; 8]));
        check_sum(
            "table of contents",
            entries,
            h.toc.offset.saturating_add(entries_len as u64),
            u64::from_le_bytes(stored),
        )?;
        check_toc(entries, h, raw)?;

        // Irradiance (format 1.1).
        let irradiance = if h.has_irradiance() {
            expect_size(
                "irradiance",
                h.irradiance.size,
                h.cube_count.checked_mul(IRRADIANCE_CUBE_BYTES as u64),
            )?;
            let bytes = backing.read(h.irradiance)?;
            check_sum(
                "irradiance",
                &bytes,
                h.irradiance.offset,
                h.irradiance_checksum,
            )?;
            Some(crate::irradiance::parse(&bytes, h.irradiance.offset)?)
        } else {
            None
        };

        Ok(Store {
            header,
            meta,
            face_raw_size: face_raw,
            backing,
            irradiance,
        })
    }

    /// The bytes of `s` where they are always in memory (the fixed sections and the table of
    /// contents); empty otherwise.
    fn resident(&self, s: Section) -> &[u8] {
        match self.backing.read(s) {
            Ok(Cow::Borrowed(b)) => b,
            _ => &[],
        }
    }

    /// Each cube's radiance in spherical harmonics (the irradiance section, cube order), or
    /// `None` for a format 1.0 store, which has none.
    pub fn irradiance(&self) -> Option<&[CubeSh]> {
        self.irradiance.as_deref()
    }

    /// The parsed header.
    pub fn header(&self) -> &Header {
        &self.header
    }

    /// Objects, patches, bake parameters, camera.
    pub fn meta(&self) -> &StoreMeta {
        &self.meta
    }

    /// The sample points, zero-copy.
    pub fn sample_points(&self) -> &[SamplePoint] {
        bytemuck::try_cast_slice(self.resident(self.header.points)).unwrap_or(&[])
    }

    /// Index width of the sample maps.
    pub fn index_width(&self) -> IndexWidth {
        self.header.index_width
    }

    /// Sample map `patch` (a Bézier patch's or an atlas page's, by global map index),
    /// zero-copy.
    pub fn sample_map(&self, patch: u32) -> Result<SampleMapView<'_>, Error> {
        let h = &self.header;
        if u64::from(patch) >= h.patch_count {
            return Err(Error::PatchOutOfRange {
                patch,
                count: u32::try_from(h.patch_count).unwrap_or(u32::MAX),
            });
        }
        // Sizes were checked on open: patch_count * per_patch == maps.size fits in u64.
        let res = u64::from(h.sample_map_resolution);
        let per_patch = res * res * (ENTRIES_PER_TEXEL * h.index_width.bytes()) as u64;
        let section = Section {
            offset: h.maps.offset + per_patch * u64::from(patch),
            size: per_patch,
        };
        let data = map_data(self.resident(section), h.index_width, section.offset)?;
        Ok(SampleMapView {
            resolution: h.sample_map_resolution,
            data,
        })
    }

    /// Number of cubes (sample points, plus the environment cube if any).
    pub fn cube_count(&self) -> u32 {
        u32::try_from(self.header.cube_count).unwrap_or(u32::MAX)
    }

    /// The environment cube's index (the last cube), if the store has one.
    pub fn env_cube_index(&self) -> Option<u32> {
        self.header
            .has_env_cube()
            .then(|| self.cube_count().saturating_sub(1))
    }

    /// Where face `face` of cube `cube` lives.
    pub fn face_entry(&self, cube: u32, face: usize) -> Result<FaceEntry, Error> {
        if cube >= self.cube_count() {
            return Err(Error::CubeOutOfRange {
                cube,
                count: self.cube_count(),
            });
        }
        if face >= FACES {
            return Err(Error::FaceOutOfRange { face });
        }
        let toc = self.resident(self.header.toc);
        Ok(FaceEntry::parse(
            toc,
            cube as usize * TOC_CUBE_BYTES + face * TOC_ENTRY_BYTES,
        ))
    }

    /// Bytes of one face's raw data: the encoded texels ([`crate::Encoding::face_bytes`]:
    /// `res² * bytes_per_texel`, or `⌈res/4⌉² * 16` for BC6H), plus `res² * 4` with the
    /// distance channel.
    pub fn face_raw_size(&self) -> usize {
        self.face_raw_size
    }

    /// Texels per cube face edge.
    pub fn cube_resolution(&self) -> u32 {
        self.header.cube_resolution
    }

    /// Size of the store in bytes.
    pub fn file_size(&self) -> u64 {
        self.backing.len()
    }

    /// Total compressed bytes of all cube faces.
    pub fn cube_bytes(&self) -> u64 {
        let toc = self.resident(self.header.toc);
        (0..self.header.cube_count as usize * FACES)
            .map(|i| FaceEntry::parse(toc, i * TOC_ENTRY_BYTES).compressed_size)
            .sum()
    }

    /// Decompresses one face into `out` (exactly [`Store::face_raw_size`] bytes): the encoded
    /// texels, then the distance plane if any, exactly as a GPU upload wants. Verifies the
    /// frame's checksum first; in a BC6H store, also that no block has a reserved mode
    /// ([`Error::ReservedBc6hMode`]), so the blocks are safe to upload as they are.
    pub fn read_face_raw(&self, cube: u32, face: usize, out: &mut [u8]) -> Result<(), Error> {
        self.read_face_raw_unchecked(cube, face, out)?;
        if self.header.encoding.is_block_compressed() {
            let color = self
                .header
                .encoding
                .face_bytes(self.header.cube_resolution)
                .unwrap_or(0)
                .min(out.len());
            crate::bc6h::check_blocks(&out[..color], cube, face)?;
        }
        Ok(())
    }

    /// [`Store::read_face_raw`] without the BC6H mode check.
    fn read_face_raw_unchecked(&self, cube: u32, face: usize, out: &mut [u8]) -> Result<(), Error> {
        let e = self.face_entry(cube, face)?;
        if out.len() != self.face_raw_size {
            return Err(Error::BufferSize {
                what: "raw face output",
                expected: self.face_raw_size as u64,
                actual: out.len() as u64,
            });
        }
        let frame = self.backing.read(Section {
            offset: e.offset,
            size: e.compressed_size,
        })?;
        let frame = &frame[..];
        let computed = xxh3_64(frame);
        if computed != e.checksum {
            return Err(Error::FaceChecksum {
                cube,
                face,
                offset: e.offset,
                stored: e.checksum,
                computed,
            });
        }
        let h = &self.header;
        let fail = |detail: String| Error::Decompress {
            cube,
            face,
            offset: e.offset,
            detail,
        };
        DECODER.with(|cell| {
            let mut state = cell.borrow_mut();
            let state = &mut *state;
            if state.dctx.is_none() {
                state.dctx =
                    Some(zstd::bulk::Decompressor::new().map_err(|e| fail(e.to_string()))?);
            }
            let Some(dctx) = state.dctx.as_mut() else {
                return Err(fail("no zstd decompression context".into()));
            };
            let filtered_size = crate::filter::filtered_face_size(
                h.filter,
                h.encoding,
                h.cube_resolution,
                h.distance_plane(),
                self.meta.bake.mantissa_bits,
            )
            .ok_or_else(|| fail("filtered face size overflows".into()))?;
            let target: &mut [u8] = match h.filter {
                Filter::None => out,
                Filter::Predict | Filter::PredictRows | Filter::PredictPacked => {
                    state.scratch.resize(filtered_size, 0);
                    &mut state.scratch
                }
            };
            // The frame must decompress to exactly the filtered size: a frame that would
            // produce more fails inside zstd (the buffer bounds it), one that produces less is
            // caught here.
            let n = dctx
                .decompress_to_buffer(frame, target)
                .map_err(|err| fail(err.to_string()))?;
            if n != target.len() {
                return Err(fail(format!(
                    "decompressed to {n} bytes, expected {}",
                    target.len()
                )));
            }
            if h.filter != Filter::None {
                unfilter_face_quantized(
                    h.filter,
                    h.encoding,
                    h.cube_resolution,
                    h.distance_plane(),
                    self.meta.bake.mantissa_bits,
                    &state.scratch,
                    out,
                )?;
            }
            if state.scratch.capacity() > MAX_KEPT_SCRATCH {
                state.scratch = Vec::new();
            }
            Ok(())
        })
    }

    /// Decompresses and decodes one face: `rgb` takes `res²` texels; `distance`, if given,
    /// takes the distance plane ([`Error::NoDistanceChannel`] if the store has none).
    pub fn read_face(
        &self,
        cube: u32,
        face: usize,
        rgb: &mut [[f32; 3]],
        distance: Option<&mut [f32]>,
    ) -> Result<(), Error> {
        if distance.is_some() && !self.header.has_distance() {
            return Err(Error::NoDistanceChannel);
        }
        let mut raw = vec![0u8; self.face_raw_size];
        self.read_face_raw_unchecked(cube, face, &mut raw)?;
        let (enc, res) = (self.header.encoding, self.header.cube_resolution);
        let color_bytes = enc.face_bytes(res).unwrap_or(usize::MAX);
        let (color, dist) = raw.split_at(color_bytes.min(raw.len()));
        decode_face_texels(enc, res, color, rgb, cube, face)?;
        if let Some(d) = distance {
            decode_distances(dist, d)?;
        }
        Ok(())
    }

    /// Decompresses all six faces of a cube into `out` (`6 * face_raw_size` bytes), face after
    /// face in layer order.
    pub fn read_cube_raw(&self, cube: u32, out: &mut [u8]) -> Result<(), Error> {
        let expected = self.face_raw_size.saturating_mul(FACES);
        if out.len() != expected {
            return Err(Error::BufferSize {
                what: "raw cube output",
                expected: expected as u64,
                actual: out.len() as u64,
            });
        }
        for (face, chunk) in out.chunks_exact_mut(self.face_raw_size.max(1)).enumerate() {
            self.read_face_raw(cube, face, chunk)?;
        }
        Ok(())
    }

    /// Decompresses and decodes a whole cube.
    pub fn read_cube(&self, cube: u32) -> Result<CubeImage, Error> {
        let res = self.header.cube_resolution;
        let mut image = CubeImage::black(res, self.header.has_distance());
        for face in 0..FACES {
            let rgb = &mut image.faces[face];
            let dist = image.distance.as_mut().map(|d| d[face].as_mut_slice());
            self.read_face(cube, face, rgb, dist)?;
        }
        Ok(image)
    }
}

fn map_data(bytes: &[u8], width: IndexWidth, offset: u64) -> Result<MapData<'_>, Error> {
    let misaligned = |_| Error::Misaligned {
        section: "sample maps",
        offset,
    };
    Ok(match width {
        IndexWidth::U16 => MapData::U16(bytemuck::try_cast_slice(bytes).map_err(misaligned)?),
        IndexWidth::U32 => MapData::U32(bytemuck::try_cast_slice(bytes).map_err(misaligned)?),
    })
}

/// Checks every TOC entry: raw size equals the face raw size, frames lie inside the payload
/// in file order — each cube's face 0 right after its 160-byte record header (which starts at
/// the 8-aligned end of the previous cube), each further face right after the previous one —
/// compressed sizes within zstd's bound, and the payload ends at the 8-aligned end of the last
/// cube.
fn check_toc(entries: &[u8], h: &Header, raw: u64) -> Result<(), Error> {
    let bound = zstd::zstd_safe::compress_bound(usize::try_from(raw).unwrap_or(usize::MAX)) as u64;
    let payload_end = h.payload.end();
    let mut cube_end = h.payload.offset;
    for cube in 0..h.cube_count as usize {
        let mut expected = align8(cube_end)
            .and_then(|v| v.checked_add(RECORD_HEADER_BYTES as u64))
            .unwrap_or(u64::MAX);
        for face in 0..FACES {
            let at = cube * TOC_CUBE_BYTES + face * TOC_ENTRY_BYTES;
            let e = FaceEntry::parse(entries, at);
            let fail = |detail: String| Error::InvalidToc {
                cube: cube as u32,
                face,
                offset: h.toc.offset.saturating_add(at as u64),
                detail,
            };
            if e.raw_size != raw {
                return Err(fail(format!(
                    "raw size {} differs from the face raw size {raw}",
                    e.raw_size
                )));
            }
            if e.compressed_size == 0 || e.compressed_size > bound {
                return Err(fail(format!(
                    "compressed size {} outside 1..={bound}",
                    e.compressed_size
                )));
            }
            if e.offset != expected {
                return Err(fail(format!(
                    "frame offset {} but the layout puts it at {expected} (overlap or gap)",
                    e.offset
                )));
            }
            let end = e.offset.checked_add(e.compressed_size);
            match end {
                Some(end) if end <= payload_end => expected = end,
                _ => {
                    return Err(fail(format!(
                        "frame {}+{} runs past the payload end {payload_end}",
                        e.offset, e.compressed_size
                    )))
                }
            }
        }
        cube_end = expected;
    }
    if align8(cube_end) != Some(payload_end) {
        return Err(Error::InvalidHeader {
            field: "cube payload",
            offset: 120,
            detail: format!("payload ends at {payload_end} but its last cube ends at {cube_end}"),
        });
    }
    Ok(())
}

/// Checks that the header `h` agrees with the metadata `meta` (encoding, resolutions, flags
/// and counts); an [`Error::InvalidHeader`] names the first header field that disagrees.
fn check_against_meta(h: &Header, meta: &StoreMeta) -> Result<(), Error> {
    let disagree = |field: &'static str, offset: u64, detail: String| Error::InvalidHeader {
        field,
        offset,
        detail: format!("{detail} (disagrees with the metadata)"),
    };
    let b = &meta.bake;
    if h.encoding != b.encoding {
        return Err(disagree("encoding", 16, format!("{}", h.encoding)));
    }
    if h.cube_resolution != b.cube_resolution {
        return Err(disagree(
            "cube_resolution",
            24,
            h.cube_resolution.to_string(),
        ));
    }
    if h.sample_map_resolution != b.sample_map_resolution {
        return Err(disagree(
            "sample_map_resolution",
            28,
            h.sample_map_resolution.to_string(),
        ));
    }
    if h.has_distance() != b.distance_channel || h.has_env_cube() != meta.has_env_cube {
        return Err(disagree("flags", 12, format!("{:#x}", h.flags)));
    }
    if h.patch_count != meta.map_count() as u64 {
        return Err(disagree("patch_count", 48, h.patch_count.to_string()));
    }
    if h.object_count != meta.objects.len() as u64 {
        return Err(disagree("object_count", 56, h.object_count.to_string()));
    }
    Ok(())
}

/// Checks the header `h`'s cube count (the sample points plus the environment cube) and
/// sample-map index width (u16 iff at most 65535 sample points).
fn check_counts(h: &Header) -> Result<(), Error> {
    let expected_cubes = h.sample_count.checked_add(u64::from(h.has_env_cube()));
    if expected_cubes != Some(h.cube_count) || h.cube_count > u64::from(u32::MAX) {
        return Err(Error::InvalidHeader {
            field: "cube_count",
            offset: 40,
            detail: format!(
                "{} cubes for {} sample points{} (must be their sum, at most {})",
                h.cube_count,
                h.sample_count,
                if h.has_env_cube() {
                    " + 1 env cube"
                } else {
                    ""
                },
                u32::MAX
            ),
        });
    }
    if h.index_width != IndexWidth::for_sample_count(h.sample_count) {
        return Err(Error::InvalidHeader {
            field: "index_bytes",
            offset: 20,
            detail: format!(
                "{:?} indices for {} sample points (u16 iff at most 65535)",
                h.index_width, h.sample_count
            ),
        });
    }
    Ok(())
}
