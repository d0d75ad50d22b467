// Depth-corrected lookups (§6.3's RGBZ).
// Its CPU twin: reference/depth.rs.

import package::shade::bindings::{
    DEPTH_ITERATIONS, DEPTH_REFINE, FAR, LOOKUP_AGREE, LOW_HIT, P, samples, slots,
};
import package::shade::cube::{face_st, load_depth, load_texel, lookup_lod, place, tap};
import package::shade::feedback::{mark_face};
import package::shading::constants::{PI};

// Set by `depth_toward` when a face it reads is not resident (the search then gives up).
var<private> depth_missing: bool;

// Distance from sample point `cube` to the first hit towards `d`: the nearest texel of its
// distance plane. Marks the face as needed; when it is not resident and `walk` (a search that
// stops there and, with the face resident, could go on to any other), every face of the cube,
// so that the frame's feedback holds at least what it needs with everything resident.
// `entry`: the cube's indirection entry, slots[cube].
fn depth_toward(cube: u32, entry: u32, d: vec3<f32>, walk: bool) -> f32 {
    let fst = face_st(d);
    let face = u32(fst.x);
    mark_face(cube, 1u << face);
    if ((entry & (1u << face)) == 0u) {
        if (walk) {
            mark_face(cube, 63u);
        }
        depth_missing = true;
        return FAR;
    }
    let at = place(entry, face);
    let n = P.cube_res;
    let x = min(u32(fst.y * f32(n)), n - 1u);
    let y = min(u32(fst.z * f32(n)), n - 1u);
    return load_depth(at.x, i32(at.y), vec2<u32>(at.z + x, y));
}

// The point of the ray from x along r at inverse distance w (w = 0: the point at infinity),
// seen from sample point p: xyz = its offset from p, w = |q − p| − D_p(q − p), negative in
// front of the surface p sees that way, positive behind it (1 at infinity).
fn depth_probe(cube: u32, p: vec3<f32>, x: vec3<f32>, r: vec3<f32>, w: f32) -> vec4<f32> {
    if (!(w > 0.0)) {
        return vec4<f32>(r, 1.0);
    }
    let d = x + r * (1.0 / w) - p;
    return vec4<f32>(d, length(d) - depth_toward(cube, slots[cube], d, true));
}

// Where sample point `cube` sees the ray from x along r meet the scene, traced against its
// distance plane as distance impostors are (Szirmay-Kalos et al. 2005; linear search, then
// refinement, as Umenhoffer et al. 2007, GPU Gems 3 ch. 17): the ray is walked in equal steps
// of inverse distance from x, about one texel of the cube each (at most depth_steps); the first
// step behind the surface brackets the hit and DEPTH_REFINE bisections narrow it; the hit is
// where the bracket's two signed distances interpolate to zero (a secant step, as in relief
// mapping: Risser et al. 2007), so that other sample points can check they see it.
// xyz: the direction to look up; w: 1 hit (xyz = the hit's offset from the sample point, its
// length the hit's distance); 0 no hit before infinity, or a face not resident (xyz = r, the
// plain lookup); -1 the ray passed behind an occluder's silhouette, farther behind the surface
// than depth_thickness allows (xyz = r; this point cannot see the hit).
fn depth_search(cube: u32, x: vec3<f32>, r: vec3<f32>) -> vec4<f32> {
    let p = samples[cube].xyz;
    let lo = length(x - p);
    if (!(lo > 0.0)) {
        return vec4<f32>(r, 0.0);
    }
    depth_missing = false;
    let w0 = 1.0 / lo;
    var a = depth_probe(cube, p, x, r, w0);
    if (depth_missing) {
        return vec4<f32>(r, 0.0);
    }
    if (a.w >= 0.0) {
        return vec4<f32>(r, -1.0);
    }
    let span = acos(clamp(dot(normalize(a.xyz), r), -1.0, 1.0));
    let steps = clamp(u32(ceil(span * f32(P.cube_res) / (0.5 * PI))), 1u, P.depth_steps);
    var wa = w0;
    var wb = 0.0;
    var b = vec4<f32>(r, 1.0);
    for (var k = 1u; k < steps; k++) {
        let w = w0 * (1.0 - f32(k) / f32(steps));
        let q = depth_probe(cube, p, x, r, w);
        if (q.w >= 0.0) {
            wb = w;
            b = q;
            break;
        }
        wa = w;
        a = q;
    }
    for (var i = 0u; i < DEPTH_REFINE; i++) {
        let wm = 0.5 * (wa + wb);
        let q = depth_probe(cube, p, x, r, wm);
        if (q.w >= 0.0) {
            wb = wm;
            b = q;
        } else {
            wa = wm;
            a = q;
        }
    }
    if (depth_missing || !(wb > 0.0)) {
        return vec4<f32>(r, 0.0);
    }
    if (b.w > P.depth_thickness * length(b.xyz)) {
        return vec4<f32>(r, -1.0);
    }
    if (b.w - a.w > 0.0) {
        let ws = wa + (wb - wa) * (-a.w / (b.w - a.w));
        if (ws > 0.0) {
            return vec4<f32>(x + r * (1.0 / ws) - p, 1.0);
        }
    }
    return vec4<f32>(b.xyz, 1.0);
}

// Whether sample point `cube` cannot see the ray from x along l, as `depth_search`'s first
// probe finds: the ray's point at x's own distance from p lies behind the surface p sees that
// way. A face not resident, or nothing that way, counts as seen. o = x − p.
fn depth_hidden(cube: u32, entry: u32, o: vec3<f32>, l: vec3<f32>) -> bool {
    let d = o + l * length(o);
    let seen = depth_toward(cube, entry, d, false);
    return seen < FAR && length(d) >= seen;
}

