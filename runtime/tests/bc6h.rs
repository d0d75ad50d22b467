//! BC6H stores on the GPU: uploaded as their blocks (`Bc6hRgbUfloat`) where the device has BC
//! texture compression, decoded to RGB9E5 on the CPU where it has not (or where it is turned
//! off), each against the CPU reference built with the same layout. On lavapipe (or whatever
//! adapter the machine has: these tests fail, never skip, without one).

use crate::common;
use crate::common::knobs::Knobs;

use common::{compare, mean, open_store, store_path_bc6h};
use oslf_format::{Encoding, Store};
use oslf_runtime::cache::{cube_bytes, slots_for_megabytes};
use oslf_runtime::face::{bc6h_levels, mip_levels, FaceLayout};
use oslf_runtime::reference::StoreCubes;
use oslf_runtime::{CacheConfig, GlossyFilter, Gpu, Mode, Order, RenderOptions, Renderer};

const W: u32 = 96;
const H: u32 = 72;

fn options() -> RenderOptions {
    RenderOptions {
        width: W,
        height: H,
        ..Default::default()
    }
}

fn open_bc6h() -> Store {
    let store = Store::open(&store_path_bc6h()).unwrap();
    assert_eq!(store.header().encoding, Encoding::Bc6h);
    assert_eq!(store.cube_resolution() % 4, 0);
    store
}

/// [`common::check_parity`] at this file's frame size.
fn check(renderer: &mut Renderer, cubes: &StoreCubes, params: Knobs, label: &str) -> Vec<[f32; 4]> {
    common::check_parity(renderer, cubes, params, (W, H), label)
}

/// Every mode on `renderer` against the CPU reference built with the renderer's own layout.
fn every_mode(renderer: &mut Renderer, what: &str) -> Vec<Vec<[f32; 4]>> {
    let cubes = StoreCubes::decode_as(renderer.store(), renderer.face_layout()).unwrap();
    let base = Knobs::default();
    let mut images = Vec::new();
    for mode in [Mode::Recon, Mode::Mirror, Mode::ReconMirror] {
        images.push(check(
            renderer,
            &cubes,
            Knobs { mode, ..base },
            &format!("{what}: {}", mode.name()),
        ));
    }
    for order in [Order::PerPoint, Order::PerDirection] {
        for filter in [GlossyFilter::Mip, GlossyFilter::Point] {
            check(
                renderer,
                &cubes,
                Knobs {
                    mode: Mode::Glossy,
                    order,
                    glossy_filter: filter,
                    nu: 10.0,
                    nv: 10.0,
                    m: 8,
                    ..base
                },
                &format!("{what}: glossy {order:?} {filter:?}"),
            );
        }
    }
    check(
        renderer,
        &cubes,
        Knobs {
            mode: Mode::ReconGlossy,
            rs: 0.3,
            rd: 0.5,
            m: 4,
            ..base
        },
        &format!("{what}: recon + C_s glossy with diffuse term"),
    );
    // The split-sum baseline prefilters the environment cube as the store holds it.
    check(
        renderer,
        &cubes,
        Knobs {
            mode: Mode::Pbr,
            source: oslf_runtime::Source::EnvMap,
            glossy_filter: GlossyFilter::SplitSum,
            roughness: 0.5,
            ..base
        },
        &format!("{what}: pbr split-sum"),
    );
    images
}

#[test]
fn bc6h_blocks_on_the_gpu_match_the_cpu_reference() {
    let gpu = Gpu::headless().unwrap();
    println!(
        "{}: BC texture compression {}",
        gpu.adapter_name,
        gpu.has_bc()
    );
    let bc = gpu.has_bc();
    let store = open_bc6h();
    let res = store.cube_resolution();
    let mut r = Renderer::new(gpu, store, CacheConfig::default()).unwrap();
    let layout = r.face_layout();
    if bc {
        assert_eq!(layout.encoding, Encoding::Bc6h);
        assert_eq!(layout.levels, bc6h_levels(res));
    } else {
        // An adapter without BC texture compression: the fallback (below) is all there is.
        assert_eq!(layout.encoding, Encoding::Rgb9e5);
    }
    every_mode(&mut r, "bc6h");
    r.gpu().take_errors().unwrap();
}

#[test]
fn bc6h_without_bc_falls_back_to_rgb9e5_and_matches_its_reference() {
    let store = open_bc6h();
    let res = store.cube_resolution();
    let gpu = Gpu::headless_without_bc().unwrap();
    assert!(!gpu.has_bc());
    assert!(!gpu
        .device
        .features()
        .contains(wgpu::Features::TEXTURE_COMPRESSION_BC));
    let mut r = Renderer::new(gpu, store, CacheConfig::default()).unwrap();
    let layout = r.face_layout();
    assert_eq!(layout.encoding, Encoding::Rgb9e5);
    assert_eq!(layout.levels, mip_levels(res));
    every_mode(&mut r, "bc6h without BC");

    // Turned off on a device that has it: the same fallback.
    let gpu = Gpu::headless().unwrap().without_bc();
    assert!(!gpu.has_bc());
    let mut r = Renderer::new(gpu, open_bc6h(), CacheConfig::default()).unwrap();
    assert_eq!(r.face_layout(), layout);
    let cubes = StoreCubes::decode_as(r.store(), r.face_layout()).unwrap();
    check(
        &mut r,
        &cubes,
        Knobs {
            mode: Mode::ReconMirror,
            ..Default::default()
        },
        "bc6h turned off: recon-mirror",
    );
}

