//! What the cache keeps and uploads for one cube face: its texels in the pool's encoding, the
//! mip chain that filtered glossy sampling reads (`FaceLayout::levels` levels, each the one
//! before filtered with a 4×4 tent weighted by solid angle and halved: [`downsample`]), and,
//! when the store has a distance channel, the distance plane as IEEE binary16 for
//! depth-corrected lookups.
//!
//! One face's payload is one byte buffer: level 0, level 1, … in order, then the distance
//! plane (`res²` little-endian `f16`). The GPU pool and the CPU reference both read it through
//! [`FaceLayout`], so they see the same bytes.
//!
//! **BC6H** ([`Encoding::Bc6h`], on adapters with BC texture compression): level 0 is the
//! store's blocks as they are (16 bytes per 4×4 texels, 1 byte per texel); levels 1.. are
//! the filtered decoded texels re-encoded at [`MIP_QUALITY`]. Every level must be whole
//! blocks at a block-aligned x in the pool's layers (faces lie side by side at `i·(res >> l)`),
//! so a BC6H chain stops at the last side that is a multiple of 4 ([`bc6h_levels`]: 32 → 32,
//! 16, 8, 4), and a face whose side is not a multiple of 4 is uploaded as RGB9E5 instead.

use half::f16;
use oslf_format::bc6h::{encode_face_with, Quality};
use oslf_format::encoding::{decode_face_texels, encode_face_texels};
use oslf_format::{Encoding, Store};

/// The BC6H encoder quality of the mip levels the runtime builds (level 0 is the store's own
/// blocks; encoding runs on every cache miss): the fastest preset, which builds them about as
/// fast as the RGB9E5 fallback decodes, at a glossy error (filtered importance sampling, the
/// only reader of the mips) close to `Fast`'s; its larger error on smooth gradients is the
/// price (docs/measurements.md, "Figures behind code comments").
pub const MIP_QUALITY: Quality = Quality::VeryFast;

/// The encoding the GPU pool holds the faces of a store of `store_encoding` in: the store's own,
/// except BC6H on an adapter without BC texture compression (`adapter_has_bc`: the device's
/// `TEXTURE_COMPRESSION_BC`, [`crate::Gpu::has_bc`]), which is decoded on the CPU and
/// re-encoded as RGB9E5 (`Rgb9e5Ufloat`). [`FaceLayout::new`] also falls back to RGB9E5 for
/// BC6H faces whose side is not a multiple of 4. The CPU reference must build its faces in
/// the same layout, so that it sees the values the GPU samples (BC6H → f32, or BC6H → f32 →
/// RGB9E5 → f32).
pub fn upload_encoding(store_encoding: Encoding, adapter_has_bc: bool) -> Encoding {
    match store_encoding {
        Encoding::Bc6h if adapter_has_bc => Encoding::Bc6h,
        Encoding::Bc6h => Encoding::Rgb9e5,
        e => e,
    }
}

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

