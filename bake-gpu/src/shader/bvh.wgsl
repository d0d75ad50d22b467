// Closest-hit and any-hit queries: a stack traversal of the obvhs BVH2 (nearer child first)
// and the CPU's watertight ray–triangle test (trace/src/bvh/triangle.rs: Woop, Benthin and
// Wald 2013 with pbrt-v3's conservative bound on t, and the self-intersection guard).

import package::capture::{attrs, nodes, out, tris};
import package::layouts::{Tri};

const F32_MAX: f32 = 3.40282347e+38;
const STACK: u32 = 64u;
// pbrt's γ(n) = nε / (1 − nε), ε = 2⁻²⁴.
fn gamma(n: f32) -> f32 {
    let e = 5.9604645e-8;
    return n * e / (1.0 - n * e);
}
// Relative self-intersection tolerance, 2⁻²¹ (bvh::SELF_TOLERANCE).
const SELF_TOLERANCE: f32 = 4.76837158e-7;

struct PreparedRay {
    origin: vec3<f32>,
    dir: vec3<f32>,
    rx: vec3<f32>,
    ry: vec3<f32>,
    rz: vec3<f32>,
    sz: f32,
    inv_dir: vec3<f32>,
    self_tolerance: f32,
    valid: bool,
}

fn finite3(v: vec3<f32>) -> bool {
    return all(abs(v) <= vec3<f32>(F32_MAX));
}

fn inv_clamped(c: f32) -> f32 {
    if abs(c) < 1e-20 {
        return select(1e20, -1e20, c < 0.0);
    }
    return 1.0 / c;
}

fn prepare_ray(o: vec3<f32>, d: vec3<f32>, t_max: f32) -> PreparedRay {
    var r: PreparedRay;
    r.valid = finite3(o) && finite3(d) && any(d != vec3<f32>(0.0)) && t_max > 0.0;
    let a = abs(d);
    var kz = 2u;
    if a.x > a.y {
        if a.x > a.z {
            kz = 0u;
        }
    } else if a.y > a.z {
        kz = 1u;
    }
    var ex = vec3<f32>(1.0, 0.0, 0.0);
    var ey = vec3<f32>(0.0, 1.0, 0.0);
    var ez = vec3<f32>(0.0, 0.0, 1.0);
    var dx = d.x;
    var dy = d.y;
    var dz = d.z;
    if kz == 0u {
        ex = vec3<f32>(0.0, 1.0, 0.0);
        ey = vec3<f32>(0.0, 0.0, 1.0);
        ez = vec3<f32>(1.0, 0.0, 0.0);
        dx = d.y;
        dy = d.z;
        dz = d.x;
    } else if kz == 1u {
        ex = vec3<f32>(0.0, 0.0, 1.0);
        ey = vec3<f32>(1.0, 0.0, 0.0);
        ez = vec3<f32>(0.0, 1.0, 0.0);
        dx = d.z;
        dy = d.x;
        dz = d.y;
    }
    let sx = -dx / dz;
    let sy = -dy / dz;
    r.origin = o;
    r.dir = d;
    r.rx = ex + ez * sx;
    r.ry = ey + ez * sy;
    r.rz = ez;
    r.sz = 1.0 / dz;
    r.inv_dir = vec3<f32>(inv_clamped(d.x), inv_clamped(d.y), inv_clamped(d.z));
    r.self_tolerance = SELF_TOLERANCE * max(max(abs(o.x), abs(o.y)), abs(o.z));
    return r;
}

// The sign-exact `a·b − c·d` (the CPU evaluates edge functions that round to 0 in f64).
fn exact_difference(a: f32, b: f32, c: f32, d: f32) -> f32 {
    let p = a * b;
    let q = c * d;
    let ep = fma(a, b, -p);
    let eq = fma(c, d, -q);
    return (p - q) + (ep - eq);
}

struct TriHit {
    t: f32,
    b: vec3<f32>,
    hit: bool,
}

