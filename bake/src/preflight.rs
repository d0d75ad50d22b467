//! Preflight (issue 15): before any slow work, estimate what a bake will cost — peak memory,
//! store size, time — from the scene and its settings alone, and refuse a bake that cannot
//! fit the machine, naming the setting to change.
//!
//! [`estimate`] is a pure function of the scene and a thread count: it reads no file and
//! traces no ray (it tessellates nothing either: triangle counts come from
//! [`crate::bezier::BezierPatch::tessellation_level`], patch areas from a 16 × 16 grid of evaluations).
//! [`check`] compares an [`Estimate`] with [`Limits`] — what the machine offers, read by
//! [`Limits::of_machine`] ([`available_memory`], [`free_space`]) or given by the caller (tests) —
//! and with hard limits that no machine lifts ([`hard_limits`]).
//!
//! Every constant below says where its figure comes from: the code it models (bake.rs,
//! capture.rs, sample_map.rs, sample_points.rs, bvh.rs, oslf-format's writer) or a measurement
//! (docs/measurements.md, or the counting-allocator test in bake/tests/preflight.rs).
//!
//! What is only estimated: the number of sample points (placement removes some, §6.3 refinement
//! adds up to as many again), the compression of the cube maps (scene-dependent; the table's
//! figures are the gazebo's), and the speed (scene- and machine-dependent, hence a range).

use std::fmt;
use std::path::{Path, PathBuf};

use crate::capture::{chunk_cubes, strata_per_side};
use crate::error::BakeError;
use crate::scene::{BakeSettings, SampleDensity, Scene};
use crate::tolerance::TESSELLATION_ERROR;

// --- memory ----------------------------------------------------------------------------------

/// Bytes of the process besides what the estimate counts (code, stacks, the parsed scene's
/// small parts, allocator slack): the quick preset of examples/gazebo.toml peaked at 37.5 MB
/// resident with `--preview none` (docs/measurements.md, "Peak memory"), of which the counted
/// heap (bake/tests/preflight.rs: the BVH build's peak) is about 33 MB.
pub const BASE_BYTES: u64 = 8_000_000;

/// Heap bytes per triangle at the peak of building the BVH (`TriangleScene::build` over
/// `Scene::instances`): the instances' meshes (positions, normals, uvs: 32 B a vertex, 12 B
/// of indices a triangle), the corners (48 B), planes (16 B), attributes (84 B) and input
/// order (4 B) that stay, the CWBVH nodes, and obvhs's build buffers. Measured with the
/// counting allocator of bake/tests/preflight.rs on examples/gazebo.toml: 582 B.
pub const BVH_BYTES_PER_TRIANGLE: u64 = 600;

/// Heap bytes per triangle the BVH keeps once built (the same measurement, after the build).
pub const BVH_RESIDENT_BYTES_PER_TRIANGLE: u64 = 300;

/// Heap bytes per placement candidate at the peak of `sample_points::place`: the candidate
/// (40 B), its position for the k-d tree (12 B) and the tree, its neighbour list in
/// `eliminate` (a `Vec` of (u32, f32) within 2 r_max: about 22 neighbours with 6 candidates
/// a point, 24 + 8 × 22 B plus allocator rounding), weight, flag and heap entry. Measured with
/// the counting allocator of bake/tests/preflight.rs at 20 000 points: 415 B.
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

/// Bytes of one captured texel as f32 RGB (capture.rs `capture_cube`), without the distance.
pub const CUBE_TEXEL_BYTES: u64 = 12;

/// Bytes the f32 distance plane adds per captured texel when `distance_channel` is on.
pub const DISTANCE_TEXEL_BYTES: u64 = 4;

// --- store -----------------------------------------------------------------------------------

/// Bytes of the store besides the sample maps, points and cube maps: header (256 B), metadata
/// (objects, patches: 192 B of control points each), alignment. Generous.
pub const STORE_FIXED_BYTES: u64 = 64 << 10;

/// Bytes per cube in the store besides its compressed faces: 6 table-of-contents entries of
/// 32 B (`oslf_format::toc::TOC_CUBE_BYTES`), the record header (160 B) and 6 zstd frame headers.
pub const STORE_CUBE_OVERHEAD_BYTES: u64 = 6 * 32 + 160 + 6 * 16;

/// Compressed bytes per cube-map texel (colour only), by encoding and `mantissa_bits`:
/// the mean of the 32² and 128² gazebo bakes of docs/measurements.md, "Store sizes and read
/// speed" (lossless table: RGB9E5 3.443 and 3.121 of 4 raw bytes; RGBA16F 4.658 and 3.985 of
/// 8; RGBA32F 9.207 of 16 — the 32² column, the only one baked from unquantised radiance;
/// quantized RGB9E5 table for `mantissa_bits` < 9; BC6H 0.973 and 0.920 of 1 raw byte, the
/// quick preset's 32² cubes and a 128² bake of the same scene converted from RGBA32F, filter
/// none: `oslf_format::bc6h`). A cube map of a simpler scene compresses
/// better; one of noisier radiance (fewer samples per texel) a little worse.
pub fn compressed_texel_bytes(encoding: oslf_format::Encoding, mantissa_bits: u32) -> f64 {
    use oslf_format::Encoding;
    match encoding {
        Encoding::Rgb9e5 => {
            // k = 1..=9 kept mantissa bits.
            const TABLE: [f64; 9] = [0.53, 0.93, 1.23, 1.56, 1.99, 2.32, 2.72, 3.19, 3.28];
            TABLE[(mantissa_bits.clamp(1, 9) - 1) as usize]
        }
        Encoding::Rgba16f => 4.32,
        Encoding::Rgba32f => 9.21,
        Encoding::Bc6h => 0.95,
    }
}

