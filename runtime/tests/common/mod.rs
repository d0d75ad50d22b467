//! A small store baked once per test binary, and image comparisons.
#![allow(dead_code)] // each test binary uses its own part

pub mod knobs;
use knobs::Knobs;

use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use oslf_bake::bake::{bake, BakeOptions};
use oslf_scene::scene::Scene;

/// The teapot on a checkered table beside a wall, under a point light and a uniform sky
/// (tests/fixtures/teapot.toml), at toy resolutions: small enough to bake in a second, rich
/// enough that every shading term differs from the others.
pub const SCENE: &str = concat!(
    include_str!("../../../tests/fixtures/teapot.toml"),
    r#"
[bake]
epsilon = 0.1
sample_count = 120
cube_resolution = 8
sample_map_resolution = 16
samples_per_texel = 1
bounces = 1
seed = 3
"#
);

/// The path of the baked test store (baked on first use).
pub fn store_path() -> PathBuf {
    static PATH: OnceLock<PathBuf> = OnceLock::new();
    PATH.get_or_init(|| bake_scene(SCENE, "oslf-runtime-tests"))
        .clone()
}

/// The path of [`SCENE`] baked without the environment cube (baked on first use).
pub fn store_path_without_env_cube() -> PathBuf {
    static PATH: OnceLock<PathBuf> = OnceLock::new();
    // SCENE ends in its [bake] table.
    PATH.get_or_init(|| {
        bake_scene(
            &format!("{SCENE}env_cube = false\n"),
            "oslf-runtime-tests-no-env",
        )
    })
    .clone()
}

/// The path of [`SCENE`] baked without the distance channel (baked on first use): a store as
/// they were before depth-corrected lookups.
pub fn store_path_without_distances() -> PathBuf {
    static PATH: OnceLock<PathBuf> = OnceLock::new();
    PATH.get_or_init(|| {
        bake_scene(
            &format!("{SCENE}distance_channel = false\n"),
            "oslf-runtime-tests-no-distance",
        )
    })
    .clone()
}

/// The path of [`SCENE`] baked with BC6H cube maps (`encoding = "bc6h"`, format v4; baked on
/// first use). Its 8² faces are whole 4×4 blocks.
pub fn store_path_bc6h() -> PathBuf {
    static PATH: OnceLock<PathBuf> = OnceLock::new();
    PATH.get_or_init(|| {
        bake_scene(
            &format!("{SCENE}encoding = \"bc6h\"\n"),
            "oslf-runtime-tests-bc6h",
        )
    })
    .clone()
}

/// Bakes `scene` into the directory `name`, made afresh under this test binary's directory in
/// Cargo's target tmp: the stores outlive the tests that share them (statics are never dropped)
/// and the next run replaces them rather than adding more.
fn bake_scene(scene: &str, name: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join(env!("CARGO_CRATE_NAME"))
        .join(name);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let scene_path = dir.join("scene.toml");
    std::fs::write(&scene_path, scene).unwrap();
    let scene = Scene::load(&scene_path, None).unwrap();
    let output = dir.join("teapot.oslf");
    let options = BakeOptions {
        output: output.clone(),
        resume: false,
        progress: None,
        cube_limit: None,
        refuse_empty_texels: false,
        device: None,
    };
    bake(&scene, &options).unwrap();
    output
}

pub fn open_store() -> oslf_format::Store {
    oslf_format::Store::open(&store_path()).unwrap()
}

/// Compares two images over the pixels where `a` has alpha 1. Returns (object pixels, share
/// of them within `tol` relative (of max(1, |reference|)), mean absolute difference).
pub fn compare(gpu: &[[f32; 4]], cpu: &[[f32; 4]], tol: f32) -> (usize, f64, f64) {
    assert_eq!(gpu.len(), cpu.len());
    let (mut n, mut ok, mut sum) = (0usize, 0usize, 0f64);
    for (g, c) in gpu.iter().zip(cpu) {
        assert_eq!(g[3], c[3], "object masks differ");
        if c[3] != 1.0 {
            continue;
        }
        n += 1;
        let mut good = true;
        for k in 0..3 {
            let d = (g[k] - c[k]).abs();
            sum += f64::from(d);
            if d > tol * c[k].abs().max(1.0) {
                good = false;
            }
        }
        ok += usize::from(good);
    }
    (n, ok as f64 / n.max(1) as f64, sum / (3 * n.max(1)) as f64)
}

/// Mean of the colour channels over object pixels.
pub fn mean(img: &[[f32; 4]]) -> f64 {
    let (mut s, mut n) = (0f64, 0usize);
    for p in img.iter().filter(|p| p[3] == 1.0) {
        s += f64::from(p[0] + p[1] + p[2]) / 3.0;
        n += 1;
    }
    s / n.max(1) as f64
}

