//! Geometry tests: Bézier patches and the teapot, the patch-file parser, tessellation,
//! built-in shapes and the BVH against brute force.

use std::f32::consts::PI;
use std::path::Path;

use glam::{Affine3A, Vec2, Vec3};
use oslf_geometry::bezier::{newell_teapot, parse_patch_file, TEAPOT_BODY_PATCHES};
use oslf_geometry::mesh::Mesh;
use oslf_scene::{shapes, BakeError};
use oslf_trace::bvh::{Instance, TriangleScene};
use oslf_trace::ray::{Intersector, Ray, ENVIRONMENT_OBJECT};

/// Small deterministic generator (xorshift64*), uniform floats in [0, 1).
struct Rng(u64);
impl Rng {
    fn next(&mut self) -> f32 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        ((self.0.wrapping_mul(0x2545_f491_4f6c_dd1d) >> 40) as f32) / (1u64 << 24) as f32
    }
    fn dir(&mut self) -> Vec3 {
        let z = 2.0 * self.next() - 1.0;
        let phi = 2.0 * PI * self.next();
        let r = (1.0 - z * z).max(0.0).sqrt();
        Vec3::new(r * phi.cos(), r * phi.sin(), z)
    }
}

/// Parameter grid including both ends.
fn grid(n: usize) -> impl Iterator<Item = (f32, f32)> {
    (0..=n).flat_map(move |i| (0..=n).map(move |j| (i as f32 / n as f32, j as f32 / n as f32)))
}

// ---------------------------------------------------------------- Bézier patches

#[test]
fn teapot_corners_interpolate_control_points() {
    let teapot = newell_teapot();
    assert_eq!(teapot.len(), 32);
    assert_eq!(TEAPOT_BODY_PATCHES.len(), 28);
    for p in &teapot {
        assert_eq!(p.eval(0.0, 0.0), p.cp[0]);
        assert_eq!(p.eval(0.0, 1.0), p.cp[3]);
        assert_eq!(p.eval(1.0, 0.0), p.cp[12]);
        assert_eq!(p.eval(1.0, 1.0), p.cp[15]);
    }
    // The rim starts at (1.4, 0, 2.4).
    assert_eq!(teapot[0].eval(0.0, 0.0), Vec3::new(1.4, 0.0, 2.4));
}

#[test]
fn partials_match_finite_differences() {
    let h = 1e-3f32;
    for p in &newell_teapot() {
        for (u, v) in [(0.3, 0.6), (0.5, 0.5), (0.1, 0.9), (0.8, 0.2)] {
            let (du, dv) = p.partials(u, v);
            let fu = (p.eval(u + h, v) - p.eval(u - h, v)) / (2.0 * h);
            let fv = (p.eval(u, v + h) - p.eval(u, v - h)) / (2.0 * h);
            let scale = 1.0 + du.length().max(dv.length());
            assert!((du - fu).length() < 2e-3 * scale, "{du} vs {fu}");
            assert!((dv - fv).length() < 2e-3 * scale, "{dv} vs {fv}");
        }
    }
}

#[test]
fn affine_transform_commutes_with_evaluation() {
    let m = Affine3A::from_scale_rotation_translation(
        Vec3::new(2.0, 0.5, 1.5),
        glam::Quat::from_rotation_z(0.7),
        Vec3::new(3.0, -1.0, 0.25),
    );
    for p in &newell_teapot() {
        let q = p.transformed(&m);
        for (u, v) in [(0.2, 0.7), (0.9, 0.4)] {
            let a = m.transform_point3(p.eval(u, v));
            assert!((a - q.eval(u, v)).length() < 1e-5);
        }
    }
}

#[test]
fn normals_finite_and_unit_everywhere() {
    for (k, p) in newell_teapot().iter().enumerate() {
        for (u, v) in grid(64) {
            let n = p.normal(u, v);
            assert!(n.is_finite(), "patch {k} ({u}, {v}) normal {n}");
            assert!((n.length() - 1.0).abs() < 1e-5, "patch {k} ({u},{v}) {n}");
        }
    }
}

