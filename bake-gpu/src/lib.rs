//! # oslf-bake-gpu: the bake's cube-map capture on the GPU
//!
//! The cube maps are what a bake spends its time on (thesis §3.2: an HDR cube map ray traced
//! at every sample point), and their Monte Carlo noise is what limits a bake's accuracy
//! indoors. This crate runs that capture as a wgpu compute shader, with the estimator of the
//! CPU path tracer (`oslf_trace::integrator`) ported line by line:
//!
//! - [`scene`]: the scene packed for the GPU: the CPU's own compressed wide BVH (obvhs's
//!   CWBVH, node for node) over the bake's own triangles (the objects tessellated as for the
//!   CPU), materials (Lambertian and glTF
//!   metallic-roughness, constant, checker and image textures), point, spot and sun lights,
//!   the environment (constant, lat-long map or Preetham sky, with the CPU's sampling tables);
//! - [`features`]: what that scene holds (environment, light kinds, material models, texture
//!   kinds), the pipeline constants the shader is specialized on, so that it compiles without
//!   the code no path of the scene reaches;
//! - [`capture`]: [`GpuCapture`], which uploads it once and captures batches of cubes
//!   (bounded memory per batch, short dispatches), implementing the bake's
//!   `CaptureDevice`, so `oslf bake --device gpu` resumes, shards and merges as the CPU bake;
//! - [`choice`]: `--device auto|cpu|gpu` decided and explained, for the CLI and the sweep;
//! - [`preview`]: the bake's preview (the scene camera's image) with the same integrator;
//! - [`layouts`]: the structs the host fills and the shader reads, each declared once for Rust
//!   and WGSL;
//! - [`shader`]: the WGSL, split as the CPU code is (random numbers, traversal, scene,
//!   integrator, capture).
//!
//! The GPU draws the CPU's random numbers: PCG32 on the stream hashed from (seed, cube, face,
//! texel), 64-bit arithmetic emulated on 32-bit words. A texel's paths therefore make the same
//! choices on both devices until their floating point parts, rounded differently (fused
//! multiply-adds, transcendental functions), first change a decision; CPU and GPU stores
//! differ by that, within the Monte Carlo noise (tests/parity.rs). On one adapter the same
//! scene and seed give the same bytes, however the cubes are batched.
//!
//! It captures on `oslf-gpu`'s device, the one the renderer uses too, and must never depend on
//! the runtime (`oslf-runtime`): a bake does not need the renderer.

pub mod capture;
pub mod choice;
pub mod error;
pub mod features;
pub mod layouts;
pub mod preview;
pub mod scene;
pub mod shader;

pub use capture::GpuCapture;
pub use error::{GpuBakeError, Result};
