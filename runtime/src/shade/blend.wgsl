// Blending (chapter 4).
// Its CPU twin: reference/blend.rs.

import package::shade::bindings::{
    BLEND, DEPTH, HIT_AGREE, INVALID, P, SOURCE, sample_maps, samples, slots,
};
import package::shade::cube::{Tap, fetch, lookup_lod};
import package::shade::depth::{depth_lookup, depth_missing, depth_search, depth_toward, low_hit};

// Vectors, not arrays: lavapipe gives every local array that is indexed dynamically its own
// scratch memory, initialized per invocation even where the code is never reached (a large
// slowdown measured with runtime/examples/lvp_probe.rs: docs/measurements.md); dynamic vector
// indexing is cheap.
struct Candidates {
    idx: vec4<u32>,
    // Directions s_j from the shaded point to sample point j, by component.
    sx: vec4<f32>,
    sy: vec4<f32>,
    sz: vec4<f32>,
    count: u32,
};

// The shaded pixel's candidates (one per invocation; a private global rather than a value
// passed to every function keeps lavapipe from copying it at each call site).
var<private> cand: Candidates;

fn cand_s(j: u32) -> vec3<f32> {
    return vec3<f32>(cand.sx[j], cand.sy[j], cand.sz[j]);
}

fn set_s(j: u32, d: vec3<f32>) {
    cand.sx[j] = d.x;
    cand.sy[j] = d.y;
    cand.sz[j] = d.z;
}

fn candidates(pid: u32, u: f32, v: f32, x: vec3<f32>, n: vec3<f32>) {
    let m = P.map_res;
    let tx = min(u32(clamp(u, 0.0, 1.0) * f32(m)), m - 1u);
    let ty = min(u32(clamp(v, 0.0, 1.0) * f32(m)), m - 1u);
    let raw = textureLoad(sample_maps, vec2<i32>(i32(tx), i32(ty)), i32(pid), 0);
    cand.count = 0u;
    for (var j = 0u; j < 4u; j++) {
        var idx = raw[j];
        if (P.index16 == 1u && idx == 0xffffu) {
            idx = INVALID;
        }
        cand.idx[j] = INVALID;
        set_s(j, n);
        if (idx != INVALID && idx < P.sample_count) {
            cand.idx[j] = idx;
            let d = samples[idx].xyz - x;
            let l2 = dot(d, d);
            if (l2 > 0.0) {
                set_s(j, d * inverseSqrt(l2));
            }
            cand.count += 1u;
        }
    }
}

fn is_resident(cube: u32) -> bool {
    return (slots[cube] & 63u) != 0u;
}

// Blend weights B_j for axis `a` (the reflection vector for B^r, the normal for B^n, the
// sample direction when blending per direction). Weights are relative to the largest, so
// B^r and B^n with huge N never underflow to an all-zero sum; if every ⟨a, s_j⟩ ≤ 0 the
// closest in angle gets weight 1.
fn one_hot(j: u32) -> vec4<f32> {
    return vec4<f32>(vec4<u32>(0u, 1u, 2u, 3u) == vec4<u32>(j));
}

fn blend_weights(a: vec3<f32>) -> vec4<f32> {
    // Written without loops or dynamic indices (see `Candidates`); the CPU reference's loops
    // compute the same values.
    let valid = cand.idx != vec4<u32>(INVALID);
    let d = vec4<f32>(dot(a, cand_s(0u)), dot(a, cand_s(1u)), dot(a, cand_s(2u)), dot(a, cand_s(3u)));
    if (!any(valid)) { return vec4<f32>(0.0); }
    var first = 3u;
    if (valid.z) { first = 2u; }
    if (valid.y) { first = 1u; }
    if (valid.x) { first = 0u; }
    var best = 0u;
    var best_dot = -2.0;
    if (valid.x && d.x > best_dot) { best_dot = d.x; best = 0u; }
    if (valid.y && d.y > best_dot) { best_dot = d.y; best = 1u; }
    if (valid.z && d.z > best_dot) { best_dot = d.z; best = 2u; }
    if (valid.w && d.w > best_dot) { best_dot = d.w; best = 3u; }
    if (BLEND == 0u) { return one_hot(first); }     // Eq. 4.3
    if (BLEND == 1u) { return one_hot(best); }      // Eq. 4.4-4.5
    // Eq. 4.9 (B^r, B^n with N = 0 reduce to it)
    if (BLEND == 2u || P.blend_n == 0.0) { return select(vec4<f32>(0.0), vec4<f32>(1.0), valid); }
    if (best_dot <= 0.0) { return one_hot(best); }
    // Eq. 4.10, 4.11, relative to the largest so that no power underflows to an all-zero sum.
    let r = max(d, vec4<f32>(0.0)) / best_dot;
    return select(vec4<f32>(0.0), pow(r, vec4<f32>(P.blend_n)), valid & (r > vec4<f32>(0.0)));
}

