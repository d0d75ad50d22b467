//! The crate's integration tests as one test binary: each file of `tests/` is a module here,
//! so that the tests link once (a binary per file linked the whole dependency tree again for
//! each) and share one copy of `common`'s fixtures, baked once per run. Run one file's tests
//! with a filter: `cargo test --release --test integration -- FILE::`. `preflight.rs` is a
//! binary of its own: its counting allocator measures the heap of one test at a time.

#[path = "bake_defaults.rs"]
mod bake_defaults;
#[path = "coverage.rs"]
mod coverage;
#[path = "extremes.rs"]
mod extremes;
#[path = "geometry.rs"]
mod geometry;
#[path = "gltf.rs"]
mod gltf;
#[path = "data/gltf_builder.rs"]
mod gltf_builder;
#[path = "ground_truth.rs"]
mod ground_truth;
#[path = "inputs.rs"]
mod inputs;
#[path = "mesh_objects.rs"]
mod mesh_objects;
#[path = "metallic_roughness.rs"]
mod metallic_roughness;
#[path = "noise.rs"]
mod noise;
#[path = "normals.rs"]
mod normals;
#[path = "object_spacing.rs"]
mod object_spacing;
#[path = "pilot.rs"]
mod pilot;
#[path = "placement.rs"]
mod placement;
#[path = "quantize.rs"]
mod quantize;
#[path = "radiance.rs"]
mod radiance;
#[path = "scene_errors.rs"]
mod scene_errors;
#[path = "textured_objects.rs"]
mod textured_objects;