/// Compressed bytes per texel of the distance plane (4 raw bytes of f32): not measured; the
/// distances of neighbouring texels are close, but their low bits are noise. Assumed 3.
pub const DISTANCE_COMPRESSED_BYTES: f64 = 3.0;

/// The store's size is given as a range around its typical value: cube maps compress by a
/// factor that depends on the scene; these bound the typical figure's error for the bakes
/// measured (0.75: a smooth scene; 1.25: noisy radiance, up to raw RGB9E5 bytes).
pub const STORE_RANGE: (f64, f64) = (0.75, 1.25);

// --- points ----------------------------------------------------------------------------------

/// Sample points as a multiple of the requested count: placement removes a few (closer than ε
/// to a surface, inside geometry) and §6.3 refinement adds points where texels found fewer
/// than four, at most as many as were placed (`bake.rs`: the budget is `points_placed`). The
/// gazebo's quick preset ends with 488 of 300, the thesis preset 1239 of 1156 (docs/
/// measurements.md), so typical is 1.3 and the most 2.
pub const POINTS_TYPICAL: f64 = 1.3;
/// See [`POINTS_TYPICAL`].
pub const POINTS_MOST: f64 = 2.0;

// --- time ------------------------------------------------------------------------------------

/// Rays per second per core for the capture's ray count as [`Estimate::capture_rays`] counts
/// it (every path vertex's closest-hit ray plus one shadow ray per delta light and one for a
/// non-black environment, cosine-culled ones included). Measured: the quick gazebo preset
/// traces 24.0 M path vertices × 3 = 72 M such rays in 22.1 CPU-s (3.3 M/s), the thesis
/// preset 4.4 G in 1559 CPU-s on an older build (2.8 M/s; docs/measurements.md, "Bake" and
/// "Capture speed"). Heavier scenes (more triangles, more bounces) are slower: 1 to 4 M/s.
pub const RAYS_PER_CORE_SECOND: (f64, f64) = (1.0e6, 4.0e6);

/// Seconds per sample-map texel and core, for one build of the maps (a k-nearest query of 16
/// or 64 points and up to 64 visibility rays; sample_map.rs `texel_indices`). Measured: the
/// gazebo's 458 752 texels took 10.7 s on 2 threads for 2–4 builds, about 15 µs each.
pub const SECONDS_PER_MAP_TEXEL: (f64, f64) = (4e-6, 30e-6);

/// How many times the sample maps are built: once, and once more after each §6.3 refinement
/// round that added points (`sample_points::REFINE_ROUNDS` = 3).
pub const MAP_BUILDS: (f64, f64) = (1.0, 4.0);

/// Seconds per triangle to build the BVH (one thread): 0.10 s for 56 540 triangles on the
/// gazebo (1.8 µs; docs/measurements.md).
pub const SECONDS_PER_TRIANGLE: (f64, f64) = (0.5e-6, 4e-6);

/// Seconds per placement candidate (one thread: `eliminate`'s neighbour search and heap), and
/// the free-space probe rays per kept point (64 directions × 2; sample_points.rs `place`).
pub const SECONDS_PER_CANDIDATE: (f64, f64) = (1e-6, 6e-6);
/// See [`SECONDS_PER_CANDIDATE`].
pub const PROBE_RAYS_PER_POINT: u64 = 128;

/// A bake whose *optimistic* time estimate exceeds this is refused by [`Limits::of_machine`]'s
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

// ---------------------------------------------------------------------------------------------

/// One term of an estimate: what it is, its size, where the size comes from, and the setting
/// that controls it.
#[derive(Clone, Debug, PartialEq)]
pub struct Term {
    /// Short name: "sample maps", "cubes in flight", "BVH", …
    pub name: &'static str,
    /// Bytes (of memory or of the store).
    pub bytes: u64,
    /// How it was computed, with the settings' values, e.g. `sample_map_resolution = 16384 ×
    /// 28 patches`.
    pub detail: String,
    /// What to change to make it smaller, e.g. `lower sample_map_resolution`.
    pub remedy: String,
}

/// One term of the time estimate.
#[derive(Clone, Debug, PartialEq)]
pub struct TimeTerm {
    pub name: &'static str,
    /// Seconds on the estimate's threads, (optimistic, pessimistic).
    pub seconds: (f64, f64),
    pub detail: String,
    pub remedy: String,
}

