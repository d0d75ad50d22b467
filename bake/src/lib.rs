//! # oslf-bake: from a scene file to an OSLF store
//!
//! The baker of offset surface light fields (Jason Ang, *Offset Surface Light Fields*, 2003).
//! It reads a scene ([`scene_file`], into the model of [`scene`]), places sample points ε above the object's Bézier patches
//! ([`sample_points`], thesis §3.1 and §3.3), ray traces an HDR cube map of the scene at each
//! ([`capture`], §3.2), finds for every texel of every patch's sample map the four nearest
//! sample points that are within φ_samplemap of the normal *and* visible ([`sample_map`],
//! Eq. 3.9–3.10), and streams it all into one store through `oslf-format` ([`bake`]).
//!
//! Modules, by role:
//!
//! | role | modules |
//! | --- | --- |
//! | geometry | [`bezier`], [`mesh`] and [`camera`] (the shared pinhole camera; all three re-exported from `oslf-geometry`, which the runtime shares), [`shapes`] (plane, box, cylinder, sphere, surface of revolution), [`obj`] (Wavefront OBJ), [`normals`] (vertex normals where a file has none: flat, smooth, crease angle), [`gltf`] (glTF 2.0 files: meshes, materials, lights, cameras), [`bvh`] (one obvhs CWBVH over every triangle, watertight ray–triangle test) |
//! | light transport | [`ray`] (rays, hits, the `Intersector` trait), [`sampling`] (PCG32, sampling triplets `sample_x` / `x_pdf` / `invert_x`, piecewise-constant distributions), [`texture`], [`material`] (Lambertian), [`light`] (point, spot, sun), [`environment`] (constant, lat-long map, Preetham sky), [`integrator`] (path tracing with next-event estimation and MIS), [`preview`] (path-traced images through a [`camera::Camera`]), [`ashikhmin_shirley`] (the glossy BRDF, its sampling triplets) |
//! | the bake | [`scene`] (the scene model: objects, shapes, lights, settings), [`scene_file`] (reading scenes: TOML files with located errors, presets, glTF and OBJ includes), [`input`] (every input file read with bounds: regular files only, size limits), [`tolerance`] (tolerances the stages share), [`surface`] (the sample-map domains), [`sample_points`], [`sample_map`], [`coverage`] (why sample-map texels are short, per object), [`capture`], [`device`] (the `CaptureDevice` trait through which another capture, the GPU's in `oslf-bake-gpu`, takes the cube maps' place), [`noise`] (the captured cubes' Monte Carlo noise), [`preflight`] (the estimate checked against the machine), [`bake`] (the pipeline's stages, resumable, deterministic), [`progress`] (the `Progress` trait the long stages report to; tools draw it) |
//! | measurement | [`ground_truth`] (ray-traced reference images of what each runtime mode approximates: the diffuse object, the mirror term, the Ashikhmin–Shirley term; the `oslf truth` command) |
//!
//! Conventions: Z is up; radiance is linear RGB in `f32`; cube maps use the wgpu/Vulkan face
//! order and orientation of `oslf_format::cube`. Every random number comes from a stream keyed
//! by (seed, cube, face, texel) or (seed, pixel), so results do not depend on the thread count.

pub mod error;
pub mod ray;

// geometry
pub use oslf_geometry::{bezier, camera, mesh};
pub mod bvh;
pub mod gltf;
pub mod normals;
pub mod obj;
pub mod shapes;

// radiance
pub mod ashikhmin_shirley;
pub mod environment;
pub mod integrator;
pub mod light;
pub mod material;
pub mod metallic_roughness;
pub mod preview;
pub mod sampling;
pub mod texture;

// the bake
pub mod bake;
pub mod capture;
pub mod coverage;
pub mod device;
pub mod ground_truth;
pub mod input;
pub mod noise;
pub mod preflight;
pub mod progress;
pub mod sample_map;
pub mod sample_points;
pub mod scene;
pub mod scene_file;
pub mod surface;
pub mod tolerance;

pub use error::{BakeError, Result};
