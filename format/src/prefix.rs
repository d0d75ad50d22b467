//! The fixed sections before a store's cube payload (header, metadata, sample points,
//! sample maps and their padding) as the writer lays them out: what `StoreWriter::create`
//! writes, what `StoreWriter::resume` and the shard writer compare a partial file with.

use crate::bytes::{align8, zero_pad};
use crate::header::{Header, Section, FLAG_DISTANCE, FLAG_ENV_CUBE, HEADER_BYTES};
use crate::meta::{
    decode_meta, encode_meta, encode_points, validate_points, SamplePoint, StoreMeta,
    SAMPLE_POINT_BYTES,
};
use crate::sample_map::{encode_maps, SampleMaps};
use crate::{Error, Filter};
use xxhash_rust::xxh3::xxh3_64;

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
        let meta_offset = HEADER_BYTES as u64;
        check_textures(meta, meta_offset)?;
        if meta.bake.sampling.is_none() {
            return Err(Error::InvalidMetadata {
                offset: meta_offset,
                detail: "the bake parameters have no sampling record (target_noise, denoised), which format 1.2 stores hold".into(),
            });
        }
        let meta_bytes = encode_meta(meta);
        // Validate by decoding what was encoded (same checks as the reader).
        let decoded = decode_meta(&meta_bytes, meta_offset, crate::VERSION)?;
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
            version: crate::VERSION,
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
            irradiance: Section::default(),
            irradiance_checksum: 0,
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
    pub(crate) fn sections(&self) -> [(&'static str, Section, &[u8]); 3] {
        [
            ("metadata", self.header.meta, &self.meta),
            ("sample points", self.header.points, &self.points),
            ("sample maps", self.header.maps, &self.maps),
        ]
    }
}

/// Checks what a writer was given: textures only on mesh objects, one texture coordinate (and
/// with a normal texture one tangent) per vertex, kinds in order without repeats, texel
/// counts matching the sizes. `offset` is the metadata section's (for the error).
fn check_textures(meta: &StoreMeta, offset: u64) -> Result<(), Error> {
    for (i, o) in meta.objects.iter().enumerate() {
        let Some(t) = &o.textures else { continue };
        let problem = match &o.mesh {
            None => Some("a Bézier object cannot hold textures".to_string()),
            Some(m) => crate::textures::check(t, m.positions.len()),
        };
        if let Some(p) = problem {
            return Err(Error::InvalidMetadata {
                offset,
                detail: format!("object {i}: {p}"),
            });
        }
    }
    Ok(())
}
