// Assembled by oslf_shading::wgsl::assemble from WGSL modules (root `package::shade::pixel`).
// Do not edit: edit the modules, then run this crate's tests with OSLF_BLESS=1 to write
// this file again.
const PI: f32 = 3.1415927;

const FRAC_1_PI: f32 = 0.31830987;

const FRAC_PI_2: f32 = 1.5707964;

const FRAC_PI_4: f32 = 0.7853982;

const GGX_MIN_ALPHA: f32 = 0.001;

const GGX_DIELECTRIC_F0: f32 = 0.04;

const SH_Y0: f32 = 0.2820948;

const SH_Y1: f32 = 0.4886025;

const SH_Y2: f32 = 1.0925484;

const SH_Y20: f32 = 0.31539157;

const SH_Y22: f32 = 0.5462742;

const SH_COSINE: vec3<f32> = vec3<f32>(1.0, 0.6666667, 0.25);

const SH_AS_DIFFUSE: vec3<f32> = vec3<f32>(0.8214286, 0.58519346, 0.26822916);

fn ggx_alpha(roughness: f32) -> f32 {
    return max(roughness * roughness, GGX_MIN_ALPHA);
}

fn ggx_distribution_denominator(a2: f32, nh: f32, sin2: f32) -> f32 {
    return a2 * nh * nh + sin2;
}

fn ggx_distribution(a2: f32, nh: f32, sin2: f32) -> f32 {
    if (nh <= 0.0) {
        return 0.0;
    }
    let d = ggx_distribution_denominator(a2, nh, sin2);
    return a2 / (PI * d * d);
}

fn ggx_distribution_at(a2: f32, n: vec3<f32>, h: vec3<f32>) -> f32 {
    let c = cross(n, h);
    return ggx_distribution(a2, dot(n, h), dot(c, c));
}

fn ggx_smith_lambda(a2: f32, c: f32) -> f32 {
    return c + sqrt(a2 + (1.0 - a2) * c * c);
}

fn ggx_smith_g1(a2: f32, c: f32) -> f32 {
    return 2.0 * c / ggx_smith_lambda(a2, c);
}

fn ggx_visibility(a2: f32, nl: f32, nv: f32) -> f32 {
    return 1.0 / (ggx_smith_lambda(a2, nl) * ggx_smith_lambda(a2, nv));
}

fn ggx_sample_visible_normal(v: vec3<f32>, alpha: f32, r2: f32, phi_fraction: f32) -> vec3<f32> {
    let vh = normalize(vec3<f32>(alpha * v.x, alpha * v.y, v.z));
    let len2 = vh.x * vh.x + vh.y * vh.y;
    var t1 = vec3<f32>(1.0, 0.0, 0.0);
    if (len2 > 0.0) {
        t1 = vec3<f32>(-vh.y, vh.x, 0.0) / sqrt(len2);
    }
    let t2 = cross(vh, t1);
    let r = sqrt(r2);
    let phi = 2.0 * PI * phi_fraction;
    let p1 = r * cos(phi);
    let s = 0.5 * (1.0 + vh.z);
    let p2 = (1.0 - s) * sqrt(max(1.0 - p1 * p1, 0.0)) + s * r * sin(phi);
    let nh = p1 * t1 + p2 * t2 + sqrt(max(1.0 - p1 * p1 - p2 * p2, 0.0)) * vh;
    let m = vec3<f32>(alpha * nh.x, alpha * nh.y, max(nh.z, 0.0));
    if (dot(m, m) > 0.0) {
        return normalize(m);
    }
    return vec3<f32>(0.0, 0.0, 1.0);
}

fn ggx_sample_distribution_cos(a2: f32, xi: f32) -> f32 {
    return sqrt(max((1.0 - xi) / (1.0 + (a2 - 1.0) * xi), 0.0));
}

fn fresnel_schlick_weight(c: f32) -> f32 {
    let k = clamp(1.0 - c, 0.0, 1.0);
    let k2 = k * k;
    return k2 * k2 * k;
}

fn fresnel_schlick(f0: f32, c: f32) -> f32 {
    return f0 + (1.0 - f0) * fresnel_schlick_weight(c);
}

fn srgb_to_linear(c: f32) -> f32 {
    if (c <= 0.04045) {
        return c / 12.92;
    }
    return pow((c + 0.055) / 1.055, 2.4);
}

fn linear_to_srgb(c: f32) -> f32 {
    let x = select(clamp(c, 0.0, 1.0), 0.0, c != c);
    if (x <= 0.0031308) {
        return 12.92 * x;
    }
    return 1.055 * pow(x, 1.0 / 2.4) - 0.055;
}

fn aces(x_in: f32) -> f32 {
    if (!(x_in > 0.0)) {
        return 0.0;
    }
    let x = min(x_in, 1000000.0);
    return clamp((x * (2.51 * x + 0.03)) / (x * (2.43 * x + 0.59) + 0.14), 0.0, 1.0);
}

fn luminance(c: vec3<f32>) -> f32 {
    return 0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z;
}

fn sh_basis(d: vec3<f32>) -> array<f32, 9> {
    return array<f32, 9>(SH_Y0, SH_Y1 * d.y, SH_Y1 * d.z, SH_Y1 * d.x, SH_Y2 * d.x * d.y, SH_Y2 * d.y * d.z, SH_Y20 * (3.0 * d.z * d.z - 1.0), SH_Y2 * d.x * d.z, SH_Y22 * (d.x * d.x - d.y * d.y));
}

fn sh_band(i: u32) -> u32 {
    if (i == 0u) {
        return 0u;
    }
    if (i <= 3u) {
        return 1u;
    }
    return 2u;
}

fn sh_convolve(c: array<vec3<f32>, 9>, bands: vec3<f32>, n: vec3<f32>) -> vec3<f32> {
    let y = sh_basis(n);
    var e = vec3<f32>(0.0);
    for (var i = 0u; i < 9u; i++) {
        e += c[i] * (y[i] * bands[sh_band(i)]);
    }
    return max(e, vec3<f32>(0.0));
}

fn sh_fresnel_cosine_weight(nv: f32) -> f32 {
    let s = 1.0 - clamp(nv, 0.0, 1.0);
    let w = 8.280397e-5 + s * (0.0020117674 + s * (0.009362331 + s * (0.007705992 + s * 0.009002511)));
    return 1.0 - w;
}

struct Params {
    view_proj: mat4x4<f32>,
    camera_pos: vec4<f32>,
    size: vec2<u32>,
    terms: u32,
    blend: u32,
    blend_n: f32,
    source: u32,
    m: u32,
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
    cam_right: vec4<f32>,
    cam_up: vec4<f32>,
    cam_forward: vec4<f32>,
    bg_color: vec4<f32>,
    background: u32,
    mip_levels: u32,
    depth_steps: u32,
    depth_thickness: f32,
    probe_pos: vec4<f32>,
    box_min: vec4<f32>,
    box_max: vec4<f32>,
    metallic: f32,
    alpha: f32,
    object_material: u32,
    min_metallic: f32,
    split_sum: u32,
    irradiance: u32,
    surface_error: f32,
    pad2: u32
}

