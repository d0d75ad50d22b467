//! The crate's integration tests as one test binary: each file of `tests/` is a module here,
//! so that the tests link once (a binary per file linked the whole dependency tree again for
//! each) and share one copy of `common`'s fixtures, baked once per run. Run one file's tests
//! with a filter: `cargo test --release --test integration -- FILE::`.

#[path = "background.rs"]
mod background;
#[path = "bc6h.rs"]
mod bc6h;
#[path = "cache.rs"]
mod cache;
mod common;
#[path = "extremes.rs"]
mod extremes;
#[path = "filtered.rs"]
mod filtered;
#[path = "host.rs"]
mod host;
#[path = "mesh.rs"]
mod mesh;
#[path = "parity.rs"]
mod parity;
#[path = "textures.rs"]
mod textures;
#[path = "web.rs"]
mod web;