#[test]
fn normals_converge_at_collapsed_edges() {
    let teapot = newell_teapot();
    // Lid top (patches 21-24) and bottom (29-32) collapse the u = 0 edge to one point.
    for k in (20..24).chain(28..32) {
        let p = &teapot[k];
        assert_eq!(p.cp[0], p.cp[3], "patch {} should be degenerate", k + 1);
        let expected = if k < 24 { Vec3::Z } else { -Vec3::Z };
        for j in 0..=8 {
            let v = j as f32 / 8.0;
            let n0 = p.normal(0.0, v);
            assert!(
                (n0 - expected).length() < 1e-5,
                "patch {} v={v}: {n0}",
                k + 1
            );
            let mut prev = f32::INFINITY;
            for e in 1..=7 {
                let u = 10f32.powi(-e);
                let d = (p.normal(u, v) - n0).length();
                assert!(d <= prev + 1e-6, "patch {} not converging at u={u}", k + 1);
                prev = d;
            }
            assert!(prev < 1e-5, "patch {} v={v}: limit off by {prev}", k + 1);
        }
    }
}

#[test]
#[allow(clippy::needless_range_loop)] // k is the patch number in messages
fn teapot_normals_point_outward() {
    let teapot = newell_teapot();
    let n = 16;
    // Body (patches 1-12): away from the z axis, except patches 1-4, the rim's lip
    // (r 1.4 -> 1.5 over z = 2.4..2.53): away from the lip's core at r = 1.45, z = 2.4.
    for k in 0..12 {
        for (u, v) in grid(n) {
            let x = teapot[k].eval(u, v);
            let nrm = teapot[k].normal(u, v);
            let radial = Vec3::new(x.x, x.y, 0.0);
            let away = if k < 4 {
                x - radial.normalize() * 1.45 - Vec3::Z * 2.4
            } else {
                radial
            };
            assert!(nrm.dot(away) > 0.0, "body patch {} ({u},{v}): {nrm}", k + 1);
        }
    }
    // Handle (13-16) and spout (17-18): tubes; away from the tube's cross-section centre, the
    // mean of the two half-tube patches at the same u.
    for pair in [[12, 13], [14, 15], [16, 17]] {
        for i in 1..n {
            let u = i as f32 / n as f32;
            let ring: Vec<Vec3> = pair
                .iter()
                .flat_map(|&k| (0..n).map(move |j| (k, j as f32 / n as f32)))
                .map(|(k, v)| teapot[k].eval(u, v))
                .collect();
            let centre = ring.iter().copied().sum::<Vec3>() / ring.len() as f32;
            for &k in &pair {
                for j in 0..=n {
                    let v = j as f32 / n as f32;
                    let d = teapot[k].eval(u, v) - centre;
                    let nrm = teapot[k].normal(u, v);
                    assert!(nrm.dot(d) > 0.0, "tube patch {} ({u},{v}): {nrm}", k + 1);
                }
            }
        }
    }
    // Spout tip (19-20) is a lip like the rim: away from the lip's core, the midpoint of its
    // inner (u = 0) and outer (u = 1) edges.
    for k in [18, 19] {
        for (u, v) in grid(n) {
            let p = &teapot[k];
            let core = (p.eval(0.0, v) + p.eval(1.0, v)) * 0.5;
            let nrm = p.normal(u, v);
            assert!(
                nrm.dot(p.eval(u, v) - core) > 0.0,
                "spout tip {} ({u},{v})",
                k + 1
            );
        }
    }
    // Lid (21-28): upward on the top and flange; away from the knob's axis on its underside.
    for k in 20..28 {
        for (u, v) in grid(n) {
            let x = teapot[k].eval(u, v);
            let nrm = teapot[k].normal(u, v);
            let away = Vec3::new(x.x, x.y, 0.0).dot(nrm) > 0.0;
            assert!(nrm.z > 0.0 || away, "lid patch {} ({u},{v}): {nrm}", k + 1);
        }
    }
    // Bottom (29-32): downward, turning outward where it meets the body (u = 1): away from
    // a point above its centre.
    for k in 28..32 {
        for (u, v) in grid(n) {
            let nrm = teapot[k].normal(u, v);
            let d = teapot[k].eval(u, v) - Vec3::new(0.0, 0.0, 0.5);
            assert!(nrm.dot(d) > 0.0, "bottom patch {} ({u},{v}): {nrm}", k + 1);
            if u < 0.5 {
                assert!(nrm.z < 0.0, "bottom patch {} ({u},{v}): {nrm}", k + 1);
            }
        }
    }
}

