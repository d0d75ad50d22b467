//! Extremes the renderer must hold: 32-bit sample-map indices (more than 65 535 sample
//! points, many more cubes than GPU slots), 1² and 2² cube maps, 1² sample maps, HDR radiance
//! from 0 and 1e-20 up to the RGB9E5 maximum, and, baked, stored and rendered, 2048² cube maps
//! and 4096² sample maps.

use crate::common;
use crate::common::knobs::Knobs;

use common::{all_finite, compare, mean};
use oslf_format::{
    encode_cube, BakeParams, CubeImage, Encoding, IndexWidth, ObjectInfo, Patch, SampleMaps,
    SamplePoint, Store, StoreMeta, StoreWriter,
};
use oslf_runtime::reference::StoreCubes;
use oslf_runtime::{CacheConfig, Gpu, Mode, RenderOptions, Renderer};
use std::path::{Path, PathBuf};

/// A flat unit patch facing +z with `points` sample points ε above it, 1² cube
/// maps whose six texels span 0 … 6.5e4, and `map_res`² sample maps of pseudo-random
/// indices.
fn synthetic_store(dir: &Path, points: usize, map_res: u32) -> PathBuf {
    synthetic_store_with(dir, points, map_res, 1)
}

/// [`synthetic_store`] with `cube_res`² cube maps: texel `i` of a face holds the face's value
/// times `1 + i` (so neighbouring texels differ and a wrong texel shows).
fn synthetic_store_with(dir: &Path, points: usize, map_res: u32, cube_res: u32) -> PathBuf {
    let mut state = 0x2545_f491_4f6c_dd1du64;
    let mut next = move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        state
    };
    let eps = 0.01f32;
    let patch = Patch {
        // u along y, v along x: the normal ∂x/∂v × ∂x/∂u is +z.
        control_points: std::array::from_fn(|k| [(k % 4) as f32 / 3.0, (k / 4) as f32 / 3.0, 0.0]),
    };
    let meta = StoreMeta {
        objects: vec![ObjectInfo {
            name: "plane".into(),
            transform: [
                [1.0, 0.0, 0.0, 0.0],
                [0.0, 1.0, 0.0, 0.0],
                [0.0, 0.0, 1.0, 0.0],
                [0.0, 0.0, 0.0, 1.0],
            ],
            base_color: [0.5, 0.5, 0.5],
            first_patch: 0,
            patch_count: 1,
            mesh: None,
            material: Default::default(),
            textures: None,
        }],
        patches: vec![patch],
        bake: BakeParams {
            epsilon: eps,
            cube_resolution: cube_res,
            sample_map_resolution: map_res,
            samples_per_texel: 1,
            encoding: Encoding::Rgb9e5,
            ..Default::default()
        },
        camera: None,
        has_env_cube: true,
    };
    let sample_points: Vec<SamplePoint> = (0..points)
        .map(|_| {
            let (u, v) = (
                (next() % 10_000) as f32 / 1e4,
                (next() % 10_000) as f32 / 1e4,
            );
            SamplePoint {
                position: [v, u, eps],
                normal: [0.0, 0.0, 1.0],
                uv: [u, v],
                patch: 0,
                object: 0,
            }
        })
        .collect();
    let maps = SampleMaps {
        resolution: map_res,
        indices: (0..map_res * map_res)
            .map(|_| std::array::from_fn(|_| (next() % points as u64) as u32))
            .collect(),
    };
    let path = dir.join(format!("synthetic-{points}-{map_res}-{cube_res}.oslf"));
    let mut w = StoreWriter::create(&path, &meta, &sample_points, &maps).unwrap();
    let values = [0.0f32, 1e-20, 0.5, 3.0, 6.5e4, 1e-3];
    for cube in 0..=points as u32 {
        let mut image = CubeImage::black(cube_res, false);
        for (f, face) in image.faces.iter_mut().enumerate() {
            let v = values[(f + cube as usize) % values.len()];
            for (i, t) in face.iter_mut().enumerate() {
                let v = (v * (1 + i) as f32).min(6.5e4);
                *t = [v, v * 0.5, v * 0.25];
            }
        }
        let (encoded, _) = encode_cube(&image, &meta.bake, cube).unwrap();
        w.append(encoded).unwrap();
    }
    w.finish().unwrap();
    path
}

