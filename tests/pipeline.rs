//! End-to-end: scene file → bake → store, checked from the outside.

use std::path::Path;

use glam::{Affine3A, Mat4, Vec3};
use oslf_bake::bake::{bake, BakeOptions};
use oslf_format::{Store, INVALID_INDEX};
use oslf_geometry::bezier::BezierPatch;
use oslf_scene::scene::Scene;
use oslf_trace::bvh::TriangleScene;
use oslf_trace::ray::Ray;

/// A small but complete scene: the teapot's lid and body on a table, a wall, a point light and
/// a uniform sky (tests/fixtures/teapot.toml), baked at toy resolutions.
const SCENE: &str = concat!(
    include_str!("fixtures/teapot.toml"),
    r#"
[bake]
epsilon = 0.1
sample_count = 60
cube_resolution = 4
sample_map_resolution = 8
samples_per_texel = 1
bounces = 1
seed = 7
"#
);

fn scene(dir: &Path) -> Scene {
    let path = dir.join("scene.toml");
    std::fs::write(&path, SCENE).unwrap();
    Scene::load(&path, None).unwrap()
}

fn bake_with_threads(
    scene: &Scene,
    output: &Path,
    threads: usize,
    limit: Option<u32>,
    resume: bool,
) {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap();
    let options = BakeOptions {
        output: output.to_path_buf(),
        resume,
        progress: None,
        cube_limit: limit,
        refuse_empty_texels: false,
        device: None,
    };
    let report = pool.install(|| bake(scene, &options)).unwrap();
    assert_eq!(report.finished, limit.is_none() || resume);
}

#[test]
fn same_scene_and_seed_give_the_same_bytes_with_one_or_two_threads() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    let scene = scene(dir);
    let a = dir.join("one.oslf");
    let b = dir.join("two.oslf");
    bake_with_threads(&scene, &a, 1, None, false);
    bake_with_threads(&scene, &b, 2, None, false);
    let (a, b) = (std::fs::read(a).unwrap(), std::fs::read(b).unwrap());
    assert!(a.len() > 1000);
    assert!(a == b, "stores differ between 1 and 2 threads");
}

#[test]
fn an_interrupted_bake_resumes_to_the_same_store() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    let scene = scene(dir);
    let whole = dir.join("whole.oslf");
    bake_with_threads(&scene, &whole, 2, None, false);

    let sliced = dir.join("sliced.oslf");
    bake_with_threads(&scene, &sliced, 2, Some(25), false);
    assert!(
        !sliced.exists(),
        "an unfinished bake must not appear under the final name"
    );
    assert!(oslf_format::writer::partial_path(&sliced).exists());
    bake_with_threads(&scene, &sliced, 2, None, true);
    assert!(!oslf_format::writer::partial_path(&sliced).exists());
    assert_eq!(
        std::fs::read(whole).unwrap(),
        std::fs::read(sliced).unwrap()
    );
}

