//! The reference's depth-corrected lookups and what they decide: a silhouette's texels, a
//! glossy sample's fixed-point steps, the candidates' common hit, and per point visible's
//! stand-ins.

use oslf_format::INVALID_INDEX;

use super::blend::Candidates;
use super::cube::face_st;
use super::tests::{bare_shader, store_constants};
use super::*;
use crate::face::FAR_DISTANCE;

/// The default shading (depth-corrected) of a store of `res`² cubes with distances and no
/// environment cube.
fn depth_uniform(res: u32) -> crate::uniform::ShadeUniform {
    use crate::params::Background;
    use crate::shading::ShadingParams;
    use crate::uniform::ShadeUniform;
    let mut k = store_constants(INVALID_INDEX, res);
    k.has_depth = true;
    let camera = oslf_geometry::Camera {
        position: Vec3::new(0.0, -5.0, 1.0),
        target: Vec3::ZERO,
        up: Vec3::Z,
        vfov_deg: 40.0,
    };
    let u = ShadeUniform::new(
        &ShadingParams::default(),
        glam::Mat4::IDENTITY,
        &camera,
        [4, 4],
        &k,
        Background::Env,
    );
    assert!(u.depth_steps > 0);
    u
}

/// A cube whose every face holds a near surface (distance 2, red) on its left half and
/// nothing (blue) on its right: a silhouette down the middle of each face.
struct Silhouette(u32);

impl CubeTexels for Silhouette {
    fn depth(&self, _: u32, _: usize, x: u32, _: u32) -> Option<f32> {
        Some(if x < self.0 / 2 { 2.0 } else { FAR_DISTANCE })
    }
    fn texel(&self, _: u32, _: usize, _: u32, x: u32, _: u32) -> Option<Vec3> {
        Some(if x < self.0 / 2 { Vec3::X } else { Vec3::Z })
    }
    fn resident(&self, _: u32) -> bool {
        true
    }
}

/// A depth-corrected lookup at a silhouette takes the radiance of the surface its hit lies
/// on, not the bilinear blend across the silhouette that a plain lookup gives: a hit at the
/// near surface's distance reads red, a ray that meets nothing blue; a hit whose distance
/// agrees with no texel, and a hidden one, the plain blend.
#[test]
fn depth_lookups_keep_the_hits_surface_at_a_silhouette() {
    let res = 8;
    let cubes = Silhouette(res);
    let shader = bare_shader(depth_uniform(res), &[Vec3::ZERO], &cubes);
    // Face +x at s = ½: halfway between texel columns 3 (near) and 4 (nothing).
    let dir = face_point(0, 0.5, 3.5 / res as f32).normalize();
    let (face, s, _) = face_st(dir);
    assert!(face == 0 && (s - 0.5).abs() < 1e-6, "{face} {s}");
    let plain = shader.lookup(0, dir).unwrap();
    assert!(
        (plain - Vec3::new(0.5, 0.0, 0.5)).length() < 1e-5,
        "{plain}"
    );
    let near = shader.depth_lookup(0, (dir * 2.0, 1.0), 0.0).unwrap();
    assert_eq!(near, Vec3::X);
    let none = shader.depth_lookup(0, (dir, 0.0), 0.0).unwrap();
    assert_eq!(none, Vec3::Z);
    let between = shader.depth_lookup(0, (dir * 50.0, 1.0), 0.0).unwrap();
    assert!((between - plain).length() < 1e-6, "{between}");
    let hidden = shader.depth_lookup(0, (dir, -1.0), 0.0).unwrap();
    assert!((hidden - plain).length() < 1e-6, "{hidden}");
}

/// A sample point's view of a ceiling at z = 10 (nothing below the horizon), or of a
/// sphere of radius 3 around it (`sphere`).
struct Ceiling {
    res: u32,
    p: Vec3,
    sphere: bool,
}

impl CubeTexels for Ceiling {
    fn depth(&self, _: u32, face: usize, x: u32, y: u32) -> Option<f32> {
        if self.sphere {
            return Some(3.0);
        }
        let d = Vec3::from_array(oslf_format::cube::texel_direction(face, x, y, self.res));
        Some(if d.z > 0.0 {
            (10.0 - self.p.z) / d.z * d.length()
        } else {
            FAR_DISTANCE
        })
    }
    fn texel(&self, _: u32, _: usize, _: u32, _: u32, _: u32) -> Option<Vec3> {
        Some(Vec3::ONE)
    }
    fn resident(&self, _: u32) -> bool {
        true
    }
}

