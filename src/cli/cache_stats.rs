//! `oslf cache-stats`: replays renders of a store (a still view and an orbit) for lists of
//! modes, blends, cache granularities and GPU cache sizes, and reports the cache's requests,
//! hits, misses, miss rate, loads, evictions, bytes decoded and times per phase, as an aligned
//! table (thesis Tables 6.3–6.7) and as CSV and JSON. See `oslf_measure::replay`.

use super::paths::{InputPath, OutputPath};
use std::time::Instant;

use super::args::{CameraArgs, ShadingArgs};
use anyhow::bail;
use oslf_format::Store;
use oslf_measure::replay::{
    self, CacheSize, CameraPath, PathKind, ReplayInfo, ReplayParam, ReplayPlan, Row, Shading,
};
use oslf_runtime::cache;
use oslf_runtime::{Blend, CacheConfig, Camera, Gpu, Granularity, Mode, RenderOptions, Renderer};

/// Replay renders of an OSLF store through the LRU cube-map cache and report its statistics,
/// per mode, blend, granularity and cache size, for a still view and an orbiting camera (the
/// thesis's Tables 6.3–6.7, plus the orbit's cold start and steady state).
///
/// Every (mode, blend, granularity, size, path) gets a fresh renderer, so its cache starts
/// empty; the paths are the same for all. The still path shows the store's camera (or
/// --camera-*) for --still-frames frames; the orbit starts there and turns --orbit-degrees
/// about the vertical axis through the target in --frames equal steps.
///
/// A request is one unit a frame's shading needs, counted once per frame however many pixels
/// read it: a cube map with granularity cube (the thesis's "read full image": any miss loads
/// all six faces), a face with granularity face (only the faces read are loaded). The pinned
/// environment cube counts every frame (1 cube or 6 faces) and always hits. A hit is a
/// requested unit resident on the GPU when the frame is first shaded, a miss one that is not
/// (misses = requests − hits). By default misses are resolved: the renderer loads them and
/// shades again (loads count those, not requests); --streaming renders as the viewer does
/// instead: misses fall back this frame and are decoded in the background.
///
/// Phases: cold = the first frame (empty cache); steady = a still view's frames after the
/// first, an orbit's frames at 360° and more (the second revolution onwards) or, for an orbit
/// shorter than that, its last half; all = every frame of the orbit.
///
/// The GPU budget is in cube-map slots for both granularities: a slot holds one cube's faces,
/// and with face granularity only the faces read are loaded into it (fewer bytes decoded and
/// uploaded, not more cubes held). When a needed face is missing, reconstruction falls back
/// to another candidate and marks what it reads too, so a budget short of the working set
/// can add a few requests.
///
/// Columns: unit = granularity; slots = GPU cache size in cube maps (as asked); over = needed
/// units the budget could not hold after the frame's last pass; MB decoded = texel bytes
/// decompressed from the store (faces found in the RAM level, --ram-mb, are not decoded
/// again); decode ms = wall time decoding, summed over the phase; frame ms = mean wall time of
/// a frame, all passes, to GPU completion. Before each path one frame looking away from the
/// object compiles the mode's pipeline; it is not counted.
#[derive(clap::Args, Debug)]
#[command(allow_negative_numbers = true)]
pub struct Args {
    /// The store (written by `oslf bake`).
    store: InputPath,
    #[command(flatten)]
    access: super::args::StoreAccessArgs,
    /// Modes, comma-separated: recon, mirror, recon-mirror, glossy, recon-glossy.
    #[arg(long, value_delimiter = ',', default_value = "recon,mirror,glossy")]
    modes: Vec<Mode>,
    /// Blends, comma-separated (distance, angle, avg, r, n); recon does not blend and runs once.
    #[arg(long = "blend", value_delimiter = ',', default_value = "n")]
    blends: Vec<Blend>,
    #[command(flatten)]
    shading: ShadingArgs,
    /// GPU cache sizes, comma-separated: a number of cube-map slots, a percentage of the
    /// store's cube maps (25%), or all.
    #[arg(long, value_delimiter = ',', default_value = "10%,50%,all")]
    slots: Vec<CacheSize>,
    /// GPU cache sizes in MB of cube-map texels instead of --slots, comma-separated.
    #[arg(long, value_delimiter = ',', conflicts_with = "slots")]
    cache_mb: Vec<f64>,
    /// RAM cache budget in MB of decoded faces.
    #[arg(long, default_value_t = 256.0)]
    ram_mb: f64,
    /// Granularities, comma-separated: cube (load whole cubes) and face (load faces read).
    #[arg(long, value_delimiter = ',', default_value = "cube,face")]
    granularity: Vec<Granularity>,
    /// Paths, comma-separated: still and orbit.
    #[arg(long, value_delimiter = ',', default_value = "still,orbit")]
    paths: Vec<PathKind>,
    /// Frames of the still path.
    #[arg(long, default_value_t = 3)]
    still_frames: u32,
    /// Frames of the orbit.
    #[arg(long, default_value_t = 24)]
    frames: u32,
    /// Total angle of the orbit in degrees (720: two revolutions, the second the steady state).
    #[arg(long, default_value_t = 720.0)]
    orbit_degrees: f32,
    #[command(flatten)]
    camera: CameraArgs,
    /// Image width.
    #[arg(long, default_value_t = 655)]
    width: u32,
    /// Image height.
    #[arg(long, default_value_t = 460)]
    height: u32,
    /// Stream as the viewer does (misses fall back, decodes in the background) instead of
    /// loading the misses and shading again.
    #[arg(long)]
    streaming: bool,
    /// Also write the rows as CSV to this file.
    #[arg(long)]
    csv: Option<OutputPath>,
    /// Also write the rows and the settings as JSON to this file.
    #[arg(long)]
    json: Option<OutputPath>,
    /// No progress lines on stderr.
    #[arg(short, long)]
    quiet: bool,
    /// Do not upload BC6H stores as BC6H blocks even where the GPU has BC texture
    /// compression: decode them on the CPU and upload RGB9E5.
    #[arg(long)]
    no_bc: bool,
}

