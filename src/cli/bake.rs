//! `oslf bake`: bakes a scene file into an OSLF store.

use std::path::PathBuf;
use std::sync::Arc;
use std::time::Instant;

use anyhow::bail;
use oslf_bake::bake::{bake_shard, check_store_writable, check_writable, BakeOptions, BakeReport};
use oslf_format::ShardSpec;
use oslf_scene::scene::{Scene, GPU_PRESET};
use oslf_scene::tolerance::TESSELLATION_ERROR;
use oslf_trace::bvh::TriangleScene;
use oslf_trace::integrator::Integrator;
use oslf_util::door::Door;
use oslf_util::image_file;

use super::paths::{declare_scene, InputPath, OutputPath};

/// Bake an offset surface light field: sample points ε above the object's Bézier patches, a
/// ray-traced HDR cube map at each, and per-patch sample maps, all written to one store.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// The scene file (TOML; see docs/scene-format.md).
    scene: InputPath,
    /// The store to write [default: the scene's name with .oslf, in the current directory;
    /// with --shard I/N, the scene's name with .oslf.shard-I-of-N].
    #[arg(short, long)]
    output: Option<OutputPath>,
    /// Bake only shard I of N (0 ≤ I < N): the cube maps i with i % N == I, plus the sample
    /// points and maps, into a shard file; `oslf store merge` joins all N shards into the
    /// store a single bake writes, byte for byte. --resume and --max-cubes work per shard.
    #[arg(long, value_name = "I/N", value_parser = parse_shard)]
    shard: Option<ShardSpec>,
    /// Apply the scene's `[presets.NAME]` over its `[bake]` settings.
    #[arg(short, long)]
    preset: Option<String>,
    /// Store the cube maps in this encoding instead of the scene's `encoding` (after the
    /// preset): rgb9e5, rgba16f, rgba32f or bc6h.
    #[arg(long, value_parser = parse_encoding)]
    encoding: Option<oslf_format::Encoding>,
    /// Continue an interrupted bake from `<output>.partial`, keeping its finished cube maps.
    #[arg(long)]
    resume: bool,
    /// Capture at most N cube maps in this run, then stop, leaving `<output>.partial` for a
    /// later `--resume` (a bake in slices).
    #[arg(long, value_name = "N")]
    max_cubes: Option<u32>,
    /// Worker threads [default: all cores]. The store is byte-identical for any count.
    #[arg(short = 'j', long)]
    threads: Option<usize>,
    /// Also render the scene camera with the bake's path tracer to this PNG (and an EXR beside
    /// it) (default: `<output>.preview.png`, none with --shard; "none" to skip).
    #[arg(long)]
    preview: Option<OutputPath>,
    /// Samples per pixel of the preview.
    #[arg(long, default_value_t = 16)]
    preview_spp: u32,
    /// Write the bake summary as JSON to this file.
    #[arg(long)]
    report_json: Option<OutputPath>,
    /// Refuse a bake whose optimistic time estimate is longer than this many hours on this
    /// machine's threads (0: no limit). Memory and disk are always checked.
    #[arg(long, default_value_t = 12.0, value_name = "HOURS")]
    max_hours: f64,
    /// What captures the cube maps: auto (the GPU on a hardware adapter, else the CPU), cpu
    /// or gpu [default: the scene's `[bake] device`, else auto]. Both compute the same
    /// estimator; their stores differ only by rounding.
    #[arg(long, value_parser = parse_device)]
    device: Option<oslf_scene::scene::DeviceChoice>,
    /// No progress bar.
    #[arg(short, long)]
    quiet: bool,
    /// Fail, before the cube maps are captured, if a sample-map texel that a view may reach
    /// has no visible sample point (without it: a warning, and the store is written).
    #[arg(long)]
    strict: bool,
}

fn parse_encoding(s: &str) -> Result<oslf_format::Encoding, String> {
    s.parse().map_err(|e: oslf_format::Error| e.to_string())
}

/// The store's path when `-o` is not given: the scene's name with .oslf in the current
/// directory, with `.shard-I-of-N` for a shard.
fn default_output(args: &Args) -> PathBuf {
    let stem = args.scene.file_stem().unwrap_or_default();
    let store = PathBuf::from(stem).with_extension("oslf");
    match args.shard {
        Some(s) => PathBuf::from(format!(
            "{}.shard-{}-of-{}",
            store.display(),
            s.index(),
            s.count()
        )),
        None => store,
    }
}