/// Every channel of every pixel finite.
pub fn all_finite(img: &[[f32; 4]]) -> bool {
    img.iter().all(|p| p.iter().all(|c| c.is_finite()))
}

/// Renders `params` at `width`×`height` on the GPU and on the CPU reference (from the same
/// G-buffer, with `cubes`); asserts agreement: 99.5 % of the object's pixels within 2e-3, mean
/// difference below 2e-3, the object covering a tenth of the frame, the image not black.
pub fn check_parity(
    renderer: &mut oslf_runtime::Renderer,
    cubes: &oslf_runtime::reference::StoreCubes,
    params: Knobs,
    (width, height): (u32, u32),
    label: &str,
) -> Vec<[f32; 4]> {
    let options = oslf_runtime::RenderOptions {
        width,
        height,
        ..Default::default()
    };
    let camera = renderer.default_view();
    let frame = renderer
        .render(&camera, &params.params(), &options)
        .unwrap();
    assert_eq!(
        frame.stats.unresolved, 0,
        "{label}: budget holds everything"
    );
    // The passes are timed on the GPU exactly where the device has timestamp queries.
    for timed in [frame.shade_gpu_seconds, frame.gbuffer_gpu_seconds] {
        assert_eq!(timed.is_some(), renderer.gpu().has_timestamps(), "{label}");
        assert!(
            timed.is_none_or(|s| s > 0.0 && s.is_finite()),
            "{label}: {timed:?}"
        );
    }
    let (cpu, _) = renderer
        .reference_image(&camera, &params.params(), cubes)
        .unwrap();
    assert!(all_finite(&frame.pixels), "{label}: non-finite GPU pixel");
    assert!(all_finite(&cpu), "{label}: non-finite CPU pixel");
    let (n, share, mae) = compare(&frame.pixels, &cpu, 2e-3);
    println!(
        "{label}: {n} object pixels, {:.4}% within 2e-3, mean |gpu-cpu| {mae:.2e}, mean {:.4}",
        share * 100.0,
        mean(&cpu)
    );
    assert!(
        n > (width * height / 10) as usize,
        "{label}: the object covers {n} pixels"
    );
    assert!(mean(&cpu) > 1e-3, "{label}: the image is black");
    assert!(
        share >= 0.995,
        "{label}: only {:.3}% of pixels agree",
        share * 100.0
    );
    assert!(mae < 2e-3, "{label}: mean difference {mae}");
    frame.pixels
}

/// The glossy cases every parity test covers, as (params, label): every integration order with
/// an isotropic and an anisotropic lobe (M = 8), then recon + C_s glossy with a diffuse term.
pub fn glossy_cases(base: Knobs) -> Vec<(Knobs, String)> {
    use oslf_runtime::{Mode, Order};
    let mut cases = Vec::new();
    for order in Order::ALL {
        for (nu, nv) in [(10.0, 10.0), (1000.0, 10.0)] {
            let p = Knobs {
                mode: Mode::Glossy,
                order,
                nu,
                nv,
                m: 8,
                ..base
            };
            cases.push((p, format!("glossy {order:?} n_u={nu} n_v={nv}")));
        }
    }
    let p = Knobs {
        mode: Mode::ReconGlossy,
        rs: 0.3,
        rd: 0.5,
        m: 4,
        ..base
    };
    cases.push((p, "recon + C_s glossy with diffuse term".into()));
    // glTF's metallic-roughness: a metal (specular only), a dielectric (with its diffuse
    // base) per direction, and a near-mirror blend of the two.
    for (metallic, roughness, order) in [
        (1.0, 0.3, Order::PerPoint),
        (0.0, 0.6, Order::PerDirection),
        (0.5, 0.05, Order::PerPoint),
        (1.0, 0.3, Order::PerPointVisible),
        (1.0, 0.3, Order::PerPointSearched),
    ] {
        let p = Knobs {
            mode: Mode::Pbr,
            order,
            metallic,
            roughness,
            m: 8,
            ..base
        };
        cases.push((
            p,
            format!("pbr {order:?} metallic {metallic} roughness {roughness}"),
        ));
    }
    // Every blend, with depth-corrected and with plain lookups.
    for (i, blend) in oslf_runtime::Blend::ALL.into_iter().enumerate() {
        let p = Knobs {
            mode: Mode::Pbr,
            metallic: 0.5,
            roughness: 0.3,
            depth: i % 2 == 0,
            blend,
            m: 4,
            ..base
        };
        cases.push((p, format!("pbr {blend:?}, depth {}", p.depth)));
    }
    cases
}