// Where sample point `cube` sees the ray from x along l meet the scene, for a glossy sample:
// the fixed-point iteration of distance impostors (Szirmay-Kalos et al. 2005). Each step reads
// the distance D the sample point p stores towards its current guess and moves the guess to
// where the ray leaves the sphere of radius D around p; DEPTH_ITERATIONS steps, each one texel
// read, instead of `depth_search`'s walk: a filtered sample reads an area many texels wide, so
// the search's texel-exact silhouettes do not show, and its cost would be paid M times per
// candidate (docs/measurements.md). Only a `fresh` sample iterates: the others of its row of
// the filtered sample grid (`filter_rows`), which lie side by side on the lobe, take the
// sphere of the distance it converged to (`seed`: in, that distance, 0 for none; out, a fresh
// sample's), reading nothing: a small change of the glossy errors for a large share of the
// frame time (docs/measurements.md). Returns the direction to look up from p (unnormalized): l itself where a step finds nothing that way (FAR, or a face
// not resident) or x outside the sphere (p sees something nearer than x that way). `entry` =
// slots[cube] and o = x − p come from `integrate`, read once for all M samples.
fn depth_iterate(cube: u32, entry: u32, o: vec3<f32>, l: vec3<f32>, fresh: bool, seed: ptr<function, f32>) -> vec3<f32> {
    let ol = dot(o, l);
    let oo = dot(o, o);
    var q = l;
    let d0 = *seed;
    if (d0 * d0 > oo) {
        q = o + l * (sqrt(ol * ol - (oo - d0 * d0)) - ol);
    }
    // A loop of zero or one pass, not an if: lavapipe runs an if's body whatever its
    // condition, but skips a loop that no invocation enters.
    for (var once = select(1u, 0u, fresh); once < 1u; once++) {
        q = l;
        *seed = 0.0;
        for (var k = 0u; k < DEPTH_ITERATIONS; k++) {
            let dist = depth_toward(cube, entry, q, true);
            if (!(dist < FAR) || !(dist * dist > oo)) {
                q = l;
                *seed = 0.0;
                break;
            }
            q = o + l * (sqrt(ol * ol - (oo - dist * dist)) - ol);
            *seed = dist;
        }
    }
    return q;
}

// Radiance of sample point `cube` for `h`, a `depth_search` result (or a hit offset with w = 1),
// at mip level `lod`. On level 0 the bilinear tap keeps only the texels whose distance agrees
// with the hit's (within LOOKUP_AGREE depth_thickness of it; for a ray that meets nothing, the
// texels that see nothing either): where the hit lies at an occluder's silhouette it takes its
// own surface's radiance, not a blend with what lies behind or in front of it (depth-guided
// reconstruction, as joint bilateral upsampling: Kopf et al. 2007). All four texels when none
// agrees, for a hit this point cannot see (w < 0), and on coarser levels (no distance mips).
fn depth_lookup(cube: u32, h: vec4<f32>, lod: f32) -> vec4<f32> {
    if (lod > 0.0 || h.w < 0.0) {
        return lookup_lod(cube, h.xyz, lod);
    }
    let t = tap(h.xyz);
    mark_face(cube, 1u << t.face);
    let entry = slots[cube];
    if ((entry & (1u << t.face)) == 0u) {
        return vec4<f32>(0.0);
    }
    var dist = FAR;
    if (h.w > 0.0) { dist = length(h.xyz); }
    let tol = min(LOOKUP_AGREE * P.depth_thickness, 0.5) * dist;
    let at = place(entry, t.face);
    let c00 = vec2<u32>(at.z + t.x0, t.y0);
    let c10 = vec2<u32>(at.z + t.x1, t.y0);
    let c01 = vec2<u32>(at.z + t.x0, t.y1);
    let c11 = vec2<u32>(at.z + t.x1, t.y1);
    let layer = i32(at.y);
    let d = vec4<f32>(load_depth(at.x, layer, c00), load_depth(at.x, layer, c10),
        load_depth(at.x, layer, c01), load_depth(at.x, layer, c11));
    var w = vec4<f32>((1.0 - t.wx) * (1.0 - t.wy), t.wx * (1.0 - t.wy), (1.0 - t.wx) * t.wy, t.wx * t.wy);
    let agree = select(vec4<f32>(0.0), w, abs(d - vec4<f32>(dist)) <= vec4<f32>(tol));
    let sum = agree.x + agree.y + agree.z + agree.w;
    if (sum > 0.0) {
        w = agree / sum;
    }
    let c = load_texel(at.x, layer, c00, 0u) * w.x + load_texel(at.x, layer, c10, 0u) * w.y
        + load_texel(at.x, layer, c01, 0u) * w.z + load_texel(at.x, layer, c11, 0u) * w.w;
    return vec4<f32>(c, 1.0);
}

// Whether `h`, sample point p's `depth_search` hit for the ray from x along l, lies lower above
// x's tangent plane (normal n) than LOW_HIT times p's distance from x: p then sees x's own
// surface at a grazing angle, where its texels' one distance each cannot say where that
// surface ends (the can's rim at 16²: docs/measurements.md).
fn low_hit(p: vec3<f32>, h: vec4<f32>, x: vec3<f32>, l: vec3<f32>, n: vec3<f32>) -> bool {
    return h.w > 0.0 && dot(p + h.xyz - x, l) * dot(l, n) < LOW_HIT * length(x - p);
}
