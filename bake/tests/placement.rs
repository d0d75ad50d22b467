//! Sample-point placement on hard-surface meshes: every point lies ε from its own face (offset
//! along the face's geometric normal, whatever the shading normals), so a box keeps its points
//! at the edges and corners; only points that truly face another surface closer than ε go.

use std::path::Path;

use glam::Vec3;
use oslf_bake::sample_points::{place, place_in, Placement, Surfaces};
use oslf_scene::scene::Scene;
use oslf_scene::tolerance::TESSELLATION_ERROR;
use oslf_trace::bvh::TriangleScene;

/// The unit cube [0, 1]³ without normals: 8 vertices, 6 quads wound outwards.
const BOX_OBJ: &str = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nv 0 0 1\nv 1 0 1\nv 0 1 1\nv 1 1 1\n\
f 1 3 4 2\nf 5 6 8 7\nf 1 2 6 5\nf 3 7 8 4\nf 1 5 7 3\nf 2 4 8 6\n";

/// A scene whose OSLF object is the box at `translate` with `extra` keys, plus `more`.
fn box_scene(d: &Path, translate: [f32; 3], extra: &str, more: &str) -> Scene {
    box_scene_baked(d, translate, extra, more, "")
}

/// [`box_scene`] with `bake` added to its `[bake]` table.
fn box_scene_baked(d: &Path, translate: [f32; 3], extra: &str, more: &str, bake: &str) -> Scene {
    std::fs::write(d.join("box.obj"), BOX_OBJ).unwrap();
    let text = format!(
        "[environment]\nuniform = [0.5, 0.5, 0.5]\n\n[[object]]\nname = \"box\"\nmesh = \"box.obj\"\n\
         transform = {{ translate = {translate:?} }}\n{extra}\nmaterial = {{ color = [0.5, 0.5, 0.5] }}\n\
         {more}\n[bake]\nepsilon = 0.05\nsample_count = 400\nsample_map_resolution = 32\n{bake}\n"
    );
    let path = d.join("scene.toml");
    std::fs::write(&path, text).unwrap();
    Scene::load(&path, None).unwrap_or_else(|e| panic!("{e}"))
}

fn placement(scene: &Scene) -> Placement {
    let geometry = TriangleScene::build(oslf_trace::bvh::scene_instances(
        scene,
        true,
        scene.bake.epsilon * TESSELLATION_ERROR,
    ))
    .unwrap();
    let surfaces = Surfaces::new(&scene.objects, &scene.bake).unwrap();
    place_in(scene, &surfaces, &geometry).unwrap()
}

/// Distance from `p` to the surface of the axis-aligned box `[lo, lo + 1]³`, from outside.
fn distance_to_box(p: Vec3, lo: Vec3) -> f32 {
    let d = (lo - p).max(p - (lo + Vec3::ONE)).max(Vec3::ZERO);
    d.length()
}

#[test]
fn a_floating_box_keeps_every_point_whatever_its_normals() {
    // Smooth normals tilt by up to 54.7° at the corners: offset along them, points near the
    // edges landed closer than ε to the neighbouring face (84 of 100 on a cube before the fix).
    for normals in ["", "normals = \"smooth\"", "normals = \"flat\""] {
        let tmp = tempfile::tempdir().unwrap();
        let d = tmp.path();
        let lo = Vec3::new(0.0, 0.0, 1.0);
        let scene = box_scene(d, lo.to_array(), normals, "");
        let p = placement(&scene);
        assert_eq!(p.placed, 400, "{normals}");
        assert_eq!(
            (p.removed_close, p.removed_inside, p.points.len()),
            (0, 0, 400),
            "{normals}"
        );
        let eps = scene.bake.epsilon;
        for (i, point) in p.points.iter().enumerate() {
            let at = Vec3::from_array(point.position);
            let n = Vec3::from_array(point.normal);
            let dist = distance_to_box(at, lo);
            assert!(
                (dist - eps).abs() < 1e-4,
                "{normals}: point {i} at {at} is {dist} from the box, ε = {eps}"
            );
            // Its normal is the face's own: one axis, pointing out.
            let axis = n.abs().max_element();
            assert!(axis > 1.0 - 1e-5, "{normals}: point {i}: normal {n}");
            let base = at - n * eps;
            assert!(distance_to_box(base, lo) < 1e-5, "{normals}: point {i}");
        }
    }
}

#[test]
fn a_box_on_a_slab_loses_only_its_bottom_and_the_rim_within_epsilon_of_the_slab() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    let lo = Vec3::ZERO;
    // A solid slab (a plane has no inside: points under it would be in free space).
    let floor = "[[box]]\nsize = [6.0, 6.0, 0.2]\ntransform = { translate = [0.0, 0.0, -0.1] }\n\
                 material = { color = [0.5, 0.5, 0.5] }\n";
    let scene = box_scene(d, lo.to_array(), "normals = \"smooth\"", floor);
    let p = placement(&scene);
    let eps = scene.bake.epsilon;
    // The free-space test probes 64 directions: within their spacing, a point 0.95ε above the
    // slab may pass.
    for point in &p.points {
        assert!(point.position[2] >= eps * 0.9, "{point:?}");
    }
    // The bottom is a sixth of the area; on each unit-high side, the rim below ε is ε of it.
    let expected_lost = p.placed as f32 * (1.0 / 6.0 + 4.0 / 6.0 * eps);
    let lost = (p.removed_close + p.removed_inside) as f32;
    assert!(
        (lost - expected_lost).abs() < 0.25 * expected_lost,
        "lost {lost} of {}, expected about {expected_lost}",
        p.placed
    );
}