/// Every sample-map entry is checked without the bake's own code paths: patches are rebuilt from
/// the store, nearest points found by a full scan (of which the bake examines the nearest
/// `MAX_CANDIDATES`), visibility by a brute-force intersector.
#[test]
fn sample_maps_hold_the_nearest_visible_in_hemisphere_points() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    let scene = scene(dir);
    let out = dir.join("s.oslf");
    bake_with_threads(&scene, &out, 2, None, false);
    let store = Store::open(&out).unwrap();
    let meta = store.meta();
    let params = &meta.bake;
    let points = store.sample_points();
    let cos_phi = params.phi_samplemap_deg.to_radians().cos();
    let geometry = TriangleScene::build(oslf_trace::bvh::scene_instances(
        &scene,
        true,
        params.epsilon / 50.0,
    ))
    .unwrap();

    let object = &meta.objects[0];
    let transform = Affine3A::from_mat4(Mat4::from_cols_array_2d(&object.transform));
    let res = params.sample_map_resolution;
    let mut checked = 0;
    for (p, patch) in meta.patches.iter().enumerate() {
        let patch = BezierPatch {
            cp: patch.control_points.map(Vec3::from_array),
        }
        .transformed(&transform);
        let map = store.sample_map(p as u32).unwrap();
        for y in 0..res {
            for x in 0..res {
                let (u, v) = ((x as f32 + 0.5) / res as f32, (y as f32 + 0.5) / res as f32);
                let t = patch.eval(u, v);
                let n = patch.normal(u, v);
                // Full scan, nearest first: the first four acceptable points.
                let mut order: Vec<usize> = (0..points.len()).collect();
                let dist = |i: usize| (Vec3::from_array(points[i].position) - t).length();
                order.sort_by(|&a, &b| dist(a).total_cmp(&dist(b)).then(a.cmp(&b)));
                let expected: Vec<u32> = order
                    .into_iter()
                    .take(oslf_bake::sample_map::MAX_CANDIDATES)
                    .filter(|&i| {
                        let s = Vec3::from_array(points[i].position);
                        let d = (s - t).normalize();
                        if n.dot(d) <= cos_phi {
                            return false;
                        }
                        let o = t + n * params.epsilon * 0.05;
                        let to = s - o;
                        let ray = Ray::new(o, to.normalize());
                        geometry
                            .intersect_brute_force(&ray, to.length() * (1.0 - 1e-4))
                            .is_none()
                    })
                    .take(4)
                    .map(|i| i as u32)
                    .collect();
                let got = map.get(x, y).unwrap();
                let valid: Vec<u32> = got
                    .iter()
                    .copied()
                    .filter(|&i| i != INVALID_INDEX)
                    .collect();
                assert_eq!(valid, expected, "patch {p} texel ({x}, {y})");
                checked += 1;
            }
        }
    }
    assert_eq!(checked, 28 * res * res);
}

#[test]
fn sample_points_sit_epsilon_above_their_patch() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    let scene = scene(dir);
    let out = dir.join("p.oslf");
    bake_with_threads(&scene, &out, 2, None, false);
    let store = Store::open(&out).unwrap();
    let meta = store.meta();
    let eps = meta.bake.epsilon;
    assert!(store.sample_points().len() > 30);
    for s in store.sample_points() {
        let patch = &scene.objects[0].patches[s.patch as usize];
        let base = patch.eval(s.uv[0], s.uv[1]);
        let offset = Vec3::from_array(s.position) - base;
        assert!(
            (offset.length() - eps).abs() < 1e-4 * eps.max(1.0),
            "{offset}"
        );
        assert!(offset.normalize().dot(Vec3::from_array(s.normal)) > 0.9999);
    }
    // Every cube decodes, finite and non-negative, and the environment cube is there.
    assert_eq!(store.cube_count() as usize, store.sample_points().len() + 1);
    for c in 0..store.cube_count() {
        let cube = store.read_cube(c).unwrap();
        for face in &cube.faces {
            assert!(face.iter().flatten().all(|v| v.is_finite() && *v >= 0.0));
        }
    }
    store.verify().unwrap();
}

/// With the distance channel on, each sample point's cube sees its own surface ε below: the
/// texel looking along −normal reports a first hit at about ε.
#[test]
fn the_distance_channel_sees_the_surface_epsilon_below() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    let path = dir.join("scene.toml");
    std::fs::write(
        &path,
        SCENE
            .replace("cube_resolution = 4", "cube_resolution = 16")
            .replace("seed = 7", "seed = 7\ndistance_channel = true"),
    )
    .unwrap();
    let scene = Scene::load(&path, None).unwrap();
    let out = dir.join("d.oslf");
    bake_with_threads(&scene, &out, 2, None, false);
    let store = Store::open(&out).unwrap();
    let eps = store.meta().bake.epsilon;
    let res = store.cube_resolution();
    for (i, s) in store.sample_points().iter().enumerate() {
        let cube = store.read_cube(i as u32).unwrap();
        let distance = cube.distance.as_ref().expect("distance channel");
        let down = -Vec3::from_array(s.normal);
        let (face, fs, ft) = oslf_format::cube::direction_to_face_st(down.to_array());
        let x = ((fs * res as f32) as u32).min(res - 1);
        let y = ((ft * res as f32) as u32).min(res - 1);
        let d = distance[face][(y * res + x) as usize];
        // The texel's centre direction is within half a texel (≈ 0.1 rad here) of −normal.
        assert!(
            d > 0.5 * eps && d < 1.5 * eps,
            "sample {i}: distance {d}, ε {eps}"
        );
    }
}
