//! The entry point: one pixel of the G-buffer shaded. As shade/pixel.wgsl, function for function.

use glam::Vec3;

use oslf_shading::color::srgb_to_linear;

use super::material::unpack2x16unorm;
use super::patch::{patch_du, patch_normal, surface_hit, tangent_frame, SurfacePoint};
use super::random::pcg;
use super::{CubeTexels, GTexel, Shader};

/// Replaces NaN and infinities by 0 (as `finite3`).
pub(super) fn finite3(c: Vec3) -> Vec3 {
    Vec3::from_array(c.to_array().map(|x| if x.is_finite() { x } else { 0.0 }))
}

/// The emissive texture's RGB that the material target's `w` holds above the flags, decoded
/// (as `emissive_of` in pixel.wgsl).
pub(super) fn emissive_of(w: u32) -> Vec3 {
    let c = |shift: u32| srgb_to_linear(((w >> shift) & 0xff) as f32 / 255.0);
    Vec3::new(c(8), c(16), c(24))
}

/// The pixel's base colour, pbr material (metallic, GGX α), emission and occlusion (as
/// `Surface`).
pub(super) struct Surface {
    pub base: Vec3,
    pub pbr: glam::Vec2,
    pub emission: Vec3,
    pub occlusion: f32,
}

#[allow(clippy::needless_range_loop, clippy::neg_cmp_op_on_partial_ord)]
impl<C: CubeTexels> Shader<'_, C> {
    /// The pbr mode's metallic and GGX α on map `patch` (as `pbr_material`): its object's
    /// material's where the store has one and the uniform takes it, else the uniform's.
    pub(super) fn pbr_material(&self, patch: u32) -> glam::Vec2 {
        let u = &self.uniform;
        match self.materials.get(patch as usize) {
            Some(m) if u.object_material != 0 && m[2] > 0.5 => glam::Vec2::new(m[0], m[1]),
            _ => glam::Vec2::new(u.metallic, u.alpha),
        }
    }

    /// The pixel's [`Surface`]: its object's, with what the object's textures give (the
    /// G-buffer's material) in their place (as `surface_of`).
    pub(super) fn surface_of(&self, patch: u32, g: &GTexel) -> Surface {
        let mut base = self
            .colors
            .get(patch as usize)
            .copied()
            .unwrap_or(Vec3::ONE);
        let mut pbr = self.pbr_material(patch);
        let mut emission = self
            .emissions
            .get(patch as usize)
            .map_or(Vec3::ZERO, |e| Vec3::new(e[0], e[1], e[2]));
        let m = g.material;
        let rg = unpack2x16unorm(m[0]);
        let bm = unpack2x16unorm(m[1]);
        let ro = unpack2x16unorm(m[2]);
        if m[3] & 1 != 0 {
            base = Vec3::new(rg.x, rg.y, bm.x);
        }
        let own = self
            .materials
            .get(patch as usize)
            .is_some_and(|o| o[2] > 0.5);
        if m[3] & 2 != 0 && self.uniform.object_material != 0 && own {
            pbr = glam::Vec2::new(bm.y, oslf_shading::ggx::alpha(ro.x));
        }
        if m[3] & 8 != 0 {
            emission *= emissive_of(m[3]);
        }
        let occlusion = if m[3] & 16 != 0 { ro.y } else { 1.0 };
        Surface {
            base,
            pbr,
            emission,
            occlusion,
        }
    }

    /// Shades pixel `(px, py)` with G-buffer texel `g`: the background with alpha 0 off the
    /// object, else the colour with alpha 1 (as `shade` in shade.wgsl).
    pub fn shade(&self, px: u32, py: u32, g: &GTexel) -> [f32; 4] {
        let u = &self.uniform;
        if g.position_patch[3] < 0.5 {
            return self.background(px, py);
        }
        let patch = (g.position_patch[3] - 0.5) as u32;
        let gx = Vec3::new(
            g.position_patch[0],
            g.position_patch[1],
            g.position_patch[2],
        );
        let guv = (g.normal_uv[2], g.normal_uv[3]);
        // The point on the patch itself, not on its triangles (the truth's shading point).
        let d = (gx - Vec3::from_slice(&u.camera_pos[..3])).normalize();
        let hit = self.patches.get(patch as usize).map_or(
            SurfacePoint {
                x: gx,
                u: guv.0,
                v: guv.1,
            },
            |p| surface_hit(p, gx, guv, d, u.surface_error),
        );
        let (x, pu, pv) = (hit.x, hit.u, hit.v);
        let ni = crate::geometry::oct_decode([g.normal_uv[0], g.normal_uv[1]]);
        let n = self
            .patches
            .get(patch as usize)
            .map_or(ni, |p| patch_normal(p, pu, pv, ni));
        let c = self.candidates(patch, pu, pv, x, n);
        let v = (Vec3::from_slice(&u.camera_pos[..3]) - x).normalize();
        let r = 2.0 * n.dot(v) * n - v; // Eq. 2.4
        let pixel = pcg(px.wrapping_add(pcg(py.wrapping_add(pcg(u.seed)))));
        let surface = self.surface_of(patch, g);
        let (base, pbr) = (surface.base, surface.pbr);
        let mut spec = Vec3::ZERO;
        if u.terms & 2 != 0 {
            spec = self.mirror(&c, x, n, r);
        } else if u.terms & 4 != 0 {
            let du = self
                .patches
                .get(patch as usize)
                .map_or(Vec3::ZERO, |p| patch_du(p, pu, pv));
            let t = tangent_frame(n, du);
            spec = self.glossy(&c, pixel, x, n, t, v, r, base, pbr);
        }
        if u.terms & 8 != 0 {
            spec *= base;
        }
        let mut color = spec;
        if u.terms & 1 != 0 {
            color += self.recon(&c, x, n); // Eq. 3.12, 4.12
        }
        if u.terms & 16 != 0 {
            // The pbr mode draws the object's occlusion texture and its own emission.
            color = color * surface.occlusion + surface.emission;
        }
        let c = finite3(color);
        [c.x, c.y, c.z, 1.0]
    }
}
