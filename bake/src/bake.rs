//! The bake pipeline: scene → BVH → sample points → sample maps → cube maps → store.

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use glam::{Affine3A, Mat4, Vec3};
use oslf_format::{
    BakeParams, CameraInfo, EncodedCube, MeshInfo, ObjectInfo, Patch, SampleMaps, SamplePoint,
    ShardSpec, ShardWriter, StoreMeta, StoreWriter,
};
use rayon::prelude::*;

use crate::bvh::TriangleScene;
use crate::capture::{capture_cube, chunk_cubes, strata_per_side, CaptureSettings};
use crate::error::{BakeError, Result};
use crate::integrator::{Integrator, RayStats};
use crate::ray::EmptyScene;
use crate::sample_map::{self, SampleMapStats};
use crate::sample_points::{self, Surfaces};
use crate::scene::Scene;
use crate::tolerance::TESSELLATION_ERROR;
use oslf_geometry::atlas::UvSource;

/// How to run a bake.
#[derive(Clone, Debug)]
pub struct BakeOptions {
    /// The store to write.
    pub output: PathBuf,
    /// Continue from `<output>.partial` if it exists (and matches this scene and settings).
    pub resume: bool,
    /// Show a progress bar on stderr.
    pub progress: bool,
    /// Capture at most this many cube maps in this run, then stop and leave `<output>.partial`
    /// for a later `resume` (a bake in slices). `None`: run to the end.
    pub cube_limit: Option<u32>,
}

/// Where the cubes go: the store, or one shard of it.
enum Sink {
    Store(Box<StoreWriter>),
    Shard(Box<ShardWriter>),
}

impl Sink {
    /// Opens the store or shard at `options.output`, resuming its partial file if asked.
    fn open(
        options: &BakeOptions,
        shard: Option<ShardSpec>,
        meta: &StoreMeta,
        points: &[SamplePoint],
        maps: &SampleMaps,
        restarted: &mut bool,
    ) -> Result<Sink> {
        let out = &options.output;
        let create = || -> Result<Sink> {
            Ok(match shard {
                Some(spec) => Sink::Shard(Box::new(ShardWriter::create(
                    out, spec, meta, points, maps,
                )?)),
                None => Sink::Store(Box::new(StoreWriter::create(out, meta, points, maps)?)),
            })
        };
        if !(options.resume && partial_path(out).exists()) {
            return create();
        }
        let resumed = match shard {
            Some(spec) => {
                ShardWriter::resume(out, spec, meta, points, maps).map(|w| Sink::Shard(Box::new(w)))
            }
            None => StoreWriter::resume(out, meta, points, maps).map(|w| Sink::Store(Box::new(w))),
        };
        match resumed {
            // create() was interrupted: there are no finished cube maps to keep.
            Err(oslf_format::Error::PartialNeverCreated { path, detail }) => {
                eprintln!(
                    "{} was never completely created ({detail}): it holds no finished cube maps, so the bake starts from scratch",
                    path.display()
                );
                *restarted = true;
                create()
            }
            result => Ok(result?),
        }
    }

    /// Cubes already in (the first ones of [`Sink::cube`]'s order).
    fn done(&self) -> u32 {
        match self {
            Sink::Store(w) => w.next_cube(),
            Sink::Shard(w) => w.appended(),
        }
    }

    /// Cubes the finished store or shard holds.
    fn total(&self) -> u32 {
        match self {
            Sink::Store(w) => w.total_cubes(),
            Sink::Shard(w) => w.shard_cubes(),
        }
    }

    /// The store's index of the `k`-th cube this sink takes.
    fn cube(&self, k: u32) -> u32 {
        match self {
            Sink::Store(_) => k,
            Sink::Shard(w) => w.spec().cube(k),
        }
    }

    fn append(&mut self, cube: EncodedCube) -> Result<()> {
        match self {
            Sink::Store(w) => w.append(cube)?,
            Sink::Shard(w) => w.append(cube)?,
        }
        Ok(())
    }
}