#[test]
fn shared_patch_edges_have_matching_normals() {
    // Neighbouring body patches share an edge (identical control points): the normals there
    // must agree in direction (consistent orientation over the whole teapot).
    let teapot = newell_teapot();
    let mut checked = 0;
    for (a, pa) in teapot.iter().enumerate() {
        for (b, pb) in teapot.iter().enumerate() {
            if a == b {
                continue;
            }
            // a's v = 1 edge equals b's v = 0 edge.
            let same = (0..4).all(|i| pa.cp[4 * i + 3] == pb.cp[4 * i]);
            if same && pa.cp[3] != pa.cp[15] {
                for i in 1..8 {
                    let u = i as f32 / 8.0;
                    let (na, nb) = (pa.normal(u, 1.0), pb.normal(u, 0.0));
                    assert!(na.dot(nb) > 0.9, "patches {} / {} at u={u}", a + 1, b + 1);
                }
                checked += 1;
            }
        }
    }
    assert!(checked >= 16, "only {checked} shared edges found");
}

// ---------------------------------------------------------------- tessellation

#[test]
fn tessellation_meets_error_bound() {
    for max_error in [0.01f32, 0.002] {
        for (k, p) in newell_teapot().iter().enumerate() {
            let n = p.tessellation_level(max_error);
            let mesh = p.tessellate(n);
            mesh.validate().unwrap();
            assert_eq!(mesh.triangles.len(), 2 * (n * n) as usize);
            let mut worst = 0.0f32;
            for t in &mesh.triangles {
                let [a, b, c] = mesh.corners(t).unwrap();
                let uv =
                    (mesh.uvs[t[0] as usize] + mesh.uvs[t[1] as usize] + mesh.uvs[t[2] as usize])
                        / 3.0;
                let flat = (a + b + c) / 3.0;
                worst = worst.max((p.eval(uv.x, uv.y) - flat).length());
            }
            assert!(
                worst < max_error,
                "patch {} n={n}: {worst} >= {max_error}",
                k + 1
            );
            // Not absurdly fine either: halving n must break the bound or n is small.
            assert!(n <= 64, "patch {} n={n} for {max_error}", k + 1);
        }
    }
}

#[test]
fn tessellation_winding_matches_normals() {
    for (k, p) in newell_teapot().iter().enumerate() {
        let mesh = p.tessellate(12);
        for t in &mesh.triangles {
            let [a, b, c] = mesh.corners(t).unwrap();
            let Some(gn) = (b - a).cross(c - a).try_normalize() else {
                continue; // collapsed edge
            };
            let vn = (mesh.normals[t[0] as usize]
                + mesh.normals[t[1] as usize]
                + mesh.normals[t[2] as usize])
                .normalize();
            assert!(gn.dot(vn) > 0.5, "patch {}: {gn} vs {vn}", k + 1);
        }
    }
}

// ---------------------------------------------------------------- patch file parser

fn parse_err(text: &str) -> (usize, usize, String) {
    match parse_patch_file(text, Path::new("test.patch")).map_err(BakeError::from) {
        Err(BakeError::Parse {
            path,
            line,
            column,
            message,
        }) => {
            assert_eq!(path, Path::new("test.patch"));
            (line, column, message)
        }
        other => panic!("expected a parse error, got {other:?}"),
    }
}

const ONE_PATCH: &str = "# comment\n1\n1 2 3 4 5 6 7 8 9 10 11 12 13 14 15 16\n16\n";

