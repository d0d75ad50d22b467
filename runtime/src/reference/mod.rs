//! The CPU reference of shade.wgsl: the same shading in Rust `f32`, function for function and
//! in the same operation order, so that GPU images can be checked against it (the parity
//! tests) and so that users without a GPU can still evaluate a G-buffer. Each file here is the
//! twin of the file of the same name under shade/ (composite.rs: the prepass of
//! renderer/composite.wgsl), its functions in the same order.
//!
//! Residency and feedback work as on the GPU: a [`CubeTexels`] says which faces are available,
//! and every face a lookup *would* read with everything resident is marked in the feedback
//! masks (bit `f` of entry `cube` = face `f` needed).
//!
//! `j` indexes the four candidates' parallel arrays (indices, directions, weights), as in
//! shade.wgsl; `!(x > 0.0)` is shade.wgsl's NaN-aware test, kept word for word.

use std::sync::atomic::AtomicU32;

use glam::Vec3;
use oslf_format::SampleMapView;
use oslf_geometry::BezierPatch;

use crate::uniform::ShadeUniform;

mod background;
mod blend;
mod composite;
mod cube;
mod depth;
#[cfg(test)]
mod depth_tests;
mod feedback;
mod glossy;
pub mod material;
mod mirror;
mod patch;
mod pixel;
mod random;
mod reconstruct;
mod seams;
mod split_sum;
mod store;
#[cfg(test)]
mod tests;

pub use composite::{prepass_motion, prepass_normal};
pub use cube::{face_point, face_st};
pub use patch::{
    patch_du, patch_dv, patch_normal, patch_point, surface_hit, tangent_frame, SurfacePoint,
};
pub use random::{filter_rows, filter_xi, pcg};
pub use seams::{seam_bilinear, seam_coords, seam_taps, SeamTaps};
pub use store::StoreCubes;

/// The mip-level bias of the pbr mode's specular (GGX) samples on its spiral of filtered
/// samples (PBR_LOD_BIAS in shade.wgsl): half a level sharper than Křivánek & Colbert's share,
/// the best of −1.5 … +1 on the room's metal teapot at M = 16 and every roughness
/// (docs/measurements.md, "The filtered set of the pbr mode"). Its diffuse samples keep 0.
pub(crate) const PBR_LOD_BIAS: f32 = -0.5;

/// Bisection steps of a depth-corrected lookup (DEPTH_REFINE in shade.wgsl).
pub(crate) const DEPTH_REFINE: u32 = 6;
/// Steps of a glossy sample's depth correction (DEPTH_ITERATIONS in shade.wgsl).
pub(crate) const DEPTH_ITERATIONS: u32 = 2;
/// Depth-thicknesses within which a texel of a depth-corrected lookup agrees with the hit, at
/// most half its distance (LOOKUP_AGREE in shade.wgsl).
pub(crate) const LOOKUP_AGREE: f32 = 1.0;
/// Newton steps of the shading pass's refinement of a G-buffer hit onto its patch
/// (`surface_hit`; REFINE_STEPS in shade.wgsl).
pub(crate) const REFINE_STEPS: u32 = 4;
/// How far outside [0, 1] a refined (u, v) may end before the ray counts as meeting another
/// patch (REFINE_SLACK in shade.wgsl).
pub(crate) const REFINE_SLACK: f32 = 1e-4;
/// How far from the pixel's ray a refined point may end, in the G-buffer tessellation's
/// tolerances, before the refinement counts as not converged (REFINE_MISS in shade.wgsl).
pub(crate) const REFINE_MISS: f32 = 0.1;
/// Depth-thicknesses within which a candidate sees the blend's common hit (HIT_AGREE in
/// shade.wgsl).
pub(crate) const HIT_AGREE: f32 = 0.25;
/// Share of the candidate's distance from x above x's tangent plane below which a glossy
/// sample's hit is not trusted (`low_hit`; LOW_HIT in shade.wgsl).
pub(crate) const LOW_HIT: f32 = 0.25;

