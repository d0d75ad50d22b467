// The split-sum baseline of the pbr mode: the environment cube prefiltered per roughness, as
// engines light a glossy object from one probe (prefilter.rs). No Monte Carlo.
// Its CPU twin: reference/split_sum.rs.

import package::shade::bindings::{DIFFUSE, P, prefiltered};
import package::shade::blend::{env_dir};
import package::shade::cube::{face_st};
import package::shade::seams::{seam_bilinear, seam_taps};

// Texel `c` (face, x, y) of mip `level` of the prefiltered environment, specular faces from
// layer 0, irradiance from layer 6.
fn prefiltered_texel(first: u32, c: vec3<u32>, level: u32) -> vec3<f32> {
    return textureLoad(prefiltered, vec2<u32>(c.y, c.z), i32(first + c.x), i32(level)).rgb;
}

// Mip `level` of the prefiltered environment (faces from layer `first`) at `fst` (`face_st`
// of a direction), bilinear across face edges as `seamless_level` reads a cube.
fn prefiltered_level(first: u32, fst: vec3<f32>, level: u32) -> vec3<f32> {
    // The level's side from the cube's (prefiltered from the store's environment cube):
    // lavapipe's textureDimensions at a level known only at run time read level 0's size.
    let t = seam_taps(fst, i32(max(P.cube_res >> level, 1u)));
    return seam_bilinear(t, prefiltered_texel(first, t.c0, level), prefiltered_texel(first, t.c1, level),
        prefiltered_texel(first, t.c2, level), prefiltered_texel(first, t.c3, level));
}

// The specular levels towards `dir` at perceptual roughness `roughness`: level
// roughness · (L − 1), blended between the two nearest.
fn prefiltered_specular(dir: vec3<f32>, roughness: f32) -> vec3<f32> {
    let top = textureNumLevels(prefiltered) - 1u;
    let l = clamp(roughness * f32(top), 0.0, f32(top));
    let l0 = u32(floor(l));
    let f = l - f32(l0);
    let fst = face_st(dir);
    let a = prefiltered_level(0u, fst, l0);
    if (!(f > 0.0)) {
        return a;
    }
    let b = prefiltered_level(0u, fst, min(l0 + 1u, top));
    return a + (b - a) * f;
}

// The split sum's second factor: GGX's directional albedo as scale and bias of F0, the
// analytic fit of Karis 2014 ("Physically Based Shading on Mobile").
fn env_brdf(roughness: f32, nv: f32) -> vec2<f32> {
    let r = roughness * vec4<f32>(-1.0, -0.0275, -0.572, 0.022) + vec4<f32>(1.0, 0.0425, 1.04, -0.04);
    let a004 = min(r.x * r.x, exp2(-9.28 * nv)) * r.x + r.y;
    return vec2<f32>(-1.04, 1.04) * a004 + r.zw;
}

// glTF's metallic-roughness BRDF lit by the prefiltered environment: the specular lobe as
// prefiltered radiance towards r (parallax-corrected with SOURCE 2) × (F0 A + B); with DIFFUSE
// the diffuse base as the irradiance at n × (1 − metallic) C (1 − F_dielectric).
fn split_sum(x: vec3<f32>, n: vec3<f32>, v: vec3<f32>, r: vec3<f32>, base: vec3<f32>, pbr: vec2<f32>) -> vec3<f32> {
    let nv = clamp(dot(n, v), 0.0, 1.0);
    let roughness = sqrt(pbr.y);
    let ab = env_brdf(roughness, nv);
    let f0 = vec3<f32>(0.04) + (base - vec3<f32>(0.04)) * pbr.x;
    var c = prefiltered_specular(env_dir(x, r), roughness) * (f0 * ab.x + vec3<f32>(ab.y));
    if (DIFFUSE) {
        let e = prefiltered_level(6u, face_st(n), 0u);
        c += e * base * ((1.0 - pbr.x) * (1.0 - (0.04 * ab.x + ab.y)));
    }
    return c;
}
