//! The bake's coverage report (a summary that explains itself): per object, its
//! short and empty sample-map texels, each group with its cause, the surface it touches and
//! where it lies.

use std::path::Path;

use oslf_bake::bake::{bake, BakeOptions, BakeReport};
use oslf_bake::coverage::{Cause, ObjectCoverage};
use oslf_scene::scene::Scene;

/// The unit cube [0, 1]³ without normals: 8 vertices, 6 quads wound outwards.
const BOX_OBJ: &str = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nv 0 0 1\nv 1 0 1\nv 0 1 1\nv 1 1 1\n\
f 1 3 4 2\nf 5 6 8 7\nf 1 2 6 5\nf 3 7 8 4\nf 1 5 7 3\nf 2 4 8 6\n";

/// Bakes the box at `translate` (a tiny capture: coverage is decided before it) with
/// `sample_count` points, plus the scene text `more`.
fn bake_box(d: &Path, translate: [f32; 3], sample_count: u32, more: &str) -> BakeReport {
    std::fs::write(d.join("box.obj"), BOX_OBJ).unwrap();
    let text = format!(
        "[environment]\nuniform = [0.5, 0.5, 0.5]\n\n[[object]]\nname = \"box\"\nmesh = \"box.obj\"\n\
         transform = {{ translate = {translate:?} }}\nnormals = \"flat\"\n\
         material = {{ color = [0.5, 0.5, 0.5] }}\n{more}\n[bake]\nepsilon = 0.05\n\
         sample_count = {sample_count}\nsample_map_resolution = 32\ncube_resolution = 4\n\
         samples_per_texel = 1\nbounces = 0\n"
    );
    let path = d.join("scene.toml");
    std::fs::write(&path, text).unwrap();
    let scene = Scene::load(&path, None).unwrap_or_else(|e| panic!("{e}"));
    let options = BakeOptions {
        output: d.join("box.oslf"),
        resume: false,
        progress: None,
        cube_limit: None,
        refuse_empty_texels: false,
        device: None,
    };
    bake(&scene, &options).unwrap_or_else(|e| panic!("{e}"))
}

/// The report's one object, checked against the global counts.
fn the_box(report: &BakeReport) -> &ObjectCoverage {
    assert_eq!(report.coverage.len(), 1, "{:?}", report.coverage);
    let c = &report.coverage[0];
    assert_eq!(c.object, "box");
    let m = &report.sample_maps;
    assert_eq!((c.texels, c.short, c.empty), (m.texels, m.short, m.empty));
    let listed: u64 = c.places.iter().map(|p| p.short).sum();
    assert_eq!(listed + c.other_short, c.short, "{c:?}");
    c
}

#[test]
fn a_box_resting_on_a_slab_has_its_bottom_unseen_with_the_slab_named_and_located() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    // A solid slab whose top is the box's bottom plane, z = 0.
    let slab = "[[box]]\nsize = [6.0, 6.0, 0.2]\ntransform = { translate = [0.0, 0.0, -0.1] }\n\
                material = { color = [0.5, 0.5, 0.5] }\n";
    let report = bake_box(d, [1.0, -0.5, 0.0], 400, slab);
    let c = the_box(&report);
    assert!(c.empty > 0, "{c:?}");
    // The largest place: the bottom, facing down, at z = 0, over the box's footprint.
    let bottom = &c.places[0];
    // In contact with the slab, and enclosed by it: no view reaches the bottom.
    assert_eq!(bottom.cause, Cause::Unseen, "{c:?}");
    assert_eq!(bottom.facing, "-z", "{c:?}");
    assert_eq!(bottom.surface.as_deref(), Some("[[box]] 0"), "{c:?}");
    assert!(
        bottom.min[2].abs() < 1e-4 && bottom.max[2].abs() < 1e-4,
        "{bottom:?}"
    );
    assert!(bottom.min[0] > 0.95 && bottom.max[0] < 2.05, "{c:#?}");
    assert!(bottom.min[1] > -0.55 && bottom.max[1] < 0.55, "{c:#?}");
    assert!(bottom.max[0] - bottom.min[0] > 0.8, "{c:#?}");
    // The bottom is a sixth of the surface: every one of its texels is empty.
    assert!(
        bottom.empty as f64 > 0.1 * c.texels as f64,
        "{} of {} texels",
        bottom.empty,
        c.texels
    );
    assert!(bottom.remedy.contains("nothing is lost"), "{bottom:?}");
    // Every empty texel is the bottom's: none a view may reach.
    assert_eq!(c.unseen_empty, c.empty, "{c:?}");
    assert_eq!(report.visible_empty(), 0, "{c:?}");
    // Nothing facing up is in contact with anything.
    assert!(
        c.places
            .iter()
            .all(|p| !matches!(p.cause, Cause::Contact | Cause::Unseen) || p.facing != "+z"),
        "{c:?}"
    );
}

