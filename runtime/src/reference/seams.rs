//! Lookups filtered across face edges (for the background). As shade/seams.wgsl, function for function.

use glam::Vec3;

use super::cube::{face_point, face_st};
use super::{CubeTexels, Shader};

/// Face and texel of a level `n` texels wide that texel `(x, y)` of `face` stands for, where
/// `(x, y)` may lie one texel off the face: then the texel of the adjacent face that the
/// direction through that texel's centre, extended on `face`'s plane, lands in (nearest
/// texel). shade.wgsl's `seam_texel` reads the same texel from a table (SEAM_LO, SEAM_HI).
pub fn seam_coords(face: usize, (x, y): (i32, i32), n: i32) -> (usize, (i32, i32)) {
    if x >= 0 && y >= 0 && x < n && y < n {
        return (face, (x, y));
    }
    let nf = n as f32;
    let (f, s, t) = face_st(face_point(
        face,
        (x as f32 + 0.5) / nf,
        (y as f32 + 0.5) / nf,
    ));
    (
        f,
        (((s * nf) as i32).min(n - 1), ((t * nf) as i32).min(n - 1)),
    )
}

/// The four texel centres around `face_st` of a direction on a level `n` texels wide, *across*
/// face edges: those off the face are the adjacent face's ([`seam_coords`]). At a corner of the
/// cube, where three faces meet, the texel off the face in both directions does not exist:
/// `corner` names it (k = column + 2 · row; 4 = none) and [`seam_bilinear`] replaces it by the
/// mean of the other three. As `SeamTaps` in shade/seams.wgsl.
pub struct SeamTaps {
    /// Face and texel of each tap, in the order (x0, y0), (x0 + 1, y0), (x0, y0 + 1),
    /// (x0 + 1, y0 + 1).
    pub c: [(usize, (i32, i32)); 4],
    pub wx: f32,
    pub wy: f32,
    pub corner: usize,
}

pub fn seam_taps((face, s, t): (usize, f32, f32), n: i32) -> SeamTaps {
    let nf = n as f32;
    let fx = s * nf - 0.5;
    let fy = t * nf - 0.5;
    let (x0, y0) = (fx.floor() as i32, fy.floor() as i32);
    let mut corner = 4;
    if (x0 < 0 || x0 + 1 >= n) && (y0 < 0 || y0 + 1 >= n) {
        corner = usize::from(x0 >= 0) + 2 * usize::from(y0 >= 0);
    }
    SeamTaps {
        c: std::array::from_fn(|k| {
            seam_coords(face, (x0 + (k & 1) as i32, y0 + (k >> 1) as i32), n)
        }),
        wx: fx - fx.floor(),
        wy: fy - fy.floor(),
        corner,
    }
}

/// The bilinear blend of the four texels read at `taps` (the corner's replaced by the mean of
/// the other three).
pub fn seam_bilinear(taps: &SeamTaps, mut t: [Vec3; 4]) -> Vec3 {
    if taps.corner < 4 {
        t[taps.corner] = Vec3::ZERO;
        t[taps.corner] = (t[0] + t[1] + t[2] + t[3]) * (1.0 / 3.0);
    }
    let top = t[0] + (t[1] - t[0]) * taps.wx;
    let bottom = t[2] + (t[3] - t[2]) * taps.wx;
    top + (bottom - top) * taps.wy
}

#[allow(clippy::neg_cmp_op_on_partial_ord)]
impl<C: CubeTexels> Shader<'_, C> {
    /// Radiance of mip `level` of `cube` at `face_st` of a direction, bilinear across face
    /// edges ([`seam_taps`]). `None` when a face it reads is not available. Marks the faces it
    /// reads when `mark` (as `seamless_level`).
    pub(super) fn seamless_level(
        &self,
        cube: u32,
        fst: (usize, f32, f32),
        level: u32,
        mark: bool,
    ) -> Option<Vec3> {
        let n = (self.uniform.cube_res >> level).max(1) as i32;
        let taps = seam_taps(fst, n);
        // Every texel is read (and its face marked) before any is missed, as on the GPU.
        let read: [Option<Vec3>; 4] = std::array::from_fn(|k| {
            if k == taps.corner {
                Some(Vec3::ZERO)
            } else {
                let (f, (x, y)) = taps.c[k];
                if mark {
                    self.mark(cube, f);
                }
                self.cubes.texel(cube, f, level, x as u32, y as u32)
            }
        });
        Some(seam_bilinear(
            &taps,
            [read[0]?, read[1]?, read[2]?, read[3]?],
        ))
    }

    /// `seamless_level` at level 0 without feedback marks: for the background only (as
    /// `seamless_read`). `lookup` (reflections, reconstruction) clamps at face edges.
    pub(super) fn seamless_read(&self, cube: u32, dir: Vec3) -> Option<Vec3> {
        self.seamless_level(cube, face_st(dir), 0, false)
    }
}