fn parse_device(s: &str) -> Result<oslf_scene::scene::DeviceChoice, String> {
    s.parse()
}

fn parse_shard(s: &str) -> Result<ShardSpec, String> {
    s.parse().map_err(|e: oslf_format::Error| e.to_string())
}

pub fn run(args: Args) -> anyhow::Result<()> {
    super::args::in_pool(args.threads, || run_in_pool(args))
}

fn run_in_pool(args: Args) -> anyhow::Result<()> {
    let mut scene = load_scene(&args, args.preset.as_deref())?;
    let output = args
        .output
        .as_ref()
        .map_or_else(|| default_output(&args), |o| o.0.clone());
    let preview = match &args.preview {
        Some(p) if p.as_os_str() == "none" => None,
        Some(p) => Some(p.0.clone()),
        // Every shard would render the same preview.
        None if args.shard.is_some() => None,
        None => Some(PathBuf::from(format!("{}.preview.png", output.display()))),
    };
    // Every input and output, declared and checked before any work.
    let mut door = Door::new();
    declare_scene(&mut door, "SCENE", &scene);
    door.output("--output", &output).output(
        "the partial store of --output",
        &oslf_format::writer::partial_path(&output),
    );
    if let (Some(png), Some(_)) = (&preview, &scene.camera) {
        door.output("--preview", png)
            .output("the EXR beside --preview", &png.with_extension("exr"));
    }
    if let Some(path) = &args.report_json {
        door.output("--report-json", path);
    }
    door.check()?;
    // Every output must be writable before the slow work starts.
    check_store_writable(&output)?;
    if let Some(path) = &args.report_json {
        check_writable(path, "the --report-json file")?;
    }
    if let (Some(png), Some(_)) = (&preview, &scene.camera) {
        check_writable(png, "the preview")?;
        check_writable(&png.with_extension("exr"), "the preview")?;
    }
    // The device first: the estimate's capture time is its measured rate.
    let (mut gpu, mut why) = choose_device(&args, &scene, args.quiet)?;
    // What a GPU makes affordable: the scene's `gpu` preset, unless another was asked for.
    if gpu.is_some() && args.preset.is_none() && scene.presets.iter().any(|p| p == GPU_PRESET) {
        scene = load_scene(&args, Some(GPU_PRESET))?;
        // Built again: the preset may change what the device holds (ε tessellates the objects,
        // `bounces` sizes the paths) and the rate its estimate is measured at.
        (gpu, why) = choose_device(&args, &scene, true)?;
        if gpu.is_some() {
            why = format!(
                "{why}; settings: the scene's preset {GPU_PRESET:?}, applied for a GPU capture (--preset NAME or --device cpu to bake otherwise)"
            );
            if !args.quiet {
                eprintln!("settings: the scene's preset {GPU_PRESET:?}, applied for a GPU capture (--preset NAME or --device cpu to bake otherwise)");
            }
        }
    }
    scene
        .warnings
        .iter()
        .for_each(|w| eprintln!("warning: {w}"));
    if !args.quiet {
        for choice in &scene.bake_choices {
            eprintln!("chosen: {choice}");
        }
    }
    let device = gpu
        .clone()
        .map(|g| g as Arc<dyn oslf_bake::device::CaptureDevice>);
    // What the bake will cost (the bake itself refuses what cannot fit, naming the setting).
    let estimate = estimate(&scene, args.shard, device.as_deref());
    if !args.quiet {
        eprintln!("{estimate}");
        for w in &estimate.warnings {
            eprintln!("warning: {w}");
        }
    }
    if !(args.max_hours.is_finite() && args.max_hours >= 0.0) {
        bail!(
            "--max-hours {} must be a number of hours ≥ 0",
            args.max_hours
        );
    }
    let mut limits = oslf_bake::preflight::Limits::of_machine(&output);
    limits.max_seconds = (args.max_hours > 0.0).then_some(args.max_hours * 3600.0);
    // The bake checks the same limits itself; checked here first to name the flag that sets
    // the time limit.
    if let Err(e) = oslf_bake::preflight::check(&estimate, &limits) {
        match e {
            oslf_bake::preflight::PreflightError::Time { .. } => {
                bail!("{e} (or raise the limit: --max-hours, 0 for none)")
            }
            e => bail!("{e}"),
        }
    }
    let options = BakeOptions {
        output: output.clone(),
        resume: args.resume,
        progress: super::progress::bars(!args.quiet),
        cube_limit: args.max_cubes,
        refuse_empty_texels: args.strict,
        device,
    };
    let report = bake_shard(&scene, &options, args.shard, &limits).map_err(with_flag_hints)?;
    print_summary(&report, &why);
    warn_empty_texels(&report);
    if !report.finished {
        println!(
            "stopped after --max-cubes; continue with --resume (the partial store is {})",
            oslf_format::writer::partial_path(&output).display()
        );
    }
    if let Some(path) = &args.report_json {
        let json = serde_json::to_string_pretty(&report)?;
        oslf_util::output_file::write_bytes(path, json.as_bytes())?;
    }

    if let Some(png) = preview {
        write_preview(&scene, gpu.as_deref(), &png, args.preview_spp)?;
    }
    Ok(())
}

