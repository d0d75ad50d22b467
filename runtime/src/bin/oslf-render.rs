//! `oslf-render`: renders an OSLF store headless to OpenEXR (linear f32, object mask in alpha)
//! and a tone-mapped PNG, and prints the cache statistics.

use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Instant;

use anyhow::{bail, Context};
use clap::Parser;
use glam::Vec3;
use oslf_bake::image_file;
use oslf_format::Store;
use oslf_runtime::reference::StoreCubes;
use oslf_runtime::{
    Blend, CacheConfig, CacheStats, Gpu, Granularity, Mode, Order, RenderOptions, Renderer,
    ShadingParams, Source,
};

/// Render an offset surface light field with wgpu: surface reconstruction, mirror reflections
/// with every blend of thesis chapter 4, Monte Carlo Ashikhmin–Shirley (chapter 5), or the
/// environment-map baseline, streaming cube maps through an LRU cache.
#[derive(Parser, Debug)]
#[command(version, about, allow_negative_numbers = true)]
struct Args {
    /// The store (written by oslf-bake).
    store: PathBuf,
    /// Output OpenEXR (linear f32 RGBA, alpha = object mask); a PNG is written beside it.
    #[arg(short, long, default_value = "render.exr")]
    output: PathBuf,
    /// recon | mirror | recon-mirror | glossy | recon-glossy.
    #[arg(long, default_value = "recon-mirror")]
    mode: Mode,
    /// distance | angle | avg | r | n (thesis 4.3, 4.4, 4.9, 4.10, 4.11).
    #[arg(long, default_value = "n")]
    blend: Blend,
    /// Lobe power N of the r and n blends (0 = avg).
    #[arg(short = 'N', long = "blend-n", default_value_t = 4.0)]
    blend_n: f32,
    /// Use the environment-map baseline (one cube at the object's centre) instead of the OSLF.
    #[arg(long)]
    envmap: bool,
    /// φ_shader in degrees (§6.3).
    #[arg(long, default_value_t = 65.0)]
    phi_shader: f32,
    /// Monte Carlo samples M per integration (glossy modes).
    #[arg(short = 'M', long, default_value_t = 16)]
    m: u32,
    /// Integration order of §5.2: per-point (integrate, then blend) or per-direction.
    #[arg(long, default_value = "per-point", value_parser = parse_order)]
    order: Order,
    /// Ashikhmin–Shirley specular reflectance R_s.
    #[arg(long, default_value_t = 1.0)]
    rs: f32,
    /// Ashikhmin–Shirley diffuse reflectance R_d (adds the diffuse term 5.4 when > 0).
    #[arg(long, default_value_t = 0.0)]
    rd: f32,
    /// Exponent n_u (along the patch's u direction).
    #[arg(long, default_value_t = 100.0)]
    nu: f32,
    /// Exponent n_v.
    #[arg(long, default_value_t = 100.0)]
    nv: f32,
    /// Seed of the Monte Carlo random numbers.
    #[arg(long, default_value_t = 0)]
    seed: u32,
    /// Image width.
    #[arg(long, default_value_t = 655)]
    width: u32,
    /// Image height.
    #[arg(long, default_value_t = 460)]
    height: u32,
    /// Camera position x,y,z [default: the store's camera, else one framing the object].
    #[arg(long, value_parser = parse_vec3)]
    camera_pos: Option<Vec3>,
    /// Camera target x,y,z.
    #[arg(long, value_parser = parse_vec3)]
    camera_target: Option<Vec3>,
    /// Vertical field of view in degrees.
    #[arg(long)]
    vfov: Option<f32>,
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
    /// PNG exposure multiplier.
    #[arg(long, default_value_t = 1.0)]
    exposure: f32,
    /// Write the frame's and the cumulative cache statistics as JSON to this file.
    #[arg(long)]
    stats_json: Option<PathBuf>,
}

fn parse_order(s: &str) -> Result<Order, String> {
    match s {
        "per-point" => Ok(Order::PerPoint),
        "per-direction" => Ok(Order::PerDirection),
        _ => Err(format!("unknown order {s:?} (per-point or per-direction)")),
    }
}

fn parse_vec3(s: &str) -> Result<Vec3, String> {
    let v: Vec<f32> = s
        .split(',')
        .map(|p| p.trim().parse::<f32>().map_err(|e| format!("{p:?}: {e}")))
        .collect::<Result<_, _>>()?;
    match v.as_slice() {
        [x, y, z] if v.iter().all(|c| c.is_finite()) => Ok(Vec3::new(*x, *y, *z)),
        _ => Err(format!("{s:?} is not three finite numbers x,y,z")),
    }
}

