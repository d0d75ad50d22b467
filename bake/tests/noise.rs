//! The noise estimate of the captured cubes: it falls as 1/√samples, it asks for
//! more samples per texel where the noise shows and not where it does not, and it leaves the
//! store as it was.

use std::path::PathBuf;
use std::sync::atomic::{AtomicU32, Ordering};

use oslf_bake::bake::{bake, BakeOptions, BakeReport};
use oslf_scene::scene::Scene;
use oslf_trace::noise::VISIBLE_RELATIVE_ERROR;

/// A fresh directory for one test, under Cargo's target tmp; the next run replaces it.
fn dir(test: &str) -> PathBuf {
    static NEXT: AtomicU32 = AtomicU32::new(0);
    let d = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!(
        "noise/{test}-{}",
        NEXT.fetch_add(1, Ordering::Relaxed)
    ));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// A sphere over a floor under a low sun and a sky, one bounce: the floor's light reflected
/// by the sphere and the sphere's by the floor arrive by random paths. Baked at
/// `samples_per_texel`; the report and the store's bytes.
fn bake_at(test: &str, samples_per_texel: u32) -> (BakeReport, Vec<u8>) {
    let d = dir(test);
    let text = format!(
        "[environment]\nuniform = [0.3, 0.4, 0.6]\n\n\
         [[directional_light]]\ndirection = [0.5, -0.3, 0.4]\nirradiance = [4.0, 4.0, 4.0]\n\n\
         [[box]]\nsize = [8.0, 8.0, 0.2]\ntransform = {{ translate = [0.0, 0.0, -0.1] }}\n\
         material = {{ color = [0.6, 0.6, 0.6] }}\n\n\
         [[object]]\nname = \"ball\"\nmesh = \"ball.obj\"\ntransform = {{ translate = [0.0, 0.0, 1.0] }}\n\
         material = {{ color = [0.5, 0.5, 0.5] }}\n\n\
         [bake]\nepsilon = 0.02\nsample_count = 24\nsample_map_resolution = 8\n\
         cube_resolution = 8\nsamples_per_texel = {samples_per_texel}\nbounces = 1\n"
    );
    std::fs::write(d.join("ball.obj"), octahedron()).unwrap();
    let path = d.join("scene.toml");
    std::fs::write(&path, text).unwrap();
    let scene = Scene::load(&path, None).unwrap_or_else(|e| panic!("{e}"));
    let output = d.join("ball.oslf");
    let options = BakeOptions {
        output: output.clone(),
        resume: false,
        progress: None,
        cube_limit: None,
        refuse_empty_texels: false,
        device: None,
    };
    let report = bake(&scene, &options).unwrap_or_else(|e| panic!("{e}"));
    (report, std::fs::read(&output).unwrap())
}

/// An octahedron of radius 0.5 (Wavefront OBJ, wound outwards).
fn octahedron() -> &'static str {
    "v 0.5 0 0\nv -0.5 0 0\nv 0 0.5 0\nv 0 -0.5 0\nv 0 0 0.5\nv 0 0 -0.5\n\
     f 1 3 5\nf 3 2 5\nf 2 4 5\nf 4 1 5\nf 3 1 6\nf 2 3 6\nf 4 2 6\nf 1 4 6\n"
}

fn error(report: &BakeReport) -> f64 {
    let noise = report.noise.as_ref().expect("a noise report");
    assert!(noise.texels > 0, "{noise:?}");
    noise.relative_error.expect("an estimate")
}

#[test]
fn four_samples_per_texel_get_a_hint_that_256_do_not_need() {
    let (few, _) = bake_at("few", 4);
    let noise = few.noise.as_ref().unwrap();
    assert!(error(&few) > VISIBLE_RELATIVE_ERROR, "{noise:?}");
    let s = noise.suggestion.as_ref().expect("a suggestion");
    // 4× the samples halve the noise; enough of them bring it under the visible level.
    assert_eq!(s.samples_per_texel, 16, "{s:?}");
    assert!(
        (s.expected_relative_error * 2.0 - error(&few)).abs() < 1e-12,
        "{s:?}"
    );
    let enough = s.samples_per_texel_below_visible;
    assert!((16..=256).contains(&enough), "{s:?}");
    assert!(
        error(&few) * (4.0 / f64::from(enough)).sqrt() <= VISIBLE_RELATIVE_ERROR,
        "{s:?}"
    );
    // What the preflight says the capture costs, times the samples' factor.
    let factor = 4.0;
    assert!(s.capture_seconds_now.0 > 0.0, "{s:?}");
    assert!(
        (s.capture_seconds.1 / s.capture_seconds_now.1 - factor).abs() < 1e-9,
        "{s:?}"
    );
    assert!(s.total_seconds.1 >= s.capture_seconds.1, "{s:?}");

    let (many, _) = bake_at("many", 256);
    let noise = many.noise.as_ref().unwrap();
    assert!(error(&many) < VISIBLE_RELATIVE_ERROR, "{noise:?}");
    assert_eq!(noise.suggestion, None);
}

#[test]
fn the_estimate_falls_as_one_over_the_square_root_of_the_samples() {
    let (four, _) = bake_at("four", 4);
    let (sixty_four, _) = bake_at("sixty-four", 64);
    let ratio = error(&four) / error(&sixty_four);
    // 16× the samples: a quarter of the error.
    assert!((ratio - 4.0).abs() < 0.8, "{ratio}");
}

#[test]
fn one_sample_per_texel_gives_no_estimate_and_the_store_is_the_same_with_it() {
    let (one, _) = bake_at("one", 1);
    let noise = one.noise.as_ref().unwrap();
    assert_eq!((noise.texels, noise.relative_error), (0, None), "{noise:?}");
    assert_eq!(noise.suggestion, None);
    // Deterministic: the same store twice (the estimate reads the samples, writes nothing).
    let (_, a) = bake_at("same-a", 4);
    let (_, b) = bake_at("same-b", 4);
    assert_eq!(a, b);
}