fn one_patch_file(points: &[String]) -> String {
    format!("{ONE_PATCH}{}\n", points.join("\n"))
}

fn grid_points() -> Vec<String> {
    (0..16)
        .map(|k| format!("{}, {}, 0.0", k / 4, k % 4))
        .collect()
}

#[test]
fn parser_accepts_commas_and_whitespace() {
    let text = one_patch_file(&grid_points());
    let p = parse_patch_file(&text, Path::new("x")).unwrap();
    assert_eq!(p.len(), 1);
    // Flat bilinear grid: evaluates exactly.
    assert!((p[0].eval(0.5, 0.25) - Vec3::new(1.5, 0.75, 0.0)).length() < 1e-6);
    let text = text.replace(' ', ",").replace(",,", ",");
    assert!(parse_patch_file(&text, Path::new("x")).is_ok());
}

#[test]
fn parser_errors_are_located() {
    // Bad number: point line 5 ("0, 1, 0.0" -> "0, 1x, 0.0"), column 4.
    let mut pts = grid_points();
    pts[1] = "0, 1x, 0.0".into();
    let (line, col, msg) = parse_err(&one_patch_file(&pts));
    assert_eq!((line, col), (6, 4), "{msg}");

    // NaN and infinity.
    let mut pts = grid_points();
    pts[2] = "0 2 nan".into();
    let (l, c, _) = parse_err(&one_patch_file(&pts));
    assert_eq!((l, c), (7, 5));
    let mut pts = grid_points();
    pts[0] = "inf 0 0".into();
    let (line, col, _) = parse_err(&one_patch_file(&pts));
    assert_eq!((line, col), (5, 1));

    // Index out of range: 17 in a file with 16 points, line 3 column 38.
    let text = one_patch_file(&grid_points()).replace(" 16\n16", " 17\n16");
    let (line, col, msg) = parse_err(&text);
    assert_eq!((line, col), (3, 37), "{msg}");
    assert!(msg.contains("17"));
    let text = one_patch_file(&grid_points()).replace("\n1 2 3", "\n0 2 3");
    assert_eq!(parse_err(&text).0, 3);

    // Wrong count: 15 indices on a patch line.
    let text = one_patch_file(&grid_points()).replace(" 15 16\n", " 15\n");
    let (line, _, msg) = parse_err(&text);
    assert_eq!(line, 3, "{msg}");
    // A point line with 2 coordinates.
    let mut pts = grid_points();
    pts[3] = "0 3".into();
    assert_eq!(parse_err(&one_patch_file(&pts)).0, 8);
    // Too few points (file ends).
    let pts = grid_points()[..15].to_vec();
    assert!(parse_err(&one_patch_file(&pts)).2.contains("15 of 16"));
    // Trailing data.
    let mut pts = grid_points();
    pts.push("1 2 3".into());
    assert_eq!(parse_err(&one_patch_file(&pts)).0, 21);
    // Bad patch count, empty field.
    let (l, c, _) = parse_err("x\n");
    assert_eq!((l, c), (1, 1));
    assert_eq!(parse_err("0\n").0, 1);
    assert_eq!(parse_err("").0, 1);
    let mut pts = grid_points();
    pts[0] = "0,,0,0".into();
    let (l, c, _) = parse_err(&one_patch_file(&pts));
    assert_eq!((l, c), (5, 3));
}

// ---------------------------------------------------------------- shapes

/// Every non-degenerate triangle's winding agrees with its vertex normals.
fn assert_winding_consistent(name: &str, m: &Mesh) {
    m.validate().unwrap();
    for t in &m.triangles {
        let [a, b, c] = m.corners(t).unwrap();
        let Some(gn) = (b - a).cross(c - a).try_normalize() else {
            continue;
        };
        for &i in t {
            assert!(
                gn.dot(m.normals[i as usize]) > 0.5,
                "{name}: {gn} vs {}",
                m.normals[i as usize]
            );
        }
    }
}