#[test]
fn more_than_65535_sample_points_with_one_texel_cube_maps_and_a_small_cache() {
    let tmp = tempfile::tempdir().unwrap();
    let path = synthetic_store(tmp.path(), 70_000, 64);
    let store = Store::open(&path).unwrap();
    assert_eq!(store.index_width(), IndexWidth::U32);
    let cubes = StoreCubes::decode(&store).unwrap();
    let config = CacheConfig {
        gpu_slots: Some(300),
        ..Default::default()
    };
    let mut r = Renderer::new(Gpu::headless().unwrap(), store, config).unwrap();
    let camera = r.default_view();
    let opts = RenderOptions {
        width: 64,
        height: 48,
        ..Default::default()
    };
    for mode in [Mode::Recon, Mode::ReconMirror, Mode::Glossy] {
        let params = Knobs {
            mode,
            m: 4,
            ..Default::default()
        };
        let frame = r.render(&camera, &params.params(), &opts).unwrap();
        assert!(all_finite(&frame.pixels), "{mode:?}");
        let mut resident = StoreCubes::decode(r.store()).unwrap();
        resident.masks = Some(r.cache().indirection());
        let (cpu, _) = r
            .reference_image(&camera, &params.params(), &resident)
            .unwrap();
        let (n, share, _) = compare(&frame.pixels, &cpu, 2e-3);
        println!(
            "{mode:?}: {n} pixels, {share} agree, mean {}, {:?}",
            mean(&cpu),
            frame.stats
        );
        assert!(n > 100, "{mode:?}: the plane covers {n} pixels");
        assert!(share >= 0.995, "{mode:?}: {share}");
        assert!(mean(&cpu) > 0.0, "{mode:?}: black");
        // With every cube available the reference is finite too.
        let (full, _) = r
            .reference_image(&camera, &params.params(), &cubes)
            .unwrap();
        assert!(all_finite(&full));
    }
}

#[test]
fn one_texel_sample_maps_render() {
    let tmp = tempfile::tempdir().unwrap();
    let path = synthetic_store(tmp.path(), 50, 1);
    let store = Store::open(&path).unwrap();
    assert_eq!(store.index_width(), IndexWidth::U16);
    let cubes = StoreCubes::decode(&store).unwrap();
    let mut r = Renderer::new(Gpu::headless().unwrap(), store, CacheConfig::default()).unwrap();
    let camera = r.default_view();
    let opts = RenderOptions {
        width: 48,
        height: 32,
        ..Default::default()
    };
    let params = Knobs::default();
    let frame = r.render(&camera, &params.params(), &opts).unwrap();
    let (cpu, _) = r
        .reference_image(&camera, &params.params(), &cubes)
        .unwrap();
    let (n, share, _) = compare(&frame.pixels, &cpu, 2e-3);
    assert!(n > 50 && share >= 0.995, "{n} {share}");
}

/// The teapot alone under a uniform sky and a point light, translated by `t`, with the camera
/// and the light moved along: the same picture wherever it is.
fn teapot_store(dir: &Path, name: &str, t: [f64; 3], seed: u64) -> PathBuf {
    let text = format!(
        r#"
[camera]
position = [{cx:?}, {cy:?}, {cz:?}]
target = [{tx:?}, {ty:?}, {tz:?}]
vfov = 36.0

[environment]
uniform = [0.6, 0.7, 0.9]

[[point_light]]
position = [{lx:?}, {ly:?}, {lz:?}]
intensity = [40.0, 38.0, 35.0]

[[object]]
patches = "newell-teapot"
select = [0, 28]
transform = {{ translate = [{ox:?}, {oy:?}, {oz:?}] }}
material = {{ color = [0.1, 0.42, 0.12] }}

[bake]
epsilon = 0.1
sample_count = 150
cube_resolution = 8
sample_map_resolution = 16
samples_per_texel = 1
bounces = 1
seed = {seed}
"#,
        cx = t[0] + 5.5,
        cy = t[1] - 6.5,
        cz = t[2] + 4.5,
        tx = t[0],
        ty = t[1],
        tz = t[2] + 1.0,
        lx = t[0] + 3.0,
        ly = t[1] - 2.0,
        lz = t[2] + 6.0,
        ox = t[0],
        oy = t[1],
        oz = t[2],
    );
    let scene_path = dir.join(format!("{name}.toml"));
    std::fs::write(&scene_path, text).unwrap();
    let scene = oslf_scene::scene::Scene::load(&scene_path, None).unwrap();
    let output = dir.join(format!("{name}.oslf"));
    let options = oslf_bake::bake::BakeOptions {
        output: output.clone(),
        resume: false,
        progress: None,
        cube_limit: None,
        refuse_empty_texels: false,
        device: None,
    };
    oslf_bake::bake::bake(&scene, &options).unwrap();
    output
}