/// Where the reference reads cube-map texels.
pub trait CubeTexels: Sync {
    /// Texel `(x, y)` of mip `level` of `face` of cube `cube`, or `None` when that face is not
    /// available (not resident, the GPU's fallback case).
    fn texel(&self, cube: u32, face: usize, level: u32, x: u32, y: u32) -> Option<Vec3>;
    /// Distance texel `(x, y)` of `face` of cube `cube` (as the GPU's binary16 plane holds it),
    /// or `None` when that face is not available or has no distance plane.
    fn depth(&self, cube: u32, face: usize, x: u32, y: u32) -> Option<f32>;
    /// Whether any face of `cube` is available.
    fn resident(&self, cube: u32) -> bool;
}

/// One pixel of the G-buffer, as gbuffer.wgsl writes it.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct GTexel {
    /// World position and sample-map id + 1 (0 = background): a Bézier patch's, or the atlas
    /// page's that gbuffer.wgsl picked from a mesh's atlas uv.
    pub position_patch: [f32; 4],
    /// Octahedral normal, u, v (on the patch, or local to the atlas page).
    pub normal_uv: [f32; 4],
    /// The material target of a store with textured objects (zero otherwise): base colour,
    /// metallic, roughness, occlusion as 16-bit unorm pairs, the object's texture flags
    /// ([`material::material_texel`]).
    pub material: [u32; 4],
}

/// Everything the shader reads besides the G-buffer.
pub struct Shader<'a, C: CubeTexels> {
    pub uniform: ShadeUniform,
    /// Sample-point positions (world space).
    pub samples: &'a [Vec3],
    /// Per cube (sample points, then the environment cube) its stored spherical-harmonic
    /// coefficients (the store's irradiance section), read where the uniform's `irradiance`
    /// says so; empty otherwise.
    pub irradiance: &'a [[Vec3; 9]],
    /// Per sample map: the world-space patch (zero control points for a mesh's atlas page,
    /// whose tangent frame then comes from the normal alone) and its object's base colour C_s.
    pub patches: &'a [BezierPatch],
    pub colors: &'a [Vec3],
    /// Per sample map: its object's material for the pbr mode (`ObjectMesh::materials`;
    /// missing entries are no material).
    pub materials: &'a [[f32; 4]],
    /// Per sample map: its object's emission (`ObjectMesh::emissions`; missing entries emit
    /// nothing).
    pub emissions: &'a [[f32; 4]],
    /// One sample map per map index (Bézier patch or atlas page).
    pub maps: &'a [SampleMapView<'a>],
    pub cubes: &'a C,
    /// Feedback masks, one per cube (sample points, then the environment cube).
    pub feedback: &'a [AtomicU32],
    /// The prefiltered environment the split-sum baseline reads (`crate::prefilter`;
    /// [`NoPrefiltered`] where none is drawn).
    pub prefiltered: &'a dyn PrefilteredTexels,
}

/// Where the reference reads the prefiltered environment of the split-sum baseline (as
/// shade.wgsl's `prefiltered` texture holds it).
pub trait PrefilteredTexels: Sync {
    /// Specular levels, one per mip (at least 1).
    fn levels(&self) -> u32;
    /// Texels a side of mip `level`.
    fn side(&self, level: u32) -> u32;
    /// Texel `(x, y)` of `face` of specular level `level`, or of the irradiance for
    /// `irradiance` (level 0 only); black out of range.
    fn texel(&self, irradiance: bool, face: usize, level: u32, x: u32, y: u32) -> Vec3;
}

/// No prefiltered environment: one black texel.
pub struct NoPrefiltered;

impl PrefilteredTexels for NoPrefiltered {
    fn levels(&self) -> u32 {
        1
    }
    fn side(&self, _: u32) -> u32 {
        1
    }
    fn texel(&self, _: bool, _: usize, _: u32, _: u32, _: u32) -> Vec3 {
        Vec3::ZERO
    }
}
