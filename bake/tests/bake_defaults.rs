//! Settings chosen from the scene where its file leaves them unset
//! (`oslf_scene::bake_defaults`): the same scene at ×0.001, ×1 and ×1000 gets the same
//! relative ε, spacings and sample points, and the same cube maps; a surface near the object
//! lowers ε; the material's lobe sets the spacing, the cube resolution and the samples per
//! texel; every choice is printed in the scene's units with the digits the object needs.

use std::path::Path;

use glam::Vec3;
use oslf_bake::sample_points::{self, Surfaces};
use oslf_scene::bake_defaults::{length_decimals, object_size, EPSILON_PER_SIZE, SPACING_PER_SIZE};
use oslf_scene::scene::{PointPlacement, Scene};
use oslf_trace::capture::{capture_cube, CaptureSettings};
use oslf_trace::integrator::Integrator;

/// The teapot above a floor `floor_gap` (× scale) under its lowest point (`None`: no floor),
/// lit by a uniform sky only (radiance is then invariant under scaling), with `material` and a
/// `[bake]` that sets only `extra`: ε and the density are chosen.
fn scene_with(scale: f64, floor_gap: Option<f64>, material: &str, extra: &str) -> String {
    let s = |v: f64| v * scale;
    // The teapot with its bottom (scale 0.1) spans x ±0.2, y −0.30…0.35 (the spout), z 0…0.315.
    let floor = floor_gap.map_or(String::new(), |g| {
        format!(
            r#"
[[box]]
size = [{f:?}, {f:?}, {t:?}]
transform = {{ translate = [0.0, 0.0, {z:?}] }}
material = {{ color = [0.5, 0.4, 0.3] }}
"#,
            f = s(3.0),
            t = s(0.1),
            z = s(-g - 0.05),
        )
    });
    format!(
        r#"
[environment]
uniform = [0.6, 0.7, 0.9]
{floor}
[[object]]
name = "teapot"
patches = "newell-teapot"
transform = {{ rotate = [0.0, 0.0, 90.0], scale = {sc:?} }}
material = {material}

[bake]
sample_map_resolution = 16
bounces = 1
seed = 3
{extra}
"#,
        sc = s(0.1),
    )
}

/// [`scene_with`] on a floor 0.002 (× scale) below the teapot: a contact.
fn scene_text(scale: f64, material: &str, extra: &str) -> String {
    scene_with(scale, Some(0.002), material, extra)
}

fn load(text: &str) -> Scene {
    Scene::from_str(text, Path::new("chosen.toml"), None).unwrap()
}

const LAMBERT: &str = "{ color = [0.1, 0.42, 0.12] }";

