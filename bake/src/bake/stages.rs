//! The stages of the bake pipeline, in the order [`crate::bake::bake_shard`] runs them: prepare,
//! place, build maps, capture, write. Each fills in its part of the [`BakeReport`].

use std::path::Path;
use std::sync::Arc;
use std::time::Instant;

use glam::Vec3;
use oslf_format::{CubeImage, SampleMaps, SamplePoint, ShardSpec, StoreMeta};
use rayon::prelude::*;

use super::meta::object_centre;
use super::report::{atlas_reports, normals_reports, BakeReport};
use super::sink::Sink;
use super::writable::check_store_writable;
use crate::coverage::{self, SurfaceNames};
use crate::device::{CaptureDevice, CapturedCube, CubeJob};
use crate::preflight::{self, Limits};
use crate::sample_map;
use crate::sample_points::{self, Placement, Surfaces};
use oslf_scene::error::Result;
use oslf_scene::scene::{BakeSettings, Scene};
use oslf_scene::tolerance::TESSELLATION_ERROR;
use oslf_trace::bvh::TriangleScene;
use oslf_trace::capture::{capture_cube, capture_cube_with_noise, chunk_cubes, CaptureSettings};
use oslf_trace::integrator::{Integrator, RayStats};
use oslf_trace::noise::NoiseStats;
use oslf_trace::progress::Progress;
use oslf_trace::ray::EmptyScene;

/// Prepare: fails now, not after the sample maps, if the store at `output` cannot be
/// written; refuses (the preflight) what cannot fit `limits`, naming the setting to change;
/// then builds the ray-tracing geometry: every triangle of the scene, the OSLF objects
/// tessellated within ε × [`TESSELLATION_ERROR`], and the names of its triangles (for the
/// coverage report, [`crate::coverage`]).
pub(super) fn prepare(
    scene: &Scene,
    output: &Path,
    shard: Option<ShardSpec>,
    limits: &Limits,
    device: Option<&Arc<dyn CaptureDevice>>,
    report: &mut BakeReport,
) -> Result<(TriangleScene, SurfaceNames)> {
    check_store_writable(output)?;
    let estimate = preflight::estimate(scene, rayon::current_num_threads());
    let capture = CaptureSettings::from_bake(&scene.bake);
    let estimate = preflight::for_device(estimate, device.map(|d| &**d), &capture);
    let estimate = match shard {
        Some(s) => estimate.for_shard(s.count()),
        None => estimate,
    };
    preflight::check(&estimate, limits)?;
    let settings = &scene.bake;
    let instances =
        oslf_trace::bvh::scene_instances(scene, true, settings.epsilon * TESSELLATION_ERROR);
    let names = SurfaceNames::of(&instances);
    let geometry = TriangleScene::build(instances)?;
    report.triangles = geometry.triangle_count();
    report.bvh_build_seconds = geometry.build_time().as_secs_f64();
    Ok((geometry, names))
}

/// Place: the sample-map domains of the OSLF objects (with the atlases of mesh objects) and
/// the sample points placed over them.
pub(super) fn place<'s>(
    scene: &'s Scene,
    geometry: &TriangleScene,
    report: &mut BakeReport,
) -> Result<(Surfaces<'s>, Placement)> {
    let t = Instant::now();
    let settings = &scene.bake;
    let surfaces = Surfaces::new(&scene.objects, settings)?;
    report.atlases = atlas_reports(scene, &surfaces);
    report.normals = normals_reports(scene);
    let placement = sample_points::place_in(scene, &surfaces, geometry)?;
    report.placement_seconds = t.elapsed().as_secs_f64();
    report.pilot_cubes = placement.pilot_cubes;
    report.points_placed = placement.placed;
    report.points_removed_close = placement.removed_close;
    report.points_removed_inside = placement.removed_inside;
    report.points_lowered = placement.lowered;
    Ok((surfaces, placement))
}