#[test]
fn shapes_outward_and_areas() {
    let plane = shapes::plane(Vec2::new(4.0, 3.0)).unwrap();
    assert_winding_consistent("plane", &plane);
    assert!(plane.normals.iter().all(|n| *n == Vec3::Z));
    assert!((plane.area() - 12.0).abs() < 1e-5);

    let cube = shapes::cuboid(Vec3::new(1.0, 2.0, 3.0)).unwrap();
    assert_winding_consistent("cuboid", &cube);
    assert!((cube.area() - 22.0).abs() < 1e-4);
    for (p, n) in cube.positions.iter().zip(&cube.normals) {
        assert!(p.dot(*n) > 0.0);
    }

    let (r, segs) = (1.5f32, 128);
    let sphere = shapes::sphere(r, segs).unwrap();
    assert_winding_consistent("sphere", &sphere);
    let exact = 4.0 * std::f64::consts::PI * f64::from(r * r);
    assert!(
        (sphere.area() - exact).abs() / exact < 2e-3,
        "{}",
        sphere.area()
    );
    for (p, n) in sphere.positions.iter().zip(&sphere.normals) {
        assert!((p.length() - r).abs() < 1e-5 && (*n - *p / r).length() < 1e-5);
    }

    let (h, segs) = (2.0f32, 256);
    let cyl = shapes::cylinder(r, h, segs, true).unwrap();
    assert_winding_consistent("cylinder", &cyl);
    let exact = 2.0 * std::f64::consts::PI * f64::from(r * h + r * r);
    assert!((cyl.area() - exact).abs() / exact < 1e-3, "{}", cyl.area());
    for (p, n) in cyl.positions.iter().zip(&cyl.normals) {
        let centre = Vec3::new(0.0, 0.0, h / 2.0);
        assert!((*p - centre).dot(*n) > 0.0, "{p} {n}");
    }
    let open = shapes::cylinder(r, h, segs, false).unwrap();
    let exact = 2.0 * std::f64::consts::PI * f64::from(r * h);
    assert!((open.area() - exact).abs() / exact < 1e-3);

    // A teacup: bottom centre -> outside -> rim -> inside -> inner bottom centre.
    let cup = shapes::revolution(
        &[
            Vec2::new(0.0, 0.0),
            Vec2::new(0.8, 0.0),
            Vec2::new(1.0, 1.0),
            Vec2::new(0.95, 1.0),
            Vec2::new(0.76, 0.05),
            Vec2::new(0.0, 0.05),
        ],
        48,
    )
    .unwrap();
    assert_winding_consistent("teacup", &cup);
    // Inside wall faces the axis, outside faces away.
    let inner = cup
        .positions
        .iter()
        .zip(&cup.normals)
        .find(|(p, _)| (p.z - 0.5).abs() < 0.3 && Vec2::new(p.x, p.y).length() < 0.87);
    if let Some((p, n)) = inner {
        assert!(Vec2::new(p.x, p.y).dot(Vec2::new(n.x, n.y)) < 0.0);
    }
}

// ---------------------------------------------------------------- BVH

fn teapot_mesh(max_error: f32) -> Mesh {
    let mut m = Mesh::new();
    for p in newell_teapot() {
        m.append(&p.tessellate(p.tessellation_level(max_error)));
    }
    m
}

fn test_scene(offset: Vec3, max_error: f32) -> (TriangleScene, Mesh) {
    let mut teapot = teapot_mesh(max_error);
    let mut floor = shapes::plane(Vec2::new(12.0, 12.0)).unwrap();
    let mut box1 = shapes::cuboid(Vec3::new(1.0, 1.5, 2.0)).unwrap();
    box1.transform(&Affine3A::from_translation(Vec3::new(3.5, 1.0, 1.0)));
    let mut ball = shapes::sphere(0.7, 32).unwrap();
    ball.transform(&Affine3A::from_translation(Vec3::new(-3.0, -2.0, 0.7)));
    let mut cyl = shapes::cylinder(0.5, 3.0, 24, true).unwrap();
    cyl.transform(&Affine3A::from_translation(Vec3::new(-2.5, 3.0, 0.0)));
    let t = Affine3A::from_translation(offset);
    for m in [&mut teapot, &mut floor, &mut box1, &mut ball, &mut cyl] {
        m.transform(&t);
    }
    let inst = |mesh: &Mesh, material, object| Instance {
        name: String::new(),
        mesh: mesh.clone(),
        material,
        object,
    };
    let scene = TriangleScene::build(vec![
        inst(&teapot, 0, 0),
        inst(&floor, 1, ENVIRONMENT_OBJECT),
        inst(&box1, 2, ENVIRONMENT_OBJECT),
        inst(&ball, 3, ENVIRONMENT_OBJECT),
        inst(&cyl, 4, ENVIRONMENT_OBJECT),
    ])
    .unwrap();
    (scene, teapot)
}

