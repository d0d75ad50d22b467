//! # oslf: offset surface light fields
//!
//! One place to reach the project's crates:
//!
//! * [`format`] (`oslf-format`): the store, a memory-mapped, compressed, checked file whose
//!   crate docs are its byte-layout specification;
//! * [`bake`] (`oslf-bake`): scene files to stores — sample points, ray-traced cube maps,
//!   visibility-culled sample maps;
//! * [`runtime`] (`oslf-runtime`): the wgpu renderer with its LRU cube-map cache and CPU
//!   reference.
//!
//! This package also owns the end-to-end tests (`tests/`), the store benchmark
//! (`benches/store.rs`) and the interactive viewer (`examples/viewer.rs`).

pub use oslf_bake as bake;
pub use oslf_format as format;
pub use oslf_runtime as runtime;
