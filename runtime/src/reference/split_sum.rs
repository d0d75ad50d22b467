//! The split-sum baseline of the pbr mode. As shade/split_sum.wgsl, function for function.

use glam::{Vec2, Vec3, Vec4};

use super::seams::{seam_bilinear, seam_taps};
use super::{face_st, CubeTexels, Shader};

#[allow(clippy::neg_cmp_op_on_partial_ord)]
impl<C: CubeTexels> Shader<'_, C> {
    /// Texel `(x, y)` of `face` of mip `level` of the prefiltered environment, specular faces
    /// from layer 0, irradiance from layer 6 (`first`).
    fn prefiltered_texel(&self, first: u32, (face, x, y): (usize, i32, i32), level: u32) -> Vec3 {
        self.prefiltered
            .texel(first == 6, face, level, x as u32, y as u32)
    }

    /// Mip `level` of the prefiltered environment (faces from layer `first`) at `face_st` of a
    /// direction, bilinear across face edges as `seamless_level` reads a cube.
    pub(super) fn prefiltered_level(&self, first: u32, fst: (usize, f32, f32), level: u32) -> Vec3 {
        let taps = seam_taps(fst, self.prefiltered.side(level) as i32);
        let texels = taps
            .c
            .map(|(f, (x, y))| self.prefiltered_texel(first, (f, x, y), level));
        seam_bilinear(&taps, texels)
    }

    /// The specular levels towards `dir` at perceptual roughness `roughness`: level
    /// roughness · (L − 1), blended between the two nearest.
    fn prefiltered_specular(&self, dir: Vec3, roughness: f32) -> Vec3 {
        let top = self.prefiltered.levels() - 1;
        let l = (roughness * top as f32).clamp(0.0, top as f32);
        let l0 = l.floor() as u32;
        let f = l - l0 as f32;
        let fst = face_st(dir);
        let a = self.prefiltered_level(0, fst, l0);
        if !(f > 0.0) {
            return a;
        }
        let b = self.prefiltered_level(0, fst, (l0 + 1).min(top));
        a + (b - a) * f
    }

    /// The split sum's second factor: GGX's directional albedo as scale and bias of F0, the
    /// analytic fit of Karis 2014 ("Physically Based Shading on Mobile").
    pub(crate) fn env_brdf(roughness: f32, nv: f32) -> Vec2 {
        let r = roughness * Vec4::new(-1.0, -0.0275, -0.572, 0.022)
            + Vec4::new(1.0, 0.0425, 1.04, -0.04);
        let a004 = (r.x * r.x).min((-9.28 * nv).exp2()) * r.x + r.y;
        Vec2::new(-1.04, 1.04) * a004 + Vec2::new(r.z, r.w)
    }

    /// glTF's metallic-roughness BRDF lit by the prefiltered environment (see
    /// `split_sum` in shade/split_sum.wgsl).
    #[allow(clippy::too_many_arguments)]
    pub(super) fn split_sum(
        &self,
        x: Vec3,
        n: Vec3,
        v: Vec3,
        r: Vec3,
        base: Vec3,
        pbr: Vec2,
    ) -> Vec3 {
        let nv = n.dot(v).clamp(0.0, 1.0);
        let roughness = pbr.y.sqrt();
        let ab = Self::env_brdf(roughness, nv);
        let f0 = Vec3::splat(0.04) + (base - Vec3::splat(0.04)) * pbr.x;
        let mut c = self.prefiltered_specular(self.env_dir(x, r), roughness)
            * (f0 * ab.x + Vec3::splat(ab.y));
        if self.uniform.min_metallic < 1.0 {
            let e = self.prefiltered_level(6, face_st(n), 0);
            c += e * base * ((1.0 - pbr.x) * (1.0 - (0.04 * ab.x + ab.y)));
        }
        c
    }
}
