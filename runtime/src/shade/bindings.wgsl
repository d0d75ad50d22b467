// The uniform, the mode's switches, the bindings, the constants.
//
// OSLF shading: one compute invocation per pixel, reading the G-buffer written by gbuffer.wgsl.
// The shader is the files of shade/ joined in the order of `SHADE_WGSL` (pipelines.rs), this
// one first. Every function has a twin in the file of the same name under reference/ (the CPU
// reference), in the same order and with the same operation order; the parity tests compare
// the two. Bindings are declared in the order of `ShadePipelines::bind_group_layout`
// (pipelines.rs).

import package::layouts::{Params};

// `struct Params` is generated from the Rust `ShadeUniform` (params.rs, whose docs say what
// each field holds) and placed before this file (pipelines.rs).

// The mode's switches are pipeline-overridable constants (set from the same values as the
// uniform's `terms`, `blend`, `source`, `order`): one pipeline per combination, so code a mode
// does not use is not in its shader. On lavapipe every branch runs under an execution mask
// whether or not any lane takes it, so unused code is not free (docs/measurements.md).
override TERMS: u32 = 1u;
override BLEND: u32 = 4u;
override SOURCE: u32 = 0u;
override ORDER: u32 = 0u;
override POOLS: u32 = 4u;
// 2^FACE_SHIFT faces lie side by side in each pool layer (pool.rs).
override FACE_SHIFT: u32 = 0u;
override DIFFUSE: bool = false;
// The diffuse part is read from the sample points' stored irradiance (the uniform's
// `irradiance` is an index into `samples`), not sampled from the cube maps.
override IRRADIANCE: bool = false;
// The uniform's `background`: what pixels off the object show.
override BACKGROUND: u32 = 0u;
// Depth-corrected lookups (the uniform's depth_steps > 0; the pool has distance planes).
override DEPTH: bool = false;
// Filtered importance sampling for the glossy term (the uniform's mip_levels > 1).
override FILTER: bool = false;
// The split-sum baseline of the pbr mode (the uniform's split_sum).
override SPLIT_SUM: bool = false;
// The store has textured objects: gb_material holds each pixel's material (gbuffer.wgsl
// fs_textured).
override TEXTURED: bool = false;

struct PatchGpu {
    cp: array<vec4<f32>, 16>,
    color: vec4<f32>,
    // Its object's material: metallic, GGX α, 1 if metallic-roughness (else 0), unused.
    material: vec4<f32>,
    // Its object's emitted radiance (the material record's), linear RGB; w unused.
    emission: vec4<f32>,
};

@group(0) @binding(0) var<uniform> P: Params;
@group(0) @binding(1) var gb_position: texture_2d<f32>;
@group(0) @binding(2) var gb_normal: texture_2d<f32>;
@group(0) @binding(3) var sample_maps: texture_2d_array<u32>;
// The sample points (object-relative, w = 1), then with IRRADIANCE from index P.irradiance
// each cube's nine spherical-harmonic coefficients (RGB, w = 0; buffers.rs sample_point_data).
@group(0) @binding(4) var<storage, read> samples: array<vec4<f32>>;
@group(0) @binding(5) var<storage, read> patches: array<PatchGpu>;
@group(0) @binding(6) var<storage, read> slots: array<u32>;
@group(0) @binding(7) var<storage, read_write> feedback: array<atomic<u32>>;
@group(0) @binding(8) var pool0: texture_2d_array<f32>;
@group(0) @binding(9) var pool1: texture_2d_array<f32>;
@group(0) @binding(10) var pool2: texture_2d_array<f32>;
@group(0) @binding(11) var pool3: texture_2d_array<f32>;
@group(0) @binding(12) var dpool0: texture_2d_array<f32>;
@group(0) @binding(13) var dpool1: texture_2d_array<f32>;
@group(0) @binding(14) var dpool2: texture_2d_array<f32>;
@group(0) @binding(15) var dpool3: texture_2d_array<f32>;
@group(0) @binding(16) var out_image: texture_storage_2d<rgba32float, write>;
// The G-buffer pass's depth: below 1.0 (the clear) where a triangle covers the pixel; the
// colour targets are not cleared, so only there do gb_position and gb_normal hold this frame.
@group(0) @binding(17) var gb_depth: texture_depth_2d;
// The prefiltered environment (prefilter.rs): layers 0–5 the specular levels' faces, one mip
// per roughness level; layers 6–11 the irradiance's faces at mip 0.
@group(0) @binding(18) var prefiltered: texture_2d_array<f32>;
// The G-buffer's material target (TEXTURED; gbuffer.wgsl `material_texel`): base colour RGB,
// metallic, roughness and occlusion as 16-bit unorm pairs, the object's texture flags in w.
@group(0) @binding(19) var gb_material: texture_2d<u32>;

const INVALID: u32 = 0xffffffffu;
// Distances at or above this mean "nothing this way" (face.rs FAR_DISTANCE, binary16's largest).
const FAR: f32 = 65504.0;
// The mip-level bias of the pbr mode's GGX samples on its spiral of filtered samples
// (`sample_spec`; reference/mod.rs PBR_LOD_BIAS).
const PBR_LOD_BIAS: f32 = -0.5;
// Bisection steps that refine a depth-corrected hit (params.rs documents the search).
const DEPTH_REFINE: u32 = 6u;
// Steps of a glossy sample's depth correction (`depth_iterate`; reference/mod.rs
// DEPTH_ITERATIONS).
const DEPTH_ITERATIONS: u32 = 2u;
// A texel of a depth-corrected lookup takes part in its bilinear tap when its distance lies
// within this many depth_thickness of the hit's, at most half of it (`depth_lookup`;
// reference/mod.rs LOOKUP_AGREE).
const LOOKUP_AGREE: f32 = 1.0;
// The shading pass's refinement of a G-buffer hit onto its patch (`surface_hit` in
// patch.wgsl; reference/mod.rs REFINE_*): Newton steps; how far the refined point may lie from
// the G-buffer's, in its tessellation's tolerances (oslf_geometry REFINE_REACH); how far its
// (u, v) may leave [0, 1]; how far from the pixel's ray it may end, in those tolerances.
const REFINE_STEPS: u32 = 4u;
const REFINE_REACH: f32 = 16.0;
const REFINE_SLACK: f32 = 1e-4;
const REFINE_MISS: f32 = 0.1;
// A candidate sees the blend's common hit when its distance toward it lies within this many
// depth_thickness (one texel angle) of the hit's (`blend_read`; reference/mod.rs HIT_AGREE).
const HIT_AGREE: f32 = 0.25;
// A glossy sample's hit lower than this share of the candidate's distance from x above x's
// tangent plane is one the candidate sees its own surface at a grazing angle for, where a
// texel's one distance cannot say where that surface ends (`low_hit`; reference/mod.rs
// LOW_HIT): per point searched reads such a sample as per point does, per direction with a
// plain lookup.
const LOW_HIT: f32 = 0.25;
