//! The bake pipeline: scene → BVH → sample points → sample maps → cube maps → store.

//!
//! Its stages, each a function of `stages` with its inputs and outputs: **prepare** (the
//! output is writable, the preflight passes, the ray-tracing geometry is built), **place**
//! (the sample-map domains and the sample points), **build maps** (the sample maps, with the
//! points added where texels found fewer than four), **capture** (a cube map at each point,
//! encoded and appended in order) and **write** (the store or shard finished). [`bake_shard`]
//! runs them in that order.

mod meta;
mod noise_report;
mod report;
mod sink;
mod stages;
mod textures;
mod writable;

use std::path::PathBuf;
use std::sync::Arc;
use std::time::Instant;

use oslf_format::ShardSpec;

use crate::coverage::{Cause, ObjectCoverage};
use crate::preflight::Limits;
pub use meta::{object_centre, store_meta};
pub use noise_report::{NoiseReport, NoiseSuggestion};
use oslf_scene::error::{BakeError, Result};
use oslf_scene::scene::Scene;
use oslf_trace::capture::strata_per_side;
use oslf_trace::progress::{self, Progress};
pub use report::{AtlasReport, BakeReport, NormalsReport};
use sink::Sink;
use stages::process_cpu_ns;
pub use writable::{check_store_writable, check_writable};

/// How to run a bake.
#[derive(Clone, Debug)]
pub struct BakeOptions {
    /// The store to write.
    pub output: PathBuf,
    /// Continue from `<output>.partial` if it exists (and matches this scene and settings).
    pub resume: bool,
    /// Where to report the progress of the sample-map and cube-map stages (`None`: nowhere).
    pub progress: Option<Arc<dyn Progress>>,
    /// Capture at most this many cube maps in this run, then stop and leave `<output>.partial`
    /// for a later `resume` (a bake in slices). `None`: run to the end.
    pub cube_limit: Option<u32>,
    /// Fail with [`BakeError::EmptyTexels`] before the cube maps are captured if a sample-map
    /// texel that a view may reach has no visible sample point at all (the runtime has nothing
    /// to reconstruct it from; [`BakeReport::visible_empty`]). `false`: bake anyway; the
    /// report counts them.
    pub refuse_empty_texels: bool,
    /// What captures the cube maps: `None`, this crate's CPU path tracer
    /// ([`oslf_trace::capture`]); else another device for this scene (the GPU,
    /// `oslf-bake-gpu`), given the cubes in batches of its size.
    pub device: Option<Arc<dyn crate::device::CaptureDevice>>,
}

/// The largest place of each object's empty texels, for [`BakeError::EmptyTexels`]:
/// `; where: object "box": 3496 texels facing down (−z) at …` (empty without any).
fn empty_places(coverage: &[ObjectCoverage]) -> String {
    let places: Vec<String> = coverage
        .iter()
        .filter_map(|c| {
            let p = c
                .places
                .iter()
                .find(|p| p.empty > 0 && p.cause != Cause::Unseen)?;
            Some(format!("object {:?}: {}", c.object, p.describe(c.decimals)))
        })
        .collect();
    if places.is_empty() {
        String::new()
    } else {
        format!("; where: {}", places.join("; "))
    }
}

/// Bakes `scene` into the store at `options.output`, after the preflight against this
/// machine's limits ([`Limits::of_machine`]).
pub fn bake(scene: &Scene, options: &BakeOptions) -> Result<BakeReport> {
    let limits = Limits::of_machine(&options.output);
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
    limits: &Limits,
) -> Result<BakeReport> {
    let start = Instant::now();
    let bake_cpu_start = process_cpu_ns();
    let settings = &scene.bake;
    let progress = progress::or_silent(&options.progress);
    let mut report = BakeReport {
        output: options.output.clone(),
        epsilon: settings.epsilon,
        chosen: scene.bake_choices.iter().map(ToString::to_string).collect(),
        cube_resolution: settings.cube_resolution,
        samples_per_texel: strata_per_side(settings.samples_per_texel).pow(2),
        shard: shard.map(|s| s.to_string()),
        ..Default::default()
    };
    let (geometry, names) = stages::prepare(
        scene,
        &options.output,
        shard,
        limits,
        options.device.as_ref(),
        &mut report,
    )?;
    let (surfaces, placement) = stages::place(scene, &geometry, &mut report)?;
    let (points, maps) = stages::build_maps(
        settings,
        &surfaces,
        placement,
        &geometry,
        &names,
        progress,
        &mut report,
    );
    let stats = report.sample_maps;
    if options.refuse_empty_texels && report.visible_empty() > 0 {
        return Err(BakeError::EmptyTexels {
            empty: report.visible_empty(),
            texels: stats.texels,
            points: report.sample_points as u64,
            where_: empty_places(&report.coverage),
        });
    }
    let meta = store_meta(scene, &surfaces);
    let mut sink = Sink::open(
        &options.output,
        options.resume,
        shard,
        &meta,
        &points,
        &maps,
        &mut report.restarted,
    )?;
    let written = stages::capture(
        scene,
        &geometry,
        &meta,
        &points,
        &mut sink,
        options.cube_limit,
        options.device.as_ref(),
        progress,
        &mut report,
    )?;
    if written.texels > 0 {
        let estimate = crate::preflight::estimate(scene, rayon::current_num_threads());
        let capture = oslf_trace::capture::CaptureSettings::from_bake(&scene.bake);
        let estimate = crate::preflight::for_device(estimate, options.device.as_deref(), &capture);
        let estimate = match shard {
            Some(s) => estimate.for_shard(s.count()),
            None => estimate,
        };
        report.noise = Some(noise_report::noise_report(
            &written.noise,
            &capture,
            &estimate,
        ));
    }
    if sink.done() < sink.total() {
        // Stopped by `cube_limit`: the partial file keeps every appended cube for `resume`.
        drop(sink);
    } else {
        stages::write(sink, &written, &mut report)?;
    }
    report.total_seconds = start.elapsed().as_secs_f64();
    report.cpu_seconds = process_cpu_ns()
        .zip(bake_cpu_start)
        .map(|(b, a)| b.saturating_sub(a) as f64 / 1e9);
    Ok(report)
}