/// A glossy sample's depth correction (`depth_iterate`) turns the direction from the
/// shaded point into the one from the sample point to where the ray meets what the sample
/// point sees: exactly on a sphere of equal distances, within a few texels' angle on a
/// ceiling where the plain direction is off by ten times more; the plain direction for a
/// ray that meets nothing, and for a shaded point outside the sphere.
#[test]
fn glossy_depth_correction_finds_where_the_ray_meets_the_stored_distances() {
    let res = 64;
    let p = Vec3::new(0.0, 0.0, 0.1);
    let x = Vec3::new(0.8, 0.3, 0.0);
    let l = Vec3::new(-0.6, 0.2, 1.0).normalize();
    let angle = |a: Vec3, b: Vec3| a.normalize().dot(b.normalize()).clamp(-1.0, 1.0).acos();
    let sphere = Ceiling {
        res,
        p,
        sphere: true,
    };
    let shader = bare_shader(depth_uniform(res), std::slice::from_ref(&p), &sphere);
    let mut seed = 0.0;
    let q = shader.depth_iterate(0, x, l, true, &mut seed);
    let along = q - (x - p);
    assert!((q.length() - 3.0).abs() < 1e-5, "{q}");
    assert!(angle(along, l) < 1e-3 && along.dot(l) > 0.0, "{q}");
    assert!((seed - 3.0).abs() < 1e-3, "{seed}");
    // The next sample of the row takes the sphere of that distance, reading nothing:
    // exact on the sphere; the plain direction without a seed.
    let l2 = Vec3::new(-0.5, 0.3, 1.0).normalize();
    let q2 = shader.depth_iterate(0, x, l2, false, &mut seed);
    assert!((q2.length() - 3.0).abs() < 1e-3, "{q2}");
    assert!(angle(q2 - (x - p), l2) < 1e-3, "{q2}");
    assert!(
        (seed - 3.0).abs() < 1e-3,
        "a warm sample keeps the seed: {seed}"
    );
    assert_eq!(shader.depth_iterate(0, x, l2, false, &mut 0.0), l2);
    let far = Vec3::new(3.0, 0.0, 0.0);
    let mut seed = 1.0;
    assert_eq!(shader.depth_iterate(0, far, l, true, &mut seed), l);
    assert_eq!(seed, 0.0, "no hit leaves no seed");

    let ceiling = Ceiling {
        res,
        p,
        sphere: false,
    };
    let shader = bare_shader(depth_uniform(res), std::slice::from_ref(&p), &ceiling);
    let hit = x + l * (10.0 / l.z) - p;
    let q = shader.depth_iterate(0, x, l, true, &mut 0.0);
    let texel = std::f32::consts::FRAC_PI_2 / res as f32;
    assert!(
        angle(q, hit) < 3.0 * texel,
        "{} texels",
        angle(q, hit) / texel
    );
    assert!(
        angle(l, hit) > 10.0 * angle(q, hit),
        "{} {}",
        angle(l, hit),
        angle(q, hit)
    );
    let down = Vec3::new(0.3, 0.0, -1.0).normalize();
    assert_eq!(shader.depth_iterate(0, x, down, true, &mut 0.0), down);
}

/// Cubes drawn by tracing: each texel's distance and radiance.
trait Trace: Sync {
    fn trace(&self, cube: u32, face: usize, x: u32, y: u32) -> (f32, Vec3);
}

/// A [`Trace`]'s cubes, every face resident.
struct Traced<T>(T);

impl<T: Trace> CubeTexels for Traced<T> {
    fn depth(&self, cube: u32, face: usize, x: u32, y: u32) -> Option<f32> {
        Some(self.0.trace(cube, face, x, y).0)
    }
    fn texel(&self, cube: u32, face: usize, _: u32, x: u32, y: u32) -> Option<Vec3> {
        Some(self.0.trace(cube, face, x, y).1)
    }
    fn resident(&self, _: u32) -> bool {
        true
    }
}

