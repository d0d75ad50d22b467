//! The crate's integration tests as one test binary: each file of `tests/` is a module here,
//! so that the tests link once (a binary per file linked the whole dependency tree again for
//! each) and share one copy of `common`'s fixtures, baked once per run. Run one file's tests
//! with a filter: `cargo test --release --test integration -- FILE::`.

#[path = "cli_adapter.rs"]
mod cli_adapter;
#[path = "cli_bake.rs"]
mod cli_bake;
#[path = "cli_cache_stats.rs"]
mod cli_cache_stats;
#[path = "cli_fallback.rs"]
mod cli_fallback;
#[path = "cli_gpu_bake.rs"]
mod cli_gpu_bake;
#[path = "cli_help.rs"]
mod cli_help;
#[path = "cli_inputs.rs"]
mod cli_inputs;
#[path = "cli_materials.rs"]
mod cli_materials;
#[path = "cli_measure.rs"]
mod cli_measure;
#[path = "cli_meshes.rs"]
mod cli_meshes;
#[path = "cli_mmap.rs"]
mod cli_mmap;
#[path = "cli_render.rs"]
mod cli_render;
#[path = "cli_shard.rs"]
mod cli_shard;
#[path = "cli_sources.rs"]
mod cli_sources;
#[path = "cli_store.rs"]
mod cli_store;
#[path = "cli_summary.rs"]
mod cli_summary;
#[path = "cli_textures.rs"]
mod cli_textures;
#[path = "cli_truth.rs"]
mod cli_truth;
#[path = "cli_values.rs"]
mod cli_values;
#[path = "cli_writers.rs"]
mod cli_writers;
#[path = "code_size.rs"]
mod code_size;
mod common;
#[path = "crate_layers.rs"]
mod crate_layers;
#[path = "example_scene.rs"]
mod example_scene;
#[path = "module_graph.rs"]
mod module_graph;
#[path = "pipeline.rs"]
mod pipeline;
#[path = "web.rs"]
mod web;