/// Build maps: the sample maps of `placement`'s points; then (§6.3) points added where
/// texels found fewer than four, at halving spacings, and the maps rebuilt, for at most
/// [`sample_points::REFINE_ROUNDS`] rounds. Returns every point and the last maps; the
/// report says per object where and why texels are still short ([`coverage::diagnose`]).
pub(super) fn build_maps(
    settings: &BakeSettings,
    surfaces: &Surfaces,
    placement: Placement,
    geometry: &TriangleScene,
    names: &SurfaceNames,
    progress: &dyn Progress,
    report: &mut BakeReport,
) -> (Vec<SamplePoint>, SampleMaps) {
    let t = Instant::now();
    let domains = surfaces.maps();
    let map_rows = domains.len() as u64 * u64::from(settings.sample_map_resolution);
    let build = |points: &[SamplePoint]| {
        // One stage per build (refinement rebuilds the maps with the added points).
        progress.start("sample-map rows", map_rows, 0);
        let built = sample_map::build(
            &domains,
            points,
            geometry,
            settings.sample_map_resolution,
            settings.phi_samplemap_deg,
            settings.epsilon,
            progress,
        );
        progress.finish();
        built
    };
    let object_sizes: Vec<f32> = surfaces
        .objects()
        .iter()
        .map(oslf_scene::bake_defaults::object_size)
        .collect();
    let mut points = placement.points;
    let (mut maps, mut map_stats) = build(&points);
    let mut min_distance = placement.radius;
    let mut rays = map_stats.rays;
    for _ in 0..sample_points::REFINE_ROUNDS {
        let short = sample_map::short_texels(&maps, &domains);
        if short.is_empty() {
            break;
        }
        let budget = report.points_placed.saturating_sub(report.points_added);
        let (added, lowered) = sample_points::refine(
            &mut points,
            &short,
            &domains,
            settings.sample_map_resolution,
            settings.epsilon,
            settings.near_surface,
            min_distance,
            budget,
            &object_sizes,
            geometry,
        );
        if added == 0 {
            break;
        }
        report.points_added += added;
        report.points_lowered += lowered;
        // Free the old maps first: at 4096² one patch's map is 256 MiB.
        maps.indices = Vec::new();
        (maps, map_stats) = build(&points);
        rays += map_stats.rays;
        min_distance *= 0.5;
    }
    map_stats.rays = rays;
    let object_names: Vec<String> = surfaces.objects().iter().map(|o| o.name.clone()).collect();
    let probe = coverage::Probe {
        geometry,
        names,
        epsilon: settings.epsilon,
        phi_samplemap_deg: settings.phi_samplemap_deg,
        object_sizes: &object_sizes,
    };
    report.coverage = coverage::diagnose(&maps, &domains, &points, &object_names, &probe);
    report.sample_points = points.len();
    report.sample_maps = map_stats;
    report.sample_map_seconds = t.elapsed().as_secs_f64();
    (points, maps)
}

/// What the capture appended: compressed bytes and texels of this run's cubes, and the noise
/// of this run's sample-point cubes ([`oslf_trace::noise`]).
#[derive(Clone, Debug, Default)]
pub(super) struct Captured {
    bytes: u64,
    pub(super) texels: u64,
    pub(super) noise: NoiseStats,
}

