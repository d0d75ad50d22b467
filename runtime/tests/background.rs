//! Backgrounds (`RenderOptions::background`): off the object a frame shows transparent black,
//! the environment cube along each pixel's camera ray, or a colour, always with alpha 0, the
//! same on the GPU as in the CPU reference; and a typed error for the environment cube of a
//! store that has none.

use crate::common;
use crate::common::knobs::Knobs;

use common::{all_finite, compare, open_store, store_path_without_env_cube};
use glam::Vec3;
use oslf_runtime::reference::StoreCubes;
use oslf_runtime::{
    Background, CacheConfig, Camera, Frame, Gpu, Mode, RenderOptions, Renderer, RuntimeError,
};

const W: u32 = 96;
const H: u32 = 72;
const COLOR: [f32; 3] = [0.25, 0.5, 2.0];

fn options(background: Background) -> RenderOptions {
    RenderOptions {
        width: W,
        height: H,
        background,
        ..Default::default()
    }
}

/// The background pixels (alpha 0) of an image.
fn background(img: &[[f32; 4]]) -> Vec<[f32; 4]> {
    img.iter().copied().filter(|p| p[3] == 0.0).collect()
}

/// Compares two images over the pixels where both have alpha 0. Returns (background pixels,
/// share of them within `tol` relative (of max(1, |cpu|)), mean absolute difference).
fn compare_background(gpu: &[[f32; 4]], cpu: &[[f32; 4]], tol: f32) -> (usize, f64, f64) {
    let (gpu, cpu) = (background(gpu), background(cpu));
    assert_eq!(gpu.len(), cpu.len(), "background masks differ");
    let (mut ok, mut sum) = (0usize, 0f64);
    for (g, c) in gpu.iter().zip(&cpu) {
        let mut good = true;
        for k in 0..3 {
            let d = (g[k] - c[k]).abs();
            sum += f64::from(d);
            good &= d <= tol * c[k].abs().max(1.0);
        }
        ok += usize::from(good);
    }
    let n = cpu.len();
    (n, ok as f64 / n.max(1) as f64, sum / (3 * n.max(1)) as f64)
}

/// Renders `params` with `bg` on the GPU and on the CPU from the same G-buffer; asserts that
/// object and background agree and that no pixel is non-finite. Returns the GPU frame.
fn check(
    r: &mut Renderer,
    cubes: &StoreCubes,
    params: Knobs,
    bg: Background,
    label: &str,
) -> Frame {
    let camera = r.default_view();
    let frame = r.render(&camera, &params.params(), &options(bg)).unwrap();
    let (cpu, _) = r.reference_image(&camera, &params.params(), cubes).unwrap();
    assert!(all_finite(&frame.pixels), "{label}: non-finite GPU pixel");
    assert!(all_finite(&cpu), "{label}: non-finite CPU pixel");
    assert!(
        frame.pixels.iter().all(|p| p[3] == 0.0 || p[3] == 1.0),
        "{label}: alpha is not a mask"
    );
    let (n, share, mae) = compare(&frame.pixels, &cpu, 2e-3);
    assert!(n > (W * H / 10) as usize, "{label}: the object covers {n}");
    assert!(
        share >= 0.995 && mae < 2e-3,
        "{label}: object {share} {mae}"
    );
    let (n, share, mae) = compare_background(&frame.pixels, &cpu, 2e-3);
    println!(
        "{label}: {n} background pixels, {:.4}% within 2e-3, mean |gpu-cpu| {mae:.2e}",
        share * 100.0
    );
    assert!(n > (W * H / 10) as usize, "{label}: {n} background pixels");
    assert!(
        share >= 0.995,
        "{label}: only {:.3}% of background pixels agree",
        share * 100.0
    );
    assert!(mae < 2e-3, "{label}: mean background difference {mae}");
    frame
}

