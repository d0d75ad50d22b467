//! Reopening a partial store after an interruption ([`crate::StoreWriter::resume`]): the
//! partial file's header, metadata, sample points and maps are compared with what `create()`
//! writes for the bake's inputs, and its complete cube records are kept.

use std::fs::File;
use std::io::{BufReader, Read, Seek, SeekFrom, Write};
use std::path::Path;

use crate::bytes::{align8, zero_pad};
use crate::cube::FACES;
use crate::differences::setting_differences;
use crate::error::io_at;
use crate::face_decoder::FaceDecoder;
use crate::header::{
    Header, Section, DECODED_CHECKSUM_FIELD, FINISH_FIELDS, FLAGS_FIELD, FLAG_COMPLETE,
    FLAG_IRRADIANCE, HEADER_BYTES, IRRADIANCE_FIELDS, SECTION_CHECKSUMS,
};
use crate::meta::{decode_meta, StoreMeta, SAMPLE_POINT_BYTES};
use crate::output_file::{open_partial, Open};
use crate::prefix::Prefix;
use crate::toc::{FaceEntry, RecordHeader, RECORD_HEADER_BYTES};
use crate::{Error, MAGIC, VERSION};
use xxhash_rust::xxh3::{xxh3_64, Xxh3};

/// A partial file reopened for [`crate::StoreWriter::resume`]: checked against a bake's
/// inputs, its torn tail dropped, and positioned after its last complete cube record.
pub(crate) struct Reopened {
    pub(crate) file: File,
    /// What `create()` writes for the bake's inputs, in the partial file's layout.
    pub(crate) prefix: Prefix,
    /// Its complete cube records.
    pub(crate) recovered: Recovered,
}

/// Reopens the partial file `partial` for the bake of `meta`, whose fixed sections
/// `create()` writes as `prefix`; errors as [`crate::StoreWriter::resume`].
pub(crate) fn reopen(
    path: &Path,
    partial: &Path,
    meta: &StoreMeta,
    prefix: Prefix,
) -> Result<Reopened, Error> {
    let mut file = open_partial(path, partial, Open::Resume)?;
    let file_len = file.metadata().map_err(io_at(partial, "stat"))?.len();
    let mut rd = PartialReader {
        partial,
        rd: BufReader::with_capacity(1 << 20, &mut file),
        file_len,
    };
    let (got, old) = rd.header()?;
    let old_meta_bytes = rd.metadata(&old, &prefix.header, meta)?;
    rd.compare_header_and_metadata(got, &old_meta_bytes, &prefix)?;
    drop(old_meta_bytes);
    let pos = rd.sections(&prefix, meta)?;
    let recovered = rd.recover_cubes(&prefix, meta, pos)?;
    drop(rd);
    restore_partial(&mut file, partial, recovered.pos, &prefix.header)?;
    Ok(Reopened {
        file,
        prefix,
        recovered,
    })
}

/// The end of the errors that find a partial file's fixed sections differ from this bake's
/// although every setting is the same.
const SAME_SETTINGS: &str =
    "although every setting is the same (written by another version of oslf?)";

/// A partial file read front to back by [`crate::StoreWriter::resume`], and the errors it reports.
struct PartialReader<'a> {
    partial: &'a Path,
    rd: BufReader<&'a mut File>,
    file_len: u64,
}

/// The complete cube records found in a partial file, and where the next one goes.
pub(crate) struct Recovered {
    /// Their TOC entries.
    pub(crate) toc: Vec<u8>,
    /// How many there are.
    pub(crate) next: u32,
    /// Their compressed bytes.
    pub(crate) cube_bytes: u64,
    /// Hash of their raw faces' checksums.
    pub(crate) decoded: Xxh3,
    /// The end of the last one.
    pub(crate) pos: u64,
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
        let mut want = prefix.header.to_bytes();
        let normalise = |b: &mut [u8; HEADER_BYTES]| {
            b[FINISH_FIELDS].fill(0);
            b[SECTION_CHECKSUMS].fill(0);
            b[DECODED_CHECKSUM_FIELD].fill(0);
            b[IRRADIANCE_FIELDS].fill(0);
            b[FLAGS_FIELD.start] &= !((FLAG_COMPLETE | FLAG_IRRADIANCE) as u8);
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

/// Parses the header of a partial file for [`crate::StoreWriter::resume`]: an OSLF header of
/// format [`VERSION`] whose fixed sections lie in the order and at the
/// places `create()` puts them. The error says what is wrong with it.
fn parse_partial_header(bytes: &[u8; HEADER_BYTES]) -> Result<Header, String> {
    if bytes[..8] != MAGIC {
        return Err(format!(
            "it is not an OSLF store (its first bytes are {:02x?}, not \"OSLFSTOR\")",
            &bytes[..8]
        ));
    }
    let version = u32::from_le_bytes([bytes[8], bytes[9], bytes[10], bytes[11]]);
    if version != VERSION {
        return Err(format!(
            "it is {}, and this writer continues only format {} files",
            match version {
                1..=crate::LAST_DEVELOPMENT_VERSION =>
                    format!("of development format version {version}, from before format 1.0"),
                crate::VERSION_1_0 | crate::VERSION_1_1 => format!(
                    "of format {}, written by an earlier oslf",
                    crate::version_name(version)
                ),
                _ => format!("of format version {version:#010x}"),
            },
            crate::version_name(VERSION)
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