/// Renders the scene camera with the bake's path tracer (on the GPU that captured, if one
/// did) to `png` and an EXR beside it.
/// The scene file of `args` with `preset` applied and `--encoding` over it.
fn load_scene(args: &Args, preset: Option<&str>) -> anyhow::Result<Scene> {
    let mut scene = Scene::load(&args.scene, preset)?;
    if let Some(encoding) = args.encoding {
        if oslf_format::meta::check_mantissa_bits(encoding, scene.bake.mantissa_bits).is_err() {
            bail!(
                "--encoding {encoding}: the scene sets mantissa_bits = {}, which applies to rgb9e5 only (remove it from the scene or preset, or bake with --encoding rgb9e5)",
                scene.bake.mantissa_bits
            );
        }
        scene.bake.encoding = encoding;
    }
    Ok(scene)
}

/// The capture device `--device` (else the scene's `[bake] device`) asks for, and why.
fn choose_device(
    args: &Args,
    scene: &Scene,
    quiet: bool,
) -> anyhow::Result<(Option<Arc<oslf_bake_gpu::GpuCapture>>, String)> {
    match args.device {
        Some(d) => super::device::capture_device(scene, d, "--device", quiet),
        None => super::device::capture_device(scene, scene.bake.device, "[bake] device", quiet),
    }
}

fn write_preview(
    scene: &Scene,
    gpu: Option<&oslf_bake_gpu::GpuCapture>,
    png: &std::path::Path,
    preview_spp: u32,
) -> anyhow::Result<()> {
    let Some(cam) = &scene.camera else {
        eprintln!("no preview: the scene has no [camera]");
        return Ok(());
    };
    let t = Instant::now();
    let (w, h) = (655, 460); // the thesis's image size (§6.1)
    let pixels = match &gpu {
        // The same integrator on the device that captured.
        Some(gpu) => gpu.preview(cam, w, h, preview_spp, scene.bake.seed)?,
        None => {
            let max_error = scene.bake.epsilon * TESSELLATION_ERROR;
            let geometry =
                TriangleScene::build(oslf_trace::bvh::scene_instances(scene, true, max_error))?;
            let integrator = Integrator::for_scene(scene, &geometry);
            let seed = scene.bake.seed;
            oslf_trace::preview::render(&integrator, cam, w, h, preview_spp, seed).0
        }
    };
    image_file::write_png(png, w, h, &pixels, 1.0)?;
    let exr = png.with_extension("exr");
    image_file::write_exr(&exr, w, h, &pixels)?;
    println!(
        "preview        {} and {} ({w}x{h}, {} spp, {:.1} s)",
        png.display(),
        exr.display(),
        preview_spp,
        t.elapsed().as_secs_f64()
    );
    Ok(())
}

/// What to change when sample-map texels see no sample point (the warning and `--strict`'s
/// error say it alike).
const EMPTY_TEXELS_REMEDY: &str = "raise sample_count (or lower sample_spacing), or lower epsilon";

/// The warning for sample-map texels without any visible sample point where a view may
/// reach them (`--strict` refuses those before the capture); empty texels no view reaches are
/// counted beside them, not warned about.
fn warn_empty_texels(report: &BakeReport) {
    let m = &report.sample_maps;
    let visible = report.visible_empty();
    if visible > 0 {
        let unseen = match report.unseen_empty() {
            0 => String::new(),
            u => format!(" (and {u} more where no view reaches)"),
        };
        eprintln!(
            "warning: {} of {} sample-map texels ({:.3}%) have no visible sample point{unseen}, so the store cannot reconstruct them; {EMPTY_TEXELS_REMEDY} (--strict refuses such a bake; the coverage lines say where and why)",
            visible,
            m.texels,
            100.0 * visible as f64 / m.texels.max(1) as f64
        );
    }
}

