// OSLF shading: one compute invocation per pixel, reading the G-buffer written by gbuffer.wgsl.
//
// Every function here has a twin in `reference.rs` (the CPU reference) with the same operation
// order; the parity tests compare the two. Bindings are declared in the order of
// `ShadePipelines::bind_group_layout` (pipelines.rs).

struct Params {
    view_proj: mat4x4<f32>,
    camera_pos: vec4<f32>,
    size: vec2<u32>,
    // Bit flags: 1 = F_recon, 2 = mirror F_refl, 4 = glossy (Ashikhmin–Shirley),
    // 8 = scale the reflection term by C_s (Eq. 4.12).
    terms: u32,
    // 0 closest distance (4.3), 1 closest angle (4.4), 2 B^avg (4.9), 3 B^r (4.10), 4 B^n (4.11)
    blend: u32,
    blend_n: f32,
    // 0 = the OSLF sample points, 1 = the environment-map baseline (one cube at the centre),
    // 2 = that cube parallax-corrected against the proxy box
    source: u32,
    m: u32,
    // 0 = integrate per sample point, then blend; 1 = blend per direction, then integrate (§5.2)
    order: u32,
    rs: f32,
    rd: f32,
    nu: f32,
    nv: f32,
    cos_phi_shader: f32,
    seed: u32,
    sample_count: u32,
    env_cube: u32,
    map_res: u32,
    index16: u32,
    cube_res: u32,
    slots_per_texture: u32,
    // The camera's basis for the rays through background pixels (oslf_geometry::Camera::
    // direction); cam_right.w = tan(vfov/2).
    cam_right: vec4<f32>,
    cam_up: vec4<f32>,
    cam_forward: vec4<f32>,
    // Linear RGB of the colour background.
    bg_color: vec4<f32>,
    // 0 none (transparent black), 1 the environment cube, 2 bg_color (RenderOptions::background)
    background: u32,
    // Mip levels the glossy term filters over (1 = point sampling; FILTER).
    mip_levels: u32,
    // Most linear-search steps of a depth-corrected lookup (0 = off; DEPTH).
    depth_steps: u32,
    // How far behind the surface a refined hit may lie, as a fraction of its distance.
    depth_thickness: f32,
    // The environment cube's centre and the parallax proxy box (SOURCE 2), all in the shader's
    // coordinates.
    probe_pos: vec4<f32>,
    box_min: vec4<f32>,
    box_max: vec4<f32>,
};

// The mode's switches are pipeline-overridable constants (set from the same values as the
// uniform's `terms`, `blend`, `source`, `order`): one pipeline per combination, so code a mode
// does not use is not in its shader. On lavapipe every branch runs under an execution mask
// whether or not any lane takes it, so unused code is not free (measured: 20× on the baseline).
override TERMS: u32 = 1u;
override BLEND: u32 = 4u;
override SOURCE: u32 = 0u;
override ORDER: u32 = 0u;
override POOLS: u32 = 4u;
// 2^FACE_SHIFT faces lie side by side in each pool layer (pool.rs).
override FACE_SHIFT: u32 = 0u;
override DIFFUSE: bool = false;
// The uniform's `background`: what pixels off the object show.
override BACKGROUND: u32 = 0u;
// Depth-corrected lookups (the uniform's depth_steps > 0; the pool has distance planes).
override DEPTH: bool = false;
// Filtered importance sampling for the glossy term (the uniform's mip_levels > 1).
override FILTER: bool = false;

struct PatchGpu {
    cp: array<vec4<f32>, 16>,
    color: vec4<f32>,
};

@group(0) @binding(0) var<uniform> P: Params;
@group(0) @binding(1) var gb_position: texture_2d<f32>;
@group(0) @binding(2) var gb_normal: texture_2d<f32>;
@group(0) @binding(3) var sample_maps: texture_2d_array<u32>;
@group(0) @binding(4) var<storage, read> samples: array<vec4<f32>>;
@group(0) @binding(5) var<storage, read> patches: array<PatchGpu>;
@group(0) @binding(6) var<storage, read> slots: array<u32>;
@group(0) @binding(7) var<storage, read_write> feedback: array<atomic<u32>>;
@group(0) @binding(8) var pool0: texture_2d_array<f32>;
@group(0) @binding(9) var pool1: texture_2d_array<f32>;
@group(0) @binding(10) var pool2: texture_2d_array<f32>;
@group(0) @binding(11) var pool3: texture_2d_array<f32>;
@group(0) @binding(12) var dpool0: texture_2d_array<f32>;
@group(0) @binding(13) var dpool1: texture_2d_array<f32>;
@group(0) @binding(14) var dpool2: texture_2d_array<f32>;
@group(0) @binding(15) var dpool3: texture_2d_array<f32>;
@group(0) @binding(16) var out_image: texture_storage_2d<rgba32float, write>;
// The G-buffer pass's depth: below 1.0 (the clear) where a triangle covers the pixel; the
// colour targets are not cleared, so only there do gb_position and gb_normal hold this frame.
@group(0) @binding(17) var gb_depth: texture_depth_2d;

