//! The preflight's cost model: what each part of a bake takes in memory, in the store and in
//! time, and the hard limits no machine lifts. Every constant says where its figure comes
//! from: the code it models or a measurement (docs/measurements.md, "Preflight constants", or
//! the counting-allocator test in bake/tests/preflight.rs).

// --- memory ----------------------------------------------------------------------------------

/// Bytes of the process besides what the estimate counts (code, stacks, the parsed scene's
/// small parts, allocator slack): the quick preset's peak resident memory less the heap the
/// estimate counts (docs/measurements.md, "Preflight constants").
pub const BASE_BYTES: u64 = 8_000_000;

/// Heap bytes per triangle at the peak of building the BVH (`TriangleScene::build` over
/// `Scene::instances`): the instances' meshes (positions, normals, uvs: 32 B a vertex, 12 B
/// of indices a triangle), the corners (48 B), planes (16 B), attributes (84 B) and input
/// order (4 B) that stay, the CWBVH nodes, and obvhs's build buffers. Measured with the
/// counting allocator of bake/tests/preflight.rs on examples/gazebo.toml (docs/
/// measurements.md, "Preflight constants").
pub const BVH_BYTES_PER_TRIANGLE: u64 = 600;

/// Heap bytes per triangle the BVH keeps once built (the same measurement, after the build).
pub const BVH_RESIDENT_BYTES_PER_TRIANGLE: u64 = 300;

/// Heap bytes per placement candidate at the peak of `sample_points::place`: the candidate
/// (40 B), its position for the k-d tree (12 B) and the tree, its neighbour list in
/// `eliminate` (a `Vec` of (u32, f32) within 2 r_max: about 22 neighbours with 6 candidates
/// a point, 24 + 8 × 22 B plus allocator rounding), weight, flag and heap entry. Measured with
/// the counting allocator of bake/tests/preflight.rs at 20 000 points (docs/measurements.md,
/// "Preflight constants").
pub const PLACEMENT_BYTES_PER_CANDIDATE: u64 = 500;

/// Candidates drawn per requested sample point (`sample_points::CANDIDATES_PER_POINT`).
pub const CANDIDATES_PER_POINT: u64 = 6;

/// Bytes of one sample point in memory while the bake holds it: the `SamplePoint` (40 B, as
/// in the store: `oslf_format::meta::SAMPLE_POINT_BYTES`), its position in the sample maps'
/// k-d tree (12 B) and the tree's nodes and index.
pub const POINT_BYTES: u64 = 72;

/// Bytes of one sample-map texel in memory: four `u32` indices (`SampleMaps::indices`,
/// sample_map.rs `build`).
pub const MAP_TEXEL_BYTES: u64 = 16;

// --- store -----------------------------------------------------------------------------------

/// Bytes of the store besides the sample maps, points and cube maps: header (256 B), metadata
/// (objects, patches: 192 B of control points each), alignment. Generous.
pub const STORE_FIXED_BYTES: u64 = 64 << 10;

/// Bytes per cube in the store besides its compressed faces: 6 table-of-contents entries of
/// 32 B (`oslf_format::toc::TOC_CUBE_BYTES`), the record header (160 B) and 6 zstd frame headers.
pub const STORE_CUBE_OVERHEAD_BYTES: u64 = 6 * 32 + 160 + 6 * 16;

pub use oslf_format::encoding::{compressed_texel_bytes, DISTANCE_COMPRESSED_BYTES};

/// The store's size is given as a range around its typical value: cube maps compress by a
/// factor that depends on the scene; these bound the typical figure's error for the bakes
/// measured (0.75: a smooth scene; 1.25: noisy radiance, up to raw RGB9E5 bytes).
pub const STORE_RANGE: (f64, f64) = (0.75, 1.25);

// --- points ----------------------------------------------------------------------------------

/// Sample points as a multiple of the requested count: placement removes a few (closer than ε
/// to a surface, inside geometry) and §6.3 refinement adds points where texels found fewer
/// than four, at most as many as were placed (`bake::stages::build_maps`: the budget is
/// `points_placed`). Typical from the gazebo's quick and thesis presets (docs/measurements.md,
/// "Preflight constants"); the most is that budget.
pub const POINTS_TYPICAL: f64 = 1.3;
/// See [`POINTS_TYPICAL`].
pub const POINTS_MOST: f64 = 2.0;

// --- time ------------------------------------------------------------------------------------

/// Rays per second per core for the capture's ray count as [`crate::preflight::Estimate::capture_rays`] counts
/// it (every path vertex's closest-hit ray plus one shadow ray per delta light and one for a
/// non-black environment, cosine-culled ones included). The range brackets the gazebo's quick
/// and thesis presets (docs/measurements.md, "Preflight constants"); heavier scenes (more
/// triangles, more bounces) are slower.
pub const RAYS_PER_CORE_SECOND: (f64, f64) = (1.0e6, 4.0e6);

/// Seconds per sample-map texel and core, for one build of the maps (a k-nearest query of 16
/// or 64 points and up to 64 visibility rays; sample_map.rs `texel_indices`). The range
/// brackets the gazebo's (docs/measurements.md, "Preflight constants").
pub const SECONDS_PER_MAP_TEXEL: (f64, f64) = (4e-6, 30e-6);

/// How many times the sample maps are built: once, and once more after each §6.3 refinement
/// round that added points (`sample_points::REFINE_ROUNDS` = 3).
pub const MAP_BUILDS: (f64, f64) = (1.0, 4.0);

/// Seconds per triangle to build the BVH (one thread); the range brackets the gazebo's
/// (docs/measurements.md, "Preflight constants").
pub const SECONDS_PER_TRIANGLE: (f64, f64) = (0.5e-6, 4e-6);

/// Seconds per placement candidate (one thread: `eliminate`'s neighbour search and heap), and
/// the free-space probe rays per kept point (64 directions × 2; sample_points.rs `place`).
pub const SECONDS_PER_CANDIDATE: (f64, f64) = (1e-6, 6e-6);
/// See [`SECONDS_PER_CANDIDATE`].
pub const PROBE_RAYS_PER_POINT: u64 = 128;

/// A bake whose *optimistic* time estimate exceeds this is refused by [`crate::preflight::Limits::of_machine`]'s
/// default: 12 hours (a bake that needs longer on this machine is better run in slices,
/// `--max-cubes` and `--resume`, or as shards).
pub const DEFAULT_MAX_SECONDS: f64 = 12.0 * 3600.0;

// --- hard limits -----------------------------------------------------------------------------

/// The largest cube face a GPU is sure to accept as a texture (wgpu's default
/// `max_texture_dimension_2d`, 8192): larger faces store fine but the runtime may not load them.
pub const GPU_TEXTURE_LIMIT: u32 = 8192;

/// Sample indices are `u32` with `u32::MAX` meaning "none" (`oslf_format::INVALID_INDEX`), and
/// the store counts cubes in a `u32`: points plus the environment cube must stay below it.
pub const MAX_SAMPLE_POINTS: u64 = u32::MAX as u64 - 1;
