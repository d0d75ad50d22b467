//! Patch geometry in `f32`: Bézier derivatives, the shading normal, the tangent frame. As shade/patch.wgsl, function for function.

use glam::Vec3;
use oslf_geometry::BezierPatch;

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