const INVALID: u32 = 0xffffffffu;
const PI: f32 = 3.14159265358979;
// Distances at or above this mean "nothing this way" (face.rs FAR_DISTANCE, binary16's largest).
const FAR: f32 = 65504.0;
// Bisection steps that refine a depth-corrected hit (params.rs documents the search).
const DEPTH_REFINE: u32 = 6u;
// Steps of a glossy sample's depth correction (`depth_iterate`; reference.rs DEPTH_ITERATIONS).
const DEPTH_ITERATIONS: u32 = 2u;
// A texel of a depth-corrected lookup takes part in its bilinear tap when its distance lies
// within this many depth_thickness of the hit's, at most half of it (`depth_lookup`;
// reference.rs LOOKUP_AGREE).
const LOOKUP_AGREE: f32 = 1.0;
// A candidate sees the blend's common hit when its distance toward it lies within this many
// depth_thickness (one texel angle) of the hit's (`blend_read`; reference.rs HIT_AGREE).
const HIT_AGREE: f32 = 0.25;

// ---- random numbers: PCG hash (Jarzynski & Olano 2020), identical in reference.rs ----

fn pcg(v: u32) -> u32 {
    let state = v * 747796405u + 2891336453u;
    let word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
    return (word >> 22u) ^ word;
}

fn rand(pixel: u32, i: u32, j: u32, k: u32) -> f32 {
    let h = pcg(pixel + pcg(i + pcg(j * 8u + k)));
    return f32(h >> 8u) * (1.0 / 16777216.0);
}

// (ξ1, ξ2) of Monte Carlo sample i of integration j at this pixel, numbers k and k + 1 of it
// (k = 0: the specular sample, k = 2: the diffuse one); ξ1 is stratified, in [i/M, (i+1)/M).
// Per-pixel random numbers for point sampling; with FILTER a fixed set, the same at every
// pixel, as Křivánek & Colbert (2008) pair it with filtered lookups: the estimate is then
// smooth instead of noisy (`filter_xi`).
fn sample_xi(pixel: u32, i: u32, j: u32, k: u32) -> vec2<f32> {
    if (FILTER) {
        return filter_xi(i);
    }
    return vec2<f32>((f32(i) + rand(pixel, i, j, k)) / f32(P.m), rand(pixel, i, j, k + 1u));
}

// (ξ1, ξ2) of filtered sample i of M. For M = n² the centres of an n × n grid of strata mapped
// to the disc by Shirley & Chiu's concentric map (1997), read as polar coordinates (ξ1 = φ/2π,
// ξ2 = r²: the disc's area measure is uniform in both): every sample's cell is compact, so
// the isotropic filtered lookup of its area covers it (Hammersley's cells near the lobe's
// peak are thin wedges, and a wide lobe's peak is then read too often). Other M: the
// Hammersley set ((i + ½)/M, radical inverse of i). reference.rs `filter_xi` computes the same.
fn filter_xi(i: u32) -> vec2<f32> {
    let n = u32(round(sqrt(f32(P.m))));
    if (n * n != P.m) {
        return vec2<f32>((f32(i) + 0.5) / f32(P.m), f32(reverseBits(i)) * 2.3283064365386963e-10);
    }
    let a = 2.0 * (f32(i % n) + 0.5) / f32(n) - 1.0;
    let b = 2.0 * (f32(i / n) + 0.5) / f32(n) - 1.0;
    if (a == 0.0 && b == 0.0) {
        return vec2<f32>(0.0); // the centre cell of an odd n
    }
    var r = b;
    var phi = 0.5 * PI - 0.25 * PI * (a / b);
    if (abs(a) > abs(b)) {
        r = a;
        phi = 0.25 * PI * (b / a);
    }
    if (r < 0.0) {
        r = -r;
        phi += PI;
    }
    let x1 = phi * (0.5 / PI);
    return vec2<f32>(x1 - floor(x1), r * r);
}

// The samples per row of the filtered set: n for M = n² with FILTER (`filter_xi`'s grid, read
// row by row), else 1 (every sample a row of its own). reference.rs `filter_rows` likewise.
fn filter_rows() -> u32 {
    let n = u32(round(sqrt(f32(P.m))));
    if (FILTER && n > 0u && n * n == P.m) {
        return n;
    }
    return 1u;
}

// ---- feedback marks ----

// The faces this invocation has read, gathered per cube (`mark_face`) and written to the
// feedback buffer once at its end (`flush_marks`) instead of one atomic per read: the four
// candidates' cubes (`mark_cube`, set after `candidates`) and the environment cube; any other
// cube is marked at once. The buffer ends the frame with the same bits either way. (Atomics
// on the few cubes every pixel reads dominated glossy frames on an NVIDIA H200:
// docs/measurements.md.)
var<private> mark_cube: vec4<u32>;
var<private> mark_bits: vec4<u32>;
var<private> mark_env: u32;

