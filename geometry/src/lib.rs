//! # oslf-geometry: what the bake and the runtime both need to see the same object
//!
//! The object of an offset surface light field is a set of bicubic Bézier patches (thesis §3.1).
//! The baker places sample points ε above them; the runtime rasterizes the same surface and looks
//! up the same sample maps; `oslf truth` renders it through the same camera. This small crate
//! holds exactly that shared vocabulary, so that neither side depends on the other:
//!
//! - [`bezier`]: patches, their evaluation and robust normals (Eq. 3.1–3.4), tessellation with
//!   an error bound, the Newell teapot and the patch-file parser;
//! - [`mesh`]: indexed triangle meshes, the common currency of tessellation, shapes and the BVH;
//! - [`atlas`]: the uv atlas of a triangle-mesh object (a `k × k` grid of sample-map pages), from
//!   the mesh's own uvs or charts of adjacent triangles laid flat, and the surface point of every atlas texel;
//! - [`camera`]: the pinhole camera and the direction through each pixel.
//!
//! It depends on `glam` and `thiserror` only. Image files, the store and the GPU live in the
//! crates that need them (`oslf-bake`, `oslf-format`, `oslf-runtime`).

pub mod atlas;
pub mod bezier;
pub mod camera;
pub mod error;
pub mod mesh;
pub mod tangents;

pub use atlas::{Atlas, AtlasOptions, TexelSurface, UvSource};
pub use bezier::BezierPatch;
pub use camera::Camera;
pub use error::{GeometryError, Result};
pub use mesh::Mesh;