/// The store's size figures the report prints.
struct StoreInfo {
    points: usize,
    cubes: u32,
    resolution: u32,
    cube_bytes: u64,
}

pub fn run(args: Args) -> anyhow::Result<()> {
    let mut door = oslf_util::door::Door::new();
    door.input("STORE", &args.store);
    if let Some(path) = &args.csv {
        door.output("--csv", path);
    }
    if let Some(path) = &args.json {
        door.output("--json", path);
    }
    door.check()?;
    check_args(&args)?;
    let ram_bytes = cache::ram_bytes(args.ram_mb)?;
    let store = args.access.open(&args.store)?;
    args.shading.check_store(&store, &args.store)?;
    let gpu = Gpu::headless_with_bc(!args.no_bc)?;
    let budgets = budgets(&args, &store, gpu.has_bc())?;
    let shadings = shadings(&args)?;

    let adapter = gpu.adapter_name.clone();
    // The paths, from the store's camera (a renderer knows the default view).
    let probe_gpu = Gpu::from_device(gpu.device.clone(), gpu.queue.clone(), adapter.clone());
    let probe_config = CacheConfig {
        gpu_slots: Some(1),
        ram_bytes,
        granularity: Granularity::Cube,
        slots_per_texture: None,
    };
    let probe = Renderer::new(probe_gpu, store, probe_config)?;
    let start = args.camera.apply(probe.default_view())?;
    let info = StoreInfo {
        points: probe.store().sample_points().len(),
        cubes: probe.store().cube_count(),
        resolution: probe.store().cube_resolution(),
        cube_bytes: cache::cube_bytes(probe.store(), gpu.has_bc()),
    };
    drop(probe);
    let paths = camera_paths(&args, start)?;
    let plan = ReplayPlan {
        shadings: &shadings,
        granularities: &args.granularity,
        budgets: &budgets,
        paths: &paths,
        options: RenderOptions {
            width: args.width,
            height: args.height,
            resolve_misses: !args.streaming,
            read_pixels: false,
            ..Default::default()
        },
        ram_bytes,
    };
    let run_start = Instant::now();
    let open = || Ok(Store::open_with(&args.store, args.access.access())?);
    let (rows, infos) = replay::replay_all(&gpu, open, &plan, |done| {
        for e in &done.failures {
            eprintln!("warning: {e} (that sample point fell back)");
        }
        if !args.quiet {
            let i = done.info;
            eprintln!(
                "[{}/{}] {} {} {} {} {}: {} frames, {:.1}% misses, {:.2} s",
                done.index,
                done.total,
                i.mode,
                i.blend,
                i.granularity,
                i.size,
                i.path,
                done.frames,
                done.rows.last().map_or(0.0, |r| 100.0 * r.miss_rate),
                done.seconds
            );
        }
    })?;
    let elapsed = run_start.elapsed().as_secs_f64();
    let report = Report {
        args: &args,
        adapter: &adapter,
        info: &info,
        paths: &paths,
        rows: &rows,
        infos: &infos,
        ram_bytes,
        seconds: elapsed,
    };
    report.print();
    report.write_files()
}