/// What a bake will cost, from its settings alone ([`estimate`]).
#[derive(Clone, Debug, PartialEq)]
pub struct Estimate {
    /// The thread count the times are for.
    pub threads: usize,
    /// Sample points: (fewest, typical, most) — see [`POINTS_TYPICAL`].
    pub sample_points: (u64, u64, u64),
    /// Cube maps the store holds, typical (points + the environment cube).
    pub cubes: u64,
    /// Triangles of the BVH (environment meshes + the tessellated OSLF objects).
    pub triangles: u64,
    /// Sample-map texels over all patches.
    pub map_texels: u64,
    /// Path vertices of the capture: cubes × 6 × res² × spp × (bounces + 1), spp rounded up to
    /// a square as the capture does (typical cube count).
    pub path_vertices: u64,
    /// Rays the capture traces at most: `path_vertices` × (1 + delta lights + 1 if the
    /// environment is not black).
    pub capture_rays: u64,
    /// The largest memory in use at once, bytes: the largest of the stages' sums (see
    /// `memory`).
    pub peak_memory_bytes: u64,
    /// The terms of the stage that peaks, largest first.
    pub memory: Vec<Term>,
    /// Which stage peaks: "placement", "sample maps" or "capture".
    pub peak_stage: &'static str,
    /// Store size: typical, and (low, high) = typical × [`STORE_RANGE`].
    pub store_bytes: u64,
    pub store_range: (u64, u64),
    /// Terms of the store size, largest first.
    pub store: Vec<Term>,
    /// Wall seconds on `threads` threads, (optimistic, pessimistic).
    pub seconds: (f64, f64),
    /// Terms of the time, largest first.
    pub time: Vec<TimeTerm>,
    /// Things that will work but may not be what was meant (shown, never refused).
    pub warnings: Vec<String>,
}

/// What the machine offers. `None`: unknown, not checked.
#[derive(Clone, Debug, PartialEq)]
pub struct Limits {
    /// Bytes of memory available (Linux: `MemAvailable`).
    pub available_memory: Option<u64>,
    /// Free bytes on the store's volume, and the directory it was measured for (named in the
    /// error).
    pub free_space: Option<(PathBuf, u64)>,
    /// Refuse a bake whose optimistic time exceeds this many seconds.
    pub max_seconds: Option<f64>,
}

impl Limits {
    /// This machine's limits for a store written at `output`: [`available_memory`],
    /// [`free_space`] of its directory, [`DEFAULT_MAX_SECONDS`].
    pub fn of_machine(output: &Path) -> Limits {
        let dir = match output.parent() {
            Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
            _ => PathBuf::from("."),
        };
        Limits {
            available_memory: available_memory(),
            free_space: free_space(&dir).map(|b| (dir, b)),
            max_seconds: Some(DEFAULT_MAX_SECONDS),
        }
    }

    /// No limit at all (only [`hard_limits`] apply).
    pub fn none() -> Limits {
        Limits {
            available_memory: None,
            free_space: None,
            max_seconds: None,
        }
    }
}

/// Why a bake was refused before it started.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum PreflightError {
    #[error(
        "the bake needs about {} of memory ({} {}: {}) but {} are available; {}",
        bytes(*.needed), .term.name, bytes(.term.bytes), .term.detail, bytes(*.available), .term.remedy
    )]
    Memory {
        needed: u64,
        available: u64,
        term: Term,
    },
    #[error(
        "the store needs about {} ({} {}: {}) but {} has {} free; {}",
        bytes(*.needed), .term.name, bytes(.term.bytes), .term.detail, .dir.display(), bytes(*.free), .term.remedy
    )]
    Disk {
        needed: u64,
        dir: PathBuf,
        free: u64,
        term: Term,
    },
    #[error(
        "the bake would take {}–{} on {threads} threads ({}: {}), more than the limit of {} (`oslf bake --max-hours`); {}",
        duration(.seconds.0), duration(.seconds.1), .term.name, .term.detail, duration(*.limit), .term.remedy
    )]
    Time {
        seconds: (f64, f64),
        threads: usize,
        limit: f64,
        term: TimeTerm,
    },
    /// A limit no machine lifts.
    #[error("{0}")]
    Impossible(String),
}

impl From<PreflightError> for BakeError {
    fn from(e: PreflightError) -> Self {
        BakeError::Invalid(e.to_string())
    }
}

/// Bytes available for new allocations: `MemAvailable` of /proc/meminfo on Linux. `None`
/// elsewhere, or if it cannot be read: then memory is not checked.
pub fn available_memory() -> Option<u64> {
    let text = std::fs::read_to_string("/proc/meminfo").ok()?;
    parse_meminfo(&text)
}

/// `MemAvailable` of a /proc/meminfo text, in bytes.
pub fn parse_meminfo(text: &str) -> Option<u64> {
    let line = text.lines().find(|l| l.starts_with("MemAvailable:"))?;
    let mut words = line.split_whitespace().skip(1);
    let kib: u64 = words.next()?.parse().ok()?;
    match words.next() {
        Some("kB") | None => kib.checked_mul(1024),
        Some(_) => None,
    }
}

/// Bytes free for an unprivileged user on the volume holding `dir` (statvfs: `f_bavail` ×
/// `f_frsize`). `None` where unknown (not Unix, or the call failed): then space is not checked.
pub fn free_space(dir: &Path) -> Option<u64> {
    #[cfg(unix)]
    {
        let s = rustix::fs::statvfs(dir).ok()?;
        Some(s.f_bavail.saturating_mul(s.f_frsize))
    }
    #[cfg(not(unix))]
    {
        let _ = dir;
        None
    }
}