/// Renders `path` from its camera on the GPU, checks it against the CPU reference, and returns
/// the GPU image.
fn render_checked(path: &Path, params: &Knobs, w: u32, h: u32) -> Vec<[f32; 4]> {
    let store = Store::open(path).unwrap();
    let cubes = StoreCubes::decode(&store).unwrap();
    let mut r = Renderer::new(Gpu::headless().unwrap(), store, CacheConfig::default()).unwrap();
    let camera = r.default_view();
    let opts = RenderOptions {
        width: w,
        height: h,
        ..Default::default()
    };
    let frame = r.render(&camera, &params.params(), &opts).unwrap();
    let (cpu, _) = r
        .reference_image(&camera, &params.params(), &cubes)
        .unwrap();
    assert!(all_finite(&frame.pixels) && all_finite(&cpu));
    let (n, share, diff) = compare(&frame.pixels, &cpu, 2e-3);
    println!(
        "{}: {:?}: {n} pixels, GPU = CPU on {share}, mean difference {diff:.2e}",
        path.display(),
        params.mode
    );
    assert!(n > 200, "{n}");
    assert!(share >= 0.995 && diff < 2e-3, "{share} {diff}");
    frame.pixels
}

/// Share of pixels (object in both) whose channels differ by at most 0.02, and the mean of
/// the largest channel difference.
fn agreement(a: &[[f32; 4]], b: &[[f32; 4]]) -> (f64, f64) {
    let (mut n, mut close, mut sum) = (0usize, 0usize, 0f64);
    for (p, q) in a.iter().zip(b) {
        if p[3] != 1.0 || q[3] != 1.0 {
            continue;
        }
        n += 1;
        let d = (0..3).map(|k| (p[k] - q[k]).abs()).fold(0f32, f32::max);
        sum += f64::from(d);
        close += usize::from(d <= 0.02);
    }
    (close as f64 / n.max(1) as f64, sum / n.max(1) as f64)
}

#[test]
fn a_teapot_far_from_the_origin_renders_as_at_the_origin() {
    // Before object-relative coordinates the far G-buffer covered 1844 pixels against 1842.
    let tmp = tempfile::tempdir().unwrap();
    let near = teapot_store(tmp.path(), "near", [0.0; 3], 3);
    let reseeded = teapot_store(tmp.path(), "reseeded", [0.0; 3], 4);
    let far = teapot_store(tmp.path(), "far", [1e5, -1e5, 1e5], 3);
    for mode in [Mode::Recon, Mode::ReconMirror] {
        let params = Knobs {
            mode,
            ..Default::default()
        };
        let a = render_checked(&near, &params, 96, 72);
        let b = render_checked(&far, &params, 96, 72);
        let c = render_checked(&reseeded, &params, 96, 72);
        let mask = |img: &[[f32; 4]]| img.iter().map(|p| p[3]).collect::<Vec<_>>();
        assert_eq!(
            mask(&a),
            mask(&b),
            "{mode:?}: the object covers other pixels"
        );
        // The far bake's points and hits are rounded to 0.0078 (so its sample points are not
        // the near bake's): it must agree with the near one as well as a bake with another
        // seed does (the Monte Carlo noise of 1 sample per texel).
        let (far_close, far_diff) = agreement(&a, &b);
        let (seed_close, seed_diff) = agreement(&a, &c);
        println!(
            "{mode:?}: far vs near: {far_close:.4} within 0.02, mean {far_diff:.4}; another seed: {seed_close:.4}, mean {seed_diff:.4}"
        );
        assert!(far_diff <= seed_diff * 1.25, "{mode:?}");
    }
}