/// A slab thicker than the box is large: a probe from the box's bottom crosses it farther than
/// the box's size whatever its direction, and still no view reaches the bottom (each probe
/// first meets the slab from inside).
#[test]
fn a_box_resting_on_a_slab_thicker_than_itself_has_its_bottom_unseen() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    let slab = "[[box]]\nsize = [8.0, 8.0, 3.0]\ntransform = { translate = [0.0, 0.0, -1.5] }\n\
                material = { color = [0.5, 0.5, 0.5] }\n";
    let report = bake_box(d, [1.0, -0.5, 0.0], 400, slab);
    let c = the_box(&report);
    assert!(c.empty > 0, "{c:?}");
    let bottom = &c.places[0];
    assert_eq!(
        (bottom.cause, bottom.facing),
        (Cause::Unseen, "-z"),
        "{c:?}"
    );
    assert_eq!(c.unseen_empty, c.empty, "{c:?}");
    assert_eq!(report.visible_empty(), 0, "{c:?}");
}

#[test]
fn a_box_hovering_closer_than_epsilon_has_its_bottom_unseen_within_and_seen_at_the_edges() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    // A slab of the box's footprint, its top half ε (0.025) under the box's bottom: no point
    // fits in the gap. From the middle of the bottom every direction within 80° of straight
    // down meets the slab within 0.025 · tan 80° = 0.14 of the point; from within 0.14 of an
    // edge, views from the side pass the slab's edge and reach it.
    let slab = "[[box]]\nsize = [1.0, 1.0, 0.2]\ntransform = { translate = [1.5, 0.0, -0.125] }\n\
                material = { color = [0.5, 0.5, 0.5] }\n";
    let report = bake_box(d, [1.0, -0.5, 0.0], 400, slab);
    let c = the_box(&report);
    let down = |cause| {
        c.places
            .iter()
            .find(|p| p.cause == cause && p.facing == "-z")
            .unwrap_or_else(|| panic!("no {cause:?} facing down: {c:#?}"))
    };
    let (unseen, seen) = (down(Cause::Unseen), down(Cause::Contact));
    assert_eq!(unseen.surface.as_deref(), Some("[[box]] 0"), "{c:#?}");
    assert_eq!(seen.surface.as_deref(), Some("[[box]] 0"), "{c:#?}");
    // The unseen texels lie inside, more than a texel (1/8 of a face here) from the edges.
    for axis in 0..2 {
        assert!(
            unseen.min[axis] > seen.min[axis] + 0.05 && unseen.max[axis] < seen.max[axis] - 0.05,
            "{c:#?}"
        );
    }
    assert!(unseen.empty > 0 && seen.empty > 0, "{c:#?}");
    assert_eq!(c.unseen_empty, unseen.empty, "{c:#?}");
    assert_eq!(report.visible_empty(), c.empty - unseen.empty, "{c:#?}");
}

#[test]
fn a_floating_box_with_few_points_is_short_for_too_few_points_not_contact() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    let report = bake_box(d, [0.0, 0.0, 1.0], 6, "");
    let c = the_box(&report);
    assert!(c.short > 0, "{c:?}");
    assert!(!c.places.is_empty());
    assert!(c.places.iter().all(|p| p.cause == Cause::Sparse), "{c:?}");
    assert!(c.places[0].remedy.contains("sample_count"), "{c:?}");
    assert_eq!(c.places[0].surface, None);
}

#[test]
fn a_well_covered_floating_box_reports_no_short_place() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    let report = bake_box(d, [0.0, 0.0, 1.0], 400, "");
    let c = the_box(&report);
    assert_eq!((c.short, c.empty), (0, 0), "{c:?}");
    assert!(c.places.is_empty());
    assert!(c.texels > 0);
}

#[test]
fn a_surface_through_the_would_be_points_is_found_and_named() {
    // A plane exactly ε above the box's top: every point of the top would lie on it. A probe
    // ray from the point skips such a surface as a self-hit; the contact test, like
    // placement's, probes segments through the point.
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    let plane = "[[plane]]\nsize = [4.0, 4.0]\ntransform = { translate = [0.5, 0.5, 2.05] }\n\
                 material = { color = [0.5, 0.5, 0.5] }\n";
    let report = bake_box(d, [0.0, 0.0, 1.0], 400, plane);
    let c = the_box(&report);
    let top = c
        .places
        .iter()
        .find(|p| p.facing == "+z")
        .unwrap_or_else(|| panic!("no place facing +z: {c:?}"));
    // Named; and, the plane reaching past the top by more than ε · tan 80°, no view reaches
    // the top's surface.
    assert_eq!(top.cause, Cause::Unseen, "{c:?}");
    assert_eq!(top.surface.as_deref(), Some("[[plane]] 0"), "{c:?}");
    assert!((top.min[2] - 2.0).abs() < 1e-4, "{top:?}");
}