/// The GPU cache sizes to replay, as (label, slots): `--cache-mb` buys cube maps of the pool's
/// real size (BC6H blocks where the GPU has BC), else the `--slots` list.
fn budgets(args: &Args, store: &Store, has_bc: bool) -> anyhow::Result<Vec<(String, Option<u32>)>> {
    let sizes: Vec<CacheSize> = if args.cache_mb.is_empty() {
        args.slots.clone()
    } else {
        args.cache_mb
            .iter()
            .map(|&mb| CacheSize::Megabytes(mb))
            .collect()
    };
    if sizes.is_empty() {
        bail!("--slots needs at least one size");
    }
    sizes
        .iter()
        .map(|s| Ok((s.label(), s.gpu_slots(store, has_bc)?)))
        .collect()
}

/// Rejects empty lists and out-of-range counts before any GPU work.
fn check_args(args: &Args) -> anyhow::Result<()> {
    if args.modes.is_empty() || args.blends.is_empty() || args.granularity.is_empty() {
        bail!("--modes, --blend and --granularity each need at least one value");
    }
    if args.paths.is_empty() {
        bail!("--paths needs at least one of still, orbit");
    }
    replay::check_frames(args.still_frames, ReplayParam::StillFrames)?;
    replay::check_frames(args.frames, ReplayParam::OrbitFrames)?;
    replay::check_degrees(args.orbit_degrees)?;
    if args.width == 0 || args.height == 0 {
        bail!("--width and --height must be at least 1");
    }
    Ok(())
}

/// Every (mode, blend) of `--modes` × `--blend`, validated; recon once, as it does not blend.
fn shadings(args: &Args) -> anyhow::Result<Vec<Shading>> {
    let mut shadings = Vec::new();
    for &mode in &args.modes {
        if mode == Mode::Recon {
            shadings.push((mode, None, args.shading.params(mode, args.blends[0])?));
        } else {
            for &blend in &args.blends {
                shadings.push((mode, Some(blend), args.shading.params(mode, blend)?));
            }
        }
    }
    shadings.dedup_by_key(|s| (s.0, s.1));
    Ok(shadings)
}

/// The camera paths of `--paths`, each once, from `start`.
fn camera_paths(args: &Args, start: Camera) -> anyhow::Result<Vec<CameraPath>> {
    let mut paths = Vec::new();
    for &kind in &args.paths {
        if paths.iter().any(|p: &CameraPath| p.kind == kind) {
            continue;
        }
        paths.push(match kind {
            PathKind::Still => CameraPath::still(start, args.still_frames)?,
            PathKind::Orbit => CameraPath::orbit(start, args.frames, args.orbit_degrees)?,
        });
    }
    Ok(paths)
}

/// Everything the run measured, for the printed report and the JSON file.
struct Report<'a> {
    args: &'a Args,
    adapter: &'a str,
    info: &'a StoreInfo,
    paths: &'a [CameraPath],
    rows: &'a [Row],
    infos: &'a [ReplayInfo],
    ram_bytes: u64,
    seconds: f64,
}

