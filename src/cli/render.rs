//! `oslf render`: renders an OSLF store headless to OpenEXR (linear f32, object mask in alpha)
//! and a tone-mapped PNG, and prints the cache statistics. Pixels off the object show the
//! `--background` (the store's environment cube by default) in both images; in the EXR their
//! alpha stays 0.

use std::time::Instant;

use anyhow::bail;
use glam::Vec3;
use oslf_bake::bake::check_writable;
use oslf_format::Store;
use oslf_runtime::cache;
use oslf_runtime::reference::StoreCubes;
use oslf_runtime::{
    Blend, CacheConfig, CacheStats, Frame, FrameBytes, Gpu, Granularity, Mode, RenderOptions,
    Renderer, ShadingParams, Source,
};
use oslf_util::image_file;

use super::args::{BackgroundArgs, CameraArgs, ShadingArgs};
use super::paths::{InputPath, OutputPath};

/// Render an offset surface light field with wgpu: surface reconstruction, mirror reflections
/// with every blend of thesis chapter 4, Monte Carlo Ashikhmin–Shirley (chapter 5), or the
/// environment-map baseline, streaming cube maps through an LRU cache.
#[derive(clap::Args, Debug)]
#[command(allow_negative_numbers = true)]
pub struct Args {
    /// The store (written by `oslf bake`).
    store: InputPath,
    #[command(flatten)]
    access: super::args::StoreAccessArgs,
    /// Output OpenEXR (linear f32 RGBA, alpha = object mask); a PNG of the RGB, background
    /// included, is written beside it.
    #[arg(short, long, default_value = "render.exr")]
    output: OutputPath,
    /// recon | mirror | recon-mirror | glossy | recon-glossy | pbr [default: pbr for a store
    /// whose objects carry a metallic-roughness material, else
    /// recon-mirror].
    #[arg(long)]
    mode: Option<Mode>,
    /// distance | angle | avg | r | n (thesis 4.3, 4.4, 4.9, 4.10, 4.11).
    #[arg(long, default_value = "n")]
    blend: Blend,
    #[command(flatten)]
    shading: ShadingArgs,
    /// Image width.
    #[arg(long, default_value_t = 655)]
    width: u32,
    /// Image height.
    #[arg(long, default_value_t = 460)]
    height: u32,
    #[command(flatten)]
    camera: CameraArgs,
    #[command(flatten)]
    background: BackgroundArgs,
    /// GPU cache budget in cube-map slots [default: every cube, as far as the device allows].
    #[arg(long, conflicts_with = "cache_mb")]
    cache_slots: Option<u32>,
    /// GPU cache budget in MB of cube-map texels.
    #[arg(long)]
    cache_mb: Option<f64>,
    /// RAM cache budget in MB of decoded faces.
    #[arg(long, default_value_t = 256.0)]
    ram_mb: f64,
    /// Load whole cubes (cube, the thesis's "read full image") or single faces (face).
    #[arg(long, default_value = "cube")]
    granularity: Granularity,
    /// Shade on the CPU with the reference implementation (the GPU still rasterizes the
    /// G-buffer); decodes every cube of the store.
    #[arg(long)]
    cpu: bool,
    /// PNG exposure multiplier, 1e-6 to 1e6 (beyond, every pixel is black or white).
    #[arg(long, default_value_t = 1.0, value_parser = super::args::parse_exposure)]
    exposure: f32,
    /// Fail (exit 1, no image written) when the image would be degraded: any sample point
    /// that fell back (a cube map that failed to decode, a budget too small for the frame's
    /// working set), or a default background the store cannot give.
    #[arg(long)]
    strict: bool,
    /// Before rendering, decode every face and check them against the store's checksum of
    /// its decoded faces (as `oslf store verify`), so that a damaged store resealed with new
    /// frame checksums cannot render silently wrong: a mismatch is a warning, an error
    /// under --strict.
    #[arg(long)]
    verify: bool,
    /// Write the frame's and the cumulative cache statistics as JSON to this file.
    #[arg(long)]
    stats_json: Option<OutputPath>,
    /// Do not upload BC6H stores as BC6H blocks even where the GPU has BC texture
    /// compression: decode them on the CPU and upload RGB9E5.
    #[arg(long)]
    no_bc: bool,
}

