//! # The OSLF runtime
//!
//! Renders an offset surface light field (an OSLF store, see `oslf-format`) with wgpu, as a
//! viewer would embed it. Thesis chapters 3–5 and §4.3:
//!
//! * **Geometry** ([`geometry`]): the object's bicubic Bézier patches, tessellated into
//!   triangles that carry patch id and (u, v), with normals taken from the limit at collapsed
//!   patch edges; and triangle-mesh objects, whose vertices carry the
//!   object's first map id, the atlas uv and the atlas grid, from which the G-buffer pass
//!   picks the atlas page (sample map) and page-local uv per pixel. Meshes shade with the
//!   interpolated vertex normal.
//! * **Frame** ([`renderer`]): a G-buffer pass writes per pixel the world position, patch id,
//!   shading normal and (u, v) (gbuffer.wgsl); a compute pass (shade.wgsl) reads the pixel's
//!   sample-map texel with `textureLoad` (indices are never interpolated, §3.4), the four
//!   sample points from a storage buffer, and their cube maps from the GPU cache, and shades:
//!   - surface reconstruction F_recon (3.11–3.12): the nearest candidate within φ_shader of the
//!     shaded normal, looked up towards the shaded point (§6.3);
//!   - mirror reflection F_refl (4.3–4.11) with every blend: closest distance, closest angle,
//!     B^avg, B^r and B^n with power N; P = F_recon + C_s·F_refl (4.12);
//!   - Ashikhmin–Shirley by Monte Carlo (5.3–5.12) with R_s, R_d, n_u, n_v, M, in both
//!     integration orders of §5.2, stratified over the four quadrants, tangent frames from
//!     ∂x/∂u so anisotropy follows the surface;
//!   - glTF's metallic-roughness BRDF with the object's base colour (the `pbr` mode): its GGX
//!     lobe by visible-normal sampling and its diffuse base by cosine sampling, read from the
//!     cube maps as the Ashikhmin–Shirley samples are, so the truth's and the bake's BRDF;
//!   - the diffuse part of both (the term 5.4, glTF's diffuse base) read, not sampled, from
//!     the irradiance each sample point stores (format 1.1: its cube in spherical harmonics,
//!     projected from every texel at bake time), convolved with the lobe at the normal and
//!     blended between the candidates ([`DiffuseSource`]; sampling stays available);
//!   - the environment-map baseline: one cube at the object's centre, by direction alone;
//!     and the baseline engines use, that cube parallax-corrected against a proxy box fitted
//!     to its distances ([`probe`]); for the pbr mode also as engines light from one probe,
//!     the cube prefiltered per roughness with the split-sum approximation ([`prefilter`]).
//!     See [`ShadingParams`].
//!
//!   Beyond the thesis, with a store's distance channel (§6.3's RGBZ; a twin R16Float pool),
//!   every mirror and glossy lookup is *depth-corrected*: each sample point's cube is traced as
//!   a distance impostor to where the ray from the shaded point meets the scene, the candidates
//!   agree on the nearest such hit, and each reads only the texels whose distances agree with
//!   it; reconstruction averages the candidates that see the shaded point. Each patch pixel is shaded
//!   where its ray meets the patch itself, refined from the G-buffer's triangle hit by Newton's
//!   method (`surface_hit`, as the ground truth refines its own), with the patch's normal there
//!   (∂x/∂u × ∂x/∂v). Glossy samples use
//!   *filtered importance sampling* (Křivánek & Colbert 2008) over per-face mip chains
//!   ([`face`]).
//!
//!   Pixels off the object keep alpha 0 and show the [`Background`] of
//!   [`RenderOptions::background`]: transparent black by default, the environment cube along
//!   each pixel's camera ray, or a constant colour.
//! * **Cache** ([`cache`]): decoded faces in RAM under a byte budget and a pool of GPU cube
//!   slots under a slot budget, both LRU, fed each frame by a feedback buffer in which the
//!   shader marks every face it needs. Whole-cube or per-face loading. Documented fallback
//!   when a needed face is not resident; statistics per frame and cumulative ([`CacheStats`]).
//! * **Host frames** ([`Renderer::encode_into`], [`Renderer::after_submit`]): the object drawn
//!   into an application's own colour and depth targets (multisampled too) through its view
//!   and projection matrices (reversed depth too), recorded into its command encoder and
//!   depth-tested both ways against its meshes by a composite pass; the feedback read back
//!   asynchronously, so a frame never waits (docs/embedding.md, "Drawing into your own
//!   frame").
//! * **Web** ([`web`]): a store as a browser's WebGPU page draws it (`oslf serve`,
//!   `oslf export-web`): every mode's uniform and override constants, the pool layout, the
//!   buffers and each cube's face payloads, computed here so that the page runs these shaders
//!   with nothing of the shading written again in JavaScript.
//! * **CPU reference** ([`reference`](mod@reference)): the same shading in Rust, function for function, used
//!   by the parity tests against the GPU.
//!
//! * **Tooling** (feature `tooling`, off by default: not what an embedding application
//!   uses): the checks of WGSL struct layouts against Rust (`wgsl_layout`).
//!
//! Measurement lives in `oslf-measure`: image error metrics (RMSE in CIELAB, PSNR) and the
//! cache replays along camera paths that `oslf cache-stats` reports (thesis Tables 6.3–6.7).
//!
//! The crate depends on `oslf-format` (the store), `oslf-geometry` (patches and the camera it
//! shares with the bake), wgpu and a few small crates; never on the bake, and it has no command
//! line of its own: the `oslf` binary (the workspace's root crate) drives it.
//!
//! Cube maps are bound as 2D texture arrays (six layers per slot) and filtered bilinearly
//! inside a face by the shader itself, so that the CPU reference can reproduce the filtering
//! exactly. BC6H stores are uploaded as their blocks (`Bc6hRgbUfloat`, 1 byte per texel) when
//! the device has BC texture compression ([`Gpu::has_bc`]), else decoded on the CPU to RGB9E5
//! ([`face`]). Numbers: f32 throughout; non-finite results are replaced by 0 before they reach a
//! pixel.
//!
//! ```no_run
//! use oslf_runtime::{CacheConfig, Gpu, Renderer, RenderOptions, ShadingParams};
//! let store = oslf_format::Store::open("gazebo.oslf".as_ref()).unwrap();
//! let mut renderer = Renderer::new(Gpu::headless().unwrap(), store, CacheConfig::default()).unwrap();
//! let camera = renderer.default_view();
//! let frame = renderer.render(&camera, &ShadingParams::default(), &RenderOptions::default()).unwrap();
//! println!("{} hits, {} misses", frame.stats.hits, frame.stats.misses);
//! ```