/// Area of a patch from a 16 × 16 grid of its points (two triangles a cell).
fn patch_area(p: &crate::bezier::BezierPatch) -> f64 {
    const N: usize = 16;
    let pt = |i: usize, j: usize| p.eval(i as f32 / N as f32, j as f32 / N as f32);
    let mut area = 0.0;
    for i in 0..N {
        for j in 0..N {
            let (a, b, c, d) = (pt(i, j), pt(i + 1, j), pt(i + 1, j + 1), pt(i, j + 1));
            area += 0.5 * f64::from((b - a).cross(c - a).length() + (c - a).cross(d - a).length());
        }
    }
    area
}

/// The quantities an estimate is computed from, derived from the scene and its settings.
struct Counts {
    /// The thread count the times are for (at least 1), and it as `f64`.
    threads: usize,
    th: f64,
    /// Sample maps over all OSLF objects: Bézier patches and mesh atlas pages.
    patches: u64,
    /// Sample points requested (`sample_count`, or the area over `sample_spacing`).
    requested: u64,
    /// Sample points: (fewest, typical, most).
    points: (u64, u64, u64),
    /// Cube maps, typical (points + the environment cube).
    cubes: u64,
    /// Triangles of the scene's BVH, and of the environment cube's second BVH.
    triangles: u64,
    env_triangles: u64,
    /// `cube_resolution`, texels of a face and of a cube.
    res: u64,
    face_texels: u64,
    cube_texels: u64,
    /// `sample_map_resolution`, and texels over all patches.
    smr: u64,
    map_texels: u64,
    /// Samples per texel as the capture takes them (a square).
    spp: u64,
    vertices_per_path: u64,
    path_vertices: u64,
    lights: u64,
    rays_per_vertex: u64,
    capture_rays: u64,
    /// Bytes of one sample-map index in the store.
    index_bytes: u64,
    /// Bytes of one cube-map texel in the store, compressed.
    stored_texel: f64,
}

/// Sample points the settings ask for: `sample_count`, or the patches' area over
/// `sample_spacing`.
fn requested_points(scene: &Scene) -> u64 {
    match scene.bake.sample_count {
        SampleDensity::Count(n) => u64::from(n),
        SampleDensity::Spacing(h) => {
            let mesh_area: f64 = scene
                .objects
                .iter()
                .filter_map(|o| o.mesh.as_ref())
                .map(|m| m.mesh.area())
                .sum();
            let area: f64 = scene
                .objects
                .iter()
                .flat_map(|o| &o.patches)
                .map(patch_area)
                .sum::<f64>()
                + mesh_area;
            (area / (0.866_025_4 * f64::from(h) * f64::from(h))).ceil() as u64
        }
    }
}

/// Triangles of the scene's BVH, and of the environment cube's second BVH (0 without one).
fn triangle_counts(scene: &Scene) -> (u64, u64) {
    let s = &scene.bake;
    // Triangles (bake.rs: `scene.instances(true, epsilon × TESSELLATION_ERROR)`; scene.rs:
    // each patch at its `tessellation_level`, two triangles a quad).
    let shape_triangles: u64 = scene
        .shapes
        .iter()
        .map(|sh| sh.mesh.triangles.len() as u64)
        .sum();
    let max_error = s.epsilon * TESSELLATION_ERROR;
    let object_triangles: u64 = scene
        .objects
        .iter()
        .flat_map(|o| &o.patches)
        .map(|p| 2 * u64::from(p.tessellation_level(max_error)).pow(2))
        .sum::<u64>()
        + scene
            .objects
            .iter()
            .filter_map(|o| o.mesh.as_ref())
            .map(|m| m.mesh.triangles.len() as u64)
            .sum::<u64>();
    let triangles = shape_triangles + object_triangles;
    // The environment cube's second BVH (bake.rs: built when the store has an environment cube
    // and the scene has shapes), alive during the capture.
    let env_triangles = if s.env_cube { shape_triangles } else { 0 };
    (triangles, env_triangles)
}