/// Relative RMS difference over object pixels, `sqrt(Σ(a−b)² / Σ b²)`.
fn relative_rms(a: &[[f32; 4]], b: &[[f32; 4]]) -> f64 {
    let (mut d, mut s) = (0f64, 0f64);
    for (p, q) in a.iter().zip(b) {
        assert_eq!(p[3], q[3], "object masks differ");
        if q[3] != 1.0 {
            continue;
        }
        for k in 0..3 {
            d += f64::from(p[k] - q[k]).powi(2);
            s += f64::from(q[k]).powi(2);
        }
    }
    (d / s.max(1e-30)).sqrt()
}

#[test]
fn bc6h_renders_close_to_rgb9e5() {
    let mut bc6h = Renderer::new(
        Gpu::headless().unwrap(),
        open_bc6h(),
        CacheConfig::default(),
    )
    .unwrap();
    let mut rgb9e5 = Renderer::new(
        Gpu::headless().unwrap(),
        open_store(),
        CacheConfig::default(),
    )
    .unwrap();
    let camera = rgb9e5.default_view();
    for mode in [Mode::Recon, Mode::Mirror, Mode::ReconMirror, Mode::Glossy] {
        let params = Knobs {
            mode,
            ..Default::default()
        };
        let a = bc6h
            .render(&camera, &params.params(), &options())
            .unwrap()
            .pixels;
        let b = rgb9e5
            .render(&camera, &params.params(), &options())
            .unwrap()
            .pixels;
        let rel = relative_rms(&a, &b);
        let (n, share, mae) = compare(&a, &b, 0.05);
        println!(
            "{}: bc6h vs rgb9e5 relative RMS {rel:.4}, {:.2}% of {n} pixels within 5%, mean |Δ| \
             {mae:.2e}, means {:.4} / {:.4}",
            mode.name(),
            share * 100.0,
            mean(&a),
            mean(&b)
        );
        assert!(rel < 0.05, "{}: relative RMS {rel}", mode.name());
        assert!((mean(&a) / mean(&b) - 1.0).abs() < 0.01, "{}", mode.name());
    }
}

#[test]
fn the_cache_counts_one_byte_per_texel_of_bc6h() {
    let gpu = Gpu::headless().unwrap();
    assert!(
        gpu.has_bc(),
        "{} has no BC texture compression",
        gpu.adapter_name
    );
    let store = open_bc6h();
    let res = store.cube_resolution() as usize;
    let depth = store.header().has_distance();
    let bc = FaceLayout::for_store(&store, true);
    let fallback = FaceLayout::for_store(&store, false);
    // Level 0: 1 byte per texel; then the 4² level (one block); then the f16 distances.
    assert_eq!(bc.level_bytes(0), res * res);
    let mips: usize = (1..bc.levels).map(|l| bc.side(l).pow(2) as usize).sum();
    let dist = if depth { 2 * res * res } else { 0 };
    assert_eq!(bc.payload_bytes(), res * res + mips + dist);
    assert_eq!(fallback.level_bytes(0), 4 * res * res);
    assert_eq!(cube_bytes(&store, true), 6 * bc.payload_bytes() as u64);
    assert_eq!(
        cube_bytes(&store, false),
        6 * fallback.payload_bytes() as u64
    );
    assert!(cube_bytes(&store, true) < cube_bytes(&store, false));
    let mb = 10.0 * cube_bytes(&store, true) as f64 / 1e6;
    assert_eq!(slots_for_megabytes(&store, mb, true).unwrap(), 10);
    assert!(slots_for_megabytes(&store, mb, false).unwrap() < 10);

    let ram_budget = 1 << 20;
    let mut r = Renderer::new(
        gpu,
        store,
        CacheConfig {
            ram_bytes: ram_budget,
            ..Default::default()
        },
    )
    .unwrap();
    assert_eq!(r.face_layout(), bc);
    let camera = r.default_view();
    let params = Knobs {
        mode: Mode::ReconMirror,
        ..Default::default()
    };
    r.render(&camera, &params.params(), &options()).unwrap();
    let s = &r.cache().cumulative;
    let payload = bc.payload_bytes() as u64;
    println!(
        "{} faces decoded, {} bytes ({} per face: {} of level 0 for {} texels)",
        s.ram_misses,
        s.bytes_decoded,
        payload,
        bc.level_bytes(0),
        res * res
    );
    assert!(s.ram_misses > 0);
    assert_eq!(s.bytes_decoded, s.ram_misses * payload);
    assert_eq!(s.bytes_uploaded % payload, 0);
    assert!(s.bytes_uploaded >= s.bytes_decoded);
    // The RAM level also holds the environment cube, loaded before the first frame's counters.
    let env_faces = 6 * u64::from(r.store().env_cube_index().is_some());
    assert_eq!(
        r.cache().ram_bytes_used(),
        (s.ram_misses + env_faces) * payload
    );
    assert!(r.cache().ram_bytes_used() <= ram_budget);
    r.gpu().take_errors().unwrap();
}
