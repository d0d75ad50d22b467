//! What the cache keeps and uploads for one cube face: its texels in the pool's encoding, the
//! mip chain that filtered glossy sampling reads (`FaceLayout::levels` levels, each a 2×2 box
//! filter of the one before), and, when the store has a distance channel, the distance plane
//! as IEEE binary16 for depth-corrected lookups.
//!
//! One face's payload is one byte buffer: level 0, level 1, … in order, then the distance
//! plane (`res²` little-endian `f16`). The GPU pool and the CPU reference both read it through
//! [`FaceLayout`], so they see the same bytes.

use half::f16;
use oslf_format::encoding::{decode_texels, encode_texels};
use oslf_format::{Encoding, Store};

/// Distances at or above this are stored as it: the largest finite binary16, and the value an
/// escaped ray (`f32::MAX` on disk) reads as. Every lookup treats it as "nothing this way".
pub const FAR_DISTANCE: f32 = 65504.0;

/// Mip levels of a face of side `res`: halving while the side stays even, down to 1 texel for
/// powers of two (32 → 6 levels; 48 → 48, 24, 12, 6, 3: 5 levels).
pub fn mip_levels(res: u32) -> u32 {
    if res == 0 {
        return 1;
    }
    res.trailing_zeros() + 1
}

/// A face's payload layout.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct FaceLayout {
    /// The encoding of the texels in the GPU pool.
    pub encoding: Encoding,
    /// The side of level 0.
    pub res: u32,
    /// Mip levels, level 0 included.
    pub levels: u32,
    /// Whether the payload ends in a distance plane.
    pub depth: bool,
}

impl FaceLayout {
    /// The layout for faces of `store` uploaded in `encoding`.
    pub fn new(store: &Store, encoding: Encoding) -> Self {
        let res = store.cube_resolution();
        Self {
            encoding,
            res,
            levels: mip_levels(res),
            depth: store.header().has_distance(),
        }
    }

    /// The layout the GPU pool uses for `store` on an adapter with (`adapter_has_bc`) or
    /// without BC texture compression: the store's encoding where the pool can hold it
    /// ([`crate::pool::upload_encoding`]).
    pub fn for_store(store: &Store, adapter_has_bc: bool) -> Self {
        Self::new(
            store,
            crate::pool::upload_encoding(store.header().encoding, adapter_has_bc),
        )
    }

    /// The side of level `l`.
    pub fn side(&self, l: u32) -> u32 {
        (self.res >> l).max(1)
    }

    /// Byte offset of level `l` in the payload.
    pub fn level_offset(&self, l: u32) -> usize {
        (0..l).map(|k| self.level_bytes(k)).sum()
    }

    /// Bytes of level `l`.
    pub fn level_bytes(&self, l: u32) -> usize {
        (self.side(l) as usize).pow(2) * self.encoding.bytes_per_texel()
    }

    /// Byte offset of the distance plane.
    pub fn depth_offset(&self) -> usize {
        self.level_offset(self.levels)
    }

    /// Bytes of the whole payload.
    pub fn payload_bytes(&self) -> usize {
        self.depth_offset()
            + if self.depth {
                (self.res as usize).pow(2) * 2
            } else {
                0
            }
    }

    /// Reads face `face` of cube `cube` from `store` and builds its payload. Level 0 is the
    /// store's own bytes when the encodings agree, else the decoded texels re-encoded.
    pub fn build(&self, store: &Store, cube: u32, face: u8) -> Result<Vec<u8>, oslf_format::Error> {
        let n = (self.res as usize).pow(2);
        let mut rgb = vec![[0.0f32; 3]; n];
        let mut dist = vec![0.0f32; if self.depth { n } else { 0 }];
        let mut out = vec![0u8; self.payload_bytes()];
        let level0 = self.level_bytes(0);
        if store.header().encoding == self.encoding {
            let mut raw = vec![0u8; store.face_raw_size()];
            store.read_face_raw(cube, face as usize, &mut raw)?;
            out[..level0].copy_from_slice(&raw[..level0]);
            decode_texels(self.encoding, &raw[..level0], &mut rgb)?;
            if self.depth {
                oslf_format::encoding::decode_distances(&raw[level0..level0 + 4 * n], &mut dist)?;
            }
        } else {
            let d = self.depth.then_some(dist.as_mut_slice());
            store.read_face(cube, face as usize, &mut rgb, d)?;
            encode_texels(self.encoding, &rgb, &mut out[..level0])?;
        }
        self.fill_mips(&mut out, rgb)?;
        if self.depth {
            let at = self.depth_offset();
            for (d, dst) in dist.iter().zip(out[at..].chunks_exact_mut(2)) {
                dst.copy_from_slice(&depth_to_f16(*d).to_le_bytes());
            }
        }
        Ok(out)
    }