/// The summary's `sample points` line: placed, removed, added and lowered.
fn print_points(r: &BakeReport) {
    let lowered = if r.points_lowered > 0 {
        format!(
            "; {} of them lowered nearer their surface than ε, near another",
            r.points_lowered
        )
    } else {
        String::new()
    };
    println!(
        "sample points  {}: {} placed, {} closer than ε to a surface, {} inside geometry, {} added where texels had fewer than four{lowered}",
        r.sample_points,
        r.points_placed,
        r.points_removed_close,
        r.points_removed_inside,
        r.points_added
    );
}

fn print_summary(r: &BakeReport, why: &str) {
    let m = &r.sample_maps;
    match &r.shard {
        Some(s) => println!(
            "shard          {} ({}: {} of the store's {} cube maps; join the shards with `oslf store merge`)",
            s,
            r.output.display(),
            r.cubes,
            r.store_cubes
        ),
        None => println!("store          {}", r.output.display()),
    }
    print_points(r);
    println!(
        "sample maps    {} texels; {} with fewer than four points ({:.3}%), {} with none",
        m.texels,
        m.short,
        100.0 * m.short as f64 / m.texels.max(1) as f64,
        m.empty
    );
    print_coverage(r);
    for a in &r.atlases {
        let uvs = match a.source {
            "lightmap" => "its TEXCOORD_1".to_string(),
            "texture" => "its TEXCOORD_0".to_string(),
            _ => format!("{} charts of its own", a.charts),
        };
        println!(
            "atlas          {:?}: {}x{} pages of {}², from {uvs}; the surface covers {:.0}% of \
             its texels ({:.0}% with the free texels beside it)",
            a.object,
            a.grid,
            a.grid,
            a.page_resolution,
            100.0 * a.fill,
            100.0 * a.used
        );
        for why in &a.rejected {
            println!("               not used: {why}");
        }
    }
    for n in &r.normals {
        println!("normals        {n}");
    }
    println!(
        "cube maps      {} of {}² texels, {} samples per texel{}",
        r.cubes,
        r.cube_resolution,
        r.samples_per_texel,
        if r.cubes_resumed > 0 {
            format!(" ({} recovered from the interrupted bake)", r.cubes_resumed)
        } else {
            String::new()
        }
    );
    println!("capture        {why}");
    print_noise(r);
    let rays = (r.rays_closest + r.rays_shadow) as f64;
    let on_cpu = r.capture_device.starts_with("CPU");
    println!(
        "rays           {} closest + {} shadow = {:.1} M, {:.2} Mrays/s{}",
        r.rays_closest,
        r.rays_shadow,
        rays / 1e6,
        r.mrays_per_second,
        match r.capture_cpu_seconds {
            Some(cpu) if cpu > 0.0 && on_cpu => format!(
                " ({:.2} Mrays per CPU-second, {:.1} CPU-s)",
                rays / cpu / 1e6,
                cpu
            ),
            _ => String::new(),
        }
    );
    if r.traversal_nodes > 0 && rays > 0.0 {
        println!(
            "traversal      {:.1} BVH nodes and {:.1} triangles tested per ray",
            r.traversal_nodes as f64 / rays,
            r.traversal_triangles as f64 / rays
        );
    }
    let pilots = match r.pilot_cubes {
        0 => String::new(),
        n => format!(" ({n} pilot cubes)"),
    };
    println!(
        "time           {:.1} s total{}: BVH {:.2} s ({} triangles), points {:.2} s{pilots}, sample maps {:.2} s, cube maps {:.1} s",
        r.total_seconds,
        r.cpu_seconds
            .map_or(String::new(), |c| format!(" ({c:.1} CPU-s)")),
        r.bvh_build_seconds,
        r.triangles,
        r.placement_seconds,
        r.sample_map_seconds,
        r.capture_seconds
    );
    println!(
        "store size     {:.2} MB, {:.3} bytes per cube-map texel{}",
        r.store_bytes as f64 / 1e6,
        r.bytes_per_texel,
        if r.clamped_texels > 0 {
            format!(
                ", {} texels clamped to the encoding's maximum",
                r.clamped_texels
            )
        } else {
            String::new()
        }
    );
}