struct GVertex {
    position_patch: vec4<f32>,
    normal_u: vec4<f32>,
    v: vec4<f32>,
    tangent: vec4<f32>
}

struct TextureParams {
    flags: u32,
    normal_scale: f32,
    occlusion_strength: f32,
    pad: u32
}

struct Prepass {
    clip_from_patch: mat4x4<f32>,
    previous_clip_from_patch: mat4x4<f32>,
    normal_from_local: mat4x4<f32>
}

fn oct_encode(n: vec3<f32>) -> vec2<f32> {
    let p = n.xy / (abs(n.x) + abs(n.y) + abs(n.z));
    if (n.z < 0.0) {
        let sx = select(-1.0, 1.0, p.x >= 0.0);
        let sy = select(-1.0, 1.0, p.y >= 0.0);
        return vec2<f32>((1.0 - abs(p.y)) * sx, (1.0 - abs(p.x)) * sy);
    }
    return p;
}

fn oct_decode(e: vec2<f32>) -> vec3<f32> {
    var n = vec3<f32>(e.x, e.y, 1.0 - abs(e.x) - abs(e.y));
    if (n.z < 0.0) {
        let sx = select(-1.0, 1.0, n.x >= 0.0);
        let sy = select(-1.0, 1.0, n.y >= 0.0);
        n = vec3<f32>((1.0 - abs(n.y)) * sx, (1.0 - abs(n.x)) * sy, n.z);
    }
    return normalize(n);
}

override TERMS: u32 = 1u;

override BLEND: u32 = 4u;

override SOURCE: u32 = 0u;

override ORDER: u32 = 0u;

override POOLS: u32 = 4u;

override FACE_SHIFT: u32 = 0u;

override DIFFUSE: bool = false;

override IRRADIANCE: bool = false;

override BACKGROUND: u32 = 0u;

override DEPTH: bool = false;

override FILTER: bool = false;

override SPLIT_SUM: bool = false;

override TEXTURED: bool = false;

struct PatchGpu {
    cp: array<vec4<f32>, 16>,
    color: vec4<f32>,
    material: vec4<f32>,
    emission: vec4<f32>
}

@group(0) @binding(0)
var<uniform> P: Params;

@group(0) @binding(1)
var gb_position: texture_2d<f32>;

@group(0) @binding(2)
var gb_normal: texture_2d<f32>;

@group(0) @binding(3)
var sample_maps: texture_2d_array<u32>;

@group(0) @binding(4)
var<storage, read> samples: array<vec4<f32>>;

@group(0) @binding(5)
var<storage, read> patches: array<PatchGpu>;

@group(0) @binding(6)
var<storage, read> slots: array<u32>;

@group(0) @binding(7)
var<storage, read_write> feedback: array<atomic<u32>>;

@group(0) @binding(8)
var pool0: texture_2d_array<f32>;

@group(0) @binding(9)
var pool1: texture_2d_array<f32>;

@group(0) @binding(10)
var pool2: texture_2d_array<f32>;

@group(0) @binding(11)
var pool3: texture_2d_array<f32>;

@group(0) @binding(12)
var dpool0: texture_2d_array<f32>;

@group(0) @binding(13)
var dpool1: texture_2d_array<f32>;

@group(0) @binding(14)
var dpool2: texture_2d_array<f32>;

@group(0) @binding(15)
var dpool3: texture_2d_array<f32>;

@group(0) @binding(16)
var out_image: texture_storage_2d<rgba32float, write>;

@group(0) @binding(17)
var gb_depth: texture_depth_2d;

@group(0) @binding(18)
var prefiltered: texture_2d_array<f32>;

@group(0) @binding(19)
var gb_material: texture_2d<u32>;

const INVALID: u32 = 4294967295u;

const FAR: f32 = 65504.0;

const PBR_LOD_BIAS: f32 = -0.5;

const DEPTH_REFINE: u32 = 6u;

const DEPTH_ITERATIONS: u32 = 2u;

const LOOKUP_AGREE: f32 = 1.0;

const REFINE_STEPS: u32 = 4u;

const REFINE_REACH: f32 = 16.0;

const REFINE_SLACK: f32 = 0.0001;

const REFINE_MISS: f32 = 0.1;

const HIT_AGREE: f32 = 0.25;

const LOW_HIT: f32 = 0.25;

fn pcg(v: u32) -> u32 {
    let state = v * 747796405u + 2891336453u;
    let word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
    return (word >> 22u) ^ word;
}

fn rand(pixel: u32, i: u32, j: u32, k: u32) -> f32 {
    let h = pcg(pixel + pcg(i + pcg(j * 8u + k)));
    return f32(h >> 8u) * (1.0 / 16777216.0);
}

fn sample_xi(pixel: u32, i: u32, j: u32, k: u32) -> vec2<f32> {
    if (FILTER) {
        return filter_xi(i, (TERMS & 16u) != 0u && k == 0u, j);
    }
    return vec2<f32>((f32(i) + rand(pixel, i, j, k)) / f32(P.m), rand(pixel, i, j, k + 1u));
}

