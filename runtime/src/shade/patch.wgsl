// Patch geometry: Bézier derivatives, the G-buffer normal of a patch, the tangent frame.
// Its CPU twin: reference/patch.rs.

import package::shade::bindings::{patches};

fn bern3(t: f32) -> vec4<f32> {
    let s = 1.0 - t;
    return vec4<f32>(s * s * s, 3.0 * t * s * s, 3.0 * t * t * s, t * t * t);
}

fn bern2(t: f32) -> vec3<f32> {
    let s = 1.0 - t;
    return vec3<f32>(s * s, 2.0 * t * s, t * t);
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
