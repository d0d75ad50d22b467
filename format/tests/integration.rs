//! The crate's integration tests as one test binary: each file of `tests/` is a module here,
//! so that the tests link once (a binary per file linked the whole dependency tree again for
//! each) and share one copy of `common`'s fixtures, baked once per run. Run one file's tests
//! with a filter: `cargo test --release --test integration -- FILE::`.

#[path = "accuracy.rs"]
mod accuracy;
#[path = "bc6h.rs"]
mod bc6h;
#[path = "changed_on_disk.rs"]
mod changed_on_disk;
mod common;
#[path = "damaged.rs"]
mod damaged;
#[path = "damaged_mapped.rs"]
mod damaged_mapped;
#[path = "damaged_positioned.rs"]
mod damaged_positioned;
#[path = "development_versions.rs"]
mod development_versions;
#[path = "irradiance.rs"]
mod irradiance;
#[path = "mapped.rs"]
mod mapped;
#[path = "mesh.rs"]
mod mesh;
#[path = "round_trip.rs"]
mod round_trip;
#[path = "sampling.rs"]
mod sampling;
#[path = "writer.rs"]
mod writer;