/// What a bake did, for the summary and for tools (`--report-json`).
#[derive(Clone, Debug, Default, serde::Serialize)]
pub struct BakeReport {
    pub output: PathBuf,
    /// Whether the store was completed (false when `cube_limit` stopped the run early).
    pub finished: bool,
    pub triangles: usize,
    pub bvh_build_seconds: f64,
    pub sample_points: usize,
    pub points_placed: usize,
    pub points_removed_close: usize,
    pub points_removed_inside: usize,
    /// Points added where sample-map texels found fewer than four (§6.3).
    pub points_added: usize,
    pub sample_maps: SampleMapStats,
    /// The atlas of each mesh object, in object order.
    pub atlases: Vec<AtlasReport>,
    /// Cubes of this store (or, for a shard, of this shard).
    pub cubes: u32,
    /// `I/N` when this bake was shard `I` of `N`; `cubes` then counts the shard's cubes.
    pub shard: Option<String>,
    /// Cubes in the merged store (equal to `cubes` unless this is a shard).
    pub store_cubes: u32,
    /// Cubes recovered from an interrupted bake instead of being traced again.
    pub cubes_resumed: u32,
    /// Whether `resume` found a partial file that was never completely created and started
    /// over (a line on stderr says so).
    pub restarted: bool,
    pub cube_resolution: u32,
    pub samples_per_texel: u32,
    pub rays_closest: u64,
    pub rays_shadow: u64,
    /// Capture rays per second, millions (closest + shadow, this run's cubes only).
    pub mrays_per_second: f64,
    pub placement_seconds: f64,
    pub sample_map_seconds: f64,
    pub capture_seconds: f64,
    /// CPU time all of the process's threads spent during the capture, where the system
    /// reports it (Linux). On a shared machine, capture rays per CPU-second do not depend on
    /// what else runs; `mrays_per_second` (wall time) does.
    pub capture_cpu_seconds: Option<f64>,
    pub total_seconds: f64,
    /// CPU time of the whole bake, all threads (Linux; see `capture_cpu_seconds`).
    pub cpu_seconds: Option<f64>,
    pub store_bytes: u64,
    /// Compressed cube-map bytes per texel.
    pub bytes_per_texel: f64,
    /// Texels whose radiance exceeded the encoding's range and were clamped.
    pub clamped_texels: u64,
}

/// How a mesh object's sample maps were laid out.
#[derive(Clone, Debug, serde::Serialize)]
pub struct AtlasReport {
    pub object: String,
    /// Pages per side: the object has `grid²` sample maps.
    pub grid: u32,
    /// Texels per page side (the sample-map resolution).
    pub page_resolution: u32,
    /// `lightmap` (TEXCOORD_1), `texture` (TEXCOORD_0, OBJ `vt`) or `charts` (per triangle).
    pub source: &'static str,
    /// The uv sets tried and not used, each with why.
    pub rejected: Vec<String>,
}

/// CPU nanoseconds run so far by the process's live threads (Linux `schedstat`), if known.
/// The worker pool's threads live for the whole bake, so differences cover them all.
fn process_cpu_ns() -> Option<u64> {
    let mut total = 0u64;
    for task in std::fs::read_dir("/proc/self/task").ok()? {
        let stat = std::fs::read_to_string(task.ok()?.path().join("schedstat")).ok()?;
        total = total.saturating_add(stat.split_whitespace().next()?.parse().ok()?);
    }
    Some(total)
}

/// Bakes `scene` into the store at `options.output`, after the preflight against this
/// machine's limits ([`crate::preflight::Limits::of_machine`]).
pub fn bake(scene: &Scene, options: &BakeOptions) -> Result<BakeReport> {
    let limits = crate::preflight::Limits::of_machine(&options.output);
    bake_shard(scene, options, None, &limits)
}