/// Random points offset `eps` above the teapot, with their surface normals.
fn sample_points(teapot: &Mesh, eps: f32, rng: &mut Rng, n: usize) -> Vec<(Vec3, Vec3)> {
    (0..n)
        .filter_map(|_| {
            let t = teapot.triangles
                [(rng.next() * teapot.triangles.len() as f32) as usize % teapot.triangles.len()];
            let [a, b, c] = teapot.corners(&t).unwrap();
            let gn = (b - a).cross(c - a).try_normalize()?;
            let (mut s, mut q) = (rng.next(), rng.next());
            if s + q > 1.0 {
                (s, q) = (1.0 - s, 1.0 - q);
            }
            Some((a + (b - a) * s + (c - a) * q + gn * eps, gn))
        })
        .collect()
}

fn compare(scene: &TriangleScene, rays: &[Ray]) -> (usize, usize) {
    let (mut hits, mut ties) = (0, 0);
    for ray in rays {
        let a = scene.intersect(ray, f32::INFINITY);
        let b = scene.intersect_brute_force(ray, f32::INFINITY);
        match (a, b) {
            (None, None) => {}
            (Some(a), Some(b)) => {
                hits += 1;
                assert!(
                    (a.t - b.t).abs() <= 1e-5 * b.t,
                    "t {} vs brute force {} for {ray:?}",
                    a.t,
                    b.t
                );
                if a.triangle != b.triangle {
                    // Only exact ties (a ray through a shared edge) may differ.
                    assert_eq!(a.t, b.t, "{ray:?}");
                    ties += 1;
                }
                assert!(a.geometric_normal.is_finite() && a.shading_normal.is_finite());
                assert!(a.shading_normal.dot(a.geometric_normal) >= 0.0);
                assert!(a.uv.is_finite() && a.position.is_finite());
                let d = (a.position - ray.at(a.t)).length();
                assert!(d <= 1e-4 * (1.0 + ray.origin.abs().max_element()), "{d}");
            }
            (a, b) => panic!("BVH {a:?} vs brute force {b:?} for {ray:?}"),
        }
        let t_cut = b.map_or(100.0, |h| h.t * 1.5);
        assert_eq!(
            scene.occluded(ray, t_cut),
            scene.intersect(ray, t_cut).is_some()
        );
        if let Some(h) = b {
            assert!(!scene.occluded(ray, h.t * (1.0 - 1e-4)));
        }
    }
    (hits, ties)
}

#[test]
fn bvh_matches_brute_force() {
    let (scene, teapot) = test_scene(Vec3::ZERO, 0.01);
    let (lo, hi) = scene.bounds();
    assert!(lo.z >= -1e-6 && hi.z > 3.0);
    let mut rng = Rng(0x1234_5678_9abc_def1);
    let mut rays = Vec::new();
    // Random rays through the scene box.
    for _ in 0..2000 {
        let o =
            lo + (hi - lo) * Vec3::new(rng.next(), rng.next(), rng.next()) * 1.2 - (hi - lo) * 0.1;
        rays.push(Ray::new(o, rng.dir()));
    }
    // Rays from sample points ε = 0.1 above the teapot (the bake's rays).
    for (o, _) in sample_points(&teapot, 0.1, &mut rng, 2000) {
        rays.push(Ray::new(o, rng.dir()));
    }
    // Axis-parallel rays.
    for k in 0..300 {
        let o = Vec3::new(rng.next() * 4.0 - 2.0, rng.next() * 4.0 - 2.0, 5.0);
        let d = [-Vec3::Z, Vec3::X, -Vec3::Y][k % 3];
        rays.push(Ray::new(o - d * 5.0, d));
    }
    let (hits, ties) = compare(&scene, &rays);
    assert!(hits > rays.len() / 4, "{hits}");
    assert!(ties < 5, "{ties}");
}