    /// Writes levels 1.. of `out` from level 0's decoded texels `rgb`.
    fn fill_mips(&self, out: &mut [u8], mut rgb: Vec<[f32; 3]>) -> Result<(), oslf_format::Error> {
        for l in 1..self.levels {
            rgb = downsample(&rgb, self.side(l - 1));
            let at = self.level_offset(l);
            encode_texels(self.encoding, &rgb, &mut out[at..at + self.level_bytes(l)])?;
        }
        Ok(())
    }

    /// Decodes level `l` of `payload` to linear RGB.
    pub fn decode_level(
        &self,
        payload: &[u8],
        l: u32,
    ) -> Result<Vec<[f32; 3]>, oslf_format::Error> {
        let at = self.level_offset(l);
        let mut rgb = vec![[0.0f32; 3]; (self.side(l) as usize).pow(2)];
        decode_texels(
            self.encoding,
            &payload[at..at + self.level_bytes(l)],
            &mut rgb,
        )?;
        Ok(rgb)
    }

    /// The distance plane of `payload` as `f32` (each value exactly its binary16), empty when
    /// the layout has none.
    pub fn decode_depth(&self, payload: &[u8]) -> Vec<f32> {
        if !self.depth {
            return Vec::new();
        }
        payload[self.depth_offset()..]
            .chunks_exact(2)
            .map(|b| f16::from_le_bytes([b[0], b[1]]).to_f32())
            .collect()
    }
}

/// A distance as the GPU's R16Float plane holds it: rounded to binary16, [`FAR_DISTANCE`] at
/// most (escaped rays and anything farther).
pub fn depth_to_f16(d: f32) -> f16 {
    f16::from_f32(d.clamp(0.0, FAR_DISTANCE))
}

/// The next mip level of a `side`² level: each texel the mean of its 2×2 block, summed in a
/// fixed order.
pub fn downsample(src: &[[f32; 3]], side: u32) -> Vec<[f32; 3]> {
    let s = side as usize;
    let h = (s / 2).max(1);
    let mut out = vec![[0.0f32; 3]; h * h];
    for y in 0..h {
        for x in 0..h {
            let at =
                |dx: usize, dy: usize| src[(2 * y + dy).min(s - 1) * s + (2 * x + dx).min(s - 1)];
            let (a, b, c, d) = (at(0, 0), at(1, 0), at(0, 1), at(1, 1));
            out[y * h + x] = std::array::from_fn(|k| ((a[k] + b[k]) + (c[k] + d[k])) * 0.25);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn mip_levels_halve_while_even() {
        assert_eq!(mip_levels(32), 6);
        assert_eq!(mip_levels(48), 5);
        assert_eq!(mip_levels(8), 4);
        assert_eq!(mip_levels(7), 1);
        assert_eq!(mip_levels(1), 1);
    }

    #[test]
    fn downsampling_keeps_the_mean() {
        let src: Vec<[f32; 3]> = (0..16).map(|i| [i as f32, 2.0 * i as f32, 1e4]).collect();
        let d = downsample(&src, 4);
        assert_eq!(d.len(), 4);
        assert_eq!(d[0], [2.5, 5.0, 1e4]);
        let mean = |v: &[[f32; 3]]| v.iter().map(|t| t[0]).sum::<f32>() / v.len() as f32;
        assert_eq!(mean(&src), mean(&d));
    }

    #[test]
    fn distances_round_to_half_and_escaped_rays_read_far() {
        assert_eq!(depth_to_f16(f32::MAX).to_f32(), FAR_DISTANCE);
        assert_eq!(depth_to_f16(1e9).to_f32(), FAR_DISTANCE);
        assert_eq!(depth_to_f16(2.5).to_f32(), 2.5);
        assert!((depth_to_f16(3.3).to_f32() - 3.3).abs() < 3.3 * 1e-3);
    }
}