#[test]
fn two_texel_cube_maps_render() {
    // 2² faces: every bilinear tap sits on a face edge, where lookups clamp.
    let tmp = tempfile::tempdir().unwrap();
    let path = synthetic_store_with(tmp.path(), 50, 4, 2);
    let store = Store::open(&path).unwrap();
    assert_eq!(store.cube_resolution(), 2);
    let cubes = StoreCubes::decode(&store).unwrap();
    let mut r = Renderer::new(Gpu::headless().unwrap(), store, CacheConfig::default()).unwrap();
    let camera = r.default_view();
    let opts = RenderOptions {
        width: 48,
        height: 32,
        ..Default::default()
    };
    for mode in [Mode::Recon, Mode::Mirror, Mode::ReconMirror] {
        let params = Knobs {
            mode,
            ..Default::default()
        };
        let frame = r.render(&camera, &params.params(), &opts).unwrap();
        let (cpu, _) = r
            .reference_image(&camera, &params.params(), &cubes)
            .unwrap();
        assert!(all_finite(&frame.pixels) && all_finite(&cpu), "{mode:?}");
        let (n, share, diff) = compare(&frame.pixels, &cpu, 2e-3);
        println!(
            "2² cube maps, {mode:?}: {n} pixels, GPU = CPU on {share}, mean difference {diff:.2e}"
        );
        assert!(
            n > 50 && share >= 0.995 && diff < 2e-3,
            "{mode:?}: {n} {share} {diff}"
        );
        assert!(mean(&cpu) > 0.0, "{mode:?}: black");
    }
}

/// Bakes the scene `text` (relative paths resolve against the test's temporary directory)
/// and returns the store and the bake's report.
fn bake_text(dir: &Path, name: &str, text: &str) -> (PathBuf, oslf_bake::bake::BakeReport) {
    let scene_path = dir.join(format!("{name}.toml"));
    std::fs::write(&scene_path, text).unwrap();
    let scene = oslf_scene::scene::Scene::load(&scene_path, None).unwrap();
    let output = dir.join(format!("{name}.oslf"));
    let options = oslf_bake::bake::BakeOptions {
        output: output.clone(),
        resume: false,
        progress: None,
        cube_limit: None,
        refuse_empty_texels: false,
        device: None,
    };
    let report = oslf_bake::bake::bake(&scene, &options).unwrap();
    assert!(report.finished);
    (output, report)
}

/// Renders `params` on the GPU with `r`'s cache as it is and checks it against the CPU
/// reference seeing the same residency: every pixel finite, at least `min_pixels` object
/// pixels, 99.5 % within 2·10⁻³ relative and a mean difference below 2·10⁻³. Returns the
/// frame's cache statistics.
fn check_parity(
    r: &mut Renderer,
    cubes: &mut StoreCubes,
    params: &Knobs,
    (w, h): (u32, u32),
    min_pixels: usize,
    what: &str,
) -> oslf_runtime::CacheStats {
    let camera = r.default_view();
    let opts = RenderOptions {
        width: w,
        height: h,
        ..Default::default()
    };
    let t = std::time::Instant::now();
    let frame = r.render(&camera, &params.params(), &opts).unwrap();
    let gpu_s = t.elapsed().as_secs_f64();
    let t = std::time::Instant::now();
    cubes.masks = Some(r.cache().indirection());
    let (cpu, _) = r.reference_image(&camera, &params.params(), cubes).unwrap();
    let cpu_s = t.elapsed().as_secs_f64();
    assert!(all_finite(&frame.pixels), "{what}: GPU pixel not finite");
    assert!(all_finite(&cpu), "{what}: CPU pixel not finite");
    let (n, share, diff) = compare(&frame.pixels, &cpu, 2e-3);
    println!(
        "{what}, {:?}: {n} pixels, GPU = CPU on {share}, mean difference {diff:.2e}, mean {:.4}; \
         GPU frame {gpu_s:.2} s, CPU reference {cpu_s:.2} s; {:?}",
        params.mode,
        mean(&cpu),
        frame.stats
    );
    assert!(n >= min_pixels, "{what}: the object covers {n} pixels");
    assert!(share >= 0.995 && diff < 2e-3, "{what}: {share} {diff}");
    assert!(mean(&cpu) > 0.0, "{what}: black");
    frame.stats
}