/// Capture: a cube map at each of `points` that `sink` still lacks (and, past the points,
/// the environment-map baseline's cube at the objects' centre, which sees the scene without
/// them), captured `chunk_cubes` at a time in parallel, encoded and appended in order; at
/// most `cube_limit` cubes in this run.
#[allow(clippy::too_many_arguments)]
pub(super) fn capture(
    scene: &Scene,
    geometry: &TriangleScene,
    meta: &StoreMeta,
    points: &[SamplePoint],
    sink: &mut Sink,
    cube_limit: Option<u32>,
    device: Option<&Arc<dyn CaptureDevice>>,
    progress: &dyn Progress,
    report: &mut BakeReport,
) -> Result<Captured> {
    report.capture_device = match device {
        Some(d) => d.describe(),
        None => format!("CPU ({} threads)", rayon::current_num_threads()),
    };
    report.cubes_resumed = sink.done();
    report.cubes = sink.total();
    report.store_cubes = sink.store_cubes();

    let capture = CaptureSettings::from_bake(&scene.bake);
    let integrator = Integrator::for_scene(scene, geometry);
    // The environment-map baseline sees the scene without the OSLF objects.
    let env_geometry = if device.is_none() && meta.has_env_cube && !scene.shapes.is_empty() {
        Some(TriangleScene::build(oslf_trace::bvh::scene_instances(
            scene, false, 0.0,
        ))?)
    } else {
        None
    };
    let centre = object_centre(scene);

    progress.start("cube maps", sink.total() as u64, sink.done() as u64);
    let t = Instant::now();
    let cpu_start = process_cpu_ns();
    let mut rays = RayStats::default();
    let mut captured = Captured::default();
    let stop_at = cube_limit.map_or(sink.total(), |limit| {
        sink.done().saturating_add(limit).min(sink.total())
    });
    let chunk = match &device {
        Some(d) => d.batch_cubes(&capture).max(1),
        None => chunk_cubes(&capture),
    };
    let encode = |i: u32, (cube, stats, noise): CapturedCube| {
        let (enc, enc_stats) = oslf_format::encode_cube(&cube, &meta.bake, i)?;
        // Each cube as it finishes, not each chunk: one cube of a slow bake (many samples
        // per texel, many lights) can take minutes.
        progress.advance(1);
        Ok((enc, enc_stats, stats, noise))
    };
    let mut append = |sink: &mut Sink, encoded: Vec<EncodedCube>| -> Result<()> {
        for (enc, enc_stats, stats, noise) in encoded {
            captured.noise.merge(&noise);
            rays.add(&stats);
            report.clamped_texels += enc_stats.clamped_texels;
            captured.bytes += enc_stats.compressed_bytes;
            captured.texels += 6 * (capture.resolution as u64).pow(2);
            sink.append(enc)?;
        }
        Ok(())
    };
    let batches: Vec<std::ops::Range<usize>> = (sink.done() as usize..stop_at as usize)
        .step_by(chunk)
        .map(|first| first..(first + chunk).min(stop_at as usize))
        .collect();
    match device {
        Some(d) => {
            let jobs: Vec<Vec<CubeJob>> = batches
                .into_iter()
                .map(|range| device_jobs(sink, range, points, centre))
                .collect();
            capture_on_device(d.as_ref(), &jobs, &capture, sink, &encode, &mut append)?;
        }
        None => {
            let cpu = CpuCapture {
                integrator: &integrator,
                env_geometry: env_geometry.as_ref(),
                points,
                centre,
                capture: &capture,
            };
            for range in batches {
                let order = &*sink;
                let encoded = range
                    .into_par_iter()
                    .map(|k| {
                        let i = order.cube(k as u32);
                        encode(i, cpu.cube(i))
                    })
                    .collect::<Result<Vec<_>>>()?;
                append(sink, encoded)?;
            }
        }
    }
    progress.finish();
    report.capture_seconds = t.elapsed().as_secs_f64();
    report.capture_cpu_seconds = process_cpu_ns()
        .zip(cpu_start)
        .map(|(b, a)| b.saturating_sub(a) as f64 / 1e9);
    report.rays_closest = rays.closest;
    report.rays_shadow = rays.shadow;
    report.traversal_nodes = rays.nodes;
    report.traversal_triangles = rays.triangles;
    report.mrays_per_second =
        (rays.closest + rays.shadow) as f64 / report.capture_seconds.max(1e-9) / 1e6;
    Ok(captured)
}

/// The CPU's capture of one cube of the store's order.
struct CpuCapture<'a> {
    integrator: &'a Integrator<'a, TriangleScene>,
    /// The scene without the objects, which the environment-map baseline's cube sees.
    env_geometry: Option<&'a TriangleScene>,
    points: &'a [SamplePoint],
    centre: Vec3,
    capture: &'a CaptureSettings,
}

impl CpuCapture<'_> {
    /// Cube `i`: a sample point's, or past them the environment-map baseline's.
    fn cube(&self, i: u32) -> CapturedCube {
        match self.points.get(i as usize) {
            Some(p) => capture_cube_with_noise(
                self.integrator,
                Vec3::from_array(p.position),
                i,
                self.capture,
            ),
            None => match self.env_geometry {
                Some(geometry) => {
                    let env = self.integrator.with_geometry(geometry);
                    with_no_noise(capture_cube(&env, self.centre, i, self.capture))
                }
                None => {
                    let env = self.integrator.with_geometry(&EmptyScene);
                    with_no_noise(capture_cube(&env, self.centre, i, self.capture))
                }
            },
        }
    }
}