/// The slab `a_box_on_a_slab_…` rests its box on: top face at z = 0.
const SLAB: &str =
    "[[box]]\nsize = [6.0, 6.0, 0.2]\ntransform = { translate = [0.0, 0.0, -0.1] }\n\
                    material = { color = [0.5, 0.5, 0.5] }\n";

#[test]
fn near_the_slab_lowered_points_keep_the_rim_and_their_height_leaves_the_gap_three_times_over() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    let lower = box_scene_baked(d, [0.0; 3], "", SLAB, "near_surface = \"lower\"");
    let remove = box_scene(d, [0.0; 3], "", SLAB);
    let (pl, pr) = (placement(&lower), placement(&remove));
    let eps = lower.bake.epsilon;
    assert_eq!(pl.placed, pr.placed);
    assert_eq!(pr.lowered, 0, "the thesis's rule lowers nothing");
    // The rim within ε of the slab stays; only the bottom (in the slab) goes.
    let bottom = pl.placed as f32 / 6.0;
    let lost = (pl.removed_close + pl.removed_inside) as f32;
    assert!(
        (lost - bottom).abs() < 0.25 * bottom,
        "lost {lost} of {}, the bottom is about {bottom}",
        pl.placed
    );
    assert!(lost < (pr.removed_close + pr.removed_inside) as f32);
    // Points that the slab does not come near are where the thesis puts them.
    let far: Vec<_> = pr
        .points
        .iter()
        .filter(|p| p.position[2] > 4.0 * eps)
        .collect();
    let far_lowered: Vec<_> = pl
        .points
        .iter()
        .filter(|p| p.position[2] > 4.0 * eps)
        .collect();
    assert_eq!(far, far_lowered);
    let mut heights = Vec::new();
    for (i, point) in pl.points.iter().enumerate() {
        let at = Vec3::from_array(point.position);
        let h = distance_to_box(at, Vec3::ZERO);
        let z = at.z;
        if (h - eps).abs() < 1e-4 {
            // At ε: the slab, in the half-space the side faces, lies at least 3ε away (up to
            // the 64 probe directions' spacing), or the point is above the rim's reach.
            assert!(z > 2.5 * eps || (z - eps).abs() < 1e-4, "point {i} at {at}");
            continue;
        }
        // Lowered: by halves, at most to ε/8, and still clear of the slab.
        let k = (eps / h).log2();
        assert!(
            (k - k.round()).abs() < 1e-3 && (1.0..=3.0).contains(&k.round()),
            "point {i} at {at}: height {h} is not ε/2, ε/4 or ε/8"
        );
        assert!(
            z >= 0.9 * h,
            "point {i} at {at}: height {h}, {z} above the slab"
        );
        assert!(
            z < 3.0 * 2.0 * h + 1e-4,
            "point {i} at {at} was lowered needlessly"
        );
        heights.push(k.round() as u32);
    }
    assert!(
        (1..=3).all(|k| heights.contains(&k)),
        "the rim's points take every height: {heights:?}"
    );
    assert_eq!(pl.lowered, heights.len());
}

#[test]
fn a_surface_of_the_points_own_object_lowers_nothing() {
    // The box and a slab under it in one mesh: the rim's points face their own object, so
    // "lower" removes them as the thesis does (a fold or a concave rim is no contact).
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    let slab = "v -3 -3 -0.2\nv 3 -3 -0.2\nv -3 3 -0.2\nv 3 3 -0.2\nv -3 -3 0\nv 3 -3 0\nv -3 3 0\nv 3 3 0\n\
                f 9 11 12 10\nf 13 14 16 15\nf 9 10 14 13\nf 11 15 16 12\nf 9 13 15 11\nf 10 12 16 14\n";
    let text = format!("{BOX_OBJ}{slab}");
    let place_with = |rule: &str| {
        // Written with the box alone, then loaded again with the slab in its mesh.
        box_scene_baked(d, [0.0; 3], "", "", rule);
        std::fs::write(d.join("box.obj"), &text).unwrap();
        let scene = Scene::load(&d.join("scene.toml"), None).unwrap_or_else(|e| panic!("{e}"));
        placement(&scene)
    };
    let (pl, pr) = (
        place_with("near_surface = \"lower\""),
        place_with("near_surface = \"remove\""),
    );
    assert_eq!(pl.lowered, 0);
    assert_eq!(pl.points, pr.points);
    assert!(pr.removed_close > 0);
}

