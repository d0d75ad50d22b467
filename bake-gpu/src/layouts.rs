//! The structs the host fills and the shader reads, each written once: declared here (and
//! the scene's records in [`crate::scene`]) with [`oslf_gpu::gpu_struct!`], which generates
//! their WGSL declarations ([`wgsl`]) for the shader ([`crate::shader::source`]).

use bytemuck::{Pod, Zeroable};

oslf_gpu::gpu_struct! {
    /// The shader's `Params` (shader/capture.wgsl).
    /// Declared in WGSL from these fields ([`Params::wgsl`]).
    #[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq)]
    pub struct Params as "Params" {
        pub resolution: u32,
        pub strata: u32,
        pub max_bounces: u32,
        /// `FLAG_*` of shader/capture.wgsl.
        pub flags: u32,
        pub seed: [u32; 2],
        /// Texels of the batch (cubes × 6 × resolution²).
        pub texels: u32,
        /// Invocations per dispatch row.
        pub row_invocations: u32,
        /// The dispatch's first texel.
        pub first: u32,
        pub _pad1: u32,
        pub _pad0: [u32; 2],
        /// Lat-long map: width, height, first texel in `texels`.
        pub env_size: [u32; 4],
        /// Sampling tables: width, height.
        pub env_tables: [u32; 4],
        /// cos and sin of the map's rotation about z.
        pub env_rotation: [f32; 4],
        pub env_constant: [f32; 4],
        /// The sky's Perez coefficients A–D of Y, x and y, their E, normalisation, sun and
        /// ground.
        pub perez_y: [f32; 4],
        pub perez_x: [f32; 4],
        pub perez_yc: [f32; 4],
        pub perez_e: [f32; 4],
        pub norm: [f32; 4],
        pub model_sun: [f32; 4],
        pub ground: [f32; 4],
        /// Rounds of `strata`² samples a texel takes at most, and the relative standard error
        /// after which it stops (0: all of them; `oslf_trace::capture::sampling_plan`).
        pub rounds: u32,
        pub target_noise: f32,
        pub _pad2: [u32; 2],
    }
}

oslf_gpu::gpu_struct! {
    /// The shader's `Job`.
    #[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq)]
    pub struct Job as "Job" {
        pub origin: [f32; 3],
        pub index: u32,
        pub sees_objects: u32,
        pub _pad: [u32; 3],
    }
}

oslf_gpu::gpu_struct! {
    /// The shader's `TexelOut`.
    /// One texel's result: radiance, distance, its samples' luminance sum and sum of squares,
    /// the closest-hit rays, (shadow rays << 1) | whether a sample hit a surface, and what
    /// its rays' traversals tested.
    #[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq)]
    pub struct TexelOut as "TexelOut" {
        pub radiance: [f32; 3],
        pub distance: f32,
        pub lum_sum: f32,
        pub lum_sq: f32,
        pub closest: u32,
        pub shadow_hit: u32,
        /// BVH nodes and triangles its rays tested.
        pub nodes: u32,
        pub tris: u32,
        /// The samples its value is the mean of (an adaptive capture's after its pilot).
        pub samples: u32,
        pub _pad: u32,
    }
}

oslf_gpu::gpu_struct! {
    /// The shader's `TraceRay`; `flags`: 1 the OSLF objects take part, 2 an any-hit query.
    #[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq)]
    pub struct TraceRay as "TraceRay" {
        pub origin: [f32; 3],
        pub t_max: f32,
        pub dir: [f32; 3],
        pub flags: u32,
    }
}

oslf_gpu::gpu_struct! {
    /// The shader's `TraceHit`.
    /// t, the hit triangle's global index (0xffffffff: none), barycentrics b1, b2; the BVH
    /// nodes and triangles the query tested.
    #[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq)]
    pub struct TraceHit as "TraceHit" {
        pub t: f32,
        pub triangle: u32,
        pub b1: f32,
        pub b2: f32,
        pub nodes: u32,
        pub tris: u32,
        pub _pad: [u32; 2],
    }
}

oslf_gpu::gpu_struct! {
    /// The shader's `PreviewCamera`.
    /// The camera's basis and lens: right, up, forward; tan(vfov / 2).
    #[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq)]
    pub struct PreviewCamera as "PreviewCamera" {
        pub position: [f32; 3],
        pub width: u32,
        pub right: [f32; 3],
        pub height: u32,
        pub up: [f32; 3],
        pub tan_half: f32,
        pub forward: [f32; 3],
        pub spp: u32,
    }
}

/// The WGSL declarations of every struct the host fills, in one string.
pub fn wgsl() -> String {
    use crate::scene::{GpuLight, Mat, Node, Tex, Tri, TriAttr};
    [
        Params::wgsl(),
        Node::wgsl(),
        Tri::wgsl(),
        TriAttr::wgsl(),
        Tex::wgsl(),
        Mat::wgsl(),
        GpuLight::wgsl(),
        Job::wgsl(),
        TexelOut::wgsl(),
        TraceRay::wgsl(),
        TraceHit::wgsl(),
        PreviewCamera::wgsl(),
    ]
    .concat()
}