/// The candidates of a texel at `x`: sample points 0 and 1 at `points`.
fn two_candidates(points: &[Vec3; 2], x: Vec3) -> Candidates {
    Candidates {
        idx: [0, 1, INVALID_INDEX, INVALID_INDEX],
        s: [
            (points[0] - x).normalize(),
            (points[1] - x).normalize(),
            Vec3::Z,
            Vec3::Z,
        ],
        count: 2,
    }
}

/// Two sample points over a ceiling 10 away (blue), with a small plate halfway (red) that
/// only the first one's cube holds (too thin for the second's texels, say).
struct TwoViews {
    res: u32,
    points: [Vec3; 2],
}

impl Trace for TwoViews {
    fn trace(&self, cube: u32, face: usize, x: u32, y: u32) -> (f32, Vec3) {
        let d = Vec3::from_array(oslf_format::cube::texel_direction(face, x, y, self.res));
        let p = self.points[cube as usize];
        if d.z <= 0.0 {
            return (FAR_DISTANCE, Vec3::Y);
        }
        let t = (5.0 - p.z) / d.z;
        let q = p + d * t;
        if cube == 0 && q.x * q.x + q.y * q.y < 0.25 {
            return (t * d.length(), Vec3::X);
        }
        ((10.0 - p.z) / d.z * d.length(), Vec3::Z)
    }
}

/// The candidates agree on the nearest hit their searches find: the plate that one
/// candidate's cube resolves is what the blend shows, the other candidate (whose distances
/// do not see the plate's point) left out, not a mix of plate and ceiling.
#[test]
fn depth_corrected_blends_agree_on_the_nearest_hit() {
    let res = 64;
    let uniform = depth_uniform(res);
    let points = [Vec3::new(0.1, 0.0, 0.1), Vec3::new(-0.1, 0.0, 0.1)];
    let cubes = Traced(TwoViews { res, points });
    let shader = bare_shader(uniform, &points, &cubes);
    let x = Vec3::ZERO;
    let c = two_candidates(&points, x);
    // Each candidate alone: the plate (the first), the ceiling (the second).
    let first = shader
        .blend_read(&c, [1.0, 0.0, 0.0, 0.0], x, Vec3::Z, 0.0, None)
        .unwrap();
    let second = shader
        .blend_read(&c, [0.0, 1.0, 0.0, 0.0], x, Vec3::Z, 0.0, None)
        .unwrap();
    assert!((first - Vec3::X).length() < 1e-5, "{first}");
    assert!((second - Vec3::Z).length() < 1e-5, "{second}");
    // Together, with the second weighted three times the first: the plate.
    let both = shader
        .blend_read(&c, [0.25, 0.75, 0.0, 0.0], x, Vec3::Z, 0.0, None)
        .unwrap();
    assert!((both - Vec3::X).length() < 1e-5, "{both}");
    // A ray past the plate's edge meets the ceiling for both.
    let past = Vec3::new(0.3, 0.0, 1.0).normalize();
    let both = shader
        .blend_read(&c, [0.25, 0.75, 0.0, 0.0], x, past, 0.0, None)
        .unwrap();
    assert!((both - Vec3::Z).length() < 1e-5, "{both}");
}

/// Two sample points: the first enclosed by a surface 0.05 away in every direction (red), the
/// second under a ceiling 10 away (blue, nothing below the horizon).
struct Enclosed {
    res: u32,
    points: [Vec3; 2],
}

impl Trace for Enclosed {
    fn trace(&self, cube: u32, face: usize, x: u32, y: u32) -> (f32, Vec3) {
        if cube == 0 {
            return (0.05, Vec3::X);
        }
        let d = Vec3::from_array(oslf_format::cube::texel_direction(face, x, y, self.res));
        if d.z <= 0.0 {
            return (FAR_DISTANCE, Vec3::Y);
        }
        ((10.0 - self.points[1].z) / d.z * d.length(), Vec3::Z)
    }
}

