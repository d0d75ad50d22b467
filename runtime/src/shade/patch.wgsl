// Patch geometry: Bézier points and derivatives, the pixel's point refined onto its patch,
// the G-buffer normal of a patch, the tangent frame.
// Its CPU twin: reference/patch.rs.

import package::shade::bindings::{P, REFINE_MISS, REFINE_REACH, REFINE_SLACK, REFINE_STEPS, patches};

fn bern3(t: f32) -> vec4<f32> {
    let s = 1.0 - t;
    return vec4<f32>(s * s * s, 3.0 * t * s * s, 3.0 * t * t * s, t * t * t);
}

fn bern2(t: f32) -> vec3<f32> {
    let s = 1.0 - t;
    return vec3<f32>(s * s, 2.0 * t * s, t * t);
}

// x(u, v) − o of patch p (Eq. 3.1) as Σ_i Σ_j (CP_ij − o) B_i(u) B_j(v): the Bernstein
// weights sum to 1, and differences from a nearby o keep f32's precision.
fn patch_point(p: u32, u: f32, v: f32, o: vec3<f32>) -> vec3<f32> {
    let bu = bern3(u);
    let bv = bern3(v);
    var x = vec3<f32>(0.0);
    for (var i = 0u; i < 4u; i++) {
        for (var j = 0u; j < 4u; j++) {
            x += (patches[p].cp[4u * i + j].xyz - o) * (bu[i] * bv[j]);
        }
    }
    return x;
}

// ∂x/∂u of patch p at (u, v) through the hodograph (derivative of Eq. 3.1).
fn patch_du(p: u32, u: f32, v: f32) -> vec3<f32> {
    let bu = bern2(u);
    let bv = bern3(v);
    var du = vec3<f32>(0.0);
    for (var i = 0u; i < 3u; i++) {
        for (var j = 0u; j < 4u; j++) {
            let d = patches[p].cp[4u * (i + 1u) + j].xyz - patches[p].cp[4u * i + j].xyz;
            du += d * (bu[i] * bv[j]);
        }
    }
    return du * 3.0;
}

// ∂x/∂v of patch p at (u, v) through the hodograph, as `patch_du`.
fn patch_dv(p: u32, u: f32, v: f32) -> vec3<f32> {
    let bu = bern3(u);
    let bv = bern2(v);
    var dv = vec3<f32>(0.0);
    for (var i = 0u; i < 4u; i++) {
        for (var j = 0u; j < 3u; j++) {
            let d = patches[p].cp[4u * i + j + 1u].xyz - patches[p].cp[4u * i + j].xyz;
            dv += d * (bu[i] * bv[j]);
        }
    }
    return dv * 3.0;
}

// A pixel's shading point: on its patch, at parameters (u, v).
struct SurfacePoint {
    x: vec3<f32>,
    u: f32,
    v: f32,
};

// Where the pixel's ray (unit direction d) meets patch p itself near the G-buffer's point x at
// (u, v), which lies on a flat triangle up to P.surface_error off the patch: REFINE_STEPS of
// Newton's method on x(u, v) − x − s·d = 0 (as oslf_geometry's BezierPatch::refine_hit, which
// the ground truth uses, in f64). The G-buffer's own point where that does not converge, ends
// off [0, 1]² (the ray meets a neighbour, whose pixel it then is not) or farther than
// REFINE_REACH tolerances away, and on mesh atlas pages (zero control points: no Jacobian).
fn surface_hit(p: u32, x: vec3<f32>, u: f32, v: f32, d: vec3<f32>) -> SurfacePoint {
    var uu = u;
    var vv = v;
    var s = 0.0;
    for (var k = 0u; k < REFINE_STEPS; k++) {
        let a = patch_du(p, uu, vv);
        let b = patch_dv(p, uu, vv);
        let f = patch_point(p, uu, vv, x) - d * s;
        // Cramer's rule for [∂x/∂u ∂x/∂v −d]·(Δu, Δv, Δs) = −f.
        let bd = cross(b, -d);
        let det = dot(a, bd);
        if (!(abs(det) > 1e-6 * length(a) * length(b))) {
            return SurfacePoint(x, u, v);
        }
        uu -= dot(f, bd) / det;
        vv -= dot(a, cross(f, -d)) / det;
        s -= dot(a, cross(b, f)) / det;
    }
    let lo = -REFINE_SLACK;
    let hi = 1.0 + REFINE_SLACK;
    if (!(uu >= lo && uu <= hi && vv >= lo && vv <= hi)) {
        return SurfacePoint(x, u, v);
    }
    let uc = clamp(uu, 0.0, 1.0);
    let vc = clamp(vv, 0.0, 1.0);
    let e = patch_point(p, uc, vc, x);
    let miss = length(e - d * dot(e, d));
    if (!(miss <= REFINE_MISS * P.surface_error && length(e) <= REFINE_REACH * P.surface_error)) {
        return SurfacePoint(x, u, v);
    }
    return SurfacePoint(x + e, uc, vc);
}

// The shading normal at (u, v) of patch p: the patch's own, ∂x/∂u × ∂x/∂v, facing as the
// G-buffer's interpolated vertex normal `ni` (which the tessellation carries, chord errors
// and all: at grazing angles a small tilt turns the reflected ray far). `ni` where the patch
// normal degenerates (a collapsed edge, whose limit normal the vertices carry), turns more
// than 25° from it, and on mesh atlas pages (zero control points).
fn patch_normal(p: u32, u: f32, v: f32, ni: vec3<f32>) -> vec3<f32> {
    let du = patch_du(p, u, v);
    let dv = patch_dv(p, u, v);
    let e = cross(du, dv);
    let len = length(e);
    if (!(len > 1e-6 * length(du) * length(dv))) {
        return ni;
    }
    let ne = select(e, -e, dot(e, ni) < 0.0) / len;
    if (!(dot(ne, ni) > 0.9)) {
        return ni;
    }
    return ne;
}

// Unit tangent from ∂x/∂u made orthogonal to n; where ∂x/∂u vanishes or is parallel to n (a
// collapsed patch edge) the frame of Duff et al. (2017) built from n alone. Pages of a triangle
// mesh's atlas have zero control points in `patches` (geometry.rs), so their ∂x/∂u is exactly
// zero and their frame always comes from n alone (as reference/patch.rs's `tangent_frame`
// does).
fn tangent_frame(n: vec3<f32>, du: vec3<f32>) -> vec3<f32> {
    let t = du - n * dot(n, du);
    let l2 = dot(t, t);
    if (l2 > 1e-12 * max(dot(du, du), 1e-30)) {
        return t * inverseSqrt(l2);
    }
    let sgn = select(-1.0, 1.0, n.z >= 0.0);
    let a = -1.0 / (sgn + n.z);
    let b = n.x * n.y * a;
    return vec3<f32>(1.0 + sgn * n.x * n.x * a, sgn * b, -sgn * n.x);
}