/// One rim patch of the teapot under a clear sky with a sun (radiance varies with direction,
/// so a wrong face or texel shows): one sample point and the environment cube (cheap: nothing
/// to hit), 1 sample per texel, no bounce.
const CUBE_2048_SCENE: &str = r#"
[environment.sky]
sun_direction = [0.7, -0.45, 0.55]
sun_irradiance = [9.0, 8.4, 7.6]

[[object]]
patches = "newell-teapot"
select = [0, 1]
material = { color = [0.1, 0.42, 0.12] }

[bake]
epsilon = 0.1
sample_count = 1
cube_resolution = 2048
sample_map_resolution = 1
samples_per_texel = 1
bounces = 0
# The colour planes are what this test is about; distances would double the 2048² faces.
distance_channel = false
"#;

#[test]
fn cube_maps_of_2048_squared_bake_store_and_render() {
    let t = std::time::Instant::now();
    let tmp = tempfile::tempdir().unwrap();
    let (path, report) = bake_text(tmp.path(), "cube2048", CUBE_2048_SCENE);
    println!(
        "bake: {:.1} s, {} sample points, {} cubes, {:.1} M rays, {} bytes",
        t.elapsed().as_secs_f64(),
        report.sample_points,
        report.cubes,
        (report.rays_closest + report.rays_shadow) as f64 / 1e6,
        report.store_bytes
    );
    let store = Store::open(&path).unwrap();
    assert_eq!(store.cube_resolution(), 2048);
    assert!(store.cube_count() >= 2, "{} cubes", store.cube_count());
    assert_eq!(store.face_raw_size(), 2048 * 2048 * 4);
    // The store round trip: every face decodes to 2048² finite, non-negative texels, the sky
    // above and the green patch below differ.
    let t = std::time::Instant::now();
    let cube = store.read_cube(0).unwrap();
    println!("read_cube: {:.2} s", t.elapsed().as_secs_f64());
    assert_eq!(cube.resolution, 2048);
    for face in &cube.faces {
        assert_eq!(face.len(), 2048 * 2048);
        assert!(face.iter().flatten().all(|c| c.is_finite() && *c >= 0.0));
    }
    let up = cube.faces[4][1024 * 2048 + 1024];
    let down = cube.faces[5][1024 * 2048 + 1024];
    assert!(
        up[2] > up[0] && up[2] > 0.01,
        "+z sees the blue sky: {up:?}"
    );
    assert!(
        down[1] > down[2] && down[1] > 0.0,
        "-z sees the green patch: {down:?}"
    );
    drop(cube);
    let t = std::time::Instant::now();
    let mut cubes = StoreCubes::decode(&store).unwrap();
    println!("decode both cubes: {:.2} s", t.elapsed().as_secs_f64());

    // A pool slot holds the six 2048² faces side by side (16384 / 2048 = 8 per layer on
    // lavapipe); then the same with one slot for two cubes, held by the pinned environment
    // cube: the sample point's cube never fits and its reflections fall back to it.
    let mut r = Renderer::new(Gpu::headless().unwrap(), store, CacheConfig::default()).unwrap();
    assert_eq!(r.cache().slots(), r.store().cube_count());
    for mode in [Mode::Recon, Mode::Mirror] {
        let params = Knobs {
            mode,
            ..Default::default()
        };
        let stats = check_parity(
            &mut r,
            &mut cubes,
            &params,
            (128, 96),
            300,
            "2048² cube maps",
        );
        assert_eq!(stats.unresolved, 0);
    }
    drop(r);
    let store = Store::open(&path).unwrap();
    let config = CacheConfig {
        gpu_slots: Some(1),
        ..Default::default()
    };
    let mut r = Renderer::new(Gpu::headless().unwrap(), store, config).unwrap();
    assert_eq!(r.cache().slots(), 1);
    let params = Knobs {
        mode: Mode::Mirror,
        ..Default::default()
    };
    let stats = check_parity(
        &mut r,
        &mut cubes,
        &params,
        (128, 96),
        300,
        "2048² cube maps, 1 GPU slot",
    );
    assert!(stats.requests >= 2 && stats.unresolved >= 1, "{stats:?}");
}