/// Per point visible: a sample whose ray its candidate cannot see (the enclosed point, whose
/// surface lies nearer than the ray's point at x's distance) reads the cube of the candidate
/// of largest weight that sees it; one that sees it reads its own; with no other candidate
/// that sees it, its own. Integrated, the enclosed candidate's estimate then shows the
/// ceiling (blue) where per point shows its enclosure (red).
#[test]
fn per_point_visible_reads_a_hidden_sample_from_a_point_that_sees_it() {
    let (points, cubes, uniform) = enclosed();
    let x = Vec3::ZERO;
    let o = |cube: usize| x - points[cube];
    let c = two_candidates(&points, x);
    let w = [0.5, 0.5, 0.0, 0.0];
    let up = sample_along(Vec3::Z);
    let shader = bare_shader(uniform, &points, &cubes);
    assert!(shader.depth_hidden(0, o(0), Vec3::Z));
    assert!(!shader.depth_hidden(1, o(1), Vec3::Z));
    assert_eq!(shader.stand_in(&c, 0, 0, w, x, &up), 1);
    assert_eq!(shader.stand_in(&c, 1, 1, w, x, &up), 1);
    assert_eq!(shader.stand_in(&c, 0, 0, [0.5, 0.0, 0.0, 0.0], x, &up), 0);
    let both_enclosed = Candidates {
        idx: [0, 0, INVALID_INDEX, INVALID_INDEX],
        ..c
    };
    assert_eq!(
        shader.stand_in(&both_enclosed, 0, 0, w, x, &up),
        0,
        "no other sees it"
    );

    let estimate = |order: u32| enclosed_estimate(uniform, order, &points, &cubes, &c, w);
    let (point, visible) = (estimate(0), estimate(2));
    assert!(point.x > 0.5 && point.z == 0.0, "{point}");
    assert!(visible.z > 0.5 && visible.x == 0.0, "{visible}");
}

/// Per point searched: each sample is read where its candidate's search meets the ray (the
/// ceiling above x, seen from the second point at a slant: not the plain direction); a sample
/// whose ray its candidate cannot see (the enclosed point: its search's w < 0) where the
/// candidate of largest weight that sees it meets the ray; with no other candidate that sees
/// it, its own search's direction. Integrated, the enclosed candidate's estimate shows the
/// ceiling (blue) where per point shows its enclosure (red).
#[test]
fn per_point_searched_reads_where_a_point_that_sees_the_ray_meets_it() {
    let (points, cubes, uniform) = enclosed();
    let x = Vec3::ZERO;
    let c = two_candidates(&points, x);
    let w = [0.5, 0.5, 0.0, 0.0];
    let up = sample_along(Vec3::Z);
    let shader = bare_shader(uniform, &points, &cubes);
    assert!(shader.depth_search(0, x, Vec3::Z).1 < 0.0, "enclosed");
    assert_eq!(
        shader.depth_search(1, x, Vec3::Z).1,
        1.0,
        "under the ceiling"
    );
    // x + 10 z seen from (−0.1, 0, 0.1).
    let want = Vec3::new(0.1, 0.0, 9.9);
    for k in [0, 1] {
        let (e, d) = shader.searched(&c, k, k, w, x, Vec3::Z, &up).unwrap();
        assert_eq!(e, 1, "candidate {k}");
        assert!((d - want).length() < 0.05 * want.length(), "{k}: {d}");
    }
    let (e, d) = shader
        .searched(&c, 0, 0, [0.5, 0.0, 0.0, 0.0], x, Vec3::Z, &up)
        .unwrap();
    assert_eq!((e, d), (0, Vec3::Z), "the other has no weight");
    let both_enclosed = Candidates {
        idx: [0, 0, INVALID_INDEX, INVALID_INDEX],
        ..c
    };
    assert_eq!(
        shader.searched(&both_enclosed, 0, 0, w, x, Vec3::Z, &up),
        Some((0, Vec3::Z)),
        "no other sees it"
    );

    let estimate = |order: u32| enclosed_estimate(uniform, order, &points, &cubes, &c, w);
    let (point, searched) = (estimate(0), estimate(3));
    assert!(point.x > 0.5 && point.z == 0.0, "{point}");
    assert!(searched.z > 0.5 && searched.x == 0.0, "{searched}");
}

/// The first candidate's glossy estimate at the origin, normal +z, under `order`, in the
/// `Enclosed` scenes' tests.
fn enclosed_estimate(
    mut uniform: crate::uniform::ShadeUniform,
    order: u32,
    points: &[Vec3; 2],
    cubes: &Traced<Enclosed>,
    c: &Candidates,
    w: [f32; 4],
) -> Vec3 {
    uniform.order = order;
    let shader = bare_shader(uniform, points, cubes);
    let (n, t, b, v) = (Vec3::Z, Vec3::X, Vec3::Y, Vec3::Z);
    let (e, ok) = shader.integrate(
        c,
        0,
        0,
        0,
        Vec3::ZERO,
        n,
        t,
        b,
        v,
        1.0,
        Vec3::ONE,
        glam::Vec2::ZERO,
        w,
    );
    assert!(ok);
    e
}

