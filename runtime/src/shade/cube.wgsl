// Cube maps: face coordinates, texel loads, bilinear and mip lookups.
// Its CPU twin: reference/cube.rs.

import package::shade::bindings::{
    FACE_SHIFT, FILTER, P, POOLS, dpool0, dpool1, dpool2, dpool3, pool0, pool1, pool2, pool3, slots,
};
import package::shade::feedback::{mark_face};
import package::shade::seams::{seamless_level};

// Face and face coordinates (s, t) of a direction: the Vulkan table in oslf_format::cube.
fn face_st(d: vec3<f32>) -> vec3<f32> {
    let a = abs(d);
    var face = 0u;
    var sc = 0.0;
    var tc = 0.0;
    var ma = 0.0;
    if (a.x >= a.y && a.x >= a.z) {
        ma = a.x;
        tc = -d.y;
        if (d.x >= 0.0) { face = 0u; sc = -d.z; } else { face = 1u; sc = d.z; }
    } else if (a.y >= a.z) {
        ma = a.y;
        sc = d.x;
        if (d.y >= 0.0) { face = 2u; tc = d.z; } else { face = 3u; tc = -d.z; }
    } else {
        ma = a.z;
        tc = -d.y;
        if (d.z >= 0.0) { face = 4u; sc = d.x; } else { face = 5u; sc = -d.x; }
    }
    if (!(ma > 0.0)) {
        return vec3<f32>(0.0, 0.5, 0.5);
    }
    let s = clamp((sc / ma + 1.0) * 0.5, 0.0, 1.0);
    let t = clamp((tc / ma + 1.0) * 0.5, 0.0, 1.0);
    return vec3<f32>(f32(face), s, t);
}

// Texel `c` of mip `level` of array layer `layer` of pool texture `tex`.
fn load_texel(tex: u32, layer: i32, c: vec2<u32>, level: u32) -> vec3<f32> {
    let p = vec2<i32>(c);
    let l = i32(level);
    // POOLS (the number of pool textures in use) is a constant, so unused arrays drop out.
    if (POOLS == 1u || tex == 0u) {
        return textureLoad(pool0, p, layer, l).rgb;
    } else if (POOLS == 2u || tex == 1u) {
        return textureLoad(pool1, p, layer, l).rgb;
    } else if (POOLS == 3u || tex == 2u) {
        return textureLoad(pool2, p, layer, l).rgb;
    }
    return textureLoad(pool3, p, layer, l).rgb;
}

// Distance texel `c` of array layer `layer` of distance texture `tex`.
fn load_depth(tex: u32, layer: i32, c: vec2<u32>) -> f32 {
    let p = vec2<i32>(c);
    if (POOLS == 1u || tex == 0u) {
        return textureLoad(dpool0, p, layer, 0).r;
    } else if (POOLS == 2u || tex == 1u) {
        return textureLoad(dpool1, p, layer, 0).r;
    } else if (POOLS == 3u || tex == 2u) {
        return textureLoad(dpool2, p, layer, 0).r;
    }
    return textureLoad(dpool3, p, layer, 0).r;
}

// Pool texture, array layer and level-0 x offset of `face` of the slot in indirection entry
// `entry` (pool.rs PoolLayout::place).
fn place(entry: u32, face: u32) -> vec3<u32> {
    let slot = entry >> 6u;
    var tex = 0u;
    var local = slot;
    if (POOLS > 1u) {
        tex = slot / P.slots_per_texture;
        local = slot % P.slots_per_texture;
    }
    let g = local * 6u + face;
    return vec3<u32>(tex, g >> FACE_SHIFT, (g & ((1u << FACE_SHIFT) - 1u)) * P.cube_res);
}

// Where a direction lands in a cube map: face, the four texels around it (clamped at the
// face's edges) and the bilinear weights. The same for every cube, so a blend computes it once.
struct Tap {
    face: u32,
    x0: u32,
    y0: u32,
    x1: u32,
    y1: u32,
    wx: f32,
    wy: f32,
};

