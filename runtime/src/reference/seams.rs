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

#[allow(clippy::needless_range_loop, clippy::neg_cmp_op_on_partial_ord)]
impl<C: CubeTexels> Shader<'_, C> {
    /// Texel `(x, y)` of mip `level` of `face` of `cube`, where `(x, y)` may lie one texel off
    /// the face: then the texel of the adjacent face it stands for ([`seam_coords`]). `None`
    /// when that face is not available. Marks the face it reads when `mark` (as `seam_texel`).
    pub(super) fn seam_texel(
        &self,
        cube: u32,
        face: usize,
        (x, y): (i32, i32),
        level: u32,
        mark: bool,
    ) -> Option<Vec3> {
        let n = (self.uniform.cube_res >> level).max(1) as i32;
        let (f, c) = seam_coords(face, (x, y), n);
        if mark {
            self.mark(cube, f);
        }
        self.cubes.texel(cube, f, level, c.0 as u32, c.1 as u32)
    }

    /// Radiance of mip `level` of `cube` at `face_st` of a direction, bilinear *across* face
    /// edges: the four
    /// texel centres around the direction on its face, those off the face read from the
    /// adjacent face ([`Self::seam_texel`]), with the usual bilinear weights. At a corner of
    /// the cube, where three faces meet, the texel off the face in both directions does not
    /// exist: it is the mean of the other three. `None` when a face it reads is not available.
    /// Marks the faces it reads when `mark` (as `seamless_level`).
    pub(super) fn seamless_level(
        &self,
        cube: u32,
        (face, s, t): (usize, f32, f32),
        level: u32,
        mark: bool,
    ) -> Option<Vec3> {
        let n = (self.uniform.cube_res >> level).max(1) as i32;
        let nf = n as f32;
        let fx = s * nf - 0.5;
        let fy = t * nf - 0.5;
        let (x0, y0) = (fx.floor() as i32, fy.floor() as i32);
        let (wx, wy) = (fx - fx.floor(), fy - fy.floor());
        // The texel off the face in both directions, as k = column + 2 * row; 4 = none.
        let mut corner = 4;
        if (x0 < 0 || x0 + 1 >= n) && (y0 < 0 || y0 + 1 >= n) {
            corner = usize::from(x0 >= 0) + 2 * usize::from(y0 >= 0);
        }
        // Every texel is read (and its face marked) before any is missed, as on the GPU.
        let read: [Option<Vec3>; 4] = std::array::from_fn(|k| {
            if k == corner {
                Some(Vec3::ZERO)
            } else {
                let at = (x0 + (k & 1) as i32, y0 + (k >> 1) as i32);
                self.seam_texel(cube, face, at, level, mark)
            }
        });
        let mut t = [read[0]?, read[1]?, read[2]?, read[3]?];
        if corner < 4 {
            t[corner] = (t[0] + t[1] + t[2] + t[3]) * (1.0 / 3.0);
        }
        let top = t[0] + (t[1] - t[0]) * wx;
        let bottom = t[2] + (t[3] - t[2]) * wx;
        Some(top + (bottom - top) * wy)
    }

    /// `seamless_level` at level 0 without feedback marks: for the background only (as
    /// `seamless_read`). `lookup` (reflections, reconstruction) clamps at face edges.
    pub(super) fn seamless_read(&self, cube: u32, dir: Vec3) -> Option<Vec3> {
        self.seamless_level(cube, face_st(dir), 0, false)
    }
}