/// The `Enclosed` scene's two points (the enclosed one first), its cubes at 16², and a
/// uniform for a near-mirror glossy lobe (n 10 000) of M = 4 without the diffuse term.
fn enclosed() -> ([Vec3; 2], Traced<Enclosed>, crate::uniform::ShadeUniform) {
    let res = 16;
    let points = [Vec3::new(0.1, 0.0, 0.1), Vec3::new(-0.1, 0.0, 0.1)];
    let mut uniform = depth_uniform(res);
    (uniform.m, uniform.rd, uniform.nu, uniform.nv) = (4, 0.0, 10000.0, 10000.0);
    (points, Traced(Enclosed { res, points }), uniform)
}

/// A glossy sample along `l` (normalized) of weight 1.
fn sample_along(l: Vec3) -> super::glossy::AsSample {
    super::glossy::AsSample {
        l: l.normalize(),
        weight: Vec3::ONE,
        lpdf: 0.0,
    }
}

/// Two sample points 0.1 above x = 0 and a wall at x = 0.5 (red below z = 0.05, green above;
/// nothing elsewhere).
struct Wall {
    res: u32,
    points: [Vec3; 2],
}

impl Trace for Wall {
    fn trace(&self, cube: u32, face: usize, x: u32, y: u32) -> (f32, Vec3) {
        let d = Vec3::from_array(oslf_format::cube::texel_direction(face, x, y, self.res));
        let p = self.points[cube as usize];
        if d.x <= 0.0 {
            return (FAR_DISTANCE, Vec3::Z);
        }
        let t = (0.5 - p.x) / d.x;
        let colour = if p.z + t * d.z < 0.05 {
            Vec3::X
        } else {
            Vec3::Y
        };
        (t * d.length(), colour)
    }
}

/// Per point searched leaves a hit lower above x's tangent plane than LOW_HIT times the
/// point's distance from x (the wall met by a ray 1° above the plane, 0.009 high, the point
/// 0.1 away) to the per point read, and keeps a higher one (45°: 0.5 high). Per direction's
/// blend (`low` given) looks such a candidate up along the ray (the wall's green, above
/// z = 0.05, where the points see it that way), where the mirror's (no `low`) reads the hit
/// (red).
#[test]
fn a_low_hit_is_read_as_if_the_search_had_not_met_it() {
    let res = 64;
    let points = [Vec3::new(0.0, 0.0, 0.1), Vec3::new(0.0, 0.1, 0.1)];
    let cubes = Traced(Wall { res, points });
    let shader = bare_shader(depth_uniform(res), &points, &cubes);
    let x = Vec3::ZERO;
    let c = two_candidates(&points, x);
    let w = [0.5, 0.5, 0.0, 0.0];
    let low = sample_along(Vec3::new(1.0, 0.0, 0.0175));
    assert_eq!(
        shader.depth_search(0, x, low.l).1,
        1.0,
        "the search meets the wall"
    );
    assert_eq!(shader.searched(&c, 0, 0, w, x, Vec3::Z, &low), None);
    let high = sample_along(Vec3::new(1.0, 0.0, 1.0));
    let (e, d) = shader.searched(&c, 0, 0, w, x, Vec3::Z, &high).unwrap();
    // The wall's point (0.5, 0, 0.5) seen from (0, 0, 0.1).
    let want = Vec3::new(0.5, 0.0, 0.4);
    assert_eq!(e, 0);
    assert!((d - want).length() < 0.02, "{d}");
    let read = |l: Vec3, low: Option<Vec3>| shader.blend_read(&c, w, x, l, 0.0, low).unwrap();
    let (plain, hit) = (read(low.l, Some(Vec3::Z)), read(low.l, None));
    assert!(plain.y > 0.99 && plain.x < 0.01, "per direction: {plain}");
    assert!(hit.x > 0.99 && hit.y < 0.01, "the mirror: {hit}");
    assert_eq!(read(high.l, Some(Vec3::Z)), read(high.l, None));
}