// Blended radiance towards `dir` from the candidates with weights `w` (Eq. 4.7). Lookups
// that are not resident are left out and the rest renormalized; `.w` is 0 when none was.
fn blend_fetch(w: vec4<f32>, t: Tap) -> vec4<f32> {
    var acc = vec3<f32>(0.0);
    var wsum = 0.0;
    for (var j = 0u; j < 4u; j++) {
        if (w[j] > 0.0) {
            let l = fetch(cand.idx[j], t);
            if (l.w > 0.0) {
                acc += l.rgb * w[j];
                wsum += w[j];
            }
        }
    }
    if (wsum > 0.0) {
        return vec4<f32>(acc / wsum, 1.0);
    }
    return vec4<f32>(0.0);
}

// Blended radiance towards `dir` for the ray from x, at mip level `lod`: each candidate looked
// up where it sees the ray meet the scene (`depth_search`, with DEPTH) or along `dir`. While
// any candidate sees the hit, those that cannot are left out; `.w` = 0 when no lookup was
// resident.
//
// With DEPTH the candidates then agree on one hit: the nearest along the ray of those their
// searches found (a thin occluder that one candidate's search resolves and another's steps
// over is still there). Every candidate whose distance plane sees that point (within HIT_AGREE
// depth_thickness) is looked up towards it, blended with its weight; the others are left out.
// When none sees it, the blend of the candidates' own hits above. With `low` (a glossy sample
// per direction; n: x's normal) a candidate's hit that is a `low_hit` counts as none: that
// candidate is looked up along `dir` and its hit is not the common one.
fn blend_read(w: vec4<f32>, x: vec3<f32>, dir: vec3<f32>, lod: f32, n: vec3<f32>, low: bool) -> vec4<f32> {
    var acc = vec3<f32>(0.0);
    var wsum = 0.0;
    var hidden = vec3<f32>(0.0);
    var hsum = 0.0;
    var near = 3.4e38;
    for (var j = 0u; j < 4u; j++) {
        if (w[j] > 0.0) {
            var h = vec4<f32>(dir, 1.0);
            var l = vec4<f32>(0.0);
            if (DEPTH) {
                h = depth_search(cand.idx[j], x, dir);
                if (low && low_hit(samples[cand.idx[j]].xyz, h, x, dir, n)) {
                    h = vec4<f32>(dir, 0.0);
                }
                if (h.w > 0.0) {
                    near = min(near, dot(h.xyz + samples[cand.idx[j]].xyz - x, dir));
                }
                l = depth_lookup(cand.idx[j], h, lod);
            } else {
                l = lookup_lod(cand.idx[j], h.xyz, lod);
            }
            if (l.w > 0.0) {
                if (h.w >= 0.0) {
                    acc += l.rgb * w[j];
                    wsum += w[j];
                } else {
                    hidden += l.rgb * w[j];
                    hsum += w[j];
                }
            }
        }
    }
    if (DEPTH && near < 3.4e38) {
        let hit = x + dir * near;
        var cacc = vec3<f32>(0.0);
        var csum = 0.0;
        for (var j = 0u; j < 4u; j++) {
            if (w[j] > 0.0) {
                let d = hit - samples[cand.idx[j]].xyz;
                let dl = length(d);
                depth_missing = false;
                let seen = depth_toward(cand.idx[j], slots[cand.idx[j]], d, false);
                if (!depth_missing && abs(dl - seen) <= HIT_AGREE * P.depth_thickness * dl) {
                    let l = depth_lookup(cand.idx[j], vec4<f32>(d, 1.0), lod);
                    if (l.w > 0.0) {
                        cacc += l.rgb * w[j];
                        csum += w[j];
                    }
                }
            }
        }
        if (csum > 0.0) {
            return vec4<f32>(cacc / csum, 1.0);
        }
    }
    if (wsum > 0.0) {
        return vec4<f32>(acc / wsum, 1.0);
    }
    if (hsum > 0.0) {
        return vec4<f32>(hidden / hsum, 1.0);
    }
    return vec4<f32>(0.0);
}

// The direction to look up the environment cube for the ray from x along `dir`: `dir` itself,
// or for the parallax-corrected baseline (SOURCE 2) the direction from the cube's centre to
// where the ray leaves the proxy box (Lagarde & Zanuttini 2012; probe.rs parallax_dir). `dir`
// when x lies outside the box.
fn env_dir(x: vec3<f32>, dir: vec3<f32>) -> vec3<f32> {
    if (SOURCE != 2u) {
        return dir;
    }
    let lo = P.box_min.xyz;
    let hi = P.box_max.xyz;
    if (!(all(x > lo) && all(x < hi))) {
        return dir;
    }
    var t = 3.4e38;
    for (var k = 0u; k < 3u; k++) {
        if (dir[k] > 1e-12) {
            t = min(t, (hi[k] - x[k]) / dir[k]);
        } else if (dir[k] < -1e-12) {
            t = min(t, (lo[k] - x[k]) / dir[k]);
        }
    }
    if (!(t > 0.0 && t < 3.4e38)) {
        return dir;
    }
    return x + dir * t - P.probe_pos.xyz;
}

// The environment cube for the ray from x along `dir` at mip level `lod`, or 0 when the store
// has none.
fn env_read(x: vec3<f32>, dir: vec3<f32>, lod: f32) -> vec3<f32> {
    if (P.env_cube == INVALID) { return vec3<f32>(0.0); }
    return lookup_lod(P.env_cube, env_dir(x, dir), lod).rgb;
}
