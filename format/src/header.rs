//! The fixed 256-byte file header (layout in `docs/format.md`, "Header").

use crate::bytes::{align8, le_u32, le_u64};
use crate::encoding::Encoding;
use crate::filter::Filter;
use crate::sample_map::IndexWidth;
use crate::{Error, MAGIC, VERSION, VERSION_1_0, VERSION_1_1};
use xxhash_rust::xxh3::xxh3_64;

/// Bytes of the header.
pub const HEADER_BYTES: usize = 256;
/// Byte offset of the header checksum (it covers bytes `0..HEADER_CHECKSUM_OFFSET`).
pub const HEADER_CHECKSUM_OFFSET: usize = 248;

/// Byte offset of the face filter id (`u32`).
pub const FILTER_OFFSET: usize = 176;
/// Byte offset of the checksum of the decoded faces (`u64`).
pub const DECODED_CHECKSUM_OFFSET: usize = 180;
/// Byte offset of the irradiance section's offset, size and checksum (three `u64`; format 1.1).
pub const IRRADIANCE_OFFSET: usize = 188;
/// First reserved (zero) byte of the header.
const RESERVED_START: usize = 212;

/// Flag bit: every face carries an `f32` distance plane.
pub const FLAG_DISTANCE: u32 = 1;
/// Flag bit: the last cube is the environment cube.
pub const FLAG_ENV_CUBE: u32 = 2;
/// Flag bit: `finish()` completed the file (table of contents present).
pub const FLAG_COMPLETE: u32 = 4;
/// Flag bit (format 1.1): the store has an irradiance section.
pub const FLAG_IRRADIANCE: u32 = 8;
const KNOWN_FLAGS: u32 = FLAG_DISTANCE | FLAG_ENV_CUBE | FLAG_COMPLETE | FLAG_IRRADIANCE;

/// Byte range of the fields `finish()` patches (payload size, TOC offset and size, file size).
pub(crate) const FINISH_FIELDS: std::ops::Range<usize> = 120..152;
/// Byte range of the metadata, points and maps checksums.
pub(crate) const SECTION_CHECKSUMS: std::ops::Range<usize> = 152..176;
/// Byte range of the irradiance section's fields, which `finish()` also patches.
pub(crate) const IRRADIANCE_FIELDS: std::ops::Range<usize> =
    IRRADIANCE_OFFSET..IRRADIANCE_OFFSET + 24;
/// Byte range of the flags field.
pub(crate) const FLAGS_FIELD: std::ops::Range<usize> = 12..16;
/// Byte range of the decoded-faces checksum, which `finish()` also patches.
pub(crate) const DECODED_CHECKSUM_FIELD: std::ops::Range<usize> =
    DECODED_CHECKSUM_OFFSET..DECODED_CHECKSUM_OFFSET + 8;

/// A section's position: byte offset and size.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Section {
    pub offset: u64,
    pub size: u64,
}

impl Section {
    /// One past the last byte (saturating; callers check with `checked_end`).
    pub fn end(&self) -> u64 {
        self.offset.saturating_add(self.size)
    }
    pub(crate) fn checked_end(&self) -> Option<u64> {
        self.offset.checked_add(self.size)
    }
}

/// The parsed header.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Header {
    /// The format version (bytes 8..12): [`VERSION`]; [`VERSION_1_1`] for a store without
    /// the sampling record; [`VERSION_1_0`] for one without an irradiance section either.
    pub version: u32,
    pub flags: u32,
    pub encoding: Encoding,
    /// The face filter (bytes 176..180).
    pub filter: Filter,
    pub index_width: IndexWidth,
    pub cube_resolution: u32,
    pub sample_map_resolution: u32,
    pub sample_count: u64,
    pub cube_count: u64,
    pub patch_count: u64,
    pub object_count: u64,
    pub meta: Section,
    pub points: Section,
    pub maps: Section,
    pub payload: Section,
    pub toc: Section,
    /// The irradiance section (bytes 188..204; format 1.1 with [`FLAG_IRRADIANCE`]), between
    /// the cube payload and the table of contents; zero otherwise.
    pub irradiance: Section,
    /// Its checksum (bytes 204..212).
    pub irradiance_checksum: u64,
    pub file_size: u64,
    pub meta_checksum: u64,
    pub points_checksum: u64,
    pub maps_checksum: u64,
    /// Checksum of the decoded faces (bytes 180..188; see `docs/format.md`): set by
    /// `finish()`, 0 in a partial file.
    pub decoded_checksum: u64,
}

/// The first reserved (zero) header byte of format `version`: format 1.0 has no irradiance
/// section, so its flag must be clear and its fields are reserved.
fn first_reserved(version: u32, flags: u32) -> Result<usize, Error> {
    if version != VERSION_1_0 {
        return Ok(RESERVED_START);
    }
    if flags & FLAG_IRRADIANCE != 0 {
        return Err(Error::InvalidHeader {
            field: "flags",
            offset: 12,
            detail: "flag bit 3 (irradiance) is set in a format 1.0 store".into(),
        });
    }
    Ok(IRRADIANCE_OFFSET)
}

