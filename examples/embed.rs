//! Embedding the runtime: open a store, render one frame headless, write it as a PNG.
//!
//! ```sh
//! oslf bake examples/gazebo.toml -o gazebo.oslf
//! cargo run --release --example embed -- gazebo.oslf embed.png
//! ```
//!
//! A viewer does the same per frame with its own camera, `resolve_misses: false` (cube maps that
//! are not resident fall back for one frame and stream in for the next) and the output texture
//! ([`Renderer::output_texture`]) instead of reading pixels back. See docs/embedding.md.

use std::path::PathBuf;

use anyhow::Context;
use oslf_runtime::{
    Background, Blend, CacheConfig, Gpu, Lookup, ReconMirror, RenderOptions, Renderer,
    ShadingParams,
};

fn main() -> anyhow::Result<()> {
    let mut args = std::env::args_os().skip(1).map(PathBuf::from);
    let (Some(store_path), Some(png)) = (args.next(), args.next()) else {
        anyhow::bail!("usage: embed STORE.oslf OUT.png");
    };
    let store = oslf_format::Store::open(&store_path)
        .with_context(|| format!("cannot open {}", store_path.display()))?;
    // The GPU: Vulkan, Metal or DX12 when there is one (lavapipe on a machine without a GPU).
    let gpu = Gpu::headless()?;
    // Every cube map may stay resident; give `gpu_slots` / `ram_bytes` to stream under a budget.
    let mut renderer = Renderer::new(gpu, store, CacheConfig::default())?;
    let camera = renderer.default_view();
    // Reconstruction plus mirror reflection, the four sample points blended by B^n (N = 4).
    let params = ShadingParams::ReconMirror(ReconMirror {
        lookup: Lookup::oslf(Blend::Normal, 4.0),
        ..Default::default()
    });
    // The object in its scene: the store's environment cube behind it, where the store has one.
    let background = match renderer.store().env_cube_index() {
        Some(_) => Background::Env,
        None => Background::None,
    };
    let options = RenderOptions {
        width: 640,
        height: 480,
        background,
        ..RenderOptions::default()
    };
    let frame = renderer.render(&camera, &params, &options)?;
    // Linear RGB with the object mask in alpha; a plain tone map to 8-bit sRGB for the PNG.
    let bytes: Vec<u8> = frame
        .pixels
        .iter()
        .flat_map(|p| {
            let srgb =
                |c: f32| (255.0 * (c.max(0.0) / (1.0 + c.max(0.0))).powf(1.0 / 2.2)).round() as u8;
            [srgb(p[0]), srgb(p[1]), srgb(p[2]), 255]
        })
        .collect();
    image::save_buffer(
        &png,
        &bytes,
        frame.width,
        frame.height,
        image::ColorType::Rgba8,
    )
    .with_context(|| format!("cannot write {}", png.display()))?;
    println!(
        "{}: {}x{}, {} cube-map requests, {} misses",
        png.display(),
        frame.width,
        frame.height,
        frame.stats.requests,
        frame.stats.misses
    );
    Ok(())
}