#[test]
fn the_choices_scale_with_the_scene_and_so_do_the_points_and_the_cubes() {
    let extra = "cube_resolution = 8\nsamples_per_texel = 1";
    let unit = load(&scene_text(1.0, LAMBERT, extra));
    let size = object_size(&unit.objects[0]);
    // The teapot curves (radius 0.12 typically) enough for the cone of Eq. 3.10 to raise ε
    // above 1/128 of its size at its spacing.
    assert!(
        unit.bake.epsilon > EPSILON_PER_SIZE * size
            && unit.bake_choices[0].why.contains("Eq. 3.10"),
        "{:?}",
        unit.bake_choices
    );
    let spacing = unit.objects[0].sample_spacing.unwrap();
    assert!((spacing - SPACING_PER_SIZE * size).abs() <= 1e-6 * size);
    let keys: Vec<&str> = unit.bake_choices.iter().map(|c| c.key).collect();
    assert_eq!(
        keys,
        ["epsilon", "near_surface", "sample_spacing", "placement"],
        "{:?}",
        unit.bake_choices
    );
    // The placement is chosen with the density: parallax, at every scale (its distances
    // count relative to their typical value, so its points scale with the scene).
    assert_eq!(unit.bake.placement, PointPlacement::Parallax);

    let place = |scene: &Scene| {
        let geometry = crate::extremes::geometry(scene);
        let surfaces = Surfaces::new(&scene.objects, &scene.bake).unwrap();
        let placement = sample_points::place(&surfaces, &scene.bake, &geometry).unwrap();
        (placement, geometry)
    };
    let (unit_points, unit_geometry) = place(&unit);
    let settings = CaptureSettings {
        resolution: 8,
        samples_per_texel: 1,
        target_noise: 0.0,
        denoise: false,
        distance_channel: true,
        seed: 3,
    };
    let unit_integrator = Integrator::for_scene(&unit, &unit_geometry);
    for scale in [1e-3, 1e3] {
        let scaled = load(&scene_text(scale, LAMBERT, extra));
        let s = scale as f32;
        assert!(
            (scaled.bake.epsilon / s - unit.bake.epsilon).abs() <= 1e-5 * unit.bake.epsilon,
            "scale {scale}: ε {} against {}",
            scaled.bake.epsilon,
            unit.bake.epsilon
        );
        let h = scaled.objects[0].sample_spacing.unwrap();
        assert!((h / s - spacing).abs() <= 1e-5 * spacing, "scale {scale}");
        // The printed values carry as many significant digits at every scale.
        let digits = |v: &str| {
            let d: String = v.chars().filter(char::is_ascii_digit).collect();
            d.trim_start_matches('0').len()
        };
        assert_eq!(
            digits(&scaled.bake_choices[0].value),
            digits(&unit.bake_choices[0].value),
            "{:?} against {:?}",
            scaled.bake_choices[0],
            unit.bake_choices[0]
        );

        // Within rounding: a point on the edge of the free-space tests may fall either way.
        let (points, geometry) = place(&scaled);
        let matched = points
            .points
            .iter()
            .filter(|a| {
                let p = Vec3::from(a.position) / s;
                unit_points
                    .points
                    .iter()
                    .any(|b| (p - Vec3::from(b.position)).length() <= 1e-4 * size)
            })
            .count();
        assert!(
            points.points.len().abs_diff(unit_points.points.len()) * 100
                <= unit_points.points.len(),
            "scale {scale}: {} points against {}",
            points.points.len(),
            unit_points.points.len()
        );
        // Weighted sample elimination breaks near-ties of its weights either way at
        // another scale: a few points move to a neighbouring candidate.
        assert!(
            matched as f64 >= 0.97 * unit_points.points.len() as f64,
            "scale {scale}: {matched} of {} points in the same relative place",
            unit_points.points.len()
        );

        // The same cubes at the first points in the same relative place (the same random
        // streams).
        let integrator = Integrator::for_scene(&scaled, &geometry);
        let (mut texels, mut agree) = (0, 0);
        let pairs = unit_points.points.iter().filter_map(|b| {
            let a = points.points.iter().find(|a| {
                (Vec3::from(a.position) / s - Vec3::from(b.position)).length() <= 1e-4 * size
            })?;
            Some((a, b))
        });
        for (i, (a, b)) in pairs.take(6).enumerate() {
            let (ca, _) = capture_cube(&integrator, Vec3::from(a.position), i as u32, &settings);
            let (cb, _) = capture_cube(
                &unit_integrator,
                Vec3::from(b.position),
                i as u32,
                &settings,
            );
            for f in 0..6 {
                for (x, y) in ca.faces[f].iter().zip(&cb.faces[f]) {
                    let (x, y) = (Vec3::from(*x), Vec3::from(*y));
                    texels += 1;
                    agree += usize::from(
                        (x - y).abs().max_element() <= 1e-2 * y.max_element().max(0.05),
                    );
                }
            }
        }
        assert!(
            agree as f64 >= 0.99 * texels as f64,
            "scale {scale}: {agree} of {texels} cube texels agree"
        );
    }
}

/// `placement = "adaptive"` at three scales: its pilot cubes' errors are relative to their
/// brightness and to their typical value, and their distances scale with the scene, so the
/// points do too, within rounding. A pilot on the edge of the free-space tests, kept at one
/// scale and not another, changes its neighbours' prediction errors, so the points around it
/// are thinned and eliminated anew (at 1e-3: 2 of 245 pilots, about 50 of 490 points; the
/// other pilots' errors agree within 1e-5): within 1 % in number, 85 % in the same place.
#[test]
fn adaptive_placement_scales_with_the_scene() {
    let extra = "cube_resolution = 8\nsamples_per_texel = 1\nplacement = \"adaptive\"";
    let place = |scale: f64| {
        let scene = load(&scene_text(scale, LAMBERT, extra));
        assert_eq!(scene.bake.placement, PointPlacement::Adaptive);
        let geometry = crate::extremes::geometry(&scene);
        let surfaces = Surfaces::new(&scene.objects, &scene.bake).unwrap();
        let placement = sample_points::place_in(&scene, &surfaces, &geometry).unwrap();
        assert!(placement.pilot_cubes > 0);
        placement.points
    };
    let unit = place(1.0);
    let size = object_size(&load(&scene_text(1.0, LAMBERT, extra)).objects[0]);
    for scale in [1e-3, 1e3] {
        let points = place(scale);
        let s = scale as f32;
        let matched = points
            .iter()
            .filter(|a| {
                let p = Vec3::from(a.position) / s;
                unit.iter()
                    .any(|b| (p - Vec3::from(b.position)).length() <= 1e-4 * size)
            })
            .count();
        assert!(
            points.len().abs_diff(unit.len()) * 100 <= unit.len(),
            "scale {scale}: {} points against {}",
            points.len(),
            unit.len()
        );
        assert!(
            matched as f64 >= 0.85 * unit.len() as f64,
            "scale {scale}: {matched} of {} points in the same relative place",
            unit.len()
        );
    }
}