fn tap(dir: vec3<f32>) -> Tap {
    let fst = face_st(dir);
    var t: Tap;
    t.face = u32(fst.x);
    let n = P.cube_res;
    let nf = f32(n);
    let fx = clamp(fst.y * nf - 0.5, 0.0, nf - 1.0);
    let fy = clamp(fst.z * nf - 0.5, 0.0, nf - 1.0);
    t.x0 = u32(floor(fx));
    t.y0 = u32(floor(fy));
    t.x1 = min(t.x0 + 1u, n - 1u);
    t.y1 = min(t.y0 + 1u, n - 1u);
    t.wx = fx - floor(fx);
    t.wy = fy - floor(fy);
    return t;
}

// Radiance of cube `cube` at tap `t`, bilinear within the face. Marks the face as needed in the
// feedback buffer. `w` is 1 when the face was resident, 0 when not (then the colour is 0 and
// must not be used).
fn fetch(cube: u32, t: Tap) -> vec4<f32> {
    mark_face(cube, 1u << t.face);
    return read_tap(cube, t);
}

// `fetch` without the feedback mark.
fn read_tap(cube: u32, t: Tap) -> vec4<f32> {
    let entry = slots[cube];
    if ((entry & (1u << t.face)) == 0u) {
        return vec4<f32>(0.0);
    }
    let at = place(entry, t.face);
    let tex = at.x;
    let layer = i32(at.y);
    let t00 = load_texel(tex, layer, vec2<u32>(at.z + t.x0, t.y0), 0u);
    let t10 = load_texel(tex, layer, vec2<u32>(at.z + t.x1, t.y0), 0u);
    let t01 = load_texel(tex, layer, vec2<u32>(at.z + t.x0, t.y1), 0u);
    let t11 = load_texel(tex, layer, vec2<u32>(at.z + t.x1, t.y1), 0u);
    let top = t00 + (t10 - t00) * t.wx;
    let bottom = t01 + (t11 - t01) * t.wx;
    return vec4<f32>(top + (bottom - top) * t.wy, 1.0);
}

// Radiance of cube `cube` towards `dir` (see `fetch`).
fn lookup(cube: u32, dir: vec3<f32>) -> vec4<f32> {
    return fetch(cube, tap(dir));
}

// Radiance of cube `cube` towards `dir` at fractional mip level `lod` (filtered importance
// sampling): `lookup` at level 0, `lookup_levels` above.
fn lookup_lod(cube: u32, dir: vec3<f32>, lod: f32) -> vec4<f32> {
    if (!(lod > 0.0)) {
        return lookup(cube, dir);
    }
    return lookup_levels(cube, slots[cube], dir, lod);
}

// Radiance of cube `cube` (indirection entry `entry` = slots[cube]) towards `dir` at mip level
// `lod` ≥ 0: bilinear across face edges (`seamless_level`: a coarse level's face seams would
// show) on the two nearest levels, blended linearly. Marks the faces it reads.
fn lookup_levels(cube: u32, entry: u32, dir: vec3<f32>, lod: f32) -> vec4<f32> {
    let top = P.mip_levels - 1u;
    let l = clamp(lod, 0.0, f32(top));
    let l0 = u32(floor(l));
    let f = l - f32(l0);
    let fst = face_st(dir);
    let a = seamless_level(cube, entry, fst, l0, true);
    if (!(f > 0.0)) {
        return a;
    }
    let b = seamless_level(cube, entry, fst, min(l0 + 1u, top), true);
    return vec4<f32>(a.rgb + (b.rgb - a.rgb) * f, a.w * b.w);
}

// The mip level for a Monte Carlo sample towards `dir` with log2(M p(dir)) = `lpdf`
// (Křivánek & Colbert 2008): ½ log2(Ω_s / Ω_p), where Ω_s = 1 / (M p) is the sample's share of
// the sphere and Ω_p = (2/N)² / (1 + s² + t²)^{3/2} the solid angle of a level-0 texel at face
// coordinates (s, t) ∈ [-1, 1]². Without their +1 bias: on the example scene it blurred narrow
// lobes (docs/measurements.md). 0 without FILTER.
fn sample_lod(dir: vec3<f32>, lpdf: f32) -> f32 {
    if (!FILTER) {
        return 0.0;
    }
    let fst = face_st(dir);
    let sc = 2.0 * fst.y - 1.0;
    let tc = 2.0 * fst.z - 1.0;
    let log_texel = 2.0 * log2(2.0 / f32(P.cube_res)) - 1.5 * log2(1.0 + sc * sc + tc * tc);
    return max(0.5 * (-lpdf - log_texel), 0.0);
}