/// Mip levels of a BC6H face of side `res` in the pool: every side a multiple of 4 (levels
/// `l` with `4 · 2^l` dividing `res`), so that each level of each face is whole blocks at a
/// block-aligned x; 32 → 4 levels (32, 16, 8, 4), 12 → 1. 1 when `res` is not a multiple of 4
/// (such faces are not uploaded as BC6H, see [`FaceLayout::new`]).
pub fn bc6h_levels(res: u32) -> u32 {
    if res == 0 || !res.is_multiple_of(4) {
        return 1;
    }
    res.trailing_zeros() - 1
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
    /// The layout for faces of `store` uploaded in `encoding`. BC6H needs a face side that is a
    /// multiple of 4 (whole blocks side by side in the pool's layers); for other sides the
    /// faces are uploaded as RGB9E5 instead.
    pub fn new(store: &Store, encoding: Encoding) -> Self {
        Self::of(
            encoding,
            store.cube_resolution(),
            store.header().has_distance(),
        )
    }

    /// The layout of faces of side `res` in `encoding`, with a distance plane when `depth`
    /// (BC6H as in [`FaceLayout::new`]).
    pub fn of(encoding: Encoding, res: u32, depth: bool) -> Self {
        let encoding = if encoding.is_block_compressed() && !res.is_multiple_of(4) {
            Encoding::Rgb9e5
        } else {
            encoding
        };
        let levels = if encoding.is_block_compressed() {
            bc6h_levels(res)
        } else {
            mip_levels(res)
        };
        Self {
            encoding,
            res,
            levels,
            depth,
        }
    }

    /// The layout the GPU pool uses for `store` on an adapter with (`adapter_has_bc`) or
    /// without BC texture compression: the store's encoding where the pool can hold it
    /// (BC6H where the adapter samples it, else RGB9E5; [`upload_encoding`]).
    pub fn for_store(store: &Store, adapter_has_bc: bool) -> Self {
        Self::new(
            store,
            upload_encoding(store.header().encoding, adapter_has_bc),
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

    /// Bytes of level `l`: `side²` texels, or `(side / 4)²` blocks of 16 bytes for BC6H.
    pub fn level_bytes(&self, l: u32) -> usize {
        self.encoding.face_bytes(self.side(l)).unwrap_or(usize::MAX)
    }

    /// Bytes of one row of level `l` as the GPU copies it (a row of texels, or of 4×4 blocks
    /// for BC6H), and the rows of the level.
    pub fn level_rows(&self, l: u32) -> (u32, u32) {
        let side = self.side(l);
        if self.encoding.is_block_compressed() {
            let blocks = side.div_ceil(4);
            (blocks * oslf_format::bc6h::BLOCK_BYTES as u32, blocks)
        } else {
            (side * self.encoding.bytes_per_texel() as u32, side)
        }
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
    /// store's own bytes when the encodings agree (BC6H blocks included: the store has checked
    /// them for reserved modes), else the decoded texels re-encoded.
    pub fn build(&self, store: &Store, cube: u32, face: u8) -> Result<Vec<u8>, oslf_format::Error> {
        let n = (self.res as usize).pow(2);
        let mut rgb = vec![[0.0f32; 3]; n];
        let mut dist = vec![0.0f32; if self.depth { n } else { 0 }];
        let mut out = vec![0u8; self.payload_bytes()];
        let level0 = self.level_bytes(0);
        if store.header().encoding == self.encoding && store.cube_resolution() == self.res {
            let mut raw = vec![0u8; store.face_raw_size()];
            store.read_face_raw(cube, face as usize, &mut raw)?;
            out[..level0].copy_from_slice(&raw[..level0]);
            decode_face_texels(
                self.encoding,
                self.res,
                &raw[..level0],
                &mut rgb,
                cube,
                face as usize,
            )?;
            if self.depth {
                oslf_format::encoding::decode_distances(&raw[level0..level0 + 4 * n], &mut dist)?;
            }
        } else {
            let d = self.depth.then_some(dist.as_mut_slice());
            store.read_face(cube, face as usize, &mut rgb, d)?;
            encode_face_texels(self.encoding, self.res, &rgb, &mut out[..level0])?;
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
            let dst = &mut out[at..at + self.level_bytes(l)];
            if self.encoding.is_block_compressed() {
                encode_face_with(&rgb, self.side(l), dst, MIP_QUALITY)?;
            } else {
                encode_face_texels(self.encoding, self.side(l), &rgb, dst)?;
            }
        }
        Ok(())
    }

    /// Decodes level `l` of `payload` to linear RGB (BC6H as the GPU decodes it, the
    /// specification's decoder). A BC6H block with a reserved mode (which [`FaceLayout::build`]
    /// never writes) is an error naming cube 0, face 0: the caller knows which face it is.
    pub fn decode_level(
        &self,
        payload: &[u8],
        l: u32,
    ) -> Result<Vec<[f32; 3]>, oslf_format::Error> {
        let at = self.level_offset(l);
        let side = self.side(l);
        let mut rgb = vec![[0.0f32; 3]; (side as usize).pow(2)];
        decode_face_texels(
            self.encoding,
            side,
            &payload[at..at + self.level_bytes(l)],
            &mut rgb,
            0,
            0,
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

/// Weights of the separable tent that [`downsample`] filters with: texels 2x − 1 … 2x + 2 of
/// the finer level for texel x of the coarser (before the solid angles and the normalisation).
const TENT: [f32; 4] = [1.0, 3.0, 3.0, 1.0];

/// The next mip level of a `side`² level: each texel the 4×4 tent [1 3 3 1] ⊗ [1 3 3 1]
/// around its 2×2 block (the face's edge texels repeated beyond it), each finer texel also
/// weighted by the solid angle it subtends, (1 + u² + v²)^(−3/2) at its centre (u, v ∈ [−1, 1]
/// across the face), normalised, summed in a fixed order: the mean radiance over the
/// directions the tent covers. A texel-space mean weighs a face's corner texels, which subtend
/// up to 5.2× less than its centre's, as much as those: the coarse levels a wide lobe's few
/// filtered samples read then held the wrong mix of directions, and a wide lobe at small M
/// came out darker than at large M (docs/measurements.md, "Mips weighted by solid angle, a
/// spiral per candidate"). The tent rather than the 2×2 box because filtered importance sampling reads
/// a few coarse levels bilinearly with a fixed set of directions: the box's blocks show there
/// as bands across a wide lobe's reflection.
pub fn downsample(src: &[[f32; 3]], side: u32) -> Vec<[f32; 3]> {
    let s = side as usize;
    let h = (s / 2).max(1);
    let clamp = |i: usize| i.clamp(1, s) - 1; // finer index i − 1, clamped to the face
    let mut out = vec![[0.0f32; 3]; h * h];
    // Each finer texel's (1 + u² + v²)^(−3/2), once per texel (a load decodes thousands of
    // faces: a power per tap doubled its time).
    let c2: Vec<f32> = (0..s)
        .map(|i| (2.0 * (i as f32 + 0.5) / s as f32 - 1.0).powi(2))
        .collect();
    let omega: Vec<f32> = (0..s * s)
        .map(|i| {
            let q = 1.0 + c2[i % s] + c2[i / s];
            1.0 / (q * q.sqrt())
        })
        .collect();
    for y in 0..h {
        for x in 0..h {
            let mut acc = [0.0f32; 3];
            let mut total = 0.0f32;
            for (dy, wy) in TENT.iter().enumerate() {
                let fy = clamp(2 * y + dy);
                for (dx, wx) in TENT.iter().enumerate() {
                    let fx = clamp(2 * x + dx);
                    let w = wx * wy * omega[fy * s + fx];
                    let t = src[fy * s + fx];
                    total += w;
                    for k in 0..3 {
                        acc[k] += t[k] * w;
                    }
                }
            }
            out[y * h + x] = acc.map(|a| a / total);
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
    fn bc6h_levels_stay_whole_blocks() {
        assert_eq!(bc6h_levels(32), 4);
        assert_eq!(bc6h_levels(64), 5);
        assert_eq!(bc6h_levels(8), 2);
        assert_eq!(bc6h_levels(4), 1);
        assert_eq!(bc6h_levels(12), 1);
        assert_eq!(bc6h_levels(6), 1);
        for res in [4u32, 8, 12, 24, 32, 48, 64] {
            let layout = FaceLayout::of(Encoding::Bc6h, res, true);
            assert_eq!(layout.encoding, Encoding::Bc6h);
            for l in 0..layout.levels {
                assert_eq!(layout.side(l) % 4, 0, "res {res} level {l}");
                assert_eq!(layout.level_bytes(l), (layout.side(l) as usize).pow(2));
            }
        }
        // 32²: 1024 + 256 + 64 + 16 bytes of blocks, then 2048 of distances.
        let l = FaceLayout::of(Encoding::Bc6h, 32, true);
        assert_eq!(l.depth_offset(), 1360);
        assert_eq!(l.payload_bytes(), 1360 + 2048);
        assert_eq!(l.level_rows(1), (64, 4));
        let rgb9e5 = FaceLayout::of(Encoding::Bc6h, 6, false);
        assert_eq!(rgb9e5.encoding, Encoding::Rgb9e5);
        assert_eq!(rgb9e5.levels, mip_levels(6));
    }

    #[test]
    fn bc6h_payloads_round_trip_through_the_layout() {
        let res = 16u32;
        let layout = FaceLayout::of(Encoding::Bc6h, res, false);
        // Smooth radiance, as cube maps mostly are (BC6H fits a line per block region).
        let src: Vec<[f32; 3]> = (0..res * res)
            .map(|i| {
                let (x, y) = ((i % 16) as f32, (i / 16) as f32);
                [0.5 + 0.03 * x, 0.4 + 0.02 * y, 1.0 + 0.01 * (x + y)]
            })
            .collect();
        let mut out = vec![0u8; layout.payload_bytes()];
        encode_face_texels(Encoding::Bc6h, res, &src, &mut out[..layout.level_bytes(0)]).unwrap();
        let level0 = layout.decode_level(&out, 0).unwrap();
        layout.fill_mips(&mut out, level0.clone()).unwrap();
        let mut expect = level0;
        for l in 1..layout.levels {
            expect = downsample(&expect, layout.side(l - 1));
            let side = layout.side(l);
            // Exactly the filtered level encoded at MIP_QUALITY, at its offset ...
            let mut blocks = vec![0u8; layout.level_bytes(l)];
            encode_face_with(&expect, side, &mut blocks, MIP_QUALITY).unwrap();
            let at = layout.level_offset(l);
            assert_eq!(&out[at..at + blocks.len()], &blocks[..], "level {l}");
            // ... and close to it on average (VeryFast fits one BC6H block to a 4² level of a
            // three-channel gradient loosely, texel by texel).
            let got = layout.decode_level(&out, l).unwrap();
            for k in 0..3 {
                let mean = |v: &[[f32; 3]]| v.iter().map(|t| t[k]).sum::<f32>() / v.len() as f32;
                let (g, e) = (mean(&got), mean(&expect));
                assert!(
                    (g - e).abs() <= 0.05 * e,
                    "level {l} channel {k}: {g} vs {e}"
                );
            }
        }
    }

    /// The solid angle of texel (x, y) of a face `n` texels wide, exactly: the cube face at
    /// distance 1 spans [−1, 1]², and a rectangle [u0, u1] × [v0, v1] on it subtends
    /// A(u1, v1) − A(u0, v1) − A(u1, v0) + A(u0, v0), A(u, v) = atan2(uv, √(u² + v² + 1)).
    fn texel_solid_angle(x: usize, y: usize, n: usize) -> f64 {
        let a = |u: f64, v: f64| (u * v).atan2((u * u + v * v + 1.0).sqrt());
        let at = |i: usize| 2.0 * i as f64 / n as f64 - 1.0;
        let (u0, u1, v0, v1) = (at(x), at(x + 1), at(y), at(y + 1));
        a(u1, v1) - a(u0, v1) - a(u1, v0) + a(u0, v0)
    }

    /// The light a level sends, Σ solid angle × radiance over its texels.
    fn light(level: &[[f32; 3]], k: usize) -> f64 {
        let n = (level.len() as f64).sqrt() as usize;
        (0..level.len())
            .map(|i| texel_solid_angle(i % n, i / n, n) * level[i][k] as f64)
            .sum()
    }

    /// Each coarser texel is a weighted mean (a constant face stays that constant), and the
    /// light a face sends stays near what level 0 sends at every level: within 0.2 % for a
    /// smooth sky, within 12 % for a bright 3 × 3 patch at a corner of the face or at its
    /// centre (the tent spreads it over texels of other solid angles). The texel-space tent
    /// this replaced sent the corner patch's light 1.93× and the centre patch's 0.54× at the
    /// 2 × 2 level: it weighed the corner's texels, which subtend less, as much as the centre's.
    #[test]
    fn downsampling_keeps_the_light_a_face_sends() {
        let n = 32usize;
        let constant = vec![[0.3f32, 2.0, 1e4]; n * n];
        for t in downsample(&constant, n as u32) {
            for (a, b) in t.iter().zip([0.3f32, 2.0, 1e4]) {
                assert!((a - b).abs() <= 1e-6 * b, "{t:?}");
            }
        }
        let smooth: Vec<[f32; 3]> = (0..n * n)
            .map(|i| {
                let (x, y) = ((i % n) as f32 / n as f32, (i / n) as f32 / n as f32);
                [
                    1.0 + x,
                    2.0 - y,
                    1.0 + 0.5 * (6.0 * x).sin() * (4.0 * y).cos(),
                ]
            })
            .collect();
        let patch = |x0: usize, y0: usize| {
            let mut face = vec![[0.01f32; 3]; n * n];
            for y in y0..y0 + 3 {
                for x in x0..x0 + 3 {
                    face[y * n + x] = [50.0, 50.0, 50.0];
                }
            }
            face
        };
        for (name, face, tolerance) in [
            ("smooth", smooth, 0.002),
            ("corner patch", patch(1, 1), 0.12),
            ("centre patch", patch(14, 14), 0.12),
        ] {
            let (mut level, mut side) = (face.clone(), n);
            while side > 1 {
                level = downsample(&level, side as u32);
                side /= 2;
                for k in 0..3 {
                    let (got, want) = (light(&level, k), light(&face, k));
                    assert!(
                        (got / want - 1.0).abs() < tolerance,
                        "{name}, channel {k}, level of {side}²: {got} against {want}"
                    );
                }
            }
        }
        // One bright texel at the centre goes into the four coarser texels around it.
        let mut spot = vec![[0.0f32; 3]; 64];
        spot[3 * 8 + 4] = [64.0, 0.0, 0.0];
        let d = downsample(&spot, 8);
        assert!(d.iter().filter(|t| t[0] > 0.0).count() == 4);
    }

    #[test]
    fn distances_round_to_half_and_escaped_rays_read_far() {
        assert_eq!(depth_to_f16(f32::MAX).to_f32(), FAR_DISTANCE);
        assert_eq!(depth_to_f16(1e9).to_f32(), FAR_DISTANCE);
        assert_eq!(depth_to_f16(2.5).to_f32(), 2.5);
        assert!((depth_to_f16(3.3).to_f32() - 3.3).abs() < 3.3 * 1e-3);
    }
}
