//! # oslf-trace: ray tracing the scene
//!
//! The CPU ray tracer of oslf over the scene model of `oslf-scene`: one BVH over every triangle
//! ([`bvh`], watertight ray–triangle test), a path tracer with next-event estimation and MIS
//! ([`integrator`]), the capture of HDR cube maps at sample points ([`capture`], thesis §3.2)
//! with their Monte Carlo noise ([`noise`]) and its bake-time filter ([`denoise`]), path-traced previews through the scene camera
//! ([`preview`]) and the ray-traced ground truth of what each runtime mode approximates
//! ([`ground_truth`], the `oslf truth` command) with the Ashikhmin–Shirley lobe it needs
//! ([`ashikhmin_shirley`]).
//!
//! | module | what |
//! | --- | --- |
//! | [`ray`] | rays, hits, the `Intersector` trait |
//! | [`bvh`] | the scene's triangles ([`bvh::scene_instances`]) in one obvhs CWBVH |
//! | [`integrator`] | path tracing with next-event estimation and MIS |
//! | [`capture`] | cube maps at sample points, deterministic per (seed, cube, face, texel) |
//! | [`noise`] | the captured cubes' Monte Carlo noise |
//! | [`denoise`] | the bake-time filter that averages that noise away where it shows |
//! | [`preview`] | path-traced images through a camera |
//! | [`ground_truth`] | reference images of the diffuse object, the mirror term, the glossy terms |
//! | [`cube_floor`] | the mirror term as a cube map at the shaded point would give it: any bake's floor |
//! | [`ashikhmin_shirley`] | the thesis's glossy BRDF (chapter 5) and its sampling triplets |
//! | [`progress`] | the `Progress` trait the long stages report to; tools draw it |
//!
//! Every random number comes from a stream keyed by (seed, cube, face, texel) or (seed, pixel),
//! so results do not depend on the thread count.
//!
//! It depends on the scene (`oslf-scene`) and never on the bake (`oslf-bake`), the runtime or
//! any GPU crate.

pub mod ashikhmin_shirley;
pub mod bvh;
pub mod capture;
pub mod cube_floor;
pub mod denoise;
pub mod ground_truth;
pub mod integrator;
pub mod noise;
pub mod preview;
pub mod progress;
pub mod ray;