fn mark_face(cube: u32, bits: u32) {
    if (cube == mark_cube.x) {
        mark_bits.x |= bits;
    } else if (cube == mark_cube.y) {
        mark_bits.y |= bits;
    } else if (cube == mark_cube.z) {
        mark_bits.z |= bits;
    } else if (cube == mark_cube.w) {
        mark_bits.w |= bits;
    } else if (cube == P.env_cube) {
        mark_env |= bits;
    } else {
        atomicOr(&feedback[cube], bits);
    }
}

fn flush_marks() {
    for (var k = 0u; k < 4u; k++) {
        if (mark_bits[k] != 0u) {
            atomicOr(&feedback[mark_cube[k]], mark_bits[k]);
        }
    }
    if (mark_env != 0u) {
        atomicOr(&feedback[P.env_cube], mark_env);
    }
}

// ---- cube maps ----

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

// ---- depth-corrected lookups (§6.3's RGBZ) ----

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

// Where sample point `cube` sees the ray from x along l meet the scene, for a glossy sample:
// the fixed-point iteration of distance impostors (Szirmay-Kalos et al. 2005). Each step reads
// the distance D the sample point p stores towards its current guess and moves the guess to
// where the ray leaves the sphere of radius D around p; DEPTH_ITERATIONS steps, each one texel
// read, instead of `depth_search`'s walk: a filtered sample reads an area many texels wide, so
// the search's texel-exact silhouettes do not show, and its cost would be paid M times per
// candidate (docs/measurements.md). Only a `fresh` sample iterates: the others of its row of
// the filtered sample grid (`filter_rows`), which lie side by side on the lobe, take the
// sphere of the distance it converged to (`seed`: in, that distance, 0 for none; out, a fresh
// sample's), reading nothing; on the example scene that moved the glossy errors at M = 16 by
// −0.3 to +2.2 % for about a fifth of the frame time on lavapipe (docs/measurements.md). Returns the direction to
// look up from p (unnormalized): l itself where a step finds nothing that way (FAR, or a face
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

// ---- geometry ----

fn oct_decode(e: vec2<f32>) -> vec3<f32> {
    var n = vec3<f32>(e.x, e.y, 1.0 - abs(e.x) - abs(e.y));
    if (n.z < 0.0) {
        let sx = select(-1.0, 1.0, n.x >= 0.0);
        let sy = select(-1.0, 1.0, n.y >= 0.0);
        n = vec3<f32>((1.0 - abs(n.y)) * sx, (1.0 - abs(n.x)) * sy, n.z);
    }
    return normalize(n);
}

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
// zero and their frame always comes from n alone (as reference.rs's `tangent_frame` does).
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

// ---- blending (chapter 4) ----