#[test]
fn bvh_far_from_origin_and_tiny_epsilon() {
    // Scene 1e5 units from the origin, ε = 0.1.
    let off = Vec3::splat(1e5);
    let (scene, teapot) = test_scene(off, 0.01);
    let mut rng = Rng(42);
    let pts = sample_points(&teapot, 0.1, &mut rng, 1000);
    let rays: Vec<Ray> = pts.iter().map(|(o, _)| Ray::new(*o, rng.dir())).collect();
    compare(&scene, &rays);
    for (o, n) in &pts {
        let h = scene
            .intersect(&Ray::new(*o, -*n), 1.0)
            .expect("surface below");
        // Other parts of the teapot (lid gap, handle) may be closer than the surface below.
        assert!(h.t < 0.13, "{}", h.t);
    }
    // At the origin with ε = 1e-6 of the teapot's size (≈ 3e-6).
    let (scene, teapot) = test_scene(Vec3::ZERO, 0.01);
    let eps = 3e-6;
    let mut found = 0;
    for (o, n) in sample_points(&teapot, eps, &mut rng, 1000) {
        let h = scene
            .intersect(&Ray::new(o, -n), 1.0)
            .expect("surface below");
        if (h.t - eps).abs() < 0.2 * eps {
            found += 1;
        }
        assert!(h.t > 0.0 && h.t < 1e-3, "{}", h.t);
        // Outward from ε above: must not see the surface it sits on.
        if let Some(h) = scene.intersect(&Ray::new(o, n), 1.0) {
            assert!(h.t > 1e-3, "self hit at {}", h.t);
        }
    }
    assert!(found > 950, "{found}");
}

#[test]
fn ray_started_on_surface_does_not_self_hit() {
    let (scene, teapot) = test_scene(Vec3::ZERO, 0.01);
    let mut rng = Rng(7);
    let mut hit_away = 0;
    for (p, n) in sample_points(&teapot, 0.0, &mut rng, 3000) {
        // Pointing away from the surface: no hit at t ≈ 0.
        let mut d = rng.dir();
        if d.dot(n) < 0.0 {
            d = -d;
        }
        if let Some(h) = scene.intersect(&Ray::new(p, d), f32::INFINITY) {
            assert!(h.t > 1e-4, "self hit at t = {}", h.t);
            hit_away += 1;
        }
        assert!(!scene.occluded(&Ray::new(p, d), 1e-4));
    }
    assert!(hit_away > 0);
    // Secondary rays spawned at hit positions (as the integrator does), to either side.
    let mut spawned = 0;
    for _ in 0..3000 {
        let o = rng.dir() * 8.0 + Vec3::Z * 1.5;
        let target = Vec3::new(rng.next() - 0.5, rng.next() - 0.5, rng.next() * 3.0);
        let Some(h) = scene.intersect(&Ray::new(o, (target - o).normalize()), f32::INFINITY) else {
            continue;
        };
        for side in [1.0, -1.0] {
            let mut d = rng.dir();
            if d.dot(h.geometric_normal) * side < 0.0 {
                d = -d;
            }
            if let Some(h2) = scene.intersect(&Ray::new(h.position, d), f32::INFINITY) {
                assert!(
                    h2.triangle != h.triangle && h2.t > 1e-5 || h2.t > 1e-3,
                    "self hit at t = {} (triangle {})",
                    h2.t,
                    h2.triangle
                );
            }
        }
        spawned += 1;
    }
    assert!(spawned > 1000, "{spawned}");
}