/// A flat unit patch facing +z (u along y, v along x), for `patches = "flat.txt"`.
const FLAT_PATCH: &str = "1
1,2,3,4,5,6,7,8,9,10,11,12,13,14,15,16
16
0,0,0
0.333333,0,0
0.666667,0,0
1,0,0
0,0.333333,0
0.333333,0.333333,0
0.666667,0.333333,0
1,0.333333,0
0,0.666667,0
0.333333,0.666667,0
0.666667,0.666667,0
1,0.666667,0
0,1,0
0.333333,1,0
0.666667,1,0
1,1,0
";

/// The flat patch with 16 sample points, all within φ_samplemap = 89° of every texel's normal
/// and visible from it (nothing else lies above the patch), so every texel of the 4096² map
/// finds its four nearest and the map is built once; the texels' sets of four differ across
/// the patch, and a point light and a red box beside it make the cube maps differ, so a wrong
/// sample-map texel changes the image (with only 4 points every texel held the same set, and
/// the test passed with the shader reading the texel at half its coordinates).
const MAP_4096_SCENE: &str = r#"
[camera]
position = [0.9, -0.5, 1.2]
target = [0.5, 0.5, 0.0]
vfov = 50.0

[environment]
uniform = [0.6, 0.7, 0.9]

[[point_light]]
position = [0.2, 0.3, 0.5]
intensity = [2.0, 1.9, 1.7]

[[box]]
size = [0.3, 1.0, 0.6]
transform = { translate = [1.4, 0.5, 0.3] }
material = { color = [0.8, 0.1, 0.1] }

[[object]]
patches = "flat.txt"
material = { color = [0.5, 0.5, 0.5] }

[bake]
epsilon = 0.1
sample_count = 16
phi_samplemap = 89.0
cube_resolution = 8
sample_map_resolution = 4096
samples_per_texel = 1
bounces = 0
"#;

#[test]
fn sample_maps_of_4096_squared_bake_store_and_render() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    std::fs::write(dir.join("flat.txt"), FLAT_PATCH).unwrap();
    let t = std::time::Instant::now();
    let (path, report) = bake_text(dir, "map4096", MAP_4096_SCENE);
    println!(
        "bake: {:.1} s (sample maps {:.1} s, {} visibility rays), {} sample points, {} bytes",
        t.elapsed().as_secs_f64(),
        report.sample_map_seconds,
        report.sample_maps.rays,
        report.sample_points,
        report.store_bytes
    );
    assert_eq!(report.sample_maps.texels, 4096 * 4096);
    assert_eq!(report.sample_maps.short, 0, "{:?}", report.sample_maps);
    assert_eq!(report.points_added, 0);
    let store = Store::open(&path).unwrap();
    // 4096² × 4 × 2 bytes = 128 MiB, zero-copy.
    assert_eq!(store.header().maps.size, 128 << 20);
    assert_eq!(store.index_width(), IndexWidth::U16);
    let map = store.sample_map(0).unwrap();
    assert_eq!(map.resolution(), 4096);
    let raw = map.as_u16().unwrap();
    assert_eq!(raw.len(), 4096 * 4096 * 4);
    // Every texel holds four points; the sets differ across the patch.
    let points = store.sample_points().len();
    assert_eq!(points, 16);
    let mut sets = std::collections::HashSet::new();
    for t in raw.chunks_exact(4) {
        assert!(t.iter().all(|&i| usize::from(i) < points), "{t:?}");
        let mut set = [t[0], t[1], t[2], t[3]];
        set.sort_unstable();
        sets.insert(set);
    }
    println!("{} distinct sets of four", sets.len());
    assert!(sets.len() >= 8, "{} sets", sets.len());
    assert_eq!(map.get(4095, 4095).map(|t| t.len()), Some(4));

    let mut cubes = StoreCubes::decode(&store).unwrap();
    let mut r = Renderer::new(Gpu::headless().unwrap(), store, CacheConfig::default()).unwrap();
    for mode in [Mode::Recon, Mode::Mirror] {
        let params = Knobs {
            mode,
            ..Default::default()
        };
        check_parity(
            &mut r,
            &mut cubes,
            &params,
            (64, 48),
            300,
            "4096² sample maps",
        );
    }
}