mod buffers;
pub mod cache;
mod error;
pub mod face;
pub mod geometry;
pub mod params;
mod pipelines;
mod pool;
pub mod prefilter;
pub mod probe;
pub mod reference;
pub mod renderer;
#[cfg(test)]
mod shader_layout;
mod shading;
mod textures;
mod uniform;
pub mod web;
/// WGSL struct layouts checked against Rust: test tooling (feature `tooling`).
#[cfg(any(test, feature = "tooling"))]
pub mod wgsl_layout;

pub use cache::{CacheConfig, CacheStats, CubeCache, DecodeFailure, Granularity};
pub use error::{Param, Result, RuntimeError};
pub use oslf_geometry::Camera;
pub use oslf_gpu::{Gpu, GpuError};
pub use params::{Background, Blend, GlossyFilter, Mode, Order, Source};
pub use renderer::{
    Frame, FrameBytes, HostPassSeconds, HostPrepass, HostTarget, HostView, PrepassTarget,
    RenderOptions, Renderer, DEPTH_SLACK, MAX_DEPTH_SLACK,
};
pub use shading::{
    AshikhminShirley, Box3, DiffuseSource, Glossy, Lookup, Mirror, MonteCarlo, Pbr, PbrIntegration,
    PbrMaterial, Probe, Recon, ReconGlossy, ReconMirror, SampleFilter, ShadingParams, ShadingParts,
};