/// Bakes shard `shard` of `scene`'s store into a shard file at `options.output`: the sample
/// points and maps as [`bake`] computes them, and the cubes `i` with `i % count == index`
/// ([`oslf_format::shard`]); `oslf store merge` joins the shards into the store [`bake`]
/// writes. `None`: the whole store, as [`bake`]. `resume` and `cube_limit` work as there.
/// Before any slow work the bake's estimate ([`crate::preflight`], of this shard's share) is
/// checked against `limits`.
pub fn bake_shard(
    scene: &Scene,
    options: &BakeOptions,
    shard: Option<ShardSpec>,
    limits: &crate::preflight::Limits,
) -> Result<BakeReport> {
    let start = Instant::now();
    let bake_cpu_start = process_cpu_ns();
    let cpu_since_start = || {
        process_cpu_ns()
            .zip(bake_cpu_start)
            .map(|(b, a)| b.saturating_sub(a) as f64 / 1e9)
    };
    // Fail now, not after the sample maps, if the store cannot be written.
    check_store_writable(&options.output)?;
    // Preflight: refuse what cannot fit this machine, naming the setting to change.
    let estimate = crate::preflight::estimate(scene, rayon::current_num_threads());
    let estimate = match shard {
        Some(s) => estimate.for_shard(s.count()),
        None => estimate,
    };
    crate::preflight::check(&estimate, limits)?;
    let settings = &scene.bake;
    let mut report = BakeReport {
        output: options.output.clone(),
        cube_resolution: settings.cube_resolution,
        samples_per_texel: strata_per_side(settings.samples_per_texel).pow(2),
        ..Default::default()
    };

    let geometry =
        TriangleScene::build(scene.instances(true, settings.epsilon * TESSELLATION_ERROR))?;
    report.triangles = geometry.triangle_count();
    report.bvh_build_seconds = geometry.build_time().as_secs_f64();

    let t = Instant::now();
    let surfaces = Surfaces::new(&scene.objects, settings)?;
    report.atlases = atlas_reports(scene, &surfaces);
    let placement = sample_points::place(&surfaces, settings, &geometry)?;
    report.placement_seconds = t.elapsed().as_secs_f64();
    report.points_placed = placement.placed;
    report.points_removed_close = placement.removed_close;
    report.points_removed_inside = placement.removed_inside;
    let points = placement.points;

    let t = Instant::now();
    let domains = surfaces.maps();
    let map_rows = domains.len() as u64 * u64::from(settings.sample_map_resolution);
    let build_maps = |points: &[SamplePoint]| {
        // One bar per build (refinement rebuilds the maps with the added points).
        let bar = progress_bar(options.progress, map_rows, "sample-map rows");
        let built = sample_map::build(
            &domains,
            points,
            &geometry,
            settings.sample_map_resolution,
            settings.phi_samplemap_deg,
            settings.epsilon,
            &bar,
        );
        bar.finish_and_clear();
        built
    };
    let mut points = points;
    let (mut maps, mut map_stats) = build_maps(&points);
    // §6.3: add points where texels found fewer than four, at halving spacings.
    let mut min_distance = placement.radius;
    let mut rays = map_stats.rays;
    for _ in 0..sample_points::REFINE_ROUNDS {
        let short = sample_map::short_texels(&maps, &domains);
        if short.is_empty() {
            break;
        }
        let budget = report.points_placed.saturating_sub(report.points_added);
        let added = sample_points::refine(
            &mut points,
            &short,
            &domains,
            settings.sample_map_resolution,
            settings.epsilon,
            min_distance,
            budget,
            &geometry,
        );
        if added == 0 {
            break;
        }
        report.points_added += added;
        // Free the old maps first: at 4096² one patch's map is 256 MiB.
        maps.indices = Vec::new();
        (maps, map_stats) = build_maps(&points);
        rays += map_stats.rays;
        min_distance *= 0.5;
    }
    map_stats.rays = rays;
    report.sample_points = points.len();
    report.sample_maps = map_stats;
    report.sample_map_seconds = t.elapsed().as_secs_f64();

    let meta = store_meta(scene, &surfaces);
    report.shard = shard.map(|s| s.to_string());
    let mut writer = Sink::open(options, shard, &meta, &points, &maps, &mut report.restarted)?;
    report.cubes_resumed = writer.done();
    report.cubes = writer.total();
    report.store_cubes = match &writer {
        Sink::Store(w) => w.total_cubes(),
        Sink::Shard(w) => w.store_cubes(),
    };

    let capture = CaptureSettings::from_bake(settings);
    let integrator = Integrator::for_scene(scene, &geometry);
    // The environment-map baseline sees the scene without the OSLF objects.
    let env_geometry = if meta.has_env_cube && !scene.shapes.is_empty() {
        Some(TriangleScene::build(scene.instances(false, 0.0))?)
    } else {
        None
    };
    let centre = object_centre(scene);

    let bar = progress_bar(options.progress, writer.total() as u64, "cube maps");
    bar.set_position(writer.done() as u64);
    let t = Instant::now();
    let cpu_start = process_cpu_ns();
    let mut rays = RayStats::default();
    let mut bytes = 0u64;
    let mut texels = 0u64;
    let stop_at = options.cube_limit.map_or(writer.total(), |limit| {
        writer.done().saturating_add(limit).min(writer.total())
    });
    let chunk = chunk_cubes(capture.resolution, capture.distance_channel);
    while writer.done() < stop_at {
        let first = writer.done() as usize;
        let end = (first + chunk).min(stop_at as usize);
        let sink = &writer;
        let encoded: Vec<_> = (first..end)
            .into_par_iter()
            .map(|k| {
                let i = sink.cube(k as u32) as usize;
                let (cube, stats) = match points.get(i) {
                    Some(p) => capture_cube(
                        &integrator,
                        Vec3::from_array(p.position),
                        i as u32,
                        &capture,
                    ),
                    // The one cube past the sample points: the environment-map baseline.
                    None => match &env_geometry {
                        Some(geometry) => {
                            let env = integrator.with_geometry(geometry);
                            capture_cube(&env, centre, i as u32, &capture)
                        }
                        None => {
                            let env = integrator.with_geometry(&EmptyScene);
                            capture_cube(&env, centre, i as u32, &capture)
                        }
                    },
                };
                let (enc, enc_stats) = oslf_format::encode_cube(&cube, &meta.bake, i as u32)?;
                // Each cube as it finishes, not each chunk: one cube of a slow bake (many
                // samples per texel, many lights) can take minutes.
                bar.inc(1);
                Ok((enc, enc_stats, stats))
            })
            .collect::<Result<Vec<_>>>()?;
        for (enc, enc_stats, stats) in encoded {
            rays.closest += stats.closest;
            rays.shadow += stats.shadow;
            report.clamped_texels += enc_stats.clamped_texels;
            bytes += enc_stats.compressed_bytes;
            texels += 6 * (capture.resolution as u64).pow(2);
            writer.append(enc)?;
        }
    }
    bar.finish_and_clear();
    report.capture_seconds = t.elapsed().as_secs_f64();
    report.capture_cpu_seconds = process_cpu_ns()
        .zip(cpu_start)
        .map(|(b, a)| b.saturating_sub(a) as f64 / 1e9);
    report.rays_closest = rays.closest;
    report.rays_shadow = rays.shadow;
    report.mrays_per_second =
        (rays.closest + rays.shadow) as f64 / report.capture_seconds.max(1e-9) / 1e6;

    if writer.done() < writer.total() {
        // Stopped by `cube_limit`: the partial file keeps every appended cube for `resume`.
        drop(writer);
        report.total_seconds = start.elapsed().as_secs_f64();
        report.cpu_seconds = cpu_since_start();
        return Ok(report);
    }
    let res = u64::from(capture.resolution);
    let (file_size, cube_bytes, all_texels) = match writer {
        Sink::Store(w) => {
            let s = w.finish()?;
            (s.file_size, s.cube_bytes, s.texels)
        }
        Sink::Shard(w) => {
            let s = w.finish()?;
            (
                s.file_size,
                s.cube_bytes,
                u64::from(s.cubes) * 6 * res * res,
            )
        }
    };
    report.finished = true;
    report.store_bytes = file_size;
    report.bytes_per_texel = if all_texels > 0 {
        cube_bytes as f64 / all_texels as f64
    } else if texels > 0 {
        bytes as f64 / texels as f64
    } else {
        0.0
    };
    report.total_seconds = start.elapsed().as_secs_f64();
    report.cpu_seconds = cpu_since_start();
    Ok(report)
}