pub fn run(args: Args) -> anyhow::Result<()> {
    check_outputs(&args)?;
    let t = Instant::now();
    let store = args.access.open(&args.store)?;
    let open_seconds = t.elapsed().as_secs_f64();
    if args.verify {
        super::store::verify_for_render(&store, &args.store, args.strict)?;
    }
    let mode = args.mode.unwrap_or_else(|| Mode::default_for(store.meta()));
    let params = args.shading.params(mode, args.blend)?;
    args.shading.check_store(&store, &args.store)?;
    let (background, note) = args.background.resolve(&store, &args.store)?;
    if let Some(note) = &note {
        if args.strict {
            bail!("{note} (--strict)");
        }
        eprintln!("note: {note}");
    }
    let ram_bytes = cache::ram_bytes(args.ram_mb)?;
    let gpu = Gpu::headless_with_bc(!args.no_bc)?;
    let gpu_slots = match (args.cache_slots, args.cache_mb) {
        (Some(s), _) => Some(s),
        (None, Some(mb)) => Some(cache::slots_for_megabytes(&store, mb, gpu.has_bc())?),
        (None, None) => None,
    };
    let config = CacheConfig {
        gpu_slots,
        ram_bytes,
        granularity: args.granularity,
        slots_per_texture: None,
    };
    check_frame_memory(&args, &store, &gpu)?;
    let adapter = gpu.adapter_name.clone();
    let t = Instant::now();
    let mut renderer = Renderer::new(gpu, store, config)?;
    let setup = t.elapsed().as_secs_f64();
    let camera = args.camera.apply(renderer.default_view())?;
    let options = RenderOptions {
        width: args.width,
        height: args.height,
        background,
        ..Default::default()
    };
    let t = Instant::now();
    let frame = renderer.render(&camera, &params, &options)?;
    let render_seconds = t.elapsed().as_secs_f64();
    let degraded = fallback_report(&renderer, &frame, &params);
    if args.strict && !degraded.is_empty() {
        bail!(
            "{}: the image would be degraded (--strict; nothing written):\n  {}",
            args.store.display(),
            degraded.join("\n  ")
        );
    }
    let mut pixels = frame.pixels.clone();
    if args.cpu {
        let t = Instant::now();
        let cubes = StoreCubes::decode_as(renderer.store(), renderer.face_layout())?;
        let (cpu, _) = renderer.reference_image(&camera, &params, &cubes)?;
        pixels = cpu;
        println!("cpu reference  {:.2} s", t.elapsed().as_secs_f64());
    }
    let rgb: Vec<Vec3> = pixels.iter().map(|p| Vec3::new(p[0], p[1], p[2])).collect();
    image_file::write_exr_rgba(&args.output, args.width, args.height, &pixels)?;
    let png = args.output.with_extension("png");
    image_file::write_png(&png, args.width, args.height, &rgb, args.exposure)?;

    println!("adapter        {adapter}");
    println!(
        "store          {}: {} sample points, {}² cube maps, {} slots on the GPU ({}); opened in {:.1} ms ({})",
        args.store.display(),
        renderer.store().sample_points().len(),
        renderer.store().cube_resolution(),
        renderer.cache().slots(),
        renderer.face_layout().encoding,
        open_seconds * 1e3,
        if args.access.mmap { "memory-mapped" } else { "positioned reads" }
    );
    print_mode(&params, args.mode.is_none());
    let gpu_time = match (frame.shade_gpu_seconds, frame.gbuffer_gpu_seconds) {
        (Some(s), Some(g)) => format!(
            ", on the GPU: shading {:.2} ms, G-buffer {:.2} ms",
            s * 1e3,
            g * 1e3
        ),
        _ => String::new(),
    };
    println!(
        "image          {} and {} ({}x{}, {} shading pass{}, {:.3} s{gpu_time}; setup {:.2} s)",
        args.output.display(),
        png.display(),
        args.width,
        args.height,
        frame.passes,
        if frame.passes == 1 { "" } else { "es" },
        render_seconds,
        setup
    );
    print_stats("frame", &frame.stats);
    for line in &degraded {
        eprintln!("warning: {}: {line}", args.store.display());
    }
    if let Some(path) = &args.stats_json {
        let json = serde_json::json!({
            "frame": frame.stats,
            "cumulative": renderer.cache().cumulative,
            "passes": frame.passes,
            "open_seconds": open_seconds,
            "setup_seconds": setup,
            "mmap": args.access.mmap,
            "render_seconds": render_seconds,
            "shade_gpu_seconds": frame.shade_gpu_seconds,
            "gbuffer_gpu_seconds": frame.gbuffer_gpu_seconds,
            "adapter": adapter,
        });
        oslf_util::output_file::write_bytes(path, serde_json::to_string_pretty(&json)?.as_bytes())?;
    }
    Ok(())
}