fn filter_xi(i: u32, spiral: bool, j: u32) -> vec2<f32> {
    if (spiral) {
        var t = 0.0;
        var s = 0.0;
        if (j < 4u) {
            t = 0.25 * f32(j);
            s = 0.25 * f32(j) - 0.375;
        }
        let g = f32(i) * 0.3819660112501051 + t;
        return vec2<f32>(g - floor(g), (f32(i) + 0.5 + s) / f32(P.m));
    }
    let n = u32(round(sqrt(f32(P.m))));
    if (n * n != P.m) {
        return vec2<f32>((f32(i) + 0.5) / f32(P.m), f32(reverseBits(i)) * 2.3283064365386963e-10);
    }
    let a = 2.0 * (f32(i % n) + 0.5) / f32(n) - 1.0;
    let b = 2.0 * (f32(i / n) + 0.5) / f32(n) - 1.0;
    if (a == 0.0 && b == 0.0) {
        return vec2<f32>(0.0);
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

fn filter_rows() -> u32 {
    let n = u32(round(sqrt(f32(P.m))));
    if (FILTER && n > 0u && n * n == P.m) {
        return n;
    }
    return 1u;
}

var<private> mark_cube: vec4<u32>;

var<private> mark_bits: vec4<u32>;

var<private> mark_env: u32;

fn mark_face(cube: u32, bits: u32) {
    if (cube == mark_cube.x) {
        mark_bits.x |= bits;
    }
    else if (cube == mark_cube.y) {
        mark_bits.y |= bits;
    }
    else if (cube == mark_cube.z) {
        mark_bits.z |= bits;
    }
    else if (cube == mark_cube.w) {
        mark_bits.w |= bits;
    }
    else if (cube == P.env_cube) {
        mark_env |= bits;
    }
    else {
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

fn face_st(d: vec3<f32>) -> vec3<f32> {
    let a = abs(d);
    var face = 0u;
    var sc = 0.0;
    var tc = 0.0;
    var ma = 0.0;
    if (a.x >= a.y && a.x >= a.z) {
        ma = a.x;
        tc = -d.y;
        if (d.x >= 0.0) {
            face = 0u;
            sc = -d.z;
        }
        else {
            face = 1u;
            sc = d.z;
        }
    }
    else if (a.y >= a.z) {
        ma = a.y;
        sc = d.x;
        if (d.y >= 0.0) {
            face = 2u;
            tc = d.z;
        }
        else {
            face = 3u;
            tc = -d.z;
        }
    }
    else {
        ma = a.z;
        tc = -d.y;
        if (d.z >= 0.0) {
            face = 4u;
            sc = d.x;
        }
        else {
            face = 5u;
            sc = -d.x;
        }
    }
    if (!(ma > 0.0)) {
        return vec3<f32>(0.0, 0.5, 0.5);
    }
    let s = clamp((sc / ma + 1.0) * 0.5, 0.0, 1.0);
    let t = clamp((tc / ma + 1.0) * 0.5, 0.0, 1.0);
    return vec3<f32>(f32(face), s, t);
}

fn load_texel(tex: u32, layer: i32, c: vec2<u32>, level: u32) -> vec3<f32> {
    let p = vec2<i32>(c);
    let l = i32(level);
    if (POOLS == 1u || tex == 0u) {
        return textureLoad(pool0, p, layer, l).rgb;
    }
    else if (POOLS == 2u || tex == 1u) {
        return textureLoad(pool1, p, layer, l).rgb;
    }
    else if (POOLS == 3u || tex == 2u) {
        return textureLoad(pool2, p, layer, l).rgb;
    }
    return textureLoad(pool3, p, layer, l).rgb;
}

fn load_depth(tex: u32, layer: i32, c: vec2<u32>) -> f32 {
    let p = vec2<i32>(c);
    if (POOLS == 1u || tex == 0u) {
        return textureLoad(dpool0, p, layer, 0).r;
    }
    else if (POOLS == 2u || tex == 1u) {
        return textureLoad(dpool1, p, layer, 0).r;
    }
    else if (POOLS == 3u || tex == 2u) {
        return textureLoad(dpool2, p, layer, 0).r;
    }
    return textureLoad(dpool3, p, layer, 0).r;
}

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

struct Tap {
    face: u32,
    x0: u32,
    y0: u32,
    x1: u32,
    y1: u32,
    wx: f32,
    wy: f32
}

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

fn fetch(cube: u32, t: Tap) -> vec4<f32> {
    mark_face(cube, 1u << t.face);
    return read_tap(cube, t);
}

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

fn lookup(cube: u32, dir: vec3<f32>) -> vec4<f32> {
    return fetch(cube, tap(dir));
}

fn lookup_lod(cube: u32, dir: vec3<f32>, lod: f32) -> vec4<f32> {
    if (!(lod > 0.0)) {
        return lookup(cube, dir);
    }
    return lookup_levels(cube, slots[cube], dir, lod);
}

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

var<private> depth_missing: bool;

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

fn depth_probe(cube: u32, p: vec3<f32>, x: vec3<f32>, r: vec3<f32>, w: f32) -> vec4<f32> {
    if (!(w > 0.0)) {
        return vec4<f32>(r, 1.0);
    }
    let d = x + r * (1.0 / w) - p;
    return vec4<f32>(d, length(d) - depth_toward(cube, slots[cube], d, true));
}

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
        }
        else {
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

fn depth_hidden(cube: u32, entry: u32, o: vec3<f32>, l: vec3<f32>) -> bool {
    let d = o + l * length(o);
    let seen = depth_toward(cube, entry, d, false);
    return seen < FAR && length(d) >= seen;
}

fn depth_iterate(cube: u32, entry: u32, o: vec3<f32>, l: vec3<f32>, fresh: bool, seed: ptr<function, f32>) -> vec3<f32> {
    let ol = dot(o, l);
    let oo = dot(o, o);
    var q = l;
    let d0 = *seed;
    if (d0 * d0 > oo) {
        q = o + l * (sqrt(ol * ol - (oo - d0 * d0)) - ol);
    }
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
    if (h.w > 0.0) {
        dist = length(h.xyz);
    }
    let tol = min(LOOKUP_AGREE * P.depth_thickness, 0.5) * dist;
    let at = place(entry, t.face);
    let c00 = vec2<u32>(at.z + t.x0, t.y0);
    let c10 = vec2<u32>(at.z + t.x1, t.y0);
    let c01 = vec2<u32>(at.z + t.x0, t.y1);
    let c11 = vec2<u32>(at.z + t.x1, t.y1);
    let layer = i32(at.y);
    let d = vec4<f32>(load_depth(at.x, layer, c00), load_depth(at.x, layer, c10), load_depth(at.x, layer, c01), load_depth(at.x, layer, c11));
    var w = vec4<f32>((1.0 - t.wx) * (1.0 - t.wy), t.wx * (1.0 - t.wy), (1.0 - t.wx) * t.wy, t.wx * t.wy);
    let agree = select(vec4<f32>(0.0), w, abs(d - vec4<f32>(dist)) <= vec4<f32>(tol));
    let sum = agree.x + agree.y + agree.z + agree.w;
    if (sum > 0.0) {
        w = agree / sum;
    }
    let c = load_texel(at.x, layer, c00, 0u) * w.x + load_texel(at.x, layer, c10, 0u) * w.y + load_texel(at.x, layer, c01, 0u) * w.z + load_texel(at.x, layer, c11, 0u) * w.w;
    return vec4<f32>(c, 1.0);
}

fn low_hit(p: vec3<f32>, h: vec4<f32>, x: vec3<f32>, l: vec3<f32>, n: vec3<f32>) -> bool {
    return h.w > 0.0 && dot(p + h.xyz - x, l) * dot(l, n) < LOW_HIT * length(x - p);
}

fn bern3(t: f32) -> vec4<f32> {
    let s = 1.0 - t;
    return vec4<f32>(s * s * s, 3.0 * t * s * s, 3.0 * t * t * s, t * t * t);
}

fn bern2(t: f32) -> vec3<f32> {
    let s = 1.0 - t;
    return vec3<f32>(s * s, 2.0 * t * s, t * t);
}

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

struct SurfacePoint {
    x: vec3<f32>,
    u: f32,
    v: f32
}

fn surface_hit(p: u32, x: vec3<f32>, u: f32, v: f32, d: vec3<f32>) -> SurfacePoint {
    var uu = u;
    var vv = v;
    var s = 0.0;
    for (var k = 0u; k < REFINE_STEPS; k++) {
        let a = patch_du(p, uu, vv);
        let b = patch_dv(p, uu, vv);
        let f = patch_point(p, uu, vv, x) - d * s;
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

struct Candidates {
    idx: vec4<u32>,
    sx: vec4<f32>,
    sy: vec4<f32>,
    sz: vec4<f32>,
    count: u32
}

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
        if (P.index16 == 1u && idx == 65535u) {
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

fn one_hot(j: u32) -> vec4<f32> {
    return vec4<f32>(vec4<u32>(0u, 1u, 2u, 3u) == vec4<u32>(j));
}

fn blend_weights(a: vec3<f32>) -> vec4<f32> {
    let valid = cand.idx != vec4<u32>(INVALID);
    let d = vec4<f32>(dot(a, cand_s(0u)), dot(a, cand_s(1u)), dot(a, cand_s(2u)), dot(a, cand_s(3u)));
    if (!any(valid)) {
        return vec4<f32>(0.0);
    }
    var first = 3u;
    if (valid.z) {
        first = 2u;
    }
    if (valid.y) {
        first = 1u;
    }
    if (valid.x) {
        first = 0u;
    }
    var best = 0u;
    var best_dot = -2.0;
    if (valid.x && d.x > best_dot) {
        best_dot = d.x;
        best = 0u;
    }
    if (valid.y && d.y > best_dot) {
        best_dot = d.y;
        best = 1u;
    }
    if (valid.z && d.z > best_dot) {
        best_dot = d.z;
        best = 2u;
    }
    if (valid.w && d.w > best_dot) {
        best_dot = d.w;
        best = 3u;
    }
    if (BLEND == 0u) {
        return one_hot(first);
    }
    if (BLEND == 1u) {
        return one_hot(best);
    }
    if (BLEND == 2u || P.blend_n == 0.0) {
        return select(vec4<f32>(0.0), vec4<f32>(1.0), valid);
    }
    if (best_dot <= 0.0) {
        return one_hot(best);
    }
    let r = max(d, vec4<f32>(0.0)) / best_dot;
    return select(vec4<f32>(0.0), pow(r, vec4<f32>(P.blend_n)), valid & (r > vec4<f32>(0.0)));
}

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
            }
            else {
                l = lookup_lod(cand.idx[j], h.xyz, lod);
            }
            if (l.w > 0.0) {
                if (h.w >= 0.0) {
                    acc += l.rgb * w[j];
                    wsum += w[j];
                }
                else {
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
        }
        else if (dir[k] < -1e-12) {
            t = min(t, (lo[k] - x[k]) / dir[k]);
        }
    }
    if (!(t > 0.0 && t < 3.4e38)) {
        return dir;
    }
    return x + dir * t - P.probe_pos.xyz;
}

fn env_read(x: vec3<f32>, dir: vec3<f32>, lod: f32) -> vec3<f32> {
    if (P.env_cube == INVALID) {
        return vec3<f32>(0.0);
    }
    return lookup_lod(P.env_cube, env_dir(x, dir), lod).rgb;
}

fn recon_choice(n: vec3<f32>, resident_only: bool) -> u32 {
    var best = 4u;
    var best_dot = -2.0;
    for (var j = 0u; j < 4u; j++) {
        if (cand.idx[j] == INVALID) {
            continue;
        }
        if (resident_only && !is_resident(cand.idx[j])) {
            continue;
        }
        let d = dot(n, cand_s(j));
        if (d >= P.cos_phi_shader) {
            return j;
        }
        if (d > best_dot) {
            best_dot = d;
            best = j;
        }
    }
    return best;
}

fn recon_visible(x: vec3<f32>, n: vec3<f32>) -> vec4<f32> {
    var acc = vec3<f32>(0.0);
    var count = 0.0;
    for (var j = 0u; j < 4u; j++) {
        let c = cand.idx[j];
        let cos_j = dot(n, cand_s(j));
        if (c == INVALID || cos_j <= 0.0) {
            continue;
        }
        let d = x - samples[c].xyz;
        depth_missing = false;
        let seen = depth_toward(c, slots[c], d, false);
        if (depth_missing || length(d) > seen * (1.0 + P.depth_thickness)) {
            continue;
        }
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
        if (m.w > 0.0) {
            return m.rgb;
        }
    }
    let ideal = recon_choice(n, false);
    if (ideal == 4u) {
        return vec3<f32>(0.0);
    }
    let want = lookup(cand.idx[ideal], x - samples[cand.idx[ideal]].xyz);
    if (want.w > 0.0) {
        return want.rgb;
    }
    let j = recon_choice(n, true);
    if (j == 4u) {
        return vec3<f32>(0.0);
    }
    let got = lookup(cand.idx[j], x - samples[cand.idx[j]].xyz);
    return got.rgb * got.w;
}

fn mirror(x: vec3<f32>, n: vec3<f32>, r: vec3<f32>) -> vec3<f32> {
    let t = tap(r);
    var b = vec4<f32>(0.0);
    if (SOURCE == 0u && cand.count > 0u) {
        var axis = r;
        if (BLEND == 4u) {
            axis = n;
        }
        let w = blend_weights(axis);
        if (DEPTH) {
            b = blend_read(w, x, r, 0.0, n, false);
        }
        else if (BLEND <= 1u) {
            var j = 0u;
            if (w.y > 0.0) {
                j = 1u;
            }
            else if (w.z > 0.0) {
                j = 2u;
            }
            else if (w.w > 0.0) {
                j = 3u;
            }
            b = fetch(cand.idx[j], t);
        }
        else {
            b = blend_fetch(w, t);
        }
    }
    if (b.w > 0.0) {
        return b.rgb;
    }
    if (P.env_cube == INVALID) {
        return vec3<f32>(0.0);
    }
    if (SOURCE == 2u) {
        return env_read(x, r, 0.0);
    }
    return fetch(P.env_cube, t).rgb;
}

struct AsSample {
    l: vec3<f32>,
    weight: vec3<f32>,
    lpdf: f32
}

fn sample_as(xi1: f32, xi2: f32, n: vec3<f32>, t: vec3<f32>, b: vec3<f32>, v: vec3<f32>, nv: f32) -> AsSample {
    var out: AsSample;
    let q = min(u32(xi1 * 4.0), 3u);
    let xq = xi1 * 4.0 - f32(q);
    let half_angle = 0.5 * PI * xq;
    var phi = atan2(sqrt(P.nu + 1.0) * sin(half_angle), sqrt(P.nv + 1.0) * cos(half_angle));
    if (q == 1u) {
        phi = PI - phi;
    }
    else if (q == 2u) {
        phi = PI + phi;
    }
    else if (q == 3u) {
        phi = 2.0 * PI - phi;
    }
    let cp = cos(phi);
    let sp = sin(phi);
    let e = P.nu * cp * cp + P.nv * sp * sp;
    let cos_theta = pow(1.0 - xi2, 1.0 / (e + 1.0));
    let sin_theta = sqrt(max(0.0, 1.0 - cos_theta * cos_theta));
    let h = t * (sin_theta * cp) + b * (sin_theta * sp) + n * cos_theta;
    let vh = dot(v, h);
    out.l = 2.0 * vh * h - v;
    out.weight = vec3<f32>(0.0);
    out.lpdf = log2(f32(P.m)) + 0.5 * log2((P.nu + 1.0) * (P.nv + 1.0)) - log2(2.0 * PI) + e / (e + 1.0) * log2(1.0 - xi2) - log2(4.0 * max(vh, 1e-30));
    let nl = dot(n, out.l);
    if (vh > 0.0 && nl > 0.0) {
        out.weight = vec3<f32>(fresnel_schlick(P.rs, vh) * nl / max(nv, nl));
    }
    return out;
}

fn sample_ggx(xi1: f32, xi2: f32, n: vec3<f32>, t: vec3<f32>, b: vec3<f32>, v: vec3<f32>, nv: f32, base: vec3<f32>, pbr: vec2<f32>) -> AsSample {
    var out: AsSample;
    let a = pbr.y;
    let a2 = a * a;
    let vl = vec3<f32>(dot(v, t), dot(v, b), nv);
    let hl = ggx_sample_visible_normal(vl, a, xi2, xi1);
    let h = t * hl.x + b * hl.y + n * hl.z;
    let vh = dot(v, h);
    out.l = 2.0 * vh * h - v;
    let nl = dot(n, out.l);
    let d = ggx_distribution_denominator(a2, hl.z, hl.x * hl.x + hl.y * hl.y);
    let g1v = ggx_smith_g1(a2, nv);
    out.lpdf = log2(f32(P.m)) + log2(max(g1v, 1e-30)) + log2(a2) - log2(max(PI * d * d, 1e-30)) - log2(4.0 * max(nv, 1e-30)) - 2.0 * PBR_LOD_BIAS;
    out.weight = vec3<f32>(0.0);
    if (vh > 0.0 && nl > 0.0 && nv > 0.0) {
        let g1l = ggx_smith_g1(a2, nl);
        let k5 = fresnel_schlick_weight(vh);
        let metal = base + (vec3<f32>(1.0) - base) * k5;
        let dielectric = vec3<f32>(fresnel_schlick(GGX_DIELECTRIC_F0, vh));
        out.weight = mix(dielectric, metal, pbr.x) * g1l;
    }
    return out;
}

fn cosine_sample(xi1: f32, r2: f32, n: vec3<f32>, t: vec3<f32>, b: vec3<f32>) -> AsSample {
    var out: AsSample;
    let phi = 2.0 * PI * xi1;
    let rad = sqrt(r2);
    let z = sqrt(max(0.0, 1.0 - r2));
    out.l = t * (rad * cos(phi)) + b * (rad * sin(phi)) + n * z;
    let nl = dot(n, out.l);
    out.lpdf = log2(f32(P.m)) + log2(max(nl, 1e-30) / PI);
    out.weight = vec3<f32>(0.0);
    return out;
}

fn sample_pbr_diffuse(xi1: f32, r2: f32, n: vec3<f32>, t: vec3<f32>, b: vec3<f32>, v: vec3<f32>, base: vec3<f32>, pbr: vec2<f32>) -> AsSample {
    var out = cosine_sample(xi1, r2, n, t, b);
    let nl = dot(n, out.l);
    var h = n;
    let hv = v + out.l;
    if (dot(hv, hv) > 0.0) {
        h = normalize(hv);
    }
    let fr = fresnel_schlick(GGX_DIELECTRIC_F0, abs(dot(v, h)));
    if (nl > 0.0 && dot(n, v) > 0.0) {
        out.weight = base * ((1.0 - pbr.x) * (1.0 - fr));
    }
    return out;
}

fn sample_diffuse(xi1: f32, r2: f32, n: vec3<f32>, t: vec3<f32>, b: vec3<f32>, nv: f32) -> AsSample {
    var out = cosine_sample(xi1, r2, n, t, b);
    let nl = dot(n, out.l);
    let fv = 1.0 - pow(1.0 - 0.5 * max(nv, 0.0), 5.0);
    let fl = 1.0 - pow(1.0 - 0.5 * max(nl, 0.0), 5.0);
    out.weight = vec3<f32>(select(0.0, 28.0 / 23.0 * P.rd * (1.0 - P.rs) * fv * fl, nl > 0.0));
    return out;
}

fn sample_radiance(cube: u32, entry: u32, o: vec3<f32>, wn: vec4<f32>, x: vec3<f32>, n: vec3<f32>, s: AsSample, lod: f32, fresh: bool, seed: ptr<function, f32>) -> vec4<f32> {
    let l = s.l;
    if (ORDER == 1u && cube == INVALID) {
        var w = wn;
        if (BLEND != 4u) {
            w = blend_weights(l);
        }
        let b = blend_read(w, x, l, lod, n, true);
        if (b.w > 0.0) {
            return b;
        }
        return vec4<f32>(env_read(x, l, lod), 1.0);
    }
    var d = l;
    if (cube == P.env_cube) {
        d = env_dir(x, l);
    }
    else if (DEPTH) {
        d = depth_iterate(cube, entry, o, l, fresh, seed);
    }
    return read_dir(cube, entry, d, lod);
}

fn read_dir(cube: u32, entry: u32, d: vec3<f32>, lod: f32) -> vec4<f32> {
    if (FILTER) {
        return lookup_levels(cube, entry, d, lod);
    }
    return lookup(cube, d);
}

fn max3(w: vec3<f32>) -> f32 {
    return max(w.x, max(w.y, w.z));
}

fn sample_spec(xi1: f32, xi2: f32, n: vec3<f32>, t: vec3<f32>, b: vec3<f32>, v: vec3<f32>, nv: f32, base: vec3<f32>, pbr: vec2<f32>) -> AsSample {
    if ((TERMS & 16u) != 0u) {
        return sample_ggx(xi1, xi2, n, t, b, v, nv, base, pbr);
    }
    return sample_as(xi1, xi2, n, t, b, v, nv);
}

fn sample_diff(xi1: f32, xi2: f32, n: vec3<f32>, t: vec3<f32>, b: vec3<f32>, v: vec3<f32>, nv: f32, base: vec3<f32>, pbr: vec2<f32>) -> AsSample {
    if ((TERMS & 16u) != 0u) {
        return sample_pbr_diffuse(xi1, xi2, n, t, b, v, base, pbr);
    }
    return sample_diffuse(xi1, xi2, n, t, b, nv);
}

struct Sums {
    r: vec4<f32>,
    g: vec4<f32>,
    b: vec4<f32>,
    ok: vec4<f32>
}

fn stand_in(k: u32, cubes: vec4<u32>, entries: vec4<u32>, used: vec4<bool>, ox: vec4<f32>, oy: vec4<f32>, oz: vec4<f32>, w: vec4<f32>, s: AsSample) -> u32 {
    var best = k;
    var best_w = 0.0;
    let hidden = cubes[k] != P.env_cube && depth_hidden(cubes[k], entries[k], vec3<f32>(ox[k], oy[k], oz[k]), s.l);
    for (var j = select(4u, 0u, hidden); j < 4u; j++) {
        if (j == k || !used[j] || !(w[j] > best_w)) {
            continue;
        }
        if (depth_hidden(cubes[j], entries[j], vec3<f32>(ox[j], oy[j], oz[j]), s.l)) {
            continue;
        }
        best = j;
        best_w = w[j];
    }
    return best;
}

struct Seen {
    e: u32,
    d: vec3<f32>
}

fn searched(k: u32, cubes: vec4<u32>, used: vec4<bool>, x: vec3<f32>, n: vec3<f32>, w: vec4<f32>, s: AsSample) -> Seen {
    let p = samples[cubes[k]].xyz;
    let h = depth_search(cubes[k], x, s.l);
    if (low_hit(p, h, x, s.l, n)) {
        return Seen(4u, s.l);
    }
    var best = Seen(k, h.xyz);
    var best_w = 0.0;
    for (var j = select(4u, 0u, h.w < 0.0); j < 4u; j++) {
        if (j == k || !used[j] || !(w[j] > best_w)) {
            continue;
        }
        let q = depth_search(cubes[j], x, s.l);
        if (q.w < 0.0) {
            continue;
        }
        best = Seen(j, q.xyz);
        best_w = w[j];
    }
    return best;
}

fn accumulate(sums: ptr<function, Sums>, k: u32, cubes: vec4<u32>, entries: vec4<u32>, used: vec4<bool>, ox: vec4<f32>, oy: vec4<f32>, oz: vec4<f32>, w: vec4<f32>, wn: vec4<f32>, x: vec3<f32>, n: vec3<f32>, s: AsSample, lod: f32, fresh: ptr<function, vec4<bool>>, seeds: ptr<function, vec4<f32>>) {
    var l: vec4<f32>;
    var plain = true;
    if (ORDER == 3u && DEPTH && cubes[k] != P.env_cube) {
        let seen = searched(k, cubes, used, x, n, w, s);
        if (seen.e < 4u) {
            l = read_dir(cubes[seen.e], entries[seen.e], seen.d, lod);
            plain = false;
        }
    }
    if (plain) {
        var e = k;
        if (ORDER == 2u && DEPTH) {
            e = stand_in(k, cubes, entries, used, ox, oy, oz, w, s);
        }
        let own = e == k;
        var seed = select(0.0, (*seeds)[k], own);
        l = sample_radiance(cubes[e], entries[e], vec3<f32>(ox[e], oy[e], oz[e]), wn, x, n, s, lod, (*fresh)[k] || !own, &seed);
        (*seeds)[k] = select((*seeds)[k], seed, own);
        (*fresh)[k] = (*fresh)[k] && !own;
    }
    if (l.w == 0.0) {
        (*sums).ok[k] = 0.0;
    }
    (*sums).r[k] += l.r * s.weight.r;
    (*sums).g[k] += l.g * s.weight.g;
    (*sums).b[k] += l.b * s.weight.b;
}

fn integrate(cubes: vec4<u32>, used: vec4<bool>, j0: u32, pixel: u32, x: vec3<f32>, n: vec3<f32>, t: vec3<f32>, b: vec3<f32>, v: vec3<f32>, nv: f32, base: vec3<f32>, pbr: vec2<f32>, w: vec4<f32>) -> Sums {
    var out = Sums(vec4<f32>(0.0), vec4<f32>(0.0), vec4<f32>(0.0), vec4<f32>(1.0));
    var wn = vec4<f32>(0.0);
    if (ORDER == 1u && BLEND == 4u) {
        wn = blend_weights(n);
    }
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
    var spec_seed = vec4<f32>(0.0);
    var diff_seed = vec4<f32>(0.0);
    var spec_fresh = vec4<bool>(true);
    var diff_fresh = vec4<bool>(true);
    let rows = filter_rows();
    let spec_shared = FILTER && (TERMS & 16u) == 0u;
    for (var i = 0u; i < P.m; i++) {
        if (i % rows == 0u) {
            spec_fresh = vec4<bool>(true);
            diff_fresh = vec4<bool>(true);
        }
        var spec: AsSample;
        var diff: AsSample;
        var spec_lod = 0.0;
        var diff_lod = 0.0;
        var drawn = false;
        for (var k = 0u; k < 4u; k++) {
            if (!used[k]) {
                continue;
            }
            if (!(spec_shared && drawn)) {
                let xi = sample_xi(pixel, i, j0 + k, 0u);
                spec = sample_spec(xi.x, xi.y, n, t, b, v, nv, base, pbr);
                spec_lod = sample_lod(spec.l, spec.lpdf);
            }
            if (DIFFUSE && !IRRADIANCE && !(FILTER && drawn)) {
                let xd = sample_xi(pixel, i, j0 + k, 2u);
                diff = sample_diff(xd.x, xd.y, n, t, b, v, nv, base, pbr);
                diff_lod = sample_lod(diff.l, diff.lpdf);
            }
            drawn = true;
            if (max3(spec.weight) > 0.0) {
                accumulate(&out, k, cubes, entries, used, ox, oy, oz, w, wn, x, n, spec, spec_lod, &spec_fresh, &spec_seed);
            }
            if (DIFFUSE && !IRRADIANCE && max3(diff.weight) > 0.0) {
                accumulate(&out, k, cubes, entries, used, ox, oy, oz, w, wn, x, n, diff, diff_lod, &diff_fresh, &diff_seed);
            }
        }
    }
    return out;
}

fn estimate(s: Sums, k: u32) -> vec3<f32> {
    return vec3<f32>(s.r[k], s.g[k], s.b[k]) / f32(max(P.m, 1u));
}

fn cube_sh(cube: u32) -> array<vec3<f32>, 9> {
    var c: array<vec3<f32>, 9>;
    for (var i = 0u; i < 9u; i++) {
        c[i] = samples[P.irradiance + 9u * cube + i].xyz;
    }
    return c;
}

fn diffuse_irradiance(use_env: bool, n: vec3<f32>, nv: f32, base: vec3<f32>, pbr: vec2<f32>) -> vec3<f32> {
    var bands = SH_AS_DIFFUSE;
    if ((TERMS & 16u) != 0u) {
        bands = SH_COSINE;
    }
    var e = vec3<f32>(0.0);
    var wsum = 0.0;
    if (!use_env) {
        let w = blend_weights(n);
        for (var k = 0u; k < 4u; k++) {
            if (w[k] > 0.0 && cand.idx[k] != INVALID) {
                e += sh_convolve(cube_sh(cand.idx[k]), bands, n) * w[k];
                wsum += w[k];
            }
        }
    }
    if (wsum > 0.0) {
        e = e / wsum;
    }
    else if (P.env_cube != INVALID) {
        e = sh_convolve(cube_sh(P.env_cube), bands, n);
    }
    if ((TERMS & 16u) != 0u) {
        if (!(nv > 0.0)) {
            return vec3<f32>(0.0);
        }
        return e * base * ((1.0 - pbr.x) * (1.0 - GGX_DIELECTRIC_F0) * sh_fresnel_cosine_weight(nv));
    }
    let fv = 1.0 - pow(1.0 - 0.5 * max(nv, 0.0), 5.0);
    return e * (28.0 / 23.0 * P.rd * (1.0 - P.rs) * fv);
}

fn glossy(pixel: u32, x: vec3<f32>, n: vec3<f32>, t: vec3<f32>, v: vec3<f32>, r: vec3<f32>, base: vec3<f32>, pbr: vec2<f32>) -> vec3<f32> {
    if (SPLIT_SUM) {
        return split_sum(x, n, v, r, base, pbr);
    }
    let b = cross(n, t);
    let nv = dot(n, v);
    let use_env = SOURCE != 0u || cand.count == 0u;
    var diffuse = vec3<f32>(0.0);
    if (DIFFUSE && IRRADIANCE) {
        diffuse = diffuse_irradiance(use_env, n, nv, base, pbr);
    }
    let one = vec4<bool>(true, false, false, false);
    if (ORDER == 1u && !use_env) {
        return estimate(integrate(vec4<u32>(INVALID), one, 4u, pixel, x, n, t, b, v, nv, base, pbr, vec4<f32>(0.0)), 0u) + diffuse;
    }
    var axis = r;
    if (BLEND == 4u) {
        axis = n;
    }
    var w = vec4<f32>(0.0);
    if (!use_env) {
        w = blend_weights(axis);
    }
    var acc = vec3<f32>(0.0);
    var wsum = 0.0;
    for (var phase = select(0u, 1u, use_env); phase < 2u; phase++) {
        var cubes = cand.idx;
        var used = (w > vec4<f32>(0.0)) & (cubes != vec4<u32>(INVALID));
        var wp = w;
        if (phase == 1u) {
            if (wsum > 0.0 || P.env_cube == INVALID) {
                break;
            }
            cubes = vec4<u32>(P.env_cube);
            used = one;
            wp = vec4<f32>(1.0, 0.0, 0.0, 0.0);
        }
        let sums = integrate(cubes, used, select(0u, 4u, phase == 1u), pixel, x, n, t, b, v, nv, base, pbr, wp);
        for (var k = 0u; k < 4u; k++) {
            if (used[k] && (sums.ok[k] > 0.0 || phase == 1u)) {
                acc += estimate(sums, k) * wp[k];
                wsum += wp[k];
            }
        }
    }
    if (wsum > 0.0) {
        return acc / wsum + diffuse;
    }
    return diffuse;
}

const SEAM_LO = vec4<u32>(568629604u, 10584325u, 716296370u, 200590563u);

const SEAM_HI = vec4<u32>(32u, 1u, 26u, 59u);

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

fn slot_texel(entry: u32, c: vec3<u32>, level: u32) -> vec3<f32> {
    let at = place(entry, c.x);
    return load_texel(at.x, i32(at.y), vec2<u32>((at.z >> level) + c.y, c.z), level);
}

struct SeamTaps {
    c0: vec3<u32>,
    c1: vec3<u32>,
    c2: vec3<u32>,
    c3: vec3<u32>,
    wx: f32,
    wy: f32,
    corner: u32
}

fn seam_taps(fst: vec3<f32>, n: i32) -> SeamTaps {
    let face = u32(fst.x);
    let nf = f32(n);
    let fx = fst.y * nf - 0.5;
    let fy = fst.z * nf - 0.5;
    let x0 = i32(floor(fx));
    let y0 = i32(floor(fy));
    var t: SeamTaps;
    t.wx = fx - floor(fx);
    t.wy = fy - floor(fy);
    t.corner = 4u;
    if ((x0 < 0 || x0 + 1 >= n) && (y0 < 0 || y0 + 1 >= n)) {
        t.corner = select(0u, 1u, x0 >= 0) + select(0u, 2u, y0 >= 0);
    }
    t.c0 = seam_texel(face, x0, y0, n);
    t.c1 = seam_texel(face, x0 + 1, y0, n);
    t.c2 = seam_texel(face, x0, y0 + 1, n);
    t.c3 = seam_texel(face, x0 + 1, y0 + 1, n);
    return t;
}

fn seam_bilinear(t: SeamTaps, a0: vec3<f32>, a1: vec3<f32>, a2: vec3<f32>, a3: vec3<f32>) -> vec3<f32> {
    var t0 = a0;
    var t1 = a1;
    var t2 = a2;
    var t3 = a3;
    if (t.corner == 0u) {
        t0 = vec3<f32>(0.0);
    }
    else if (t.corner == 1u) {
        t1 = vec3<f32>(0.0);
    }
    else if (t.corner == 2u) {
        t2 = vec3<f32>(0.0);
    }
    else if (t.corner == 3u) {
        t3 = vec3<f32>(0.0);
    }
    let mean = (t0 + t1 + t2 + t3) * (1.0 / 3.0);
    if (t.corner == 0u) {
        t0 = mean;
    }
    else if (t.corner == 1u) {
        t1 = mean;
    }
    else if (t.corner == 2u) {
        t2 = mean;
    }
    else if (t.corner == 3u) {
        t3 = mean;
    }
    let top = t0 + (t1 - t0) * t.wx;
    let bottom = t2 + (t3 - t2) * t.wx;
    return top + (bottom - top) * t.wy;
}

fn seamless_level(cube: u32, entry: u32, fst: vec3<f32>, level: u32, mark: bool) -> vec4<f32> {
    let t = seam_taps(fst, i32(max(P.cube_res >> level, 1u)));
    let bits = select(1u << t.c0.x, 0u, t.corner == 0u) | select(1u << t.c1.x, 0u, t.corner == 1u) | select(1u << t.c2.x, 0u, t.corner == 2u) | select(1u << t.c3.x, 0u, t.corner == 3u);
    if (mark) {
        mark_face(cube, bits);
    }
    if ((entry & bits) != bits) {
        return vec4<f32>(0.0);
    }
    let c = seam_bilinear(t, slot_texel(entry, t.c0, level), slot_texel(entry, t.c1, level), slot_texel(entry, t.c2, level), slot_texel(entry, t.c3, level));
    return vec4<f32>(c, 1.0);
}

fn seamless_read(cube: u32, dir: vec3<f32>) -> vec3<f32> {
    return seamless_level(cube, slots[cube], face_st(dir), 0u, false).rgb;
}

fn prefiltered_texel(first: u32, c: vec3<u32>, level: u32) -> vec3<f32> {
    return textureLoad(prefiltered, vec2<u32>(c.y, c.z), i32(first + c.x), i32(level)).rgb;
}

fn prefiltered_level(first: u32, fst: vec3<f32>, level: u32) -> vec3<f32> {
    let t = seam_taps(fst, i32(max(P.cube_res >> level, 1u)));
    return seam_bilinear(t, prefiltered_texel(first, t.c0, level), prefiltered_texel(first, t.c1, level), prefiltered_texel(first, t.c2, level), prefiltered_texel(first, t.c3, level));
}

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

fn env_brdf(roughness: f32, nv: f32) -> vec2<f32> {
    let r = roughness * vec4<f32>(-1.0, -0.0275, -0.572, 0.022) + vec4<f32>(1.0, 0.0425, 1.04, -0.04);
    let a004 = min(r.x * r.x, exp2(-9.28 * nv)) * r.x + r.y;
    return vec2<f32>(-1.04, 1.04) * a004 + r.zw;
}

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

fn camera_ray(px: vec2<u32>) -> vec3<f32> {
    let w = f32(P.size.x);
    let h = f32(P.size.y);
    let aspect = w / h;
    let tan_half = P.cam_right.w;
    let sx = (2.0 * (f32(px.x) + 0.5) / w - 1.0) * aspect * tan_half;
    let sy = (1.0 - 2.0 * (f32(px.y) + 0.5) / h) * tan_half;
    let d = P.cam_forward.xyz + P.cam_right.xyz * sx + P.cam_up.xyz * sy;
    let l2 = dot(d, d);
    if (l2 > 0.0 && l2 <= 3e38) {
        return d * inverseSqrt(l2);
    }
    return P.cam_forward.xyz;
}

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

fn finite3(c: vec3<f32>) -> vec3<f32> {
    var o = c;
    for (var k = 0u; k < 3u; k++) {
        let x = c[k];
        if (!(x == x) || abs(x) > 3e38) {
            o[k] = 0.0;
        }
    }
    return o;
}

fn emissive_of(w: u32) -> vec3<f32> {
    let c = vec3<f32>(vec3<u32>((w >> 8u) & 255u, (w >> 16u) & 255u, (w >> 24u) & 255u)) / 255.0;
    return vec3<f32>(srgb_to_linear(c.x), srgb_to_linear(c.y), srgb_to_linear(c.z));
}

fn pbr_material(pid: u32) -> vec2<f32> {
    let m = patches[pid].material;
    if (P.object_material != 0u && m.z > 0.5) {
        return m.xy;
    }
    return vec2<f32>(P.metallic, P.alpha);
}

struct Surface {
    base: vec3<f32>,
    pbr: vec2<f32>,
    emission: vec3<f32>,
    occlusion: f32
}

fn surface_of(pid: u32, px: vec2<i32>) -> Surface {
    var s: Surface;
    s.base = patches[pid].color.rgb;
    s.pbr = pbr_material(pid);
    s.emission = patches[pid].emission.rgb;
    s.occlusion = 1.0;
    if (TEXTURED) {
        let m = textureLoad(gb_material, px, 0);
        let rg = unpack2x16unorm(m.x);
        let bm = unpack2x16unorm(m.y);
        let ro = unpack2x16unorm(m.z);
        if ((m.w & 1u) != 0u) {
            s.base = vec3<f32>(rg.x, rg.y, bm.x);
        }
        if ((m.w & 2u) != 0u && P.object_material != 0u && patches[pid].material.z > 0.5) {
            s.pbr = vec2<f32>(bm.y, ggx_alpha(ro.x));
        }
        if ((m.w & 8u) != 0u) {
            s.emission = s.emission * emissive_of(m.w);
        }
        if ((m.w & 16u) != 0u) {
            s.occlusion = ro.y;
        }
    }
    return s;
}

@compute @workgroup_size(8, 8, 1)
fn shade(@builtin(global_invocation_id) gid: vec3<u32>) {
    if (gid.x >= P.size.x || gid.y >= P.size.y) {
        return;
    }
    let px = vec2<i32>(i32(gid.x), i32(gid.y));
    let g0 = textureLoad(gb_position, px, 0);
    let g1 = textureLoad(gb_normal, px, 0);
    if (!(textureLoad(gb_depth, px, 0) < 1.0) || g0.w < 0.5) {
        textureStore(out_image, px, background(gid.xy));
        return;
    }
    let pid = u32(g0.w - 0.5);
    let hit = surface_hit(pid, g0.xyz, g1.z, g1.w, normalize(g0.xyz - P.camera_pos.xyz));
    let x = hit.x;
    let u = hit.u;
    let v_param = hit.v;
    let n = patch_normal(pid, u, v_param, oct_decode(g1.xy));
    candidates(pid, u, v_param, x, n);
    mark_cube = cand.idx;
    mark_bits = vec4<u32>(0u);
    mark_env = 0u;
    let v = normalize(P.camera_pos.xyz - x);
    let r = 2.0 * dot(n, v) * n - v;
    let pixel = pcg(gid.x + pcg(gid.y + pcg(P.seed)));
    let surface = surface_of(pid, px);
    let base = surface.base;
    var spec = vec3<f32>(0.0);
    if ((TERMS & 2u) != 0u) {
        spec = mirror(x, n, r);
    }
    else if ((TERMS & 4u) != 0u) {
        let t = tangent_frame(n, patch_du(pid, u, v_param));
        spec = glossy(pixel, x, n, t, v, r, base, surface.pbr);
    }
    if ((TERMS & 8u) != 0u) {
        spec *= base;
    }
    var color = spec;
    if ((TERMS & 1u) != 0u) {
        color += recon(x, n);
    }
    if ((TERMS & 16u) != 0u) {
        color = color * surface.occlusion + surface.emission;
    }
    flush_marks();
    textureStore(out_image, px, vec4<f32>(finite3(color), 1.0));
}