impl Counts {
    /// Derives the counts of baking `scene` on `threads` threads.
    fn of(scene: &Scene, threads: usize) -> Counts {
        let s = &scene.bake;
        let threads = threads.max(1);
        let th = threads as f64;
        // Sample maps: one per patch, k² per mesh atlas (laid out as the bake will; a mesh
        // the atlas refuses fails the bake itself, and counts as one map here).
        let patches: u64 = match crate::surface::Surfaces::new(&scene.objects, s) {
            Ok(surfaces) => u64::from(surfaces.map_count()),
            Err(_) => scene
                .objects
                .iter()
                .map(|o| o.patches.len() as u64 + u64::from(o.mesh.is_some()))
                .sum(),
        };

        // Sample points.
        let requested = requested_points(scene);
        let points = (
            requested,
            (requested as f64 * POINTS_TYPICAL).ceil() as u64,
            (requested as f64 * POINTS_MOST).ceil() as u64,
        );
        let env_cube = u64::from(s.env_cube);
        let cubes = points.1 + env_cube;

        let (triangles, env_triangles) = triangle_counts(scene);

        let res = u64::from(s.cube_resolution);
        let face_texels = res * res;
        let cube_texels = 6 * face_texels;
        let smr = u64::from(s.sample_map_resolution);
        let map_texels = patches * smr * smr;
        let spp = u64::from(strata_per_side(s.samples_per_texel)).pow(2);
        let vertices_per_path = u64::from(s.bounces) + 1;
        let path_vertices = cubes
            .saturating_mul(cube_texels)
            .saturating_mul(spp)
            .saturating_mul(vertices_per_path);
        let lights = scene.lights.len() as u64;
        let rays_per_vertex = 1 + lights + u64::from(!scene.environment.is_black());
        let capture_rays = path_vertices.saturating_mul(rays_per_vertex);

        // The store stores indices as u16 when there are fewer than 65 535 points
        // (oslf_format `IndexWidth::for_sample_count`), else u32; `Prefix::build` encodes the maps
        // into a buffer of that size while the maps are held.
        let index_bytes: u64 = if points.2 < 65_535 { 2 } else { 4 };
        let stored_texel = compressed_texel_bytes(s.encoding, s.mantissa_bits)
            + if s.distance_channel {
                DISTANCE_COMPRESSED_BYTES
            } else {
                0.0
            };
        Counts {
            threads,
            th,
            patches,
            requested,
            points,
            cubes,
            triangles,
            env_triangles,
            res,
            face_texels,
            cube_texels,
            smr,
            map_texels,
            spp,
            vertices_per_path,
            path_vertices,
            lights,
            rays_per_vertex,
            capture_rays,
            index_bytes,
            stored_texel,
        }
    }
}

/// The sum of the terms' bytes, saturating.
fn total_bytes(terms: &[Term]) -> u64 {
    terms.iter().fold(0u64, |a, t| a.saturating_add(t.bytes))
}

/// The memory term of the BVHs at their peak.
fn bvh_term(s: &BakeSettings, c: &Counts) -> Term {
    let (triangles, env_triangles) = (c.triangles, c.env_triangles);
    // The scene's BVH at its build peak, or once built plus the environment cube's BVH at its
    // build peak (built after the sample maps), whichever is larger.
    let bvh_bytes = (triangles.saturating_mul(BVH_BYTES_PER_TRIANGLE)).max(
        triangles
            .saturating_mul(BVH_RESIDENT_BYTES_PER_TRIANGLE)
            .saturating_add(env_triangles.saturating_mul(BVH_BYTES_PER_TRIANGLE)),
    );
    Term {
        name: "BVH",
        bytes: bvh_bytes,
        detail: format!(
            "{triangles} triangles{}: the environment meshes and the OSLF patches tessellated to epsilon = {} / 50",
            if env_triangles > 0 {
                format!(" + {env_triangles} for the environment cube")
            } else {
                String::new()
            },
            s.epsilon
        ),
        remedy: "raise epsilon or use fewer segments in the environment shapes".into(),
    }
}

/// The memory term of the cubes being captured and encoded at once.
fn cubes_in_flight_term(s: &BakeSettings, c: &Counts) -> Term {
    let res = c.res;
    // bake.rs: `chunk_cubes` cubes are captured in parallel and all of them, encoded, are
    // collected before they are appended; each holds its f32 faces until encoded
    // (capture.rs), and each encoder a raw and a filtered face (oslf-format cube.rs).
    let chunk = chunk_cubes(s.cube_resolution, s.distance_channel) as u64;
    let texel_bytes = CUBE_TEXEL_BYTES
        + if s.distance_channel {
            DISTANCE_TEXEL_BYTES
        } else {
            0
        };
    // BC6H's encoder also stages each face as padded RGBA binary16 (8 B per texel).
    let staging = if s.encoding.is_block_compressed() {
        8
    } else {
        0
    };
    let raw_texel =
        s.encoding.bytes_per_texel() as u64 + staging + if s.distance_channel { 4 } else { 0 };
    let encoders = chunk.min(c.threads as u64);
    let in_flight = chunk
        .saturating_mul(c.cube_texels)
        .saturating_mul(texel_bytes)
        .saturating_add(encoders.saturating_mul(2 * c.face_texels * raw_texel))
        .saturating_add((chunk as f64 * c.cube_texels as f64 * c.stored_texel) as u64);
    Term {
        name: "cubes in flight",
        bytes: in_flight,
        detail: format!(
            "cube_resolution = {res}: {chunk} × 6 × {res}² texels × {texel_bytes} B as f32{}, encoded",
            if s.distance_channel { " with distance" } else { "" }
        ),
        remedy: "lower cube_resolution".into(),
    }
}