/// The irradiance section's position and checksum (bytes 188..212): zero without its flag.
fn parse_irradiance_fields(b: &[u8], flags: u32) -> Result<(Section, u64), Error> {
    let irradiance = Section {
        offset: le_u64(b, IRRADIANCE_OFFSET),
        size: le_u64(b, IRRADIANCE_OFFSET + 8),
    };
    let checksum = le_u64(b, IRRADIANCE_OFFSET + 16);
    if flags & FLAG_IRRADIANCE == 0 && (irradiance != Section::default() || checksum != 0) {
        return Err(Error::InvalidHeader {
            field: "irradiance",
            offset: IRRADIANCE_OFFSET as u64,
            detail: "the irradiance section's fields must be zero without flag bit 3".into(),
        });
    }
    Ok((irradiance, checksum))
}

impl Header {
    pub fn has_distance(&self) -> bool {
        self.flags & FLAG_DISTANCE != 0
    }
    /// How the faces hold their distance plane: none, or on the distance lattice of the cube
    /// resolution.
    pub fn distance_plane(&self) -> crate::DistancePlane {
        crate::DistancePlane::for_store(self.cube_resolution, self.has_distance())
    }
    pub fn has_env_cube(&self) -> bool {
        self.flags & FLAG_ENV_CUBE != 0
    }
    pub fn is_complete(&self) -> bool {
        self.flags & FLAG_COMPLETE != 0
    }
    pub fn has_irradiance(&self) -> bool {
        self.flags & FLAG_IRRADIANCE != 0
    }

    /// Serialises the header, checksum included.
    pub fn to_bytes(&self) -> [u8; HEADER_BYTES] {
        let mut b = [0u8; HEADER_BYTES];
        let mut put = |off: usize, v: &[u8]| b[off..off + v.len()].copy_from_slice(v);
        put(0, &MAGIC);
        put(8, &self.version.to_le_bytes());
        put(12, &self.flags.to_le_bytes());
        put(16, &self.encoding.tag().to_le_bytes());
        put(20, &(self.index_width.bytes() as u32).to_le_bytes());
        put(24, &self.cube_resolution.to_le_bytes());
        put(28, &self.sample_map_resolution.to_le_bytes());
        put(32, &self.sample_count.to_le_bytes());
        put(40, &self.cube_count.to_le_bytes());
        put(48, &self.patch_count.to_le_bytes());
        put(56, &self.object_count.to_le_bytes());
        let sections = [self.meta, self.points, self.maps, self.payload, self.toc];
        for (i, s) in sections.iter().enumerate() {
            put(64 + 16 * i, &s.offset.to_le_bytes());
            put(72 + 16 * i, &s.size.to_le_bytes());
        }
        put(144, &self.file_size.to_le_bytes());
        put(152, &self.meta_checksum.to_le_bytes());
        put(160, &self.points_checksum.to_le_bytes());
        put(168, &self.maps_checksum.to_le_bytes());
        put(FILTER_OFFSET, &self.filter.id().to_le_bytes());
        put(
            DECODED_CHECKSUM_OFFSET,
            &self.decoded_checksum.to_le_bytes(),
        );
        put(IRRADIANCE_OFFSET, &self.irradiance.offset.to_le_bytes());
        put(IRRADIANCE_OFFSET + 8, &self.irradiance.size.to_le_bytes());
        put(
            IRRADIANCE_OFFSET + 16,
            &self.irradiance_checksum.to_le_bytes(),
        );
        let sum = xxh3_64(&b[..HEADER_CHECKSUM_OFFSET]);
        b[HEADER_CHECKSUM_OFFSET..].copy_from_slice(&sum.to_le_bytes());
        b
    }

