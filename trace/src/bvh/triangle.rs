//! The watertight ray–triangle test (Woop, Benthin and Wald 2013, with pbrt-v3's
//! conservative bound on `t`), scalar and SSE, bit for bit the same.

use glam::Vec3;

use super::prepared_ray::PreparedRay;

/// A triangle's corners by coordinate (`x[i]` is corner `i`'s x; lane 3 is 0), so that the
/// triangle test loads each coordinate of all three corners as one SSE vector.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(16))]
pub(super) struct Corners {
    pub(super) x: [f32; 4],
    pub(super) y: [f32; 4],
    pub(super) z: [f32; 4],
}

impl Corners {
    pub(super) fn new(v: &[Vec3; 3]) -> Self {
        Corners {
            x: [v[0].x, v[1].x, v[2].x, 0.0],
            y: [v[0].y, v[1].y, v[2].y, 0.0],
            z: [v[0].z, v[1].z, v[2].z, 0.0],
        }
    }

    pub(super) fn vertices(&self) -> [Vec3; 3] {
        [0, 1, 2].map(|i| Vec3::new(self.x[i], self.y[i], self.z[i]))
    }
}

/// A ray–triangle hit: distance and barycentric weights of the three corners.
#[derive(Clone, Copy, Debug)]
pub(super) struct TriHit {
    pub(super) t: f32,
    pub(super) barycentric: [f32; 3],
}

/// pbrt's γ(n) = nε / (1 − nε) for f32 (ε = 2⁻²⁴).
pub(super) const fn gamma(n: f32) -> f32 {
    let e = f32::EPSILON * 0.5;
    n * e / (1.0 - n * e)
}

/// Watertight ray–triangle intersection (Woop, Benthin, Wald 2013; pbrt-v3 §3.6.2) with
/// `t` in `(δ_t, t_max)`, δ_t the conservative rounding-error bound of `t`.
///
/// SSE version of [`intersect_triangle_scalar`]: the three corners' sheared coordinates and
/// edge functions in one vector each, every lane by the same operations in the same order as
/// the scalar code (so the same bits: `tests::simd_triangle_test_is_the_scalar_one`); the
/// rest, reached by few candidates, is the scalar code.
#[cfg(target_arch = "x86_64")]
#[inline(always)]
pub(super) fn intersect_triangle(
    c: &Corners,
    plane: &[f32; 4],
    r: &PreparedRay,
    t_max: f32,
) -> Option<TriHit> {
    use std::arch::x86_64::*;
    // SAFETY: SSE2 is part of x86_64; the loads read the 16-byte-aligned `[f32; 4]` fields
    // of `*c`.
    let (xs, ys, e) = unsafe {
        let px = _mm_sub_ps(_mm_load_ps(c.x.as_ptr()), _mm_set1_ps(r.origin.x));
        let py = _mm_sub_ps(_mm_load_ps(c.y.as_ptr()), _mm_set1_ps(r.origin.y));
        let pz = _mm_sub_ps(_mm_load_ps(c.z.as_ptr()), _mm_set1_ps(r.origin.z));
        // `Vec3::dot`: (a.x·b.x + a.y·b.y) + a.z·b.z.
        let dot = |a: Vec3| {
            _mm_add_ps(
                _mm_add_ps(
                    _mm_mul_ps(_mm_set1_ps(a.x), px),
                    _mm_mul_ps(_mm_set1_ps(a.y), py),
                ),
                _mm_mul_ps(_mm_set1_ps(a.z), pz),
            )
        };
        let xs = dot(r.rx);
        let ys = dot(r.ry);
        // Lane i: x_{i+1}·y_{i+2} − y_{i+1}·x_{i+2} (indices mod 3).
        let x12 = _mm_shuffle_ps::<0b11_00_10_01>(xs, xs);
        let y20 = _mm_shuffle_ps::<0b11_01_00_10>(ys, ys);
        let y12 = _mm_shuffle_ps::<0b11_00_10_01>(ys, ys);
        let x20 = _mm_shuffle_ps::<0b11_01_00_10>(xs, xs);
        let e = _mm_sub_ps(_mm_mul_ps(x12, y20), _mm_mul_ps(y12, x20));
        let zero = _mm_setzero_ps();
        let neg = _mm_movemask_ps(_mm_cmplt_ps(e, zero)) & 7;
        let pos = _mm_movemask_ps(_mm_cmpgt_ps(e, zero)) & 7;
        let on_edge = _mm_movemask_ps(_mm_cmpeq_ps(e, zero)) & 7;
        if on_edge == 0 && neg != 0 && pos != 0 {
            return None;
        }
        let mut out = [[0f32; 4]; 3];
        _mm_storeu_ps(out[0].as_mut_ptr(), xs);
        _mm_storeu_ps(out[1].as_mut_ptr(), ys);
        _mm_storeu_ps(out[2].as_mut_ptr(), e);
        (out[0], out[1], out[2])
    };
    let [x0, x1, x2, _] = xs;
    let [y0, y1, y2, _] = ys;
    let [e0, e1, e2, _] = e;
    let p = c.vertices().map(|v| v - r.origin);
    intersect_triangle_finish(p, [x0, x1, x2], [y0, y1, y2], [e0, e1, e2], plane, r, t_max)
}