/// The memory terms of the stage that peaks, largest first, the stage's name and its total.
fn memory_terms(s: &BakeSettings, c: &Counts) -> (&'static str, Vec<Term>, u64) {
    let (requested, points, lights) = (c.requested, c.points, c.lights);
    let (smr, patches, map_texels, index_bytes) = (c.smr, c.patches, c.map_texels, c.index_bytes);
    // --- memory, by stage ---
    let bvh = bvh_term(s, c);
    let light_term = Term {
        name: "lights",
        bytes: lights * std::mem::size_of::<crate::light::Light>() as u64,
        detail: format!("{lights} lights"),
        remedy: "use fewer point lights".into(),
    };
    let base = Term {
        name: "program and scene",
        bytes: BASE_BYTES,
        detail: "measured on the quick gazebo preset".into(),
        remedy: "nothing to change".into(),
    };
    let placement = Term {
        name: "placement",
        bytes: (requested * CANDIDATES_PER_POINT).saturating_mul(PLACEMENT_BYTES_PER_CANDIDATE),
        detail: format!(
            "sample_count = {requested} × {CANDIDATES_PER_POINT} candidates × {PLACEMENT_BYTES_PER_CANDIDATE} B"
        ),
        remedy: "lower sample_count (or raise sample_spacing)".into(),
    };
    let points_term = Term {
        name: "sample points",
        bytes: points.2 * POINT_BYTES,
        detail: format!("up to {} points × {POINT_BYTES} B", points.2),
        remedy: "lower sample_count (or raise sample_spacing)".into(),
    };
    let maps = Term {
        name: "sample maps",
        bytes: map_texels.saturating_mul(MAP_TEXEL_BYTES + 4 * index_bytes),
        detail: format!(
            "sample_map_resolution = {smr}² × {patches} patches × ({MAP_TEXEL_BYTES} B + {} B encoded)",
            4 * index_bytes
        ),
        remedy: "lower sample_map_resolution".into(),
    };
    let maps_held = Term {
        bytes: map_texels.saturating_mul(MAP_TEXEL_BYTES),
        detail: format!("sample_map_resolution = {smr}² × {patches} patches × {MAP_TEXEL_BYTES} B"),
        ..maps.clone()
    };
    let cubes_term = cubes_in_flight_term(s, c);
    let stages: [(&'static str, Vec<Term>); 3] = [
        (
            "placement",
            vec![base.clone(), bvh.clone(), light_term.clone(), placement],
        ),
        (
            "sample maps",
            vec![
                base.clone(),
                bvh.clone(),
                light_term.clone(),
                points_term.clone(),
                maps,
            ],
        ),
        (
            "capture",
            vec![base, bvh, light_term, points_term, maps_held, cubes_term],
        ),
    ];
    let (peak_stage, mut memory) = stages
        .into_iter()
        .max_by_key(|(_, terms)| total_bytes(terms))
        .expect("three stages");
    memory.sort_by_key(|t| std::cmp::Reverse(t.bytes));
    let peak_memory_bytes = total_bytes(&memory);
    (peak_stage, memory, peak_memory_bytes)
}

/// The store's terms, largest first, its typical size and its range.
fn store_terms(s: &BakeSettings, c: &Counts) -> (Vec<Term>, u64, (u64, u64)) {
    let (smr, patches, points, cubes, res) = (c.smr, c.patches, c.points, c.cubes, c.res);
    let (requested, stored_texel) = (c.requested, c.stored_texel);
    // --- store ---
    // oslf-format writer: header and metadata, points (40 B each), the maps uncompressed at
    // `index_bytes` per entry, then per cube its compressed faces and table entries.
    let store_maps = Term {
        name: "sample maps",
        bytes: c.map_texels.saturating_mul(4 * c.index_bytes),
        detail: format!(
            "sample_map_resolution = {smr}² × {patches} patches × {} B",
            4 * c.index_bytes
        ),
        remedy: "lower sample_map_resolution".into(),
    };
    let store_points = Term {
        name: "sample points",
        bytes: points.1 * oslf_format::meta::SAMPLE_POINT_BYTES as u64,
        detail: format!("{} points × 40 B", points.1),
        remedy: "lower sample_count".into(),
    };
    let per_cube = (c.cube_texels as f64 * stored_texel) as u64 + STORE_CUBE_OVERHEAD_BYTES;
    let mantissa_hint = if s.encoding == oslf_format::Encoding::Rgb9e5 && s.mantissa_bits == 9 {
        ", or use mantissa_bits (e.g. 3)"
    } else if s.encoding != oslf_format::Encoding::Rgb9e5 && !s.encoding.is_block_compressed() {
        ", or use encoding = \"rgb9e5\" or \"bc6h\""
    } else {
        ""
    };
    let store_cubes = Term {
        name: "cube maps",
        bytes: cubes.saturating_mul(per_cube),
        detail: format!(
            "{cubes} cubes (sample_count = {requested}) × 6 × cube_resolution {res}² × {stored_texel:.2} B ({}, mantissa_bits = {})",
            s.encoding, s.mantissa_bits
        ),
        remedy: format!("lower cube_resolution or sample_count{mantissa_hint}"),
    };
    let mut store = vec![store_maps, store_points, store_cubes];
    store.sort_by_key(|t| std::cmp::Reverse(t.bytes));
    let store_bytes = total_bytes(&store).saturating_add(STORE_FIXED_BYTES);
    let store_range = (
        (store_bytes as f64 * STORE_RANGE.0) as u64,
        (store_bytes as f64 * STORE_RANGE.1) as u64,
    );
    (store, store_bytes, store_range)
}

/// The time term of the capture, naming the setting that costs the most.
fn capture_time_term(scene: &Scene, c: &Counts) -> TimeTerm {
    let (spp, vertices_per_path, rays_per_vertex) = (c.spp, c.vertices_per_path, c.rays_per_vertex);
    let (cubes, res, lights, capture_rays, th) = (c.cubes, c.res, c.lights, c.capture_rays, c.th);
    // The capture: name the factor furthest above the quick preset's (300 points, 32², 4 spp,
    // 1 bounce, 1 light + sky).
    let factors = [
        (spp as f64 / 4.0, "lower samples_per_texel"),
        (c.face_texels as f64 / 1024.0, "lower cube_resolution"),
        (c.requested as f64 / 300.0, "lower sample_count"),
        (vertices_per_path as f64 / 2.0, "lower bounces"),
        (rays_per_vertex as f64 / 3.0, "use fewer point lights"),
    ];
    let capture_remedy = factors
        .iter()
        .max_by(|a, b| a.0.total_cmp(&b.0))
        .map_or("", |f| f.1)
        .to_string();
    TimeTerm {
        name: "cube maps",
        seconds: (
            capture_rays as f64 * 0.5 / (RAYS_PER_CORE_SECOND.1 * th),
            capture_rays as f64 / (RAYS_PER_CORE_SECOND.0 * th),
        ),
        detail: format!(
            "{cubes} cubes × 6 × {res}² texels × samples_per_texel {spp} × {vertices_per_path} vertices (bounces = {}) × {rays_per_vertex} rays ({lights} lights{}) = {:.3e} rays",
            scene.bake.bounces,
            if scene.environment.is_black() { "" } else { " + environment" },
            capture_rays as f64
        ),
        remedy: capture_remedy,
    }
}

/// The time terms, largest first, and the total (optimistic, pessimistic) seconds.
fn time_terms(scene: &Scene, c: &Counts) -> (Vec<TimeTerm>, (f64, f64)) {
    let (smr, patches, requested, th) = (c.smr, c.patches, c.requested, c.th);
    // --- time ---
    let capture = capture_time_term(scene, c);
    let map_work = c.map_texels as f64;
    let sample_maps_time = TimeTerm {
        name: "sample maps",
        seconds: (
            map_work * MAP_BUILDS.0 * SECONDS_PER_MAP_TEXEL.0 / th,
            map_work * MAP_BUILDS.1 * SECONDS_PER_MAP_TEXEL.1 / th,
        ),
        detail: format!("sample_map_resolution = {smr}² × {patches} patches, built 1 to 4 times"),
        remedy: "lower sample_map_resolution".into(),
    };
    // sample_points.rs: elimination and the free-space probes run on one thread.
    let cands = (requested * CANDIDATES_PER_POINT) as f64;
    let probes = (requested * PROBE_RAYS_PER_POINT) as f64;
    let placement_time = TimeTerm {
        name: "placement",
        seconds: (
            cands * SECONDS_PER_CANDIDATE.0 + probes / RAYS_PER_CORE_SECOND.1,
            cands * SECONDS_PER_CANDIDATE.1 + probes / RAYS_PER_CORE_SECOND.0,
        ),
        detail: format!(
            "sample_count = {requested} × {CANDIDATES_PER_POINT} candidates, one thread"
        ),
        remedy: "lower sample_count".into(),
    };
    let bvh_triangles = c.triangles + c.env_triangles;
    let bvh_time = TimeTerm {
        name: "BVH",
        seconds: (
            bvh_triangles as f64 * SECONDS_PER_TRIANGLE.0,
            bvh_triangles as f64 * SECONDS_PER_TRIANGLE.1,
        ),
        detail: format!("{bvh_triangles} triangles"),
        remedy: "raise epsilon or simplify the environment meshes".into(),
    };
    let mut time = vec![capture, sample_maps_time, placement_time, bvh_time];
    time.sort_by(|a, b| b.seconds.1.total_cmp(&a.seconds.1));
    let seconds = time
        .iter()
        .fold((0.0, 0.0), |a, t| (a.0 + t.seconds.0, a.1 + t.seconds.1));
    (time, seconds)
}

/// Settings that will work but may not be what was meant: textures larger than every GPU
/// accepts.
fn warnings(s: &BakeSettings) -> Vec<String> {
    // --- warnings ---
    let mut warnings = Vec::new();
    if s.cube_resolution > GPU_TEXTURE_LIMIT {
        warnings.push(format!(
            "cube_resolution = {} is larger than the {GPU_TEXTURE_LIMIT}² textures every GPU accepts: the store is valid but the runtime may not load it",
            s.cube_resolution
        ));
    }
    if s.sample_map_resolution > GPU_TEXTURE_LIMIT {
        warnings.push(format!(
            "sample_map_resolution = {} is larger than the {GPU_TEXTURE_LIMIT}² textures every GPU accepts: the store is valid but the runtime may not load it",
            s.sample_map_resolution
        ));
    }
    warnings
}

/// Estimates what baking `scene` costs on `threads` threads. Pure: reads no file.
pub fn estimate(scene: &Scene, threads: usize) -> Estimate {
    let s = &scene.bake;
    let c = Counts::of(scene, threads);
    let (peak_stage, memory, peak_memory_bytes) = memory_terms(s, &c);
    let (store, store_bytes, store_range) = store_terms(s, &c);
    let (time, seconds) = time_terms(scene, &c);
    Estimate {
        threads: c.threads,
        sample_points: c.points,
        cubes: c.cubes,
        triangles: c.triangles,
        map_texels: c.map_texels,
        path_vertices: c.path_vertices,
        capture_rays: c.capture_rays,
        peak_memory_bytes,
        memory,
        peak_stage,
        store_bytes,
        store_range,
        store,
        seconds,
        time,
        warnings: warnings(s),
    }
}

/// Refuses what no machine can bake: more sample points (plus the environment cube) than the
/// `u32` sample index and cube count allow.
pub fn hard_limits(e: &Estimate) -> Result<(), PreflightError> {
    if e.sample_points.2 + 1 > MAX_SAMPLE_POINTS {
        return Err(PreflightError::Impossible(format!(
            "up to {} sample points do not fit the store's u32 sample indices (at most {MAX_SAMPLE_POINTS}); lower sample_count",
            e.sample_points.2
        )));
    }
    Ok(())
}

impl Estimate {
    /// The share of one shard of `count` (`oslf bake --shard I/N`): the cube maps, their store
    /// bytes and their capture time divided by `count` (shards differ by at most one cube);
    /// the sample points, sample maps, BVH and memory stay whole, as every shard computes them.
    pub fn for_shard(mut self, count: u32) -> Self {
        let n = u64::from(count.max(1));
        let share = |b: u64| b.div_ceil(n);
        self.cubes = share(self.cubes);
        self.path_vertices = share(self.path_vertices);
        self.capture_rays = share(self.capture_rays);
        let mut store_delta = 0;
        for t in self.store.iter_mut().filter(|t| t.name == "cube maps") {
            let kept = share(t.bytes);
            store_delta += t.bytes - kept;
            t.bytes = kept;
            t.detail = format!("{} (1/{n} of it in this shard)", t.detail);
        }
        self.store.sort_by_key(|t| std::cmp::Reverse(t.bytes));
        self.store_bytes -= store_delta;
        self.store_range = (
            (self.store_bytes as f64 * STORE_RANGE.0) as u64,
            (self.store_bytes as f64 * STORE_RANGE.1) as u64,
        );
        for t in self.time.iter_mut().filter(|t| t.name == "cube maps") {
            t.seconds = (t.seconds.0 / n as f64, t.seconds.1 / n as f64);
            t.detail = format!("{} (1/{n} of it in this shard)", t.detail);
        }
        self.time
            .sort_by(|a, b| b.seconds.1.total_cmp(&a.seconds.1));
        self.seconds = self
            .time
            .iter()
            .fold((0.0, 0.0), |a, t| (a.0 + t.seconds.0, a.1 + t.seconds.1));
        self
    }
}

/// Checks `e` against [`hard_limits`] and `limits`: memory (the peak against the available
/// memory), disk (the typical store size against the free space), time (the optimistic time
/// against `max_seconds`), in that order. The error names the largest term and its setting.
pub fn check(e: &Estimate, limits: &Limits) -> Result<(), PreflightError> {
    hard_limits(e)?;
    if let Some(available) = limits.available_memory {
        if e.peak_memory_bytes > available {
            return Err(PreflightError::Memory {
                needed: e.peak_memory_bytes,
                available,
                term: e.memory[0].clone(),
            });
        }
    }
    if let Some((dir, free)) = &limits.free_space {
        if e.store_bytes > *free {
            return Err(PreflightError::Disk {
                needed: e.store_bytes,
                dir: dir.clone(),
                free: *free,
                term: e.store[0].clone(),
            });
        }
    }
    if let Some(limit) = limits.max_seconds {
        if e.seconds.0 > limit {
            return Err(PreflightError::Time {
                seconds: e.seconds,
                threads: e.threads,
                limit,
                term: e.time[0].clone(),
            });
        }
    }
    Ok(())
}

/// `bytes` in SI units with three significant digits: `37.5 MB`, `1.65 TB`.
pub fn bytes(b: u64) -> String {
    const UNITS: [&str; 6] = ["B", "kB", "MB", "GB", "TB", "PB"];
    let mut v = b as f64;
    let mut u = 0;
    while v >= 1000.0 && u + 1 < UNITS.len() {
        v /= 1000.0;
        u += 1;
    }
    if u == 0 {
        format!("{b} B")
    } else if v >= 100.0 {
        format!("{v:.0} {}", UNITS[u])
    } else {
        format!("{v:.1} {}", UNITS[u])
    }
}

/// Seconds as `40 s`, `12 min`, `3.5 h`, `14 days`.
pub fn duration(s: f64) -> String {
    if s < 1.0 {
        "<1 s".into()
    } else if s < 90.0 {
        format!("{s:.0} s")
    } else if s < 90.0 * 60.0 {
        format!("{:.0} min", s / 60.0)
    } else if s < 48.0 * 3600.0 {
        format!("{:.1} h", s / 3600.0)
    } else if s < 2.0 * 365.0 * 86400.0 {
        format!("{:.0} days", s / 86400.0)
    } else {
        format!("{:.0} years", s / (365.0 * 86400.0))
    }
}

impl fmt::Display for Estimate {
    /// One line: `estimate: peak memory ~38 MB, store ~14 MB, time ~9 s–1 min on 2 threads`.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "estimate: peak memory ~{}, store ~{}, time ~{}–{} on {} thread{}",
            bytes(self.peak_memory_bytes),
            bytes(self.store_bytes),
            duration(self.seconds.0),
            duration(self.seconds.1),
            self.threads,
            if self.threads == 1 { "" } else { "s" }
        )
    }
}