fn main() -> ExitCode {
    match run(Args::parse()) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
}

fn run(args: Args) -> anyhow::Result<()> {
    let store = Store::open(&args.store)
        .with_context(|| format!("cannot open store {}", args.store.display()))?;
    let params = ShadingParams {
        mode: args.mode,
        blend: args.blend,
        blend_n: args.blend_n,
        source: if args.envmap {
            Source::EnvMap
        } else {
            Source::Oslf
        },
        phi_shader_deg: args.phi_shader,
        m: args.m,
        order: args.order,
        rs: args.rs,
        rd: args.rd,
        nu: args.nu,
        nv: args.nv,
        seed: args.seed,
    };
    params.validate()?;
    if args.envmap && store.env_cube_index().is_none() {
        bail!(
            "{} has no environment cube (bake with env_cube = true)",
            args.store.display()
        );
    }
    if !(args.ram_mb.is_finite() && args.ram_mb >= 0.0) {
        bail!("--ram-mb must be a non-negative number");
    }
    let res = u64::from(store.cube_resolution());
    let cube_bytes = 6 * res * res * store.header().encoding.bytes_per_texel() as u64;
    let gpu_slots = match (args.cache_slots, args.cache_mb) {
        (Some(s), _) => Some(s),
        (None, Some(mb)) => {
            if !(mb.is_finite() && mb > 0.0) {
                bail!("--cache-mb must be a positive number");
            }
            let slots = (mb * 1e6 / cube_bytes as f64).floor();
            if slots < 1.0 {
                bail!(
                    "--cache-mb {mb} holds no cube map ({:.3} MB each)",
                    cube_bytes as f64 / 1e6
                );
            }
            Some(slots.min(f64::from(u32::MAX)) as u32)
        }
        (None, None) => None,
    };
    let config = CacheConfig {
        gpu_slots,
        ram_bytes: (args.ram_mb * 1e6) as u64,
        granularity: args.granularity,
        slots_per_texture: None,
    };
    let gpu = Gpu::headless()?;
    let adapter = gpu.adapter_name.clone();
    let t = Instant::now();
    let mut renderer = Renderer::new(gpu, store, config)?;
    let setup = t.elapsed().as_secs_f64();
    let mut camera = renderer.default_view();
    if let Some(p) = args.camera_pos {
        camera.position = p;
    }
    if let Some(p) = args.camera_target {
        camera.target = p;
    }
    if let Some(v) = args.vfov {
        camera.vfov_deg = v;
    }
    camera.validate()?;
    let options = RenderOptions {
        width: args.width,
        height: args.height,
        ..Default::default()
    };
    let t = Instant::now();
    let frame = renderer.render(&camera, &params, &options)?;
    let render_seconds = t.elapsed().as_secs_f64();
    let mut pixels = frame.pixels.clone();
    if args.cpu {
        let t = Instant::now();
        let cubes = StoreCubes::decode(renderer.store())?;
        let (cpu, _) = renderer.reference_image(&camera, &params, &cubes)?;
        pixels = cpu;
        println!("cpu reference  {:.2} s", t.elapsed().as_secs_f64());
    }
    let rgb: Vec<Vec3> = pixels.iter().map(|p| Vec3::new(p[0], p[1], p[2])).collect();
    oslf_bake::image_file::write_exr_rgba(&args.output, args.width, args.height, &pixels)?;
    let png = args.output.with_extension("png");
    image_file::write_png(&png, args.width, args.height, &rgb, args.exposure)?;

    println!("adapter        {adapter}");
    println!(
        "store          {}: {} sample points, {}² cube maps, {} slots on the GPU",
        args.store.display(),
        renderer.store().sample_points().len(),
        renderer.store().cube_resolution(),
        renderer.cache().slots()
    );
    println!(
        "image          {} and {} ({}x{}, {} shading pass{}, {:.3} s; setup {:.2} s)",
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
    for e in &renderer.cache().errors {
        eprintln!("warning: {e} (that sample point fell back)");
    }
    if let Some(path) = &args.stats_json {
        let json = serde_json::json!({
            "frame": frame.stats,
            "cumulative": renderer.cache().cumulative,
            "passes": frame.passes,
            "render_seconds": render_seconds,
            "adapter": adapter,
        });
        std::fs::write(path, serde_json::to_string_pretty(&json)?)
            .with_context(|| format!("cannot write {}", path.display()))?;
    }
    Ok(())
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
