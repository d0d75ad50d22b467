//! The terms of an estimate: the counts a scene and its settings give (points, triangles,
//! texels, cubes), and from them each memory, store and time term.

use super::costs::*;
use crate::pilot::{pilot_count, PILOT_RESOLUTION, PILOT_SAMPLES};
use oslf_scene::scene::{BakeSettings, PointPlacement, SampleDensity, Scene};
use oslf_scene::tolerance::TESSELLATION_ERROR;
use oslf_trace::capture::{captured_texel_bytes, chunk_cubes, strata_per_side, CaptureSettings};

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

/// Area of a patch from a 16 × 16 grid of its points (two triangles a cell).
pub(super) fn patch_area(p: &oslf_geometry::bezier::BezierPatch) -> f64 {
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
pub(super) struct Counts {
    /// The thread count the times are for (at least 1), and it as `f64`.
    pub(super) threads: usize,
    pub(super) th: f64,
    /// Sample maps over all OSLF objects: Bézier patches and mesh atlas pages.
    pub(super) patches: u64,
    /// Sample points requested (`sample_count`, or the area over `sample_spacing`).
    pub(super) requested: u64,
    /// Sample points: (fewest, typical, most).
    pub(super) points: (u64, u64, u64),
    /// Cube maps, typical (points + the environment cube).
    pub(super) cubes: u64,
    /// Triangles of the scene's BVH, and of the environment cube's second BVH.
    pub(super) triangles: u64,
    pub(super) env_triangles: u64,
    /// `cube_resolution`, texels of a face and of a cube.
    pub(super) res: u64,
    pub(super) face_texels: u64,
    pub(super) cube_texels: u64,
    /// `sample_map_resolution`, and texels over all patches.
    pub(super) smr: u64,
    pub(super) map_texels: u64,
    /// Samples per texel as the capture takes them (a square).
    pub(super) spp: u64,
    pub(super) vertices_per_path: u64,
    pub(super) path_vertices: u64,
    pub(super) lights: u64,
    pub(super) rays_per_vertex: u64,
    pub(super) capture_rays: u64,
    /// Bytes of one sample-map index in the store.
    pub(super) index_bytes: u64,
    /// Bytes of one cube-map texel in the store, compressed.
    pub(super) stored_texel: f64,
}

/// Sample points the settings ask for: `sample_count`, or the area over `sample_spacing`, of
/// the objects without a `sample_spacing` of their own, plus each other object's area over
/// its own spacing.
pub(super) fn requested_points(scene: &Scene) -> u64 {
    let area = |o: &oslf_scene::scene::OslfObject| {
        o.patches.iter().map(patch_area).sum::<f64>()
            + o.mesh.as_ref().map_or(0.0, |m| m.mesh.area())
    };
    let at = |area: f64, h: f32| (area / (0.866_025_4 * f64::from(h) * f64::from(h))).ceil() as u64;
    let shared: Vec<_> = scene
        .objects
        .iter()
        .filter(|o| o.sample_spacing.is_none())
        .collect();
    let own: u64 = scene
        .objects
        .iter()
        .filter_map(|o| Some(at(area(o), o.sample_spacing?)))
        .sum();
    let base = match scene.bake.sample_count {
        _ if shared.is_empty() => 0,
        SampleDensity::Count(n) => u64::from(n),
        SampleDensity::Spacing(h) => at(shared.iter().map(|o| area(o)).sum(), h),
    };
    base + own
}

/// Triangles of the scene's BVH, and of the environment cube's second BVH (0 without one).
pub(super) fn triangle_counts(scene: &Scene) -> (u64, u64) {
    let s = &scene.bake;
    // Triangles (bake/stages.rs: `scene_instances(scene, true, epsilon × TESSELLATION_ERROR)`; scene.rs:
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
    // The environment cube's second BVH (bake/stages.rs: built when the store has an environment cube
    // and the scene has shapes), alive during the capture.
    let env_triangles = if s.env_cube { shape_triangles } else { 0 };
    (triangles, env_triangles)
}

impl Counts {
    /// Derives the counts of baking `scene` on `threads` threads.
    pub(super) fn of(scene: &Scene, threads: usize) -> Counts {
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
pub(super) fn total_bytes(terms: &[Term]) -> u64 {
    terms.iter().fold(0u64, |a, t| a.saturating_add(t.bytes))
}

/// The memory term of the BVHs at their peak.
pub(super) fn bvh_term(s: &BakeSettings, c: &Counts) -> Term {
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
pub(super) fn cubes_in_flight_term(s: &BakeSettings, c: &Counts) -> Term {
    let res = c.res;
    // bake/stages.rs: `chunk_cubes` cubes are captured in parallel and all of them, encoded, are
    // collected before they are appended; each holds its f32 faces until encoded
    // (capture.rs), and each encoder a raw and a filtered face (oslf-format cube.rs).
    let capture = CaptureSettings::from_bake(s);
    let chunk = chunk_cubes(&capture) as u64;
    let texel_bytes = captured_texel_bytes(&capture);
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
            "cube_resolution = {res}: {chunk} × 6 × {res}² texels × {texel_bytes} B as f32{}{}, encoded",
            if s.distance_channel { " with distance" } else { "" },
            if s.denoise { " and variance" } else { "" }
        ),
        remedy: "lower cube_resolution".into(),
    }
}

/// The memory terms of the stage that peaks, largest first, the stage's name and its total.
pub(super) fn memory_terms(s: &BakeSettings, c: &Counts) -> (&'static str, Vec<Term>, u64) {
    let (requested, points, lights) = (c.requested, c.points, c.lights);
    let (smr, patches, map_texels, index_bytes) = (c.smr, c.patches, c.map_texels, c.index_bytes);
    // --- memory, by stage ---
    let bvh = bvh_term(s, c);
    let light_term = Term {
        name: "lights",
        bytes: lights * std::mem::size_of::<oslf_scene::light::Light>() as u64,
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
pub(super) fn store_terms(s: &BakeSettings, c: &Counts) -> (Vec<Term>, u64, (u64, u64)) {
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
pub(super) fn capture_time_term(scene: &Scene, c: &Counts) -> TimeTerm {
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
pub(super) fn time_terms(scene: &Scene, c: &Counts) -> (Vec<TimeTerm>, (f64, f64)) {
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
    // Adaptive placement's pilot cubes (crate::pilot), on the CPU whatever the device.
    let pilot_time = (scene.bake.placement == PointPlacement::Adaptive).then(|| {
        let pilots = pilot_count(requested as usize) as u64;
        let rays = (pilots * 6 * u64::from(PILOT_RESOLUTION).pow(2) * u64::from(PILOT_SAMPLES))
            as f64
            * c.vertices_per_path as f64
            * c.rays_per_vertex as f64;
        TimeTerm {
            name: "pilot cubes",
            seconds: (
                rays * 0.5 / (RAYS_PER_CORE_SECOND.1 * th),
                rays / (RAYS_PER_CORE_SECOND.0 * th),
            ),
            detail: format!(
                "placement = \"adaptive\": {pilots} pilot cubes × 6 × {PILOT_RESOLUTION}² texels × {PILOT_SAMPLES} samples = {rays:.3e} rays"
            ),
            remedy: "use placement = \"parallax\"".into(),
        }
    });
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
    time.extend(pilot_time);
    time.sort_by(|a, b| b.seconds.1.total_cmp(&a.seconds.1));
    let seconds = time
        .iter()
        .fold((0.0, 0.0), |a, t| (a.0 + t.seconds.0, a.1 + t.seconds.1));
    (time, seconds)
}

/// Settings that will work but may not be what was meant: textures larger than every GPU
/// accepts.
pub(super) fn warnings(s: &BakeSettings) -> Vec<String> {
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