#[test]
fn a_surface_close_under_the_object_lowers_epsilon() {
    // Points dense enough that the cone of Eq. 3.10 needs less than the size or the gap give.
    let extra = "cube_resolution = 8\nsamples_per_texel = 1\nsample_count = 4000";
    let open = load(&scene_with(1.0, None, LAMBERT, extra));
    assert!(open.bake_choices[0]
        .why
        .starts_with("1/128 of object \"teapot\"'s size"));
    let size = object_size(&open.objects[0]);
    // A floor just beyond the size-based ε under the teapot's bottom: its gap bounds ε.
    let gap = 1.1 * f64::from(EPSILON_PER_SIZE * size);
    let near = load(&scene_with(1.0, Some(gap), LAMBERT, extra));
    let chosen = &near.bake_choices[0];
    assert_eq!(chosen.key, "epsilon");
    assert!(
        near.bake.epsilon < 0.99 * open.bake.epsilon,
        "{chosen}; open: {}",
        open.bake_choices[0]
    );
    assert!(near.bake.epsilon >= 0.5 * gap as f32 * 0.99, "{chosen}");
    assert!(chosen.why.contains("gap"), "{chosen}");
    // Resting on it (a contact) or far below, the floor changes nothing.
    for far in [0.0, 0.3] {
        let s = load(&scene_with(1.0, Some(far), LAMBERT, extra));
        assert_eq!(s.bake.epsilon, open.bake.epsilon, "{}", s.bake_choices[0]);
    }
}

#[test]
fn the_lobe_sets_the_spacing_the_cube_resolution_and_the_samples() {
    let mirror = load(&scene_text(1.0, LAMBERT, ""));
    let rough = load(&scene_text(
        1.0,
        "{ color = [0.9, 0.6, 0.3], metallic = 1.0, roughness = 0.6 }",
        "",
    ));
    let glossy = load(&scene_text(
        1.0,
        "{ color = [0.9, 0.6, 0.3], metallic = 1.0, roughness = 0.2 }",
        "",
    ));
    // A mirror: the sharpest cubes by default, 4 samples per texel at the same rays per cube.
    assert_eq!(mirror.bake.cube_resolution, 64);
    assert_eq!(mirror.bake.samples_per_texel, 4);
    // Roughness 0.2 (α 0.04): texels of at most 0.04 rad, 64²; 0.6 (α 0.36): 16².
    assert_eq!(glossy.bake.cube_resolution, 64);
    assert_eq!(rough.bake.cube_resolution, 16);
    assert_eq!(rough.bake.samples_per_texel, 16);
    let h = |s: &Scene| s.objects[0].sample_spacing.unwrap();
    assert!(h(&mirror) < h(&glossy) && h(&glossy) < h(&rough));
    for s in [&mirror, &rough] {
        let keys: Vec<&str> = s.bake_choices.iter().map(|c| c.key).collect();
        assert_eq!(
            keys,
            [
                "epsilon",
                "near_surface",
                "sample_spacing",
                "placement",
                "cube_resolution",
                "samples_per_texel"
            ]
        );
    }
    let cube = rough
        .bake_choices
        .iter()
        .find(|c| c.key == "cube_resolution")
        .unwrap();
    assert!(cube.why.contains("roughness 0.600"), "{cube}");
    // What the file sets stays.
    let set = load(&scene_text(
        1.0,
        LAMBERT,
        "epsilon = 0.01\nsample_count = 50",
    ));
    assert_eq!(set.bake.epsilon, 0.01);
    assert!(set
        .bake_choices
        .iter()
        .all(|c| c.key != "epsilon" && c.key != "sample_spacing"));
    assert_eq!(set.objects[0].sample_spacing, None);
}