#[test]
fn a_point_lying_on_another_surface_is_too_close() {
    // A plate at z = 0 and a floor plane at z = ε: every offset point lies on the floor. A
    // probe ray from the point itself skips the floor as a self-hit; the free-space test must
    // not.
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    std::fs::write(
        d.join("plate.obj"),
        "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n",
    )
    .unwrap();
    let text = "[environment]\nuniform = [0.5, 0.5, 0.5]\n\n[[object]]\nname = \"plate\"\n\
                mesh = \"plate.obj\"\nmaterial = { color = [0.5, 0.5, 0.5] }\n\n[[plane]]\n\
                size = [4.0, 4.0]\ntransform = { translate = [0.5, 0.5, 0.05] }\n\
                material = { color = [0.5, 0.5, 0.5] }\n\n[bake]\nepsilon = 0.05\n\
                sample_count = 50\nsample_map_resolution = 16\n";
    let path = d.join("scene.toml");
    std::fs::write(&path, text).unwrap();
    let scene = Scene::load(&path, None).unwrap_or_else(|e| panic!("{e}"));
    let geometry = TriangleScene::build(oslf_trace::bvh::scene_instances(
        &scene,
        true,
        scene.bake.epsilon * TESSELLATION_ERROR,
    ))
    .unwrap();
    let surfaces = Surfaces::new(&scene.objects, &scene.bake).unwrap();
    let e = place(&surfaces, &scene.bake, &geometry).unwrap_err();
    assert!(
        e.to_string()
            .contains("all 50 sample points were removed (50 closer than ε"),
        "{e}"
    );
}

/// `placement = "parallax"` and `"adaptive"`: a plate (2 × 1, facing up) with a wall standing
/// 0.1 beyond one short edge and only the sky beyond the other. Parallax puts more of the
/// same count of points on the half by the wall (where a reflection changes fastest from point
/// to point), at least 1.8 times the far half's; adaptive placement at least 1.5 times, its
/// pilot cubes finding the near wall's edge against the sky moving most between points there.
/// Uniform placement splits them evenly (within 15 %).
#[test]
fn parallax_and_adaptive_placements_are_denser_where_the_surroundings_are_near() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    std::fs::write(
        d.join("plate.obj"),
        "v 0 0 0\nv 2 0 0\nv 2 1 0\nv 0 1 0\nf 1 2 3 4\n",
    )
    .unwrap();
    let halves = |rule: &str| {
        let text = format!(
            "[environment]\nuniform = [0.5, 0.5, 0.5]\n\n[[object]]\nname = \"plate\"\n\
             mesh = \"plate.obj\"\nmaterial = {{ color = [0.5, 0.5, 0.5] }}\n\n[[box]]\n\
             size = [0.1, 3.0, 2.0]\ntransform = {{ translate = [-0.15, 0.5, 0.5] }}\n\
             material = {{ color = [0.5, 0.5, 0.5] }}\n\n[bake]\nepsilon = 0.01\n\
             sample_count = 400\nsample_map_resolution = 16\nplacement = \"{rule}\"\n"
        );
        let path = d.join("scene.toml");
        std::fs::write(&path, text).unwrap();
        let scene = Scene::load(&path, None).unwrap_or_else(|e| panic!("{e}"));
        let p = placement(&scene);
        assert_eq!(p.placed, 400, "{rule}: the count is the setting's");
        let near = p.points.iter().filter(|s| s.position[0] < 1.0).count();
        (near, p.points.len() - near)
    };
    let (near, far) = halves("uniform");
    assert!(
        (near as f32 / far as f32 - 1.0).abs() < 0.15,
        "uniform: {near} near the wall, {far} far"
    );
    // Adaptive's far half still sees the wall, 1 to 2 away across the plate: its pilots'
    // views move less from point to point there, not nothing (253 against 147 points).
    for (rule, ratio) in [("parallax", 1.8), ("adaptive", 1.5)] {
        let (near, far) = halves(rule);
        assert!(
            near as f32 >= ratio * far as f32,
            "{rule}: {near} near the wall, {far} far"
        );
    }
}

/// Adaptive placement captures pilot cubes, so it needs the scene's light: [`place`], which
/// has only the geometry, says so instead of placing points some other way.
#[test]
fn adaptive_placement_without_the_scene_light_is_an_error() {
    let tmp = tempfile::tempdir().unwrap();
    let scene = box_scene_baked(
        tmp.path(),
        [0.0, 0.0, 1.0],
        "",
        "",
        "placement = \"adaptive\"",
    );
    let geometry =
        TriangleScene::build(oslf_trace::bvh::scene_instances(&scene, true, 0.001)).unwrap();
    let surfaces = Surfaces::new(&scene.objects, &scene.bake).unwrap();
    let e = place(&surfaces, &scene.bake, &geometry)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("placement \"adaptive\"") && e.contains("place_lit"),
        "{e}"
    );
    let lit = placement(&scene);
    assert!(lit.pilot_cubes >= 16, "{} pilot cubes", lit.pilot_cubes);
    assert_eq!(lit.points.len(), 400);
}
