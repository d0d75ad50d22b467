//! # oslf-scene: the scene model and the files it is read from
//!
//! What a bake, a ground truth and a viewer agree on before any ray is traced: the objects (Bézier
//! patches or triangle meshes marked as OSLF objects), the environment shapes around them, their
//! materials and textures, the lights, the environment (constant, lat-long map, sky), the camera
//! and the bake's settings ([`scene`]), and the three formats a scene comes in: TOML scene files
//! with located errors and presets ([`scene_file`]), glTF 2.0 ([`gltf`]) and Wavefront OBJ
//! ([`obj`]), every file read with bounds ([`input`]).
//!
//! | role | modules |
//! | --- | --- |
//! | the model | [`scene`] (objects, shapes, lights, settings), [`bake_defaults`] (the settings a scene file leaves unset, chosen from the objects' sizes, surroundings and materials), [`object_measure`] (what those choices read of an object), [`shapes`] (plane, box, cylinder, sphere, surface of revolution), [`normals`] (vertex normals where a file has none: flat, smooth, crease angle), [`tolerance`] (tolerances the stages share) |
//! | appearance | [`texture`] (constants, checkerboards, images), [`material`] (Lambertian and glTF metallic-roughness, as the path tracer evaluates them), [`metallic_roughness`] (glTF's BRDF over oslf-shading's GGX), [`light`] (point, spot, sun), [`environment`] (constant, lat-long map, Preetham sky, and their importance sampling), [`sampling`] (tabulated distributions) |
//! | files | [`scene_file`] (TOML scene files: located errors, presets, includes), [`gltf`] (glTF 2.0: meshes, materials, lights, cameras), [`obj`] (Wavefront OBJ), [`input`] (every input file read with bounds: regular files only, size limits) |
//! | errors | [`error`] ([`BakeError`], the error of the scene, the tracer and the bake) |
//!
//! Conventions: Z is up; radiance is linear RGB in `f32`. Patches, meshes and the camera are
//! `oslf-geometry`'s, which the runtime shares; shading maths is `oslf-shading`'s.
//!
//! It must never depend on the tracer (`oslf-trace`), the bake (`oslf-bake`), the runtime or
//! any GPU crate: reading a scene needs none of them.

pub mod bake_defaults;
pub mod environment;
pub mod error;
pub mod gltf;
pub mod input;
pub mod light;
pub mod material;
pub mod metallic_roughness;
pub mod normals;
pub mod obj;
pub mod object_measure;
pub mod sampling;
pub mod scene;
pub mod scene_file;
pub mod shapes;
pub mod texture;
pub mod tolerance;

pub use error::{BakeError, Result};