#[test]
fn lengths_print_with_the_digits_the_object_needs() {
    // ε of a 6 cm object at real scale: four decimals, not "0.0".
    assert_eq!(length_decimals(0.0012), 4);
    let small = load(&scene_text(
        0.01,
        LAMBERT,
        "cube_resolution = 8\nsamples_per_texel = 1",
    ));
    let eps = &small.bake_choices[0];
    let printed: f32 = eps.value.parse().unwrap();
    assert!(
        (printed - small.bake.epsilon).abs() <= 0.06 * small.bake.epsilon,
        "{eps}"
    );
    assert!(printed > 0.0);
}

#[test]
fn a_given_density_raises_epsilon_to_what_the_cone_of_eq_3_10_needs() {
    // 20 points over the teapot: about 0.2 apart, so a texel's four points lie up to 0.3 away,
    // within 5° of its tangent plane unless ε is at least 0.3 · tan 5°.
    let sparse = load(&scene_text(1.0, LAMBERT, "sample_count = 20"));
    let chosen = &sparse.bake_choices[0];
    assert!(chosen.why.contains("Eq. 3.10"), "{chosen}");
    let size = object_size(&sparse.objects[0]);
    assert!(sparse.bake.epsilon > EPSILON_PER_SIZE * size, "{chosen}");
    // Dense enough, the size rules.
    let dense = load(&scene_text(1.0, LAMBERT, "sample_count = 2000"));
    assert!(
        dense.bake_choices[0].why.starts_with("1/128"),
        "{}",
        dense.bake_choices[0]
    );
}

#[test]
fn a_store_budget_lowers_the_chosen_resolution_then_widens_the_spacing() {
    let free = load(&scene_text(1.0, LAMBERT, ""));
    let measures: Vec<_> = free
        .objects
        .iter()
        .map(|o| oslf_scene::bake_defaults::measure(o, &free.shapes, &free.materials))
        .collect();
    let unbounded = oslf_scene::bake_defaults::store_estimate(&free.objects, &measures, &free.bake);
    // A quarter of the free choice's store: 64² → 32², as many points.
    let quarter = unbounded / 4e6 * 1.01;
    let fit = load(&scene_text(
        1.0,
        LAMBERT,
        &format!("store_budget_mb = {quarter}"),
    ));
    assert_eq!(fit.bake.cube_resolution, 32, "{:?}", fit.bake_choices);
    assert_eq!(fit.bake.samples_per_texel, 16);
    assert_eq!(
        fit.objects[0].sample_spacing,
        free.objects[0].sample_spacing
    );
    let line = fit.bake_choices.last().unwrap();
    assert_eq!(line.key, "store_budget_mb");
    assert!(line.why.starts_with("met"), "{line}");
    // A hundredth: the smallest cube maps, and the spacing widened.
    let tight = load(&scene_text(
        1.0,
        LAMBERT,
        &format!("store_budget_mb = {}", unbounded / 1e8),
    ));
    assert_eq!(tight.bake.cube_resolution, 16);
    assert!(tight.objects[0].sample_spacing > free.objects[0].sample_spacing);
    let est = |s: &Scene| {
        let m: Vec<_> = s
            .objects
            .iter()
            .map(|o| oslf_scene::bake_defaults::measure(o, &s.shapes, &s.materials))
            .collect();
        oslf_scene::bake_defaults::store_estimate(&s.objects, &m, &s.bake)
    };
    // ε rises with the spacing, to what the cone of Eq. 3.10 needs there.
    assert!(tight.bake.epsilon > free.bake.epsilon);
    let line = tight.bake_choices.last().unwrap();
    assert!(line.why.starts_with("met"), "{line}");
    assert!(est(&tight) <= unbounded / 1e2 * 1.001, "{line}");
    // Settings the file gives are not the budget's to change.
    let fixed = load(&scene_text(
        1.0,
        LAMBERT,
        "store_budget_mb = 0.001\ncube_resolution = 64\nsample_count = 400",
    ));
    assert_eq!(fixed.bake.cube_resolution, 64);
    let line = fixed.bake_choices.last().unwrap();
    assert!(line.why.starts_with("not met"), "{line}");
}
