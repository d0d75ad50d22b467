//! glTF 2.0's metallic-roughness BRDF (the specification's Appendix B): a Trowbridge–Reitz
//! (GGX) specular lobe with separable Smith masking-shadowing and Schlick's Fresnel, over a
//! Lambertian base for dielectrics (F₀ = 0.04, index of refraction 1.5), mixed by `metallic`.
//! The path tracer draws environment materials with it (`oslf_trace::integrator`) and the ground
//! truth the OSLF object in the `pbr` mode (`oslf_trace::ground_truth::Term::Pbr`); the runtime's
//! `pbr` mode evaluates the same formulas in its shader and CPU reference.
//!
//! With `α = roughness²`, `h` the half vector of `v` (towards the viewer) and `l` (towards the
//! light), all cosines taken against the shading normal `n`:
//!
//! - `D = α² χ⁺(n·h) / (π ((n·h)² (α² − 1) + 1)²)`
//! - `V = 1 / ((n·l + √(α² + (1 − α²)(n·l)²)) (n·v + √(α² + (1 − α²)(n·v)²)))`
//! - `specular = V · D`
//! - `metal = specular · (c + (1 − c)(1 − v·h)⁵)`, with `c` the base colour
//! - `dielectric = mix(c / π, specular, 0.04 + 0.96 (1 − v·h)⁵)`
//! - `f = mix(dielectric, metal, metallic)`
//!
//! The model is the specification's, energy included: a metal reflects at most what arrives
//! (less as it roughens: single scattering), but a dielectric's diffuse base is weighted by
//! Fresnel at the half vector, not the view, so at grazing views it reflects more than arrives
//! (a smooth one seen 78° from the normal, 1.30 of a white furnace; `tests/metallic_roughness.rs`).
//!
//! `α` is at least [`MIN_ALPHA`](oslf_shading::ggx::MIN_ALPHA) ([`oslf_shading::ggx`], where `D`, `V`, `G₁` and the
//! visible-normal sampling are written once for every path).
//!
//! Sampling: with probability `p = ½ + ½·metallic` a microfacet normal is drawn from the
//! distribution of visible normals (Heitz 2018, "Sampling the GGX Distribution of Visible
//! Normals") and `v` reflected about it, else a cosine-weighted direction; the density is the
//! mixture's, so one sample serves both lobes without bias.

use std::f32::consts::FRAC_1_PI;

use glam::{Vec2, Vec3};
use oslf_shading::fresnel::{schlick, schlick_weight};
use oslf_shading::ggx::{self, DIELECTRIC_F0};

use oslf_shading::warp::{cosine_hemisphere_pdf, sample_cosine_hemisphere, Frame};

/// A metallic-roughness surface at one point: glTF's factors times its textures.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MetallicRoughness {
    /// Base colour `c`, each component in `[0, 1]`.
    pub base_color: Vec3,
    /// 0 for a dielectric, 1 for a metal.
    pub metallic: f32,
    /// Perceptual roughness; `α = roughness²`.
    pub roughness: f32,
}

/// A direction drawn by [`MetallicRoughness::sample`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BrdfSample {
    /// The direction towards the light, unit, world space.
    pub wi: Vec3,
    /// `f · cos θᵢ / pdf`.
    pub weight: Vec3,
    /// The density of `wi` (solid angle).
    pub pdf: f32,
}

impl MetallicRoughness {
    /// `α = roughness²`, at least [`MIN_ALPHA`](oslf_shading::ggx::MIN_ALPHA).
    pub fn alpha(&self) -> f32 {
        ggx::alpha(self.roughness)
    }

    /// Probability of drawing from the specular lobe.
    fn specular_probability(&self) -> f32 {
        0.5 + 0.5 * self.metallic
    }

    /// The BRDF for view direction `wo` and light direction `wi` (both unit, pointing away
    /// from the surface) about the shading normal `n`; zero where either is below it.
    pub fn eval(&self, n: Vec3, wo: Vec3, wi: Vec3) -> Vec3 {
        let (nv, nl) = (n.dot(wo), n.dot(wi));
        if nv <= 0.0 || nl <= 0.0 {
            return Vec3::ZERO;
        }
        let Some(h) = (wo + wi).try_normalize() else {
            return Vec3::ZERO;
        };
        let a2 = self.alpha() * self.alpha();
        let vh = wo.dot(h).abs();
        let specular = ggx::visibility(a2, nl, nv) * ggx::distribution_at(a2, n, h);
        let k5 = schlick_weight(vh);
        let c = self.base_color;
        let metal = specular * (c + (Vec3::ONE - c) * k5);
        let fr = schlick(DIELECTRIC_F0, vh);
        let dielectric = c * FRAC_1_PI * (1.0 - fr) + Vec3::splat(specular * fr);
        dielectric.lerp(metal, self.metallic)
    }

    /// The density with which [`MetallicRoughness::sample`] draws `wi` for `wo` about `n`.
    pub fn pdf(&self, n: Vec3, wo: Vec3, wi: Vec3) -> f32 {
        let (nv, nl) = (n.dot(wo), n.dot(wi));
        if nv <= 0.0 || nl <= 0.0 {
            return 0.0;
        }
        let Some(h) = (wo + wi).try_normalize() else {
            return 0.0;
        };
        let a2 = self.alpha() * self.alpha();
        // Visible normals: D_v(h) = G₁(v) (v·h)⁺ D(h) / (n·v); reflection: / (4 v·h).
        let specular = ggx::smith_g1(a2, nv) * ggx::distribution_at(a2, n, h) / (4.0 * nv);
        let p = self.specular_probability();
        p * specular + (1.0 - p) * cosine_hemisphere_pdf(nl)
    }

    /// Draws a light direction for `wo` about `n` from `u` (three uniform numbers: the lobe,
    /// then the direction); `None` where the draw falls below the surface or `wo` is below it.
    pub fn sample(&self, n: Vec3, wo: Vec3, lobe: f32, u: Vec2) -> Option<BrdfSample> {
        let frame = Frame::from_normal(n);
        let v = frame.to_local(wo);
        if v.z <= 0.0 {
            return None;
        }
        let wi = if lobe < self.specular_probability() {
            let m = frame.to_world(ggx::sample_visible_normal(v, self.alpha(), u.x, u.y));
            (2.0 * wo.dot(m) * m - wo).try_normalize()?
        } else {
            frame.to_world(sample_cosine_hemisphere(u))
        };
        let pdf = self.pdf(n, wo, wi);
        let nl = n.dot(wi);
        if !(pdf > 0.0 && pdf.is_finite() && nl > 0.0) {
            return None;
        }
        let weight = self.eval(n, wo, wi) * (nl / pdf);
        weight.is_finite().then_some(BrdfSample { wi, weight, pdf })
    }
}