// Vectors, not arrays: lavapipe gives every local array that is indexed dynamically its own
// scratch memory, initialized per invocation even where the code is never reached (a 10×
// slowdown measured with runtime/examples/lvp_probe.rs); dynamic vector indexing is cheap.
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
// When none sees it, the blend of the candidates' own hits above.
fn blend_read(w: vec4<f32>, x: vec3<f32>, dir: vec3<f32>, lod: f32) -> vec4<f32> {
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

// ---- surface reconstruction (3.11–3.12, §6.3) ----

fn recon_choice(n: vec3<f32>, resident_only: bool) -> u32 {
    var best = 4u;
    var best_dot = -2.0;
    for (var j = 0u; j < 4u; j++) {
        if (cand.idx[j] == INVALID) { continue; }
        if (resident_only && !is_resident(cand.idx[j])) { continue; }
        let d = dot(n, cand_s(j));
        if (d >= P.cos_phi_shader) { return j; }
        if (d > best_dot) { best_dot = d; best = j; }
    }
    return best;
}

// With DEPTH: the mean, weighted by ⟨n, s_j⟩, over every candidate in front of x that sees x
// by its distance plane (x no farther than the surface it sees that way, within
// depth_thickness). The baked object is diffuse, so each such cube holds x's radiance, each
// with its own Monte Carlo noise: the mean of k is less noisy than the one the thesis picks,
// and the weight favours the views that resolve x best. Each is read depth-guided
// (`depth_lookup`), so that x at the object's silhouette does not take in what lies behind it.
// `.w` = 0 when no candidate qualifies (then the thesis's choice within φ_shader, below).
fn recon_visible(x: vec3<f32>, n: vec3<f32>) -> vec4<f32> {
    var acc = vec3<f32>(0.0);
    var count = 0.0;
    for (var j = 0u; j < 4u; j++) {
        let c = cand.idx[j];
        let cos_j = dot(n, cand_s(j));
        if (c == INVALID || cos_j <= 0.0) { continue; }
        let d = x - samples[c].xyz;
        depth_missing = false;
        let seen = depth_toward(c, slots[c], d, false);
        if (depth_missing || length(d) > seen * (1.0 + P.depth_thickness)) { continue; }
        let l = depth_lookup(c, vec4<f32>(d, 1.0), 0.0);
        if (l.w > 0.0) {
            acc += l.rgb * cos_j;
            count += cos_j;
        }
    }
    if (count > 0.0) {
        return vec4<f32>(acc / count, 1.0);
    }
    return vec4<f32>(0.0);
}

fn recon(x: vec3<f32>, n: vec3<f32>) -> vec3<f32> {
    if (DEPTH) {
        let m = recon_visible(x, n);
        if (m.w > 0.0) { return m.rgb; }
    }
    // The choice with every cube resident is what the frame needs (marked in the feedback).
    let ideal = recon_choice(n, false);
    if (ideal == 4u) { return vec3<f32>(0.0); }
    let want = lookup(cand.idx[ideal], x - samples[cand.idx[ideal]].xyz);
    if (want.w > 0.0) { return want.rgb; }
    let j = recon_choice(n, true);
    if (j == 4u) { return vec3<f32>(0.0); }
    let got = lookup(cand.idx[j], x - samples[cand.idx[j]].xyz);
    return got.rgb * got.w;
}

// ---- mirror reflection (chapter 4) ----

fn mirror(x: vec3<f32>, n: vec3<f32>, r: vec3<f32>) -> vec3<f32> {
    // Without DEPTH every cube is looked up towards r: one tap serves the candidates and the
    // fallback.
    let t = tap(r);
    var b = vec4<f32>(0.0);
    if (SOURCE == 0u && cand.count > 0u) {
        var axis = r;
        if (BLEND == 4u) { axis = n; }
        let w = blend_weights(axis);
        if (DEPTH) {
            b = blend_read(w, x, r, 0.0);
        } else if (BLEND <= 1u) {
            // One candidate has weight 1: one lookup instead of four masked ones.
            var j = 0u;
            if (w.y > 0.0) { j = 1u; } else if (w.z > 0.0) { j = 2u; } else if (w.w > 0.0) { j = 3u; }
            b = fetch(cand.idx[j], t);
        } else {
            b = blend_fetch(w, t);
        }
    }
    if (b.w > 0.0) { return b.rgb; }
    if (P.env_cube == INVALID) { return vec3<f32>(0.0); }
    if (SOURCE == 2u) { return env_read(x, r, 0.0); }
    return fetch(P.env_cube, t).rgb;
}

// ---- Ashikhmin–Shirley by Monte Carlo (chapter 5) ----

struct AsSample {
    l: vec3<f32>,
    // f_r ⟨n,l⟩ / p(l): the weight of L_i(l) in Eq. 5.12; 0 for samples below the surface.
    weight: f32,
    // log2(M p(l)), p the solid-angle density l was drawn with: the sample's mip level
    // (`sample_lod`).
    lpdf: f32,
};

fn fresnel(rs: f32, c: f32) -> f32 {
    // Eq. 5.7 (Schlick)
    let k = clamp(1.0 - c, 0.0, 1.0);
    let k2 = k * k;
    return rs + (1.0 - rs) * k2 * k2 * k;
}

// The specular lobe's sample at (ξ1, ξ2): ξ1 picks the quadrant and φ in it (Eq. 5.9 with the
// exponent in φ, see NOTES.md), ξ2 the angle from n, reflected about h (5.10). With k = v the estimator
// f_sr ⟨n,l⟩ / p(l) of 5.5, 5.8, 5.11 reduces to F(⟨v,h⟩) ⟨n,l⟩ / max(⟨n,v⟩, ⟨n,l⟩):
// no exponent, no 0/0 at h = n, finite for any n_u, n_v.
fn sample_as(xi1: f32, xi2: f32, n: vec3<f32>, t: vec3<f32>, b: vec3<f32>, v: vec3<f32>, nv: f32) -> AsSample {
    var out: AsSample;
    let q = min(u32(xi1 * 4.0), 3u);
    let xq = xi1 * 4.0 - f32(q);
    let half_angle = 0.5 * PI * xq;
    var phi = atan2(sqrt(P.nu + 1.0) * sin(half_angle), sqrt(P.nv + 1.0) * cos(half_angle));
    if (q == 1u) { phi = PI - phi; } else if (q == 2u) { phi = PI + phi; } else if (q == 3u) { phi = 2.0 * PI - phi; }
    let cp = cos(phi);
    let sp = sin(phi);
    let e = P.nu * cp * cp + P.nv * sp * sp;
    let cos_theta = pow(1.0 - xi2, 1.0 / (e + 1.0));
    let sin_theta = sqrt(max(0.0, 1.0 - cos_theta * cos_theta));
    let h = t * (sin_theta * cp) + b * (sin_theta * sp) + n * cos_theta;
    let vh = dot(v, h);
    out.l = 2.0 * vh * h - v;
    out.weight = 0.0;
    // p(h) = √((n_u+1)(n_v+1)) / 2π · ⟨n,h⟩^e (5.8), with ⟨n,h⟩^e = (1 − ξ2)^(e/(e+1)) from the
    // inversion above (finite for any exponent); p(l) = p(h) / 4⟨v,h⟩ (5.11).
    out.lpdf = log2(f32(P.m)) + 0.5 * log2((P.nu + 1.0) * (P.nv + 1.0)) - log2(2.0 * PI)
        + e / (e + 1.0) * log2(1.0 - xi2) - log2(4.0 * max(vh, 1e-30));
    let nl = dot(n, out.l);
    if (vh > 0.0 && nl > 0.0) {
        out.weight = fresnel(P.rs, vh) * nl / max(nv, nl);
    }
    return out;
}

// Cosine-weighted sample for the diffuse term 5.4: f_dr ⟨n,l⟩ / p(l) = π f_dr.
fn sample_diffuse(xi1: f32, r2: f32, n: vec3<f32>, t: vec3<f32>, b: vec3<f32>, nv: f32) -> AsSample {
    var out: AsSample;
    let phi = 2.0 * PI * xi1;
    let rad = sqrt(r2);
    let z = sqrt(max(0.0, 1.0 - r2));
    out.l = t * (rad * cos(phi)) + b * (rad * sin(phi)) + n * z;
    let nl = dot(n, out.l);
    out.lpdf = log2(f32(P.m)) + log2(max(nl, 1e-30) / PI); // p(l) = ⟨n,l⟩ / π
    let fv = 1.0 - pow(1.0 - 0.5 * max(nv, 0.0), 5.0);
    let fl = 1.0 - pow(1.0 - 0.5 * max(nl, 0.0), 5.0);
    out.weight = select(0.0, 28.0 / 23.0 * P.rd * (1.0 - P.rs) * fv * fl, nl > 0.0); // Eq. 5.4 × π
    return out;
}

// The radiance of sample `s` for the shaded point x: cube `cube` (depth-corrected for a
// sample point with DEPTH, parallax-corrected for the environment cube with SOURCE 2), or (per
// direction, cube = INVALID) the blend of the candidates with the environment cube where none
// is resident; filtered at mip level `lod` (`sample_lod`) with FILTER. `.w` = 0 when a cube's
// face was not resident.
fn sample_radiance(cube: u32, entry: u32, o: vec3<f32>, wn: vec4<f32>, x: vec3<f32>, s: AsSample, lod: f32, fresh: bool, seed: ptr<function, f32>) -> vec4<f32> {
    let l = s.l;
    if (ORDER == 1u && cube == INVALID) {
        var w = wn;
        if (BLEND != 4u) { w = blend_weights(l); }
        let b = blend_read(w, x, l, lod);
        if (b.w > 0.0) { return b; }
        return vec4<f32>(env_read(x, l, lod), 1.0);
    }
    var d = l;
    if (cube == P.env_cube) {
        d = env_dir(x, l);
    } else if (DEPTH) {
        d = depth_iterate(cube, entry, o, l, fresh, seed);
    }
    // With FILTER every level through `lookup_levels`, level 0 too: lavapipe would run
    // `lookup_lod`'s branch to `lookup` for every sample (FIS + depth frames 1.2× as long).
    if (FILTER) {
        return lookup_levels(cube, entry, d, lod);
    }
    return lookup(cube, d);
}

// Per-cube sums of an integration (Eq. 5.12), by component: entry k belongs to `cubes[k]`.
struct Sums {
    r: vec4<f32>,
    g: vec4<f32>,
    b: vec4<f32>,
    // 0 where a face that entry needed was not resident.
    ok: vec4<f32>,
};

// Adds sample `s`'s radiance × weight to entry k of `sums` (`sample_radiance` of cube `cube`;
// `fresh` and `seed` as `depth_iterate`).
// A function, not a loop over the two kinds of sample: lavapipe ran FIS frames up to 1.8×
// slower with even a one-pass loop around the read.
fn accumulate(sums: ptr<function, Sums>, k: u32, cube: u32, entry: u32, o: vec3<f32>, wn: vec4<f32>, x: vec3<f32>, s: AsSample, lod: f32, fresh: bool, seed: ptr<function, f32>) {
    let l = sample_radiance(cube, entry, o, wn, x, s, lod, fresh, seed);
    if (l.w == 0.0) { (*sums).ok[k] = 0.0; }
    (*sums).r[k] += l.r * s.weight;
    (*sums).g[k] += l.g * s.weight;
    (*sums).b[k] += l.b * s.weight;
}

// The M samples' sums of radiance × weight (Eq. 5.12, before ÷ M) from up to four sources at
// once: entry k integrates over `cubes[k]` where `used[k]`, with the random numbers of
// integration j0 + k; cube INVALID is the blend of the candidates per direction. With FILTER
// every source takes the same fixed samples, so each is drawn once for all of them. The
// diffuse term 5.4 is compiled in only when R_d > 0 (override DIFFUSE). One loop with one
// call site: lavapipe pays for every inlined copy whether it runs or not.
fn integrate(cubes: vec4<u32>, used: vec4<bool>, j0: u32, pixel: u32, x: vec3<f32>, n: vec3<f32>, t: vec3<f32>, b: vec3<f32>, v: vec3<f32>, nv: f32) -> Sums {
    var out = Sums(vec4<f32>(0.0), vec4<f32>(0.0), vec4<f32>(0.0), vec4<f32>(1.0));
    var wn = vec4<f32>(0.0);
    if (ORDER == 1u && BLEND == 4u) { wn = blend_weights(n); }
    var entries = vec4<u32>(0u);
    var ox = vec4<f32>(0.0);
    var oy = vec4<f32>(0.0);
    var oz = vec4<f32>(0.0);
    for (var k = 0u; k < 4u; k++) {
        if (used[k] && cubes[k] != INVALID) {
            entries[k] = slots[cubes[k]];
            let o = x - samples[cubes[k]].xyz;
            ox[k] = o.x;
            oy[k] = o.y;
            oz[k] = o.z;
        }
    }
    // Per candidate and kind of sample, the distance `depth_iterate`'s fresh sample of the row
    // converged to, and whether the row has had its fresh sample yet.
    var spec_seed = vec4<f32>(0.0);
    var diff_seed = vec4<f32>(0.0);
    var spec_fresh = true;
    var diff_fresh = true;
    let rows = filter_rows();
    for (var i = 0u; i < P.m; i++) {
        if (i % rows == 0u) {
            spec_fresh = true;
            diff_fresh = true;
        }
        var spec: AsSample;
        var diff: AsSample;
        var spec_lod = 0.0;
        var diff_lod = 0.0;
        if (FILTER) {
            let xi = filter_xi(i);
            spec = sample_as(xi.x, xi.y, n, t, b, v, nv);
            spec_lod = sample_lod(spec.l, spec.lpdf);
            if (DIFFUSE) {
                diff = sample_diffuse(xi.x, xi.y, n, t, b, nv);
                diff_lod = sample_lod(diff.l, diff.lpdf);
            }
        }
        for (var k = 0u; k < 4u; k++) {
            if (!used[k]) { continue; }
            if (!FILTER) {
                let xi = sample_xi(pixel, i, j0 + k, 0u);
                spec = sample_as(xi.x, xi.y, n, t, b, v, nv);
                if (DIFFUSE) {
                    let xd = sample_xi(pixel, i, j0 + k, 2u);
                    diff = sample_diffuse(xd.x, xd.y, n, t, b, nv);
                }
            }
            if (spec.weight > 0.0) {
                var seed = spec_seed[k];
                accumulate(&out, k, cubes[k], entries[k], vec3<f32>(ox[k], oy[k], oz[k]), wn, x, spec, spec_lod, spec_fresh, &seed);
                spec_seed[k] = seed;
            }
            if (DIFFUSE && diff.weight > 0.0) {
                var seed = diff_seed[k];
                accumulate(&out, k, cubes[k], entries[k], vec3<f32>(ox[k], oy[k], oz[k]), wn, x, diff, diff_lod, diff_fresh, &seed);
                diff_seed[k] = seed;
            }
        }
        // The weights do not depend on the candidate: a row's fresh sample is its first one
        // above the surface.
        spec_fresh = spec_fresh && !(spec.weight > 0.0);
        diff_fresh = diff_fresh && !(DIFFUSE && diff.weight > 0.0);
    }
    return out;
}

// Entry k of `integrate`'s sums as the estimate (÷ M).
fn estimate(s: Sums, k: u32) -> vec3<f32> {
    return vec3<f32>(s.r[k], s.g[k], s.b[k]) / f32(max(P.m, 1u));
}

// Per point (order A): integrate at each candidate with its own random vectors, then blend
// (4.7); the environment cube (integration 4) when no candidate is usable. Per direction
// (order B): one integration over the blend. Both passes through one `integrate` call.
fn glossy(pixel: u32, x: vec3<f32>, n: vec3<f32>, t: vec3<f32>, v: vec3<f32>, r: vec3<f32>) -> vec3<f32> {
    let b = cross(n, t);
    let nv = dot(n, v);
    let use_env = SOURCE != 0u || cand.count == 0u;
    let one = vec4<bool>(true, false, false, false);
    if (ORDER == 1u && !use_env) {
        return estimate(integrate(vec4<u32>(INVALID), one, 4u, pixel, x, n, t, b, v, nv), 0u);
    }
    var axis = r;
    if (BLEND == 4u) { axis = n; }
    var w = vec4<f32>(0.0);
    if (!use_env) { w = blend_weights(axis); }
    var acc = vec3<f32>(0.0);
    var wsum = 0.0;
    // Phase 0: the candidates; phase 1: the environment cube, when none was usable.
    for (var phase = select(0u, 1u, use_env); phase < 2u; phase++) {
        var cubes = cand.idx;
        var used = (w > vec4<f32>(0.0)) & (cubes != vec4<u32>(INVALID));
        var wp = w;
        if (phase == 1u) {
            if (wsum > 0.0 || P.env_cube == INVALID) { break; }
            cubes = vec4<u32>(P.env_cube);
            used = one;
            wp = vec4<f32>(1.0, 0.0, 0.0, 0.0);
        }
        let sums = integrate(cubes, used, select(0u, 4u, phase == 1u), pixel, x, n, t, b, v, nv);
        for (var k = 0u; k < 4u; k++) {
            if (used[k] && (sums.ok[k] > 0.0 || phase == 1u)) {
                acc += estimate(sums, k) * wp[k];
                wsum += wp[k];
            }
        }
    }
    if (wsum > 0.0) { return acc / wsum; }
    return vec3<f32>(0.0);
}

// Replaces NaN and infinities by 0 so that nothing non-finite reaches a pixel.
fn finite3(c: vec3<f32>) -> vec3<f32> {
    var o = c;
    for (var k = 0u; k < 3u; k++) {
        let x = c[k];
        if (!(x == x) || abs(x) > 3.0e38) { o[k] = 0.0; }
    }
    return o;
}

// ---- background ----

// The unit direction of the camera ray through the centre of pixel `px`, as
// oslf_geometry::Camera::direction computes it; the viewing direction where that degenerates.
fn camera_ray(px: vec2<u32>) -> vec3<f32> {
    let w = f32(P.size.x);
    let h = f32(P.size.y);
    let aspect = w / h;
    let tan_half = P.cam_right.w;
    let sx = (2.0 * (f32(px.x) + 0.5) / w - 1.0) * aspect * tan_half;
    let sy = (1.0 - 2.0 * (f32(px.y) + 0.5) / h) * tan_half;
    let d = P.cam_forward.xyz + P.cam_right.xyz * sx + P.cam_up.xyz * sy;
    let l2 = dot(d, d);
    if (l2 > 0.0 && l2 <= 3.0e38) {
        return d * inverseSqrt(l2);
    }
    return P.cam_forward.xyz;
}

// The texel of the adjacent face that texel (x, y) one texel off `face`'s edge stands for, per
// edge (left, right, top, bottom) and face 6 bits: the adjacent face (3 bits); 8: the edge's
// own coordinate runs along the adjacent face's x (else its y); 16: reversed (n − 1 − it);
// 32: the texel lies at the adjacent face's far side (n − 1, else 0). SEAM_LO holds faces 0–4,
// SEAM_HI face 5. The same texel as `face_st` of the direction through the off-face texel's
// centre extended on `face`'s plane (the edge's coordinate a lands on (a + 1)·n/(n + 1), so
// at texel a): reference.rs `seam_texel` computes it that way.
const SEAM_LO = vec4<u32>(0x21e49964u, 0x00a18105u, 0x2ab1d0b2u, 0x0bf4c4e3u);
const SEAM_HI = vec4<u32>(0x20u, 0x1u, 0x1au, 0x3bu);

// Face and texel (x, y) of a level n texels wide that texel (x, y) of `face` stands for, where
// (x, y) may lie one texel off the face (not off two edges at once: a corner gets a valid
// texel of no meaning): then the texel of the adjacent face it stands for (SEAM_LO).
fn seam_texel(face: u32, x: i32, y: i32, n: i32) -> vec3<u32> {
    let in_x = x >= 0 && x < n;
    if (in_x && y >= 0 && y < n) {
        return vec3<u32>(face, u32(x), u32(y));
    }
    var e = select(0u, 1u, x >= n);
    var a = clamp(y, 0, n - 1);
    if (in_x) {
        e = select(2u, 3u, y >= n);
        a = x;
    }
    let code = select(SEAM_LO[e] >> (6u * face), SEAM_HI[e], face == 5u) & 63u;
    let along = u32(select(a, n - 1 - a, (code & 16u) != 0u));
    let fixed = select(0u, u32(n - 1), (code & 32u) != 0u);
    if ((code & 8u) != 0u) {
        return vec3<u32>(code & 7u, along, fixed);
    }
    return vec3<u32>(code & 7u, fixed, along);
}

// Texel `c` (face, x, y) of mip `level` of the slot in indirection entry `entry`.
fn slot_texel(entry: u32, c: vec3<u32>, level: u32) -> vec3<f32> {
    let at = place(entry, c.x);
    return load_texel(at.x, i32(at.y), vec2<u32>((at.z >> level) + c.y, c.z), level);
}

// Radiance of mip `level` of cube `cube` at `fst` (`face_st` of the direction: face and face
// coordinates), bilinear ACROSS face edges: the four texel centres around the direction on its
// face, those off the face read from the adjacent face (`seam_texel`), with the usual bilinear
// weights. At a corner of the cube, where three faces meet, the texel off the face in both
// directions does not exist: it is the mean of the other three. `.w` = 0 when a face it reads
// is not resident. Marks the faces it reads when `mark`. The four texels are found first and
// then read alike, so that an invocation at a face edge differs from its neighbours only in
// `seam_texel`'s arithmetic, not in what it loads (lavapipe runs every path any lane takes).
// Written without a local array (see `Candidates`).
fn seamless_level(cube: u32, entry: u32, fst: vec3<f32>, level: u32, mark: bool) -> vec4<f32> {
    let face = u32(fst.x);
    let n = i32(max(P.cube_res >> level, 1u));
    let nf = f32(n);
    let fx = fst.y * nf - 0.5;
    let fy = fst.z * nf - 0.5;
    let x0 = i32(floor(fx));
    let y0 = i32(floor(fy));
    let wx = fx - floor(fx);
    let wy = fy - floor(fy);
    // The texel off the face in both directions, as k = column + 2 * row; 4 = none.
    var corner = 4u;
    if ((x0 < 0 || x0 + 1 >= n) && (y0 < 0 || y0 + 1 >= n)) {
        corner = select(0u, 1u, x0 >= 0) + select(0u, 2u, y0 >= 0);
    }
    let c0 = seam_texel(face, x0, y0, n);
    let c1 = seam_texel(face, x0 + 1, y0, n);
    let c2 = seam_texel(face, x0, y0 + 1, n);
    let c3 = seam_texel(face, x0 + 1, y0 + 1, n);
    let bits = select(1u << c0.x, 0u, corner == 0u) | select(1u << c1.x, 0u, corner == 1u)
        | select(1u << c2.x, 0u, corner == 2u) | select(1u << c3.x, 0u, corner == 3u);
    if (mark) {
        mark_face(cube, bits);
    }
    if ((entry & bits) != bits) {
        return vec4<f32>(0.0);
    }
    // The corner's texel is loaded too (a valid address; the value is replaced below).
    var t0 = slot_texel(entry, c0, level);
    var t1 = slot_texel(entry, c1, level);
    var t2 = slot_texel(entry, c2, level);
    var t3 = slot_texel(entry, c3, level);
    if (corner == 0u) { t0 = vec3<f32>(0.0); } else if (corner == 1u) { t1 = vec3<f32>(0.0); } else if (corner == 2u) { t2 = vec3<f32>(0.0); } else if (corner == 3u) { t3 = vec3<f32>(0.0); }
    let mean = (t0 + t1 + t2 + t3) * (1.0 / 3.0);
    if (corner == 0u) { t0 = mean; } else if (corner == 1u) { t1 = mean; } else if (corner == 2u) { t2 = mean; } else if (corner == 3u) { t3 = mean; }
    let top = t0 + (t1 - t0) * wx;
    let bottom = t2 + (t3 - t2) * wx;
    return vec4<f32>(top + (bottom - top) * wy, 1.0);
}

// `seamless_level` at level 0 without feedback marks: for the background only. `lookup`
// (reflections, reconstruction) clamps at face edges, and every published error figure
// depends on that; filtered glossy samples (`lookup_lod`) read across edges at every level.
fn seamless_read(cube: u32, dir: vec3<f32>) -> vec3<f32> {
    return seamless_level(cube, slots[cube], face_st(dir), 0u, false).rgb;
}

// What background pixel `px` shows, alpha 0. The environment cube is pinned resident, so it is
// read without a feedback mark: the cache statistics stay those of the object. It is filtered
// across face edges (`seamless_read`), so the background shows no seams.
fn background(px: vec2<u32>) -> vec4<f32> {
    if (BACKGROUND == 0u) {
        return vec4<f32>(0.0);
    }
    var c = P.bg_color.rgb;
    if (BACKGROUND == 1u) {
        c = vec3<f32>(0.0);
        if (P.env_cube != INVALID) {
            c = seamless_read(P.env_cube, camera_ray(px));
        }
    }
    return vec4<f32>(finite3(c), 0.0);
}

@compute @workgroup_size(8, 8, 1)
fn shade(@builtin(global_invocation_id) gid: vec3<u32>) {
    if (gid.x >= P.size.x || gid.y >= P.size.y) { return; }
    let px = vec2<i32>(i32(gid.x), i32(gid.y));
    let g0 = textureLoad(gb_position, px, 0);
    let g1 = textureLoad(gb_normal, px, 0);
    if (!(textureLoad(gb_depth, px, 0) < 1.0) || g0.w < 0.5) {
        textureStore(out_image, px, background(gid.xy));
        return;
    }
    let pid = u32(g0.w - 0.5);
    let x = g0.xyz;
    let u = g1.z;
    let v_param = g1.w;
    let n = patch_normal(pid, u, v_param, oct_decode(g1.xy));
    candidates(pid, u, v_param, x, n);
    mark_cube = cand.idx;
    mark_bits = vec4<u32>(0u);
    mark_env = 0u;
    let v = normalize(P.camera_pos.xyz - x);
    let r = 2.0 * dot(n, v) * n - v; // Eq. 2.4
    let pixel = pcg(gid.x + pcg(gid.y + pcg(P.seed)));

    var spec = vec3<f32>(0.0);
    if ((TERMS & 2u) != 0u) {
        spec = mirror(x, n, r);
    } else if ((TERMS & 4u) != 0u) {
        let t = tangent_frame(n, patch_du(pid, u, v_param));
        spec = glossy(pixel, x, n, t, v, r);
    }
    if ((TERMS & 8u) != 0u) {
        spec *= patches[pid].color.rgb;
    }
    var color = spec;
    if ((TERMS & 1u) != 0u) {
        color += recon(x, n); // Eq. 3.12, 4.12
    }
    flush_marks();
    textureStore(out_image, px, vec4<f32>(finite3(color), 1.0));
}