/// Refuses, before any slow work, a frame whose images cannot fit in the memory available,
/// naming what takes the room and the flags to change.
fn check_frame_memory(args: &Args, store: &Store, gpu: &Gpu) -> anyhow::Result<()> {
    let frame = FrameBytes::of(args.width, args.height);
    let pixels = u64::from(args.width) * u64::from(args.height);
    // This command's own copies: the pixels (RGBA f32), RGB for the PNG, the EXR writer's
    // RGBA f32 and the PNG's 8-bit RGB.
    let images = pixels * (16 + 12 + 16 + 3);
    let cpu_reference = if args.cpu {
        let res = u64::from(store.cube_resolution());
        u64::from(store.cube_count()) * 6 * res * res * 12
    } else {
        0
    };
    let targets = if gpu.shares_system_memory {
        frame.gpu
    } else {
        0
    };
    let needed = frame.readback + images + cpu_reference + targets;
    let Some(available) = oslf_util::machine::available_memory() else {
        return Ok(());
    };
    if needed > available {
        let gb = |b: u64| b as f64 / 1e9;
        bail!(
            "a {}x{} frame needs about {:.1} GB of memory ({:.1} GB of images and read-back{}{}) \
             but {:.1} GB are available; lower --width and --height",
            args.width,
            args.height,
            gb(needed),
            gb(frame.readback + images),
            if targets > 0 {
                format!(
                    ", {:.1} GB of render targets on a GPU that uses system memory",
                    gb(targets)
                )
            } else {
                String::new()
            },
            if args.cpu {
                format!(
                    ", {:.1} GB of decoded cube maps for --cpu",
                    gb(cpu_reference)
                )
            } else {
                String::new()
            },
            gb(available)
        );
    }
    Ok(())
}

