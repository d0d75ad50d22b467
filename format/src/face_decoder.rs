//! Checking and decoding cube frames read from a file being written: the records of a partial
//! store that [`crate::StoreWriter::resume`] recovers, and the faces a finished store's
//! irradiance section is projected from ([`crate::StoreWriter::finish`]).

use std::io::Read;
use std::path::Path;

use crate::cube::face_raw_size;
use crate::header::Header;
use crate::Error;
use xxhash_rust::xxh3::xxh3_64;

/// Checks and decodes the face frames of a partial file's cube records, reusing its buffers.
pub(crate) struct FaceDecoder<'h> {
    header: &'h Header,
    mantissa_bits: u32,
    /// Bytes of a raw face, as records state it and as a length.
    pub(crate) raw: u64,
    raw_len: usize,
    /// The largest frame a raw face compresses to.
    pub(crate) bound: usize,
    /// Bytes of a filtered face, as a frame decompresses to.
    filtered_len: usize,
    dctx: zstd::bulk::Decompressor<'static>,
    frame: Vec<u8>,
    filtered: Vec<u8>,
    raw_face: Vec<u8>,
}

impl<'h> FaceDecoder<'h> {
    /// A decoder for the faces of a store with header `h` and `mantissa_bits`.
    pub(crate) fn new(h: &'h Header, mantissa_bits: u32, partial: &Path) -> Result<Self, Error> {
        let raw = face_raw_size(h.encoding, h.cube_resolution, h.has_distance())?;
        let raw_len = usize::try_from(raw).unwrap_or(usize::MAX);
        let bound = zstd::zstd_safe::compress_bound(raw_len);
        let filtered_len = crate::filter::filtered_face_size(
            h.filter,
            h.encoding,
            h.cube_resolution,
            h.distance_plane(),
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
    pub(crate) fn read_face(
        &mut self,
        rd: &mut impl Read,
        size: usize,
        checksum: u64,
    ) -> Option<u64> {
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
                h.distance_plane(),
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

    /// The raw face the last successful [`FaceDecoder::read_face`] decoded: encoded texels,
    /// then the distance plane.
    pub(crate) fn raw_face(&self) -> &[u8] {
        &self.raw_face
    }
}