/// Watertight ray–triangle intersection: the portable version of the SSE one.
#[cfg(not(target_arch = "x86_64"))]
#[inline(always)]
pub(super) fn intersect_triangle(
    c: &Corners,
    plane: &[f32; 4],
    r: &PreparedRay,
    t_max: f32,
) -> Option<TriHit> {
    intersect_triangle_scalar(&c.vertices(), plane, r, t_max)
}

/// Watertight ray–triangle intersection (Woop, Benthin, Wald 2013; pbrt-v3 §3.6.2) with
/// `t` in `(δ_t, t_max)`, δ_t the conservative rounding-error bound of `t`.
#[cfg_attr(target_arch = "x86_64", allow(dead_code))]
#[inline(always)]
pub(super) fn intersect_triangle_scalar(
    v: &[Vec3; 3],
    plane: &[f32; 4],
    r: &PreparedRay,
    t_max: f32,
) -> Option<TriHit> {
    let p0 = v[0] - r.origin;
    let p1 = v[1] - r.origin;
    let p2 = v[2] - r.origin;
    let (x0, x1, x2) = (r.rx.dot(p0), r.rx.dot(p1), r.rx.dot(p2));
    let (y0, y1, y2) = (r.ry.dot(p0), r.ry.dot(p1), r.ry.dot(p2));
    let e0 = x1 * y2 - y1 * x2;
    let e1 = x2 * y0 - y2 * x0;
    let e2 = x0 * y1 - y0 * x1;
    intersect_triangle_finish(
        [p0, p1, p2],
        [x0, x1, x2],
        [y0, y1, y2],
        [e0, e1, e2],
        plane,
        r,
        t_max,
    )
}

/// The watertight test from the corners relative to the origin `p`, their sheared `x` and
/// `y` and the edge functions `e` on.
#[inline(always)]
pub(super) fn intersect_triangle_finish(
    [p0, p1, p2]: [Vec3; 3],
    [x0, x1, x2]: [f32; 3],
    [y0, y1, y2]: [f32; 3],
    [mut e0, mut e1, mut e2]: [f32; 3],
    plane: &[f32; 4],
    r: &PreparedRay,
    t_max: f32,
) -> Option<TriHit> {
    if e0 == 0.0 || e1 == 0.0 || e2 == 0.0 {
        // Exact edge functions on (near) edges: what makes the test watertight.
        let (x0, x1, x2) = (f64::from(x0), f64::from(x1), f64::from(x2));
        let (y0, y1, y2) = (f64::from(y0), f64::from(y1), f64::from(y2));
        e0 = (x1 * y2 - y1 * x2) as f32;
        e1 = (x2 * y0 - y2 * x0) as f32;
        e2 = (x0 * y1 - y0 * x1) as f32;
    }
    if (e0 < 0.0 || e1 < 0.0 || e2 < 0.0) && (e0 > 0.0 || e1 > 0.0 || e2 > 0.0) {
        return None;
    }
    let det = e0 + e1 + e2;
    if det == 0.0 {
        return None;
    }
    let z0 = r.rz.dot(p0) * r.sz;
    let z1 = r.rz.dot(p1) * r.sz;
    let z2 = r.rz.dot(p2) * r.sz;
    let t_scaled = e0 * z0 + e1 * z1 + e2 * z2;
    // t in (0, t_max), exclusive at both ends.
    if det < 0.0 && (t_scaled >= 0.0 || t_scaled <= t_max * det) {
        return None;
    }
    if det > 0.0 && (t_scaled <= 0.0 || t_scaled >= t_max * det) {
        return None;
    }
    let inv_det = 1.0 / det;
    let t = t_scaled * inv_det;
    // Conservative bound on the rounding error of t (pbrt-v3, "Conservative Ray–Bounds
    // Intersections" / triangle t error): reject hits not provably in front of the origin.
    let max_zt = z0.abs().max(z1.abs()).max(z2.abs());
    let delta_z = gamma(3.0) * max_zt;
    let max_xt = x0.abs().max(x1.abs()).max(x2.abs());
    let max_yt = y0.abs().max(y1.abs()).max(y2.abs());
    let delta_x = gamma(5.0) * (max_xt + max_zt);
    let delta_y = gamma(5.0) * (max_yt + max_zt);
    let delta_e = 2.0 * (gamma(2.0) * max_xt * max_yt + delta_y * max_xt + delta_x * max_yt);
    let max_e = e0.abs().max(e1.abs()).max(e2.abs());
    let delta_t =
        3.0 * (gamma(3.0) * max_e * max_zt + delta_e * max_zt + delta_z * max_e) * inv_det.abs();
    if t.is_nan() || t <= delta_t {
        return None;
    }
    // Self-intersection guard: a ray whose origin lies on this triangle's plane up to the
    // rounding of a computed surface point (a few ulps of the origin's coordinates) started
    // on this surface and must not re-hit it.
    let n = Vec3::new(plane[0], plane[1], plane[2]);
    let plane_distance = t * r.dir.dot(n).abs();
    if plane_distance <= r.self_tolerance * plane[3] {
        return None;
    }
    Some(TriHit {
        t,
        barycentric: [e0 * inv_det, e1 * inv_det, e2 * inv_det],
    })
}

/// The unnormalised normal of a triangle and its length (see `TriangleScene::planes`).
pub(super) fn triangle_plane(v: &[Vec3; 3]) -> [f32; 4] {
    let n = (v[1] - v[0]).cross(v[2] - v[0]);
    [n.x, n.y, n.z, n.length()]
}