fn intersect_triangle(tri: Tri, r: PreparedRay, t_max: f32) -> TriHit {
    var out: TriHit;
    out.hit = false;
    let p0 = tri.v0.xyz - r.origin;
    let p1 = tri.v1.xyz - r.origin;
    let p2 = tri.v2.xyz - r.origin;
    let x0 = dot(r.rx, p0);
    let x1 = dot(r.rx, p1);
    let x2 = dot(r.rx, p2);
    let y0 = dot(r.ry, p0);
    let y1 = dot(r.ry, p1);
    let y2 = dot(r.ry, p2);
    var e0 = x1 * y2 - y1 * x2;
    var e1 = x2 * y0 - y2 * x0;
    var e2 = x0 * y1 - y0 * x1;
    if e0 == 0.0 || e1 == 0.0 || e2 == 0.0 {
        e0 = exact_difference(x1, y2, y1, x2);
        e1 = exact_difference(x2, y0, y2, x0);
        e2 = exact_difference(x0, y1, y0, x1);
    }
    if (e0 < 0.0 || e1 < 0.0 || e2 < 0.0) && (e0 > 0.0 || e1 > 0.0 || e2 > 0.0) {
        return out;
    }
    let det = e0 + e1 + e2;
    if det == 0.0 {
        return out;
    }
    let z0 = dot(r.rz, p0) * r.sz;
    let z1 = dot(r.rz, p1) * r.sz;
    let z2 = dot(r.rz, p2) * r.sz;
    let t_scaled = e0 * z0 + e1 * z1 + e2 * z2;
    if det < 0.0 && (t_scaled >= 0.0 || t_scaled <= t_max * det) {
        return out;
    }
    if det > 0.0 && (t_scaled <= 0.0 || t_scaled >= t_max * det) {
        return out;
    }
    let inv_det = 1.0 / det;
    let t = t_scaled * inv_det;
    let max_zt = max(max(abs(z0), abs(z1)), abs(z2));
    let delta_z = gamma(3.0) * max_zt;
    let max_xt = max(max(abs(x0), abs(x1)), abs(x2));
    let max_yt = max(max(abs(y0), abs(y1)), abs(y2));
    let delta_x = gamma(5.0) * (max_xt + max_zt);
    let delta_y = gamma(5.0) * (max_yt + max_zt);
    let delta_e = 2.0 * (gamma(2.0) * max_xt * max_yt + delta_y * max_xt + delta_x * max_yt);
    let max_e = max(max(abs(e0), abs(e1)), abs(e2));
    let delta_t = 3.0 * (gamma(3.0) * max_e * max_zt + delta_e * max_zt + delta_z * max_e) * abs(inv_det);
    if !(t > delta_t) {
        return out;
    }
    let plane_distance = t * abs(dot(r.dir, tri.plane.xyz));
    if plane_distance <= r.self_tolerance * tri.plane.w {
        return out;
    }
    out.t = t;
    out.b = vec3<f32>(e0, e1, e2) * inv_det;
    out.hit = true;
    return out;
}

// The entry distance of the ray into a node's box (clipped at 0), or F32_MAX if it misses the
// box before `t_max`; the far end is widened by its rounding error.
fn enter_box(lo: vec3<f32>, hi: vec3<f32>, r: PreparedRay, t_max: f32) -> f32 {
    let t0 = (lo - r.origin) * r.inv_dir;
    let t1 = (hi - r.origin) * r.inv_dir;
    let near = max(max(min(t0.x, t1.x), min(t0.y, t1.y)), max(min(t0.z, t1.z), 0.0));
    let far = min(min(max(t0.x, t1.x), max(t0.y, t1.y)), max(t0.z, t1.z)) * (1.0 + 2.0 * gamma(3.0));
    if near <= far && near < t_max {
        return near;
    }
    return F32_MAX;
}

struct Hit {
    t: f32,
    slot: u32,
    b: vec3<f32>,
    found: bool,
}

// Whether triangle `slot` takes part: not when the query leaves out the OSLF objects (the
// environment-map baseline's view) and it belongs to one.
fn included(slot: u32, objects: bool) -> bool {
    return objects || attrs[slot].object == ENVIRONMENT_OBJECT;
}

const ENVIRONMENT_OBJECT: u32 = 0xffffffffu;

// The closest hit with t in (0, t_max), or none; `any_hit`: stop at the first.
fn traverse(o: vec3<f32>, d: vec3<f32>, t_max: f32, objects: bool, any_hit: bool) -> Hit {
    var best: Hit;
    best.found = false;
    best.t = t_max;
    let r = prepare_ray(o, d, t_max);
    if !r.valid {
        return best;
    }
    var stack: array<u32, STACK>;
    var stack_t: array<f32, STACK>;
    var top = 0u;
    var node = 0u;
    if enter_box(nodes[0].min, nodes[0].max, r, best.t) == F32_MAX {
        return best;
    }
    loop {
        let n = nodes[node];
        if n.count > 0u {
            for (var i = 0u; i < n.count; i++) {
                let slot = n.first + i;
                if !included(slot, objects) {
                    continue;
                }
                let h = intersect_triangle(tris[slot], r, best.t);
                if h.hit {
                    best.t = h.t;
                    best.slot = slot;
                    best.b = h.b;
                    best.found = true;
                    if any_hit {
                        return best;
                    }
                }
            }
        } else {
            let a = n.first;
            let ta = enter_box(nodes[a].min, nodes[a].max, r, best.t);
            let tb = enter_box(nodes[a + 1u].min, nodes[a + 1u].max, r, best.t);
            if ta != F32_MAX || tb != F32_MAX {
                var near = a;
                var far = a + 1u;
                var far_t = tb;
                if tb < ta {
                    near = a + 1u;
                    far = a;
                    far_t = ta;
                }
                if far_t != F32_MAX {
                    stack[top] = far;
                    stack_t[top] = far_t;
                    top = top + 1u;
                }
                node = near;
                continue;
            }
        }
        // The next stacked node the ray still enters before its closest hit so far.
        loop {
            if top == 0u || stack_t[top - 1u] < best.t {
                break;
            }
            top = top - 1u;
        }
        if top == 0u {
            break;
        }
        top = top - 1u;
        node = stack[top];
    }
    return best;
}