impl Report<'_> {
    /// The settings, the table, and what setting up the renderers cost.
    fn print(&self) {
        let (args, info) = (self.args, self.info);
        println!("adapter  {}", self.adapter);
        println!(
            "store    {}: {} sample points, {} cube maps of 6×{}² ({:.4} MB each)",
            args.store.display(),
            info.points,
            info.cubes,
            info.resolution,
            info.cube_bytes as f64 / 1e6
        );
        println!(
            "frames   {}×{}, misses {}; RAM level {} MB",
            args.width,
            args.height,
            if args.streaming {
                "streamed (the viewer's way: fall back, decode in the background)"
            } else {
                "resolved (loaded, then shaded again)"
            },
            args.ram_mb
        );
        for p in self.paths {
            match p.kind {
                PathKind::Still => println!(
                    "still    {} frames of one view; steady: {}",
                    p.cameras.len(),
                    p.steady_note
                ),
                PathKind::Orbit => println!(
                    "orbit    {} frames over {}° ({:.2}° apart); steady: {}",
                    p.cameras.len(),
                    args.orbit_degrees,
                    f64::from(args.orbit_degrees) / p.cameras.len() as f64,
                    p.steady_note
                ),
            }
        }
        println!(
            "units    requests, hits, misses, loads and over: cubes (unit cube) or faces (unit face)"
        );
        println!();
        print!("{}", oslf_measure::cache_stats::format_table(self.rows));
        println!();
        let infos = self.infos;
        println!(
            "{} renderers in {:.1} s (each: setup {:.0}–{:.0} ms, pipeline compile {:.0}–{:.0} ms, not counted above)",
            infos.len(),
            self.seconds,
            infos.iter().map(|i| i.renderer_ms).fold(f64::INFINITY, f64::min),
            infos.iter().map(|i| i.renderer_ms).fold(0.0, f64::max),
            infos.iter().map(|i| i.setup_ms).fold(f64::INFINITY, f64::min),
            infos.iter().map(|i| i.setup_ms).fold(0.0, f64::max),
        );
    }

    /// `--csv FILE` (the rows) and `--json FILE` (rows and settings), where asked for.
    fn write_files(&self) -> anyhow::Result<()> {
        if let Some(path) = &self.args.csv {
            let csv = oslf_measure::cache_stats::to_csv(self.rows);
            oslf_util::output_file::write_bytes(path, csv.as_bytes())?;
        }
        if let Some(path) = &self.args.json {
            let json = serde_json::to_string_pretty(&self.json())?;
            oslf_util::output_file::write_bytes(path, json.as_bytes())?;
        }
        Ok(())
    }

    /// The rows with every setting that produced them.
    fn json(&self) -> serde_json::Value {
        let (args, info) = (self.args, self.info);
        serde_json::json!({
            "store": args.store.0,
            "adapter": self.adapter,
            "sample_points": info.points,
            "cube_maps": info.cubes,
            "cube_resolution": info.resolution,
            "cube_bytes": info.cube_bytes,
            "width": args.width,
            "height": args.height,
            "streaming": args.streaming,
            "ram_bytes": self.ram_bytes,
            "shading": {
                "blend_n": args.shading.blend_n(),
                "source": args.shading.source().name(),
                "depth": !args.shading.no_depth,
                "glossy_filter": args.shading.glossy_filter.name(),
                "phi_shader": args.shading.phi_shader,
                "m": args.shading.m,
                "order": args.shading.order,
                "rs": args.shading.rs,
                "rd": args.shading.rd,
                "nu": args.shading.nu,
                "nv": args.shading.nv,
                "seed": args.shading.seed,
            },
            "paths": self.paths.iter().map(|p| serde_json::json!({
                "path": p.kind.name(),
                "frames": p.cameras.len(),
                "degrees": match p.kind {
                    PathKind::Still => 0.0,
                    PathKind::Orbit => args.orbit_degrees,
                },
                "steady_from_frame": p.steady_from + 1,
                "steady": p.steady_note,
            })).collect::<Vec<_>>(),
            "replays": self.infos,
            "seconds": self.seconds,
            "rows": self.rows,
        })
    }
}