/// Checks, without changing any file, that `path` can be written: its directory exists and
/// accepts a new file (a probe file is created there and removed at once), or, if `path`
/// exists, it is a file that opens for writing. `what` names the file in the error
/// ([`BakeError::Unwritable`]). Run it for every output before slow work.
pub fn check_writable(path: &Path, what: &'static str) -> Result<()> {
    check_file_writable(path, path, what)
}

/// [`check_writable`] for the store `output`, which is written through `<output>.partial`
/// and renamed: the partial file must be writable. [`bake`] runs it first.
pub fn check_store_writable(output: &Path) -> Result<()> {
    check_file_writable(output, &partial_path(output), "the store")
}

/// [`check_writable`] for `file`, naming `named` in the error (the store is written through
/// its partial file).
fn check_file_writable(named: &Path, file: &Path, what: &'static str) -> Result<()> {
    let fail = |detail: String| BakeError::Unwritable {
        what,
        path: named.to_path_buf(),
        detail,
    };
    let dir = match file.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    match std::fs::metadata(dir) {
        Ok(m) if m.is_dir() => {}
        Ok(_) => return Err(fail(format!("{} is not a directory", dir.display()))),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
            return Err(fail(format!(
                "the directory {} does not exist",
                dir.display()
            )))
        }
        Err(e) => return Err(fail(format!("{}: {e}", dir.display()))),
    }
    if named.is_dir() {
        return Err(fail("it is a directory".into()));
    }
    if file.exists() {
        // Opening for writing without truncating changes nothing.
        return match std::fs::OpenOptions::new().write(true).open(file) {
            Ok(_) => Ok(()),
            Err(e) => Err(fail(format!("{}: {e}", file.display()))),
        };
    }
    let mut name = std::ffi::OsString::from(".");
    name.push(file.file_name().unwrap_or_default());
    name.push(format!(".{}.probe", std::process::id()));
    let probe = dir.join(name);
    match std::fs::OpenOptions::new()
        .write(true)
        .create_new(true)
        .open(&probe)
    {
        Ok(_) => {
            let _ = std::fs::remove_file(&probe);
            Ok(())
        }
        Err(e) => Err(fail(format!(
            "cannot create a file in {}: {e}",
            dir.display()
        ))),
    }
}