/// The noise of the cubes (a `noise` line) and, when it shows, a `hint` line: what to raise
/// and what it costs, by the preflight's estimate and by this bake's capture time.
fn print_noise(r: &BakeReport) {
    use oslf_bake::preflight::duration;
    let Some(n) = &r.noise else {
        return;
    };
    let percent = |e: f64| format!("{:.1}%", 100.0 * e);
    let Some(error) = n.relative_error else {
        println!(
            "noise          {}",
            if n.samples_per_texel < 2 {
                "not estimated: one sample per texel has no variance to measure (samples_per_texel = 4 or more gives an estimate)"
            } else {
                "none measured: no cube texel saw a lit surface"
            }
        );
        return;
    };
    let level = match (n.target, n.mean_samples_per_texel) {
        (Some(target), Some(mean)) => format!(
            "±{} relative standard error of the cube texels that see a surface, measured (adaptive: each texel sampled to ±{} or {} samples, {mean:.1} per texel on average with the 8 of its pilot)",
            percent(error),
            percent(target),
            n.samples_per_texel,
        ),
        _ => format!(
            "±{} relative standard error of the cube texels that see a surface ({} samples per texel)",
            percent(error),
            n.samples_per_texel,
        ),
    };
    let level = if n.denoised {
        format!("{level}, before denoising")
    } else {
        level
    };
    let Some(s) = &n.suggestion else {
        println!(
            "noise          {level}: below the {} that shows",
            percent(n.visible_above)
        );
        return;
    };
    if n.denoised {
        println!(
            "noise          {level}: above {}; the filter averaged it where the contrast is below it, blurring what lies there",
            percent(n.visible_above)
        );
    } else {
        println!(
            "noise          {level}: above {}, it shows as speckle in reflections (denoise = true averages it)",
            percent(n.visible_above)
        );
    }
    let factor = f64::from(s.samples_per_texel) / f64::from(n.samples_per_texel.max(1));
    let range = |(a, b): (f64, f64)| format!("{}–{}", duration(a), duration(b));
    let further = if s.samples_per_texel_below_visible > s.samples_per_texel {
        let times =
            f64::from(s.samples_per_texel_below_visible) / f64::from(n.samples_per_texel.max(1));
        format!(
            "; {} bring it under {}, at {times:.0}× the time",
            s.samples_per_texel_below_visible,
            percent(n.visible_above)
        )
    } else {
        String::new()
    };
    println!(
        "hint           raise samples_per_texel to {} to halve the noise (to ±{}): the cube maps take {factor:.0}× as long, {} on {} threads by the preflight's estimate (now {}{}){further}",
        s.samples_per_texel,
        percent(s.expected_relative_error),
        range(s.capture_seconds),
        s.threads,
        range(s.capture_seconds_now),
        // This run's capture time compares only when it captured the whole store.
        if r.finished && r.cubes_resumed == 0 {
            format!("; this bake's took {:.1} s", r.capture_seconds)
        } else {
            String::new()
        }
    );
}

/// Per object with short texels: a `coverage` line (how many) and a line per place (where,
/// why, what to do).
fn print_coverage(r: &BakeReport) {
    for c in r.coverage.iter().filter(|c| c.short > 0) {
        println!("coverage       {c}");
        for place in &c.places {
            println!("               {}", place.describe(c.decimals));
        }
    }
}

/// `e`, where the store writer could not resume a partial store or `--strict` refused the
/// sample maps, with what to do in this command's flags.
fn with_flag_hints(e: oslf_scene::BakeError) -> anyhow::Error {
    use oslf_format::Error::{ResumeMismatch, ResumeSettings};
    let hint = match &e {
        oslf_scene::BakeError::Format(ResumeSettings { .. }) => {
            "; bake without --resume to start over, or pass the settings it was started with"
        }
        oslf_scene::BakeError::Format(ResumeMismatch { .. }) => {
            "; bake without --resume to start over"
        }
        oslf_scene::BakeError::EmptyTexels { .. } => {
            return anyhow::anyhow!("{e} (--strict); {EMPTY_TEXELS_REMEDY}")
        }
        _ => return e.into(),
    };
    anyhow::anyhow!("{e}{hint}")
}

/// What baking `scene` (or one shard of it) will cost on this machine's threads.
fn estimate(
    scene: &Scene,
    shard: Option<ShardSpec>,
    device: Option<&dyn oslf_bake::device::CaptureDevice>,
) -> oslf_bake::preflight::Estimate {
    let estimate = oslf_bake::preflight::estimate(scene, rayon::current_num_threads());
    let capture = oslf_trace::capture::CaptureSettings::from_bake(&scene.bake);
    let estimate = oslf_bake::preflight::for_device(estimate, device, &capture);
    match shard {
        Some(s) => estimate.for_shard(s.count()),
        None => estimate,
    }
}
