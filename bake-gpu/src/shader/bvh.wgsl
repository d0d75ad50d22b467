// Closest-hit and any-hit queries: the CPU's traversal of the compressed wide BVH
// (trace/src/bvh: obvhs's `traverse!`, Ylitie, Karras and Laine 2017: children in the order of
// the ray's octant, a stack of node groups, a leaf's triangles before the next node) with the
// CPU's node test (trace/src/bvh/node.rs) and watertight ray–triangle test
// (trace/src/bvh/triangle.rs: Woop, Benthin and Wald 2013 with pbrt-v3's conservative bound on
// t, and the self-intersection guard). The same tree, order and tests, so the same hits.

import package::capture::{nodes, out, tris};
import package::layouts::{Node, Tri};

const F32_MAX: f32 = 3.40282347e+38;
// oslf_trace::bvh::MAX_BVH_DEPTH: one group per level at most.
const STACK: u32 = 32u;
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

// Relative rounding error allowed for in each slab distance (node.rs SLAB_PAD).
const SLAB_PAD: f32 = 1e-6;

// obvhs's `oct_inv4`: in each byte, bit 2, 1, 0 set where d.x, d.y, d.z is not negative.
fn octant_inv4(d: vec3<f32>) -> u32 {
    return select(0x04040404u, 0u, d.x < 0.0) | select(0x02020202u, 0u, d.y < 0.0)
        | select(0x01010101u, 0u, d.z < 0.0);
}

// Which children of `n` the ray enters within [0, t_max], as node.rs `intersect_node`'s hit
// mask: bit 24 + (slot ^ octant) per entered inner child, and per entered leaf its triangles'
// bits (the unary count shifted to its first triangle's offset).
fn intersect_node(n: Node, r: PreparedRay, t_max: f32, oct: u32) -> u32 {
    let e = vec3<u32>(n.e_imask, n.e_imask >> 8u, n.e_imask >> 16u) & vec3<u32>(0xffu);
    let a = bitcast<vec3<f32>>(e << vec3<u32>(23u)) * r.inv_dir;
    let o = (n.p - r.origin) * r.inv_dir;
    let pad = (abs(o) + abs(a) * 255.0) * SLAB_PAD;
    // The near and far planes per axis: (min, max), swapped where the direction is negative.
    let nx = select(n.x.xy, n.x.zw, r.dir.x < 0.0);
    let fx = select(n.x.zw, n.x.xy, r.dir.x < 0.0);
    let ny = select(n.y.xy, n.y.zw, r.dir.y < 0.0);
    let fy = select(n.y.zw, n.y.xy, r.dir.y < 0.0);
    let nz = select(n.z.xy, n.z.zw, r.dir.z < 0.0);
    let fz = select(n.z.zw, n.z.xy, r.dir.z < 0.0);
    let octant = oct & 0xffu;
    var mask = 0u;
    for (var c = 0u; c < 8u; c++) {
        let w = c >> 2u;
        let s = (c & 3u) * 8u;
        let m = extractBits(n.child_meta[w], s, 8u);
        if m == 0u {
            continue; // an empty slot
        }
        let qn = vec3<f32>(vec3<u32>(extractBits(nx[w], s, 8u), extractBits(ny[w], s, 8u), extractBits(nz[w], s, 8u)));
        let qf = vec3<f32>(vec3<u32>(extractBits(fx[w], s, 8u), extractBits(fy[w], s, 8u), extractBits(fz[w], s, 8u)));
        let t0 = qn * a + o - pad;
        let t1 = qf * a + o + pad;
        let tmin = max(max(t0.x, t0.y), max(t0.z, 0.0));
        let tmax = min(min(t1.x, t1.y), min(t1.z, t_max));
        if tmin <= tmax {
            // Inner children have bits 3 and 4 of their meta byte set (24 + slot).
            let inner = (m & (m << 1u) & 0x10u) != 0u;
            let bit_index = (m ^ select(0u, octant, inner)) & 0x1fu;
            mask |= ((m >> 5u) & 7u) << bit_index;
        }
    }
    return mask;
}

struct Hit {
    t: f32,
    slot: u32,
    b: vec3<f32>,
    found: bool,
    // Nodes and triangles tested (the traversal's counters).
    nodes: u32,
    tris: u32,
}

// Whether triangle `tri` takes part: not when the query leaves out the OSLF objects (the
// environment-map baseline's view) and it belongs to one (its `v1.w` is 0).
fn included(tri: Tri, objects: bool) -> bool {
    return objects || tri.v1.w != 0.0;
}

// The traversal's stack of node groups: one per invocation, not per query, because a
// function's variables are zeroed at every call (a CPU adapter stores all of it each time).
var<private> stack: array<vec2<u32>, STACK>;

// The closest hit with t in (0, t_max), or none; `any_hit`: stop at the first.
fn traverse(o: vec3<f32>, d: vec3<f32>, t_max: f32, objects: bool, any_hit: bool) -> Hit {
    var best: Hit;
    best.found = false;
    best.t = t_max;
    best.nodes = 0u;
    best.tris = 0u;
    let r = prepare_ray(o, d, t_max);
    if !r.valid {
        return best;
    }
    let oct = octant_inv4(d);
    var top = 0u;
    // The node group: its first node, and bits 24 + order of its children still to visit
    // over the mask of its inner children (the root: the one child of a virtual parent).
    var group = vec2<u32>(0u, 0x80000000u);
    // The triangle group: its first slot and the bits of the triangles still to test.
    var prims = vec2<u32>(0u, 0u);
    loop {
        while prims.y != 0u {
            let k = firstLeadingBit(prims.y);
            prims.y &= ~(1u << k);
            let slot = prims.x + k;
            let tri = tris[slot];
            if !included(tri, objects) {
                continue;
            }
            best.tris += 1u;
            let h = intersect_triangle(tri, r, best.t);
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
        if (group.y & 0xff000000u) != 0u {
            let bits = group.y;
            let k = firstLeadingBit(bits);
            group.y &= ~(1u << k);
            if (group.y & 0xff000000u) != 0u {
                stack[top] = group;
                top += 1u;
            }
            // The child's slot, and its index among the inner children stored in slot order.
            let slot = (k - 24u) ^ (oct & 0xffu);
            let index = group.x + countOneBits(bits & ~(0xffffffffu << slot));
            let n = nodes[index];
            best.nodes += 1u;
            let hits = intersect_node(n, r, best.t, oct);
            group = vec2<u32>(n.child_base, (hits & 0xff000000u) | (n.e_imask >> 24u));
            prims = vec2<u32>(n.primitive_base, hits & 0x00ffffffu);
        } else {
            group = vec2<u32>(0u);
        }
        if prims.y == 0u && (group.y & 0xff000000u) == 0u {
            if top == 0u {
                break;
            }
            top -= 1u;
            group = stack[top];
        }
    }
    return best;
}
