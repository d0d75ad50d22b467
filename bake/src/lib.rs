//! # oslf-bake: from a scene to an OSLF store
//!
//! The baker of offset surface light fields (Jason Ang, *Offset Surface Light Fields*, 2003).
//! Given a scene (`oslf-scene`) it places sample points ε above the objects' surfaces
//! ([`sample_points`], thesis §3.1 and §3.3, over the domains of [`surface`]), has a cube map
//! captured at each (`oslf-trace`'s capture, or another [`device`]: the GPU's in
//! `oslf-bake-gpu`), finds for every texel of every sample map the four nearest sample points
//! that are within φ_samplemap of the normal *and* visible ([`sample_map`], Eq. 3.9–3.10), and
//! streams it all into one store through `oslf-format` ([`bake`]). Before any slow work it
//! checks the estimate against the machine ([`preflight`]); after the sample maps it says
//! where and why texels are short ([`coverage`]).
//!
//! | module | what |
//! | --- | --- |
//! | [`surface`] | the sample-map domains of patches and meshes |
//! | [`sample_points`] | placing points ε above the surfaces |
//! | [`pilot`] | pilot cubes and their leave-one-out error, for adaptive placement |
//! | [`sample_map`] | the four nearest visible points per texel |
//! | [`coverage`] | why sample-map texels are short, per object |
//! | [`device`] | the `CaptureDevice` trait through which another capture takes the CPU's place |
//! | [`preflight`] | time, memory and disk estimated and checked before the bake |
//! | [`bake`] | the pipeline's stages, resumable, deterministic |
//!
//! It depends on the scene and the tracer, never on wgpu: the GPU capture plugs in through
//! [`device::CaptureDevice`].

pub mod bake;
pub mod coverage;
pub mod device;
pub mod pilot;
pub mod preflight;
pub mod sample_map;
pub mod sample_points;
pub mod surface;