/// What the frame fell back on, and why, one line each; empty when the image is exact.
fn fallback_report(renderer: &Renderer, frame: &Frame, params: &ShadingParams) -> Vec<String> {
    let store = renderer.store();
    let env = store.env_cube_index();
    let reflects = !matches!(params.mode(), Mode::Recon);
    let mut lines: Vec<String> = Vec::new();
    if params.depth() && !store.header().has_distance() && params.source() == Source::Oslf {
        lines.push(format!(
            "the store has no distance channel, so {} are not depth-corrected: plain lookups as \
             the thesis did (rebake with distance_channel = true, or pass --no-depth)",
            if reflects {
                "reflections and reconstruction"
            } else {
                "reconstruction lookups"
            }
        ));
    }
    lines.extend(renderer.cache().errors.iter().map(|e| {
        if Some(e.cube) == env {
            format!(
                "the environment cube (cube {}) face {} cannot be decoded: {}; the \
                     background, the environment-map baseline and every reflection that falls \
                     back to it show black there",
                e.cube, e.face, e.message
            )
        } else {
            format!(
                "cube {} (sample point {}) face {} cannot be decoded: {}; that sample point \
                     is left out of its blends",
                e.cube, e.cube, e.face, e.message
            )
        }
    }));
    if frame.fallbacks > 0 {
        let unit = match renderer.cache().granularity() {
            Granularity::Cube => "cube maps",
            Granularity::Face => "faces",
        };
        let why = if frame.stats.unresolved > 0 {
            format!(
                "the GPU budget of {} cube-map slots cannot hold the frame's working set of {} \
                 {unit}; raise --cache-slots or --cache-mb",
                renderer.cache().slots(),
                frame.stats.requests
            )
        } else if !renderer.cache().errors.is_empty() {
            "they failed to decode (above)".to_string()
        } else {
            format!(
                "they were still loading after {} shading passes",
                frame.passes
            )
        };
        lines.push(format!(
            "{} needed {unit} were not resident in the final shading pass, so their sample \
             points fell back (left out of the blends; the environment cube where none was \
             left): {why}",
            frame.fallbacks
        ));
    }
    // A memory-mapped store written in place since it was opened: what was read may be of
    // neither version (docs/store.md, "Two readers").
    lines.extend(store.changed_since_open());
    lines
}

fn print_stats(label: &str, s: &CacheStats) {
    println!(
        "cache {label:<8} {} requests, {} hits, {} misses ({:.1}% miss rate), {} loaded, {} evicted, {} over budget",
        s.requests,
        s.hits,
        s.misses,
        100.0 * s.miss_rate,
        s.loads,
        s.evictions,
        s.unresolved
    );
    println!(
        "               RAM {} hits / {} decoded, {:.2} MB decoded in {:.3} s, {:.2} MB uploaded in {:.3} s{}",
        s.ram_hits,
        s.ram_misses,
        s.bytes_decoded as f64 / 1e6,
        s.decode_seconds,
        s.bytes_uploaded as f64 / 1e6,
        s.upload_seconds,
        if s.decode_errors > 0 {
            format!(", {} faces failed to decode", s.decode_errors)
        } else {
            String::new()
        }
    );
}

/// Every output is checked before any work: `-o` names the OpenEXR file (the PNG goes beside
/// it, so `-o` cannot end in `.png`), and each file can be written.
fn check_outputs(args: &Args) -> anyhow::Result<()> {
    let png = args.output.with_extension("png");
    if png == args.output.0 {
        bail!(
            "-o {}: the render is written as OpenEXR to -o and as a tone-mapped PNG beside it, \
             which would be the same file; give an .exr path such as {}",
            args.output.display(),
            args.output.with_extension("exr").display()
        );
    }
    let mut door = oslf_util::door::Door::new();
    door.input("STORE", &args.store)
        .output("--output", &args.output)
        .output("the PNG beside --output", &png);
    if let Some(path) = &args.stats_json {
        door.output("--stats-json", path);
    }
    door.check()?;
    check_writable(&args.output, "the image")?;
    check_writable(&png, "the PNG")?;
    if let Some(path) = &args.stats_json {
        check_writable(path, "the --stats-json file")?;
    }
    Ok(())
}

/// The summary's `mode` line: the mode, whether it was the store's default, and whether
/// objects take their own materials.
fn print_mode(params: &oslf_runtime::ShadingParams, defaulted: bool) {
    let materials = if params.material().is_some_and(|m| m.object_material) {
        ", objects with a metallic-roughness material in the store shaded with it"
    } else {
        ""
    };
    let default = if defaulted {
        " (the default for this store)"
    } else {
        ""
    };
    println!(
        "mode           {}{default}{materials}",
        params.mode().name()
    );
}