#[test]
fn env_and_colour_backgrounds_match_the_cpu_reference() {
    let store = open_store();
    let cubes = StoreCubes::decode(&store).unwrap();
    let mut r = Renderer::new(Gpu::headless().unwrap(), store, CacheConfig::default()).unwrap();
    let base = Knobs::default();
    for params in [
        base,
        Knobs {
            mode: Mode::Glossy,
            m: 4,
            ..base
        },
    ] {
        let mode = params.mode.name();
        let env = check(
            &mut r,
            &cubes,
            params,
            Background::Env,
            &format!("{mode} env"),
        );
        let sky = background(&env.pixels);
        let lit = sky.iter().filter(|p| p[0] + p[1] + p[2] > 0.0).count();
        assert!(
            lit * 100 >= sky.len() * 99,
            "{mode}: {lit} of {} environment background pixels are non-black",
            sky.len()
        );
        let colour = check(
            &mut r,
            &cubes,
            params,
            Background::Color(COLOR),
            &format!("{mode} colour"),
        );
        for p in background(&colour.pixels) {
            assert_eq!(p, [COLOR[0], COLOR[1], COLOR[2], 0.0], "{mode}");
        }
        let none = check(
            &mut r,
            &cubes,
            params,
            Background::None,
            &format!("{mode} none"),
        );
        for p in background(&none.pixels) {
            assert_eq!(p, [0.0; 4], "{mode}");
        }
    }
}

/// Views whose backgrounds cross edges (vertical and horizontal in the image) and corners of
/// the environment cube, where the background filters across faces: the GPU matches the CPU
/// reference there too.
#[test]
fn env_backgrounds_across_face_edges_and_corners_match_the_cpu_reference() {
    let store = open_store();
    let cubes = StoreCubes::decode(&store).unwrap();
    let count = store.cube_count();
    // One pool array, and the pool spread over four (faces of one cube in several arrays).
    for (label, config) in [
        ("one array", CacheConfig::default()),
        (
            "four arrays",
            CacheConfig {
                slots_per_texture: Some(count.div_ceil(4)),
                ..Default::default()
            },
        ),
    ] {
        let mut r = Renderer::new(Gpu::headless().unwrap(), open_store(), config).unwrap();
        views(&mut r, &cubes, label);
    }
}

/// Renders the views of `env_backgrounds_across_face_edges_and_corners_match_the_cpu_reference`.
fn views(r: &mut Renderer, cubes: &StoreCubes, label: &str) {
    let params = Knobs::default();
    // The default view's position, looking away from the object.
    let position = r.default_view().position;
    for (dir, up) in [
        (Vec3::new(1.0, 1.0, 1.0), Vec3::Z),
        (Vec3::new(-1.0, -1.0, 1.0), Vec3::Z),
        (Vec3::new(1.0, -1.0, 0.1), Vec3::Z),
        (Vec3::new(0.1, -1.0, 1.0), Vec3::X),
        (Vec3::new(1.0, 0.05, 1.0), Vec3::Y),
    ] {
        let camera = Camera {
            position,
            target: position + dir,
            up,
            vfov_deg: 60.0,
        };
        let frame = r
            .render(&camera, &params.params(), &options(Background::Env))
            .unwrap();
        let (cpu, _) = r.reference_image(&camera, &params.params(), cubes).unwrap();
        assert!(
            all_finite(&frame.pixels) && all_finite(&cpu),
            "{label} {dir}"
        );
        let (n, share, mae) = compare_background(&frame.pixels, &cpu, 2e-3);
        println!(
            "{label} {dir}: {n} background pixels, {:.4}% within 2e-3, mean |gpu-cpu| {mae:.2e}",
            share * 100.0
        );
        assert!(
            n > (W * H / 2) as usize,
            "{label} {dir}: {n} background pixels"
        );
        assert!(share >= 0.995 && mae < 2e-3, "{label} {dir}: {share} {mae}");
    }
}