/// The batches of `jobs` captured on `device`, encoded and appended in order: the device
/// captures batch k + 1 while the CPU encodes batch k, so neither waits for the other.
fn capture_on_device(
    device: &dyn CaptureDevice,
    jobs: &[Vec<CubeJob>],
    capture: &CaptureSettings,
    sink: &mut Sink,
    encode: &(dyn Fn(u32, CapturedCube) -> Result<EncodedCube> + Sync),
    append: &mut dyn FnMut(&mut Sink, Vec<EncodedCube>) -> Result<()>,
) -> Result<()> {
    let mut pending: Option<(&[CubeJob], Vec<CapturedCube>)> = None;
    for k in 0..=jobs.len() {
        let (next, encoded) = std::thread::scope(|s| {
            let next = jobs.get(k).map(|batch| {
                (
                    batch.as_slice(),
                    s.spawn(|| device_capture(device, batch, capture)),
                )
            });
            let encoded = pending.take().map(|(batch, cubes)| {
                batch
                    .par_iter()
                    .zip(cubes)
                    .map(|(job, cube)| encode(job.index, cube))
                    .collect::<Result<Vec<_>>>()
            });
            let next = next.map(|(batch, handle)| {
                let cubes = handle.join().unwrap_or_else(|_| {
                    Err(oslf_scene::BakeError::Device {
                        device: device.describe(),
                        message: "the capture thread panicked".into(),
                    })
                });
                cubes.map(|cubes| (batch, cubes))
            });
            (next, encoded)
        });
        // The finished batch is kept before an error of the next one is reported: `--resume`
        // continues after it.
        if let Some(encoded) = encoded {
            append(sink, encoded?)?;
        }
        pending = next.transpose()?;
    }
    Ok(())
}

/// A cube encoded for the store, with the statistics the report sums.
type EncodedCube = (
    oslf_format::EncodedCube,
    oslf_format::EncodeStats,
    RayStats,
    NoiseStats,
);

/// `device`'s capture of `jobs`, checked to return one cube per job.
fn device_capture(
    device: &dyn CaptureDevice,
    jobs: &[CubeJob],
    capture: &CaptureSettings,
) -> Result<Vec<CapturedCube>> {
    let cubes = device.capture(jobs, capture)?;
    if cubes.len() != jobs.len() {
        return Err(oslf_scene::BakeError::Device {
            device: device.describe(),
            message: format!("{} cubes returned for {}", cubes.len(), jobs.len()),
        });
    }
    Ok(cubes)
}

/// The cubes `range` of `sink`'s order as jobs for a capture device: sample points, and past
/// them the environment-map baseline's cube at `centre`, which sees the scene without the
/// objects.
fn device_jobs(
    sink: &Sink,
    range: std::ops::Range<usize>,
    points: &[SamplePoint],
    centre: Vec3,
) -> Vec<CubeJob> {
    range
        .map(|k| {
            let index = sink.cube(k as u32);
            match points.get(index as usize) {
                Some(p) => CubeJob {
                    origin: Vec3::from_array(p.position),
                    index,
                    sees_objects: true,
                },
                None => CubeJob {
                    origin: centre,
                    index,
                    sees_objects: false,
                },
            }
        })
        .collect()
}

/// A capture without a noise estimate: the environment-map baseline's cube is no sample
/// point's and does not count towards the noise of the store's cubes.
fn with_no_noise((cube, stats): (CubeImage, RayStats)) -> (CubeImage, RayStats, NoiseStats) {
    (cube, stats, NoiseStats::default())
}

/// Write: finishes the store or shard (every cube in) and reports its size and compressed
/// bytes per texel.
pub(super) fn write(sink: Sink, captured: &Captured, report: &mut BakeReport) -> Result<()> {
    let res = u64::from(report.cube_resolution);
    let (file_size, cube_bytes, all_texels) = match sink {
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
    } else if captured.texels > 0 {
        captured.bytes as f64 / captured.texels as f64
    } else {
        0.0
    };
    Ok(())
}

/// CPU nanoseconds run so far by the process's live threads (Linux `schedstat`), if known.
/// The worker pool's threads live for the whole bake, so differences cover them all.
pub(super) fn process_cpu_ns() -> Option<u64> {
    let mut total = 0u64;
    for task in std::fs::read_dir("/proc/self/task").ok()? {
        let stat = std::fs::read_to_string(task.ok()?.path().join("schedstat")).ok()?;
        total = total.saturating_add(stat.split_whitespace().next()?.parse().ok()?);
    }
    Some(total)
}