    /// Parses and checks the header: magic, version, checksum, flags, tags, reserved bytes
    /// 188..248.
    /// Section positions are checked against the file by [`Header::check_layout`].
    pub fn parse(bytes: &[u8]) -> Result<Header, Error> {
        let Some(b) = bytes.get(..HEADER_BYTES) else {
            return Err(Error::Truncated {
                section: "header",
                offset: 0,
                end: HEADER_BYTES as u64,
                file_size: bytes.len() as u64,
            });
        };
        let mut magic = [0u8; 8];
        magic.copy_from_slice(&b[..8]);
        if magic == crate::SHARD_MAGIC {
            return Err(Error::IsShard);
        }
        if magic != MAGIC {
            return Err(Error::BadMagic {
                found: magic,
                expected: MAGIC,
            });
        }
        let version = le_u32(b, 8);
        if ![VERSION, VERSION_1_1, VERSION_1_0].contains(&version) {
            return Err(Error::UnsupportedVersion { found: version });
        }
        let stored = le_u64(b, HEADER_CHECKSUM_OFFSET);
        let computed = xxh3_64(&b[..HEADER_CHECKSUM_OFFSET]);
        if stored != computed {
            return Err(Error::ChecksumMismatch {
                section: "header",
                offset: HEADER_CHECKSUM_OFFSET as u64,
                stored,
                computed,
            });
        }
        let invalid = |field: &'static str, offset: u64, detail: String| Error::InvalidHeader {
            field,
            offset,
            detail,
        };
        let flags = le_u32(b, 12);
        if flags & !KNOWN_FLAGS != 0 {
            return Err(invalid(
                "flags",
                12,
                format!("unknown flag bits {:#x}", flags & !KNOWN_FLAGS),
            ));
        }
        let first_reserved = first_reserved(version, flags)?;
        let tag = le_u32(b, 16);
        let encoding = Encoding::from_tag(tag)
            .ok_or_else(|| invalid("encoding", 16, format!("unknown encoding tag {tag}")))?;
        let index_width = match le_u32(b, 20) {
            2 => IndexWidth::U16,
            4 => IndexWidth::U32,
            w => return Err(invalid("index_bytes", 20, format!("{w} (must be 2 or 4)"))),
        };
        let filter_id = le_u32(b, FILTER_OFFSET);
        let filter = Filter::from_id(filter_id).ok_or(Error::UnknownFilter {
            id: filter_id,
            offset: FILTER_OFFSET as u64,
        })?;
        if let Some(i) = b[first_reserved..HEADER_CHECKSUM_OFFSET]
            .iter()
            .position(|v| *v != 0)
        {
            return Err(invalid(
                "reserved",
                (first_reserved + i) as u64,
                "reserved bytes must be zero".into(),
            ));
        }
        let section = |i: usize| Section {
            offset: le_u64(b, 64 + 16 * i),
            size: le_u64(b, 72 + 16 * i),
        };
        let (irradiance, irradiance_checksum) = parse_irradiance_fields(b, flags)?;
        Ok(Header {
            version,
            flags,
            encoding,
            filter,
            index_width,
            cube_resolution: le_u32(b, 24),
            sample_map_resolution: le_u32(b, 28),
            sample_count: le_u64(b, 32),
            cube_count: le_u64(b, 40),
            patch_count: le_u64(b, 48),
            object_count: le_u64(b, 56),
            meta: section(0),
            points: section(1),
            maps: section(2),
            payload: section(3),
            toc: section(4),
            irradiance,
            irradiance_checksum,
            file_size: le_u64(b, 144),
            meta_checksum: le_u64(b, 152),
            points_checksum: le_u64(b, 160),
            maps_checksum: le_u64(b, 168),
            decoded_checksum: le_u64(b, DECODED_CHECKSUM_OFFSET),
        })
    }

    /// Checks that the sections lie inside a file of `file_size` bytes, in order
    /// (metadata, points, maps, payload, irradiance where the flag says so, TOC), 8-byte aligned, without overlaps, with only the
    /// padding the layout allows between them, and that the TOC ends the file.
    pub fn check_layout(&self, file_size: u64) -> Result<(), Error> {
        if self.file_size != file_size {
            return Err(Error::InvalidHeader {
                field: "file_size",
                offset: 144,
                detail: format!(
                    "header says {} bytes, the file has {file_size}",
                    self.file_size
                ),
            });
        }
        let mut sections = vec![
            ("metadata", self.meta),
            ("sample points", self.points),
            ("sample maps", self.maps),
            ("cube payload", self.payload),
        ];
        if self.has_irradiance() {
            sections.push(("irradiance", self.irradiance));
        }
        sections.push(("table of contents", self.toc));
        let mut prev: (&'static str, u64) = ("header", HEADER_BYTES as u64);
        for (name, s) in sections {
            let end = s.checked_end().filter(|e| *e <= file_size);
            let Some(end) = end else {
                return Err(Error::SectionOutOfBounds {
                    section: name,
                    offset: s.offset,
                    size: s.size,
                    file_size,
                });
            };
            if s.offset % 8 != 0 {
                return Err(Error::Misaligned {
                    section: name,
                    offset: s.offset,
                });
            }
            if s.offset < prev.1 {
                return Err(Error::SectionOverlap {
                    first: prev.0,
                    first_end: prev.1,
                    second: name,
                    offset: s.offset,
                });
            }
            // Only the zero padding to the next multiple of 8 may separate sections (the
            // payload's records are themselves padded, so the TOC follows it directly).
            if Some(s.offset) != align8(prev.1) {
                return Err(Error::InvalidHeader {
                    field: name,
                    offset: 64,
                    detail: format!(
                        "section starts at {} but must start at {} (right after {})",
                        s.offset,
                        align8(prev.1).unwrap_or(u64::MAX),
                        prev.0
                    ),
                });
            }
            prev = (name, end);
        }
        if prev.1 != file_size {
            return Err(Error::InvalidHeader {
                field: "table of contents",
                offset: 128,
                detail: format!(
                    "the table of contents ends at {} but the file has {file_size} bytes",
                    prev.1
                ),
            });
        }
        Ok(())
    }
}