#[test]
fn the_background_changes_neither_the_object_nor_the_mask_nor_the_cache_counters() {
    let mut r = Renderer::new(
        Gpu::headless().unwrap(),
        open_store(),
        CacheConfig::default(),
    )
    .unwrap();
    let camera = r.default_view();
    let params = Knobs::default();
    let frames: Vec<Frame> = [
        Background::None,
        Background::Env,
        Background::Color(COLOR),
        Background::None,
    ]
    .into_iter()
    .map(|bg| r.render(&camera, &params.params(), &options(bg)).unwrap())
    .collect();
    let none = &frames[0];
    assert!(
        none.pixels.iter().any(|p| p[3] == 0.0),
        "the view shows some background"
    );
    for f in &frames[1..] {
        for (a, b) in none.pixels.iter().zip(&f.pixels) {
            assert_eq!(a[3], b[3], "the object mask changed");
            if a[3] == 1.0 {
                assert_eq!(a, b, "an object pixel changed");
            }
        }
        assert_eq!(f.stats.requests, frames[3].stats.requests);
        assert_eq!(f.stats.misses, 0);
    }
    let env = background(&frames[1].pixels);
    assert!(env.iter().all(|p| p[3] == 0.0));
    assert!(
        env.iter().any(|p| p[0] + p[1] + p[2] > 0.0),
        "the environment background is black"
    );
}

/// A frame shows nothing of the previous one: the G-buffer pass clears only depth, and the
/// shading pass and `read_gbuffer` take a pixel as covered by its depth, not by the colour
/// targets, which keep the last view's texels where nothing covers them now. After a close
/// view, a far one matches a fresh renderer's bit for bit, image and G-buffer.
#[test]
fn a_frame_keeps_nothing_of_the_previous_view() {
    let new = || {
        Renderer::new(
            Gpu::headless().unwrap(),
            open_store(),
            CacheConfig::default(),
        )
        .unwrap()
    };
    let mut r = new();
    let near = r.default_view();
    let far = Camera {
        position: near.target + (near.position - near.target) * 3.0,
        ..near
    };
    let params = Knobs::default();
    let opts = options(Background::None);
    let first = r.render(&near, &params.params(), &opts).unwrap();
    let second = r.render(&far, &params.params(), &opts).unwrap();
    let mut fresh = new();
    let alone = fresh.render(&far, &params.params(), &opts).unwrap();
    let covered = |f: &Frame| f.pixels.iter().filter(|p| p[3] == 1.0).count();
    assert!(
        covered(&first) > 2 * covered(&alone),
        "the far view shows the object smaller: {} against {} pixels",
        covered(&first),
        covered(&alone)
    );
    assert!(
        second.pixels == alone.pixels,
        "the far view differs after the near one"
    );
    let (a, b) = (r.read_gbuffer().unwrap(), fresh.read_gbuffer().unwrap());
    assert!(
        a.iter()
            .zip(&b)
            .all(|(a, b)| a.position_patch == b.position_patch && a.normal_uv == b.normal_uv),
        "the G-buffer keeps texels of the near view"
    );
}

#[test]
fn an_env_background_without_an_environment_cube_is_a_parameter_error() {
    let store = oslf_format::Store::open(&store_path_without_env_cube()).unwrap();
    assert_eq!(store.env_cube_index(), None);
    let mut r = Renderer::new(Gpu::headless().unwrap(), store, CacheConfig::default()).unwrap();
    let camera = r.default_view();
    let params = Knobs::default();
    match r.render(&camera, &params.params(), &options(Background::Env)) {
        Err(RuntimeError::Parameter(m)) => assert!(m.contains("no environment cube"), "{m}"),
        other => panic!("expected a parameter error, got {other:?}"),
    }
    let colour = r
        .render(
            &camera,
            &params.params(),
            &options(Background::Color(COLOR)),
        )
        .unwrap();
    let bg = background(&colour.pixels);
    assert!(!bg.is_empty());
    assert!(bg.iter().all(|p| *p == [COLOR[0], COLOR[1], COLOR[2], 0.0]));
    for bad in [
        [-1.0, 0.0, 0.0],
        [f32::NAN, 0.0, 0.0],
        [0.0, f32::INFINITY, 0.0],
    ] {
        let e = r
            .render(&camera, &params.params(), &options(Background::Color(bad)))
            .unwrap_err();
        assert!(matches!(e, RuntimeError::Parameter(_)), "{e:?}");
    }
}
