//! Patch geometry in `f32`: Bézier points and derivatives, the pixel's point refined onto its
//! patch, the shading normal, the tangent frame. As shade/patch.wgsl, function for function.

use glam::Vec3;
use oslf_geometry::bezier::REFINE_REACH;
use oslf_geometry::BezierPatch;

use super::{REFINE_MISS, REFINE_SLACK, REFINE_STEPS};

// f32 twins of shade.wgsl's Bernstein polynomials; `oslf_geometry::bezier` evaluates in f64, which
// the GPU cannot match.
pub(super) fn bern3(t: f32) -> [f32; 4] {
    let s = 1.0 - t;
    [s * s * s, 3.0 * t * s * s, 3.0 * t * t * s, t * t * t]
}

pub(super) fn bern2(t: f32) -> [f32; 3] {
    let s = 1.0 - t;
    [s * s, 2.0 * t * s, t * t]
}

/// `x(u, v) − o` (Eq. 3.1) as Σ (CP_ij − o) B_i(u) B_j(v), in `f32` (as `patch_point` in
/// shade.wgsl).
pub fn patch_point(p: &BezierPatch, u: f32, v: f32, o: Vec3) -> Vec3 {
    let (bu, bv) = (bern3(u), bern3(v));
    let mut x = Vec3::ZERO;
    for (i, bui) in bu.iter().enumerate() {
        for (j, bvj) in bv.iter().enumerate() {
            x += (p.cp[4 * i + j] - o) * (bui * bvj);
        }
    }
    x
}

/// ∂x/∂u through the hodograph, in `f32` (as `patch_du` in shade.wgsl).
pub fn patch_du(p: &BezierPatch, u: f32, v: f32) -> Vec3 {
    let (bu, bv) = (bern2(u), bern3(v));
    let mut du = Vec3::ZERO;
    for (i, bui) in bu.iter().enumerate() {
        for (j, bvj) in bv.iter().enumerate() {
            let d = p.cp[4 * (i + 1) + j] - p.cp[4 * i + j];
            du += d * (bui * bvj);
        }
    }
    du * 3.0
}

/// ∂x/∂v through the hodograph, in `f32` (as `patch_dv` in shade.wgsl).
pub fn patch_dv(p: &BezierPatch, u: f32, v: f32) -> Vec3 {
    let (bu, bv) = (bern3(u), bern2(v));
    let mut dv = Vec3::ZERO;
    for (i, bui) in bu.iter().enumerate() {
        for (j, bvj) in bv.iter().enumerate() {
            let d = p.cp[4 * i + j + 1] - p.cp[4 * i + j];
            dv += d * (bui * bvj);
        }
    }
    dv * 3.0
}

/// A pixel's shading point: on its patch, at parameters `(u, v)` (as `SurfacePoint`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurfacePoint {
    pub x: Vec3,
    pub u: f32,
    pub v: f32,
}

/// Where the pixel's ray (unit direction `d`) meets patch `p` itself near the G-buffer's point
/// `x` at `(u, v)`, which lies up to `surface_error` off it on a flat triangle: Newton's method
/// from there; the G-buffer's point where that fails (as `surface_hit` in shade.wgsl).
#[allow(clippy::neg_cmp_op_on_partial_ord)]
pub fn surface_hit(
    p: &BezierPatch,
    x: Vec3,
    (u, v): (f32, f32),
    d: Vec3,
    surface_error: f32,
) -> SurfacePoint {
    let keep = SurfacePoint { x, u, v };
    let (mut uu, mut vv, mut s) = (u, v, 0.0f32);
    for _ in 0..REFINE_STEPS {
        let a = patch_du(p, uu, vv);
        let b = patch_dv(p, uu, vv);
        let f = patch_point(p, uu, vv, x) - d * s;
        // Cramer's rule for [∂x/∂u ∂x/∂v −d]·(Δu, Δv, Δs) = −f.
        let bd = b.cross(-d);
        let det = a.dot(bd);
        if !(det.abs() > 1e-6 * a.length() * b.length()) {
            return keep;
        }
        uu -= f.dot(bd) / det;
        vv -= a.dot(f.cross(-d)) / det;
        s -= a.dot(b.cross(f)) / det;
    }
    let (lo, hi) = (-REFINE_SLACK, 1.0 + REFINE_SLACK);
    if !(uu >= lo && uu <= hi && vv >= lo && vv <= hi) {
        return keep;
    }
    let (uc, vc) = (uu.clamp(0.0, 1.0), vv.clamp(0.0, 1.0));
    let e = patch_point(p, uc, vc, x);
    let miss = (e - d * e.dot(d)).length();
    if !(miss <= REFINE_MISS * surface_error && e.length() <= REFINE_REACH * surface_error) {
        return keep;
    }
    SurfacePoint {
        x: x + e,
        u: uc,
        v: vc,
    }
}

/// The shading normal at `(u, v)`: the patch's ∂x/∂u × ∂x/∂v facing as the interpolated
/// vertex normal `ni`, or `ni` where that degenerates or turns more than 25° from it (as
/// `patch_normal` in shade.wgsl).
#[allow(clippy::neg_cmp_op_on_partial_ord)]
pub fn patch_normal(p: &BezierPatch, u: f32, v: f32, ni: Vec3) -> Vec3 {
    let (du, dv) = (patch_du(p, u, v), patch_dv(p, u, v));
    let e = du.cross(dv);
    let len = e.length();
    if !(len > 1e-6 * du.length() * dv.length()) {
        return ni;
    }
    let ne = (if e.dot(ni) < 0.0 { -e } else { e }) / len;
    if !(ne.dot(ni) > 0.9) {
        return ni;
    }
    ne
}

/// Unit tangent orthogonal to `n` from ∂x/∂u, or the frame of Duff et al. (2017) where ∂x/∂u
/// vanishes or is parallel to `n` (as `tangent_frame` in shade.wgsl).
pub fn tangent_frame(n: Vec3, du: Vec3) -> Vec3 {
    let t = du - n * n.dot(du);
    let l2 = t.dot(t);
    if l2 > 1e-12 * du.dot(du).max(1e-30) {
        return t / l2.sqrt();
    }
    let sgn = if n.z >= 0.0 { 1.0 } else { -1.0 };
    let a = -1.0 / (sgn + n.z);
    let b = n.x * n.y * a;
    Vec3::new(1.0 + sgn * n.x * n.x * a, sgn * b, -sgn * n.x)
}
