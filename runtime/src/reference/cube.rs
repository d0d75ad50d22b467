//! Cube maps: face coordinates, bilinear taps, mip lookups. As shade/cube.wgsl, function for function.

use glam::Vec3;

use super::{CubeTexels, Shader};

/// Face and face coordinates of a direction: [`oslf_format::cube::direction_to_face_st`].
pub fn face_st(d: Vec3) -> (usize, f32, f32) {
    oslf_format::cube::direction_to_face_st(d.to_array())
}

/// The point of `face`'s plane (major axis ±1) at face coordinates `(s, t)`, which may lie
/// outside `[0, 1]`: the inverse of [`face_st`] ([`oslf_format::cube::face_st_to_direction`],
/// not normalized).
pub fn face_point(face: usize, s: f32, t: f32) -> Vec3 {
    let sc = 2.0 * s - 1.0;
    let tc = 2.0 * t - 1.0;
    match face {
        0 => Vec3::new(1.0, -tc, -sc),
        1 => Vec3::new(-1.0, -tc, sc),
        2 => Vec3::new(sc, 1.0, tc),
        3 => Vec3::new(sc, -1.0, -tc),
        4 => Vec3::new(sc, -tc, 1.0),
        _ => Vec3::new(-sc, -tc, -1.0),
    }
}

/// The four texels and bilinear weights of face coordinates (as `Tap` in shade.wgsl).
pub(super) use oslf_format::cube::Tap;

#[allow(clippy::needless_range_loop, clippy::neg_cmp_op_on_partial_ord)]
impl<C: CubeTexels> Shader<'_, C> {
    /// `lookup` on mip `level`, without the feedback mark (as `read_tap`): bilinear
    /// within the face.
    pub(super) fn read_tap(
        &self,
        cube: u32,
        face: usize,
        s: f32,
        t: f32,
        level: u32,
    ) -> Option<Vec3> {
        let Tap {
            x0,
            y0,
            x1,
            y1,
            wx,
            wy,
        } = Tap::new((self.uniform.cube_res >> level).max(1), s, t);
        let t00 = self.cubes.texel(cube, face, level, x0, y0)?;
        let t10 = self.cubes.texel(cube, face, level, x1, y0)?;
        let t01 = self.cubes.texel(cube, face, level, x0, y1)?;
        let t11 = self.cubes.texel(cube, face, level, x1, y1)?;
        let top = t00 + (t10 - t00) * wx;
        let bottom = t01 + (t11 - t01) * wx;
        Some(top + (bottom - top) * wy)
    }

    /// Radiance of `cube` towards `dir`, marking the face as needed (as `lookup`/`fetch`).
    pub(super) fn lookup(&self, cube: u32, dir: Vec3) -> Option<Vec3> {
        let (face, s, t) = face_st(dir);
        self.mark(cube, face);
        self.read_tap(cube, face, s, t, 0)
    }

    /// Radiance of `cube` towards `dir` at fractional mip level `lod`, marking the face (as
    /// `lookup_lod`).
    pub(super) fn lookup_lod(&self, cube: u32, dir: Vec3, lod: f32) -> Option<Vec3> {
        if !(lod > 0.0) {
            return self.lookup(cube, dir);
        }
        self.lookup_levels(cube, dir, lod)
    }

    /// Radiance of `cube` towards `dir` at mip level `lod` ≥ 0 across face edges, the two
    /// nearest levels blended (as `lookup_levels`).
    pub(super) fn lookup_levels(&self, cube: u32, dir: Vec3, lod: f32) -> Option<Vec3> {
        let top = self.uniform.mip_levels - 1;
        let l = lod.clamp(0.0, top as f32);
        let l0 = l.floor() as u32;
        let f = l - l0 as f32;
        let fst = face_st(dir);
        let a = self.seamless_level(cube, fst, l0, true);
        if !(f > 0.0) {
            return a;
        }
        let b = self.seamless_level(cube, fst, (l0 + 1).min(top), true);
        Some(a? + (b? - a?) * f)
    }

    /// The mip level of a sample towards `dir` with log2(M p) = `lpdf` (as `sample_lod`).
    pub(super) fn sample_lod(&self, dir: Vec3, lpdf: f32) -> f32 {
        if self.uniform.mip_levels <= 1 {
            return 0.0;
        }
        let (_, s, t) = face_st(dir);
        let (sc, tc) = (2.0 * s - 1.0, 2.0 * t - 1.0);
        let log_texel = 2.0 * (2.0 / self.uniform.cube_res as f32).log2()
            - 1.5 * (1.0 + sc * sc + tc * tc).log2();
        (0.5 * (-lpdf - log_texel)).max(0.0)
    }
}