/// Where the writer keeps an unfinished store.
pub fn partial_path(output: &Path) -> PathBuf {
    let mut name = output.as_os_str().to_os_string();
    name.push(".partial");
    PathBuf::from(name)
}

/// The atlases of `scene`'s mesh objects, for the report.
fn atlas_reports(scene: &Scene, surfaces: &Surfaces) -> Vec<AtlasReport> {
    let name = |s: UvSource| match s {
        UvSource::Lightmap => "lightmap",
        UvSource::Texture => "texture",
        UvSource::Charts => "charts",
    };
    scene
        .objects
        .iter()
        .enumerate()
        .filter_map(|(i, o)| {
            let atlas = surfaces.atlas(i)?;
            Some(AtlasReport {
                object: o.name.clone(),
                grid: atlas.grid,
                page_resolution: atlas.page_resolution,
                source: name(atlas.source),
                rejected: atlas
                    .rejected
                    .iter()
                    .map(|(s, why)| format!("{}: {why}", name(*s)))
                    .collect(),
            })
        })
        .collect()
}

/// Everything the store says about the scene and the bake, besides the points, maps and cubes.
/// A mesh object is stored in world space (identity transform) with its atlas's vertices.
pub fn store_meta(scene: &Scene, surfaces: &Surfaces) -> StoreMeta {
    let s = &scene.bake;
    let mut objects = Vec::new();
    let mut patches = Vec::new();
    for (i, o) in scene.objects.iter().enumerate() {
        let (transform, patch_count, mesh) = match surfaces.atlas(i) {
            None => (o.transform, o.object_patches.len() as u32, None),
            Some(atlas) => {
                let m = &atlas.mesh;
                let mesh = MeshInfo {
                    atlas_grid: atlas.grid,
                    positions: m.positions.iter().map(|p| p.to_array()).collect(),
                    normals: m.normals.iter().map(|n| n.to_array()).collect(),
                    uvs: m.uvs.iter().map(|uv| uv.to_array()).collect(),
                    triangles: m.triangles.clone(),
                };
                (Affine3A::IDENTITY, atlas.grid * atlas.grid, Some(mesh))
            }
        };
        objects.push(ObjectInfo {
            name: o.name.clone(),
            transform: Mat4::from(transform).to_cols_array_2d(),
            base_color: o.base_color.to_array(),
            first_patch: surfaces.first_map(i),
            patch_count,
            mesh,
        });
        patches.extend(o.object_patches.iter().map(|p| Patch {
            control_points: p.cp.map(|c| c.to_array()),
        }));
    }
    StoreMeta {
        objects,
        patches,
        bake: BakeParams {
            epsilon: s.epsilon,
            phi_samplemap_deg: s.phi_samplemap_deg,
            cube_resolution: s.cube_resolution,
            sample_map_resolution: s.sample_map_resolution,
            samples_per_texel: strata_per_side(s.samples_per_texel).pow(2),
            bounces: s.bounces,
            seed: s.seed,
            encoding: s.encoding,
            distance_channel: s.distance_channel,
            zstd_level: s.zstd_level,
            scene_hash: scene.hash,
            mantissa_bits: s.mantissa_bits,
        },
        camera: scene.camera.as_ref().map(|c| CameraInfo {
            position: c.position.to_array(),
            target: c.target.to_array(),
            up: c.up.to_array(),
            vfov_deg: c.vfov_deg,
        }),
        has_env_cube: s.env_cube,
    }
}

/// Centre of the bounding box of all OSLF patches' control points and mesh vertices (world
/// space).
pub fn object_centre(scene: &Scene) -> Vec3 {
    let mut lo = Vec3::splat(f32::MAX);
    let mut hi = Vec3::splat(f32::MIN);
    for c in scene.objects.iter().flat_map(|o| o.points()) {
        lo = lo.min(c);
        hi = hi.max(c);
    }
    (lo + hi) * 0.5
}

/// A progress bar with ETA on stderr (hidden when not `enabled`), counting `what`.
pub(crate) fn progress_bar(enabled: bool, total: u64, what: &str) -> indicatif::ProgressBar {
    if !enabled {
        return indicatif::ProgressBar::hidden();
    }
    let bar = indicatif::ProgressBar::new(total);
    bar.set_style(
        indicatif::ProgressStyle::with_template(
            &format!("{{spinner}} {what} {{bar:40}} {{pos}}/{{len}} [{{elapsed_precise}} < ETA {{eta_precise}}] {{per_sec}}"),
        )
        .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
    );
    bar.enable_steady_tick(Duration::from_millis(200));
    bar
}
