// Assembled by oslf_shading::wgsl::assemble from WGSL modules (root `package::capture`).
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

fn mul32x32(a: u32, b: u32) -> vec2<u32> {
    let a0 = a & 65535u;
    let a1 = a >> 16u;
    let b0 = b & 65535u;
    let b1 = b >> 16u;
    let p00 = a0 * b0;
    let p01 = a0 * b1;
    let p10 = a1 * b0;
    let p11 = a1 * b1;
    let mid = (p00 >> 16u) + (p01 & 65535u) + (p10 & 65535u);
    return vec2<u32>((p00 & 65535u) | (mid << 16u), p11 + (p01 >> 16u) + (p10 >> 16u) + (mid >> 16u));
}

fn mul64(a: vec2<u32>, b: vec2<u32>) -> vec2<u32> {
    var r = mul32x32(a.x, b.x);
    r.y = r.y + a.x * b.y + a.y * b.x;
    return r;
}

fn add64(a: vec2<u32>, b: vec2<u32>) -> vec2<u32> {
    let lo = a.x + b.x;
    return vec2<u32>(lo, a.y + b.y + select(0u, 1u, lo < a.x));
}

fn shr64(a: vec2<u32>, n: u32) -> vec2<u32> {
    return vec2<u32>((a.x >> n) | (a.y << (32u - n)), a.y >> n);
}

fn mix64(z0: vec2<u32>) -> vec2<u32> {
    var z = z0;
    z = mul64(z ^ shr64(z, 30u), vec2<u32>(484763065u, 3210233709u));
    z = mul64(z ^ shr64(z, 27u), vec2<u32>(321982955u, 2496678331u));
    return z ^ shr64(z, 31u);
}

const GOLDEN: vec2<u32> = vec2<u32>(2135587861u, 2654435769u);

fn hash4(a: vec2<u32>, b: vec2<u32>, c: vec2<u32>, d: vec2<u32>) -> vec2<u32> {
    var h = mix64(GOLDEN ^ vec2<u32>(4u, 0u));
    h = mix64(h ^ mix64(add64(a, GOLDEN)));
    h = mix64(h ^ mix64(add64(b, GOLDEN)));
    h = mix64(h ^ mix64(add64(c, GOLDEN)));
    h = mix64(h ^ mix64(add64(d, GOLDEN)));
    return h;
}

struct Rng {
    state: vec2<u32>,
    inc: vec2<u32>
}

const PCG_MULT: vec2<u32> = vec2<u32>(1284865837u, 1481765933u);

fn rng_next_u32(rng: ptr<function, Rng>) -> u32 {
    let old = (*rng).state;
    (*rng).state = add64(mul64(old, PCG_MULT), (*rng).inc);
    let xorshifted = shr64(shr64(old, 18u) ^ old, 27u).x;
    let rot = old.y >> 27u;
    return (xorshifted >> rot) | (xorshifted << ((32u - rot) & 31u));
}

fn rng_new(seed: vec2<u32>, stream: vec2<u32>) -> Rng {
    var rng = Rng(vec2<u32>(0u, 0u), vec2<u32>((stream.x << 1u) | 1u, (stream.y << 1u) | (stream.x >> 31u)));
    rng_next_u32(&rng);
    rng.state = add64(rng.state, seed);
    rng_next_u32(&rng);
    return rng;
}

fn rng_f32(rng: ptr<function, Rng>) -> f32 {
    return f32(rng_next_u32(rng) >> 8u) * (1.0 / 16777216.0);
}

fn rng_vec2(rng: ptr<function, Rng>) -> vec2<f32> {
    let x = rng_f32(rng);
    let y = rng_f32(rng);
    return vec2<f32>(x, y);
}

fn sample_uniform_disk_concentric(u: vec2<f32>) -> vec2<f32> {
    let o = 2.0 * u - vec2<f32>(1.0);
    if o.x == 0.0 && o.y == 0.0 {
        return vec2<f32>(0.0);
    }
    var r = o.y;
    var theta = FRAC_PI_2 - FRAC_PI_4 * (o.x / o.y);
    if abs(o.x) > abs(o.y) {
        r = o.x;
        theta = FRAC_PI_4 * (o.y / o.x);
    }
    return r * vec2<f32>(cos(theta), sin(theta));
}

fn sample_cosine_hemisphere(u: vec2<f32>) -> vec3<f32> {
    let d = sample_uniform_disk_concentric(u);
    return vec3<f32>(d, sqrt(max(1.0 - dot(d, d), 0.0)));
}

fn cosine_hemisphere_pdf(cos_theta: f32) -> f32 {
    if cos_theta > 0.0 {
        return cos_theta * FRAC_1_PI;
    }
    return 0.0;
}

fn sample_uniform_sphere(u: vec2<f32>) -> vec3<f32> {
    let z = 1.0 - 2.0 * u.x;
    let r = sqrt(max(1.0 - z * z, 0.0));
    let phi = 2.0 * PI * u.y;
    return vec3<f32>(r * cos(phi), r * sin(phi), z);
}

struct Frame {
    x: vec3<f32>,
    y: vec3<f32>,
    z: vec3<f32>
}

fn frame_from_normal(n_in: vec3<f32>) -> Frame {
    var n = vec3<f32>(0.0, 0.0, 1.0);
    let l = length(n_in);
    if l > 0.0 && abs(l) <= 3.40282347e38 && abs(1.0 / l) <= 3.40282347e38 {
        n = n_in / l;
    }
    let sign = select(-1.0, 1.0, n.z >= 0.0);
    let a = -1.0 / (sign + n.z);
    let b = n.x * n.y * a;
    return Frame(vec3<f32>(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x), vec3<f32>(b, sign + n.y * n.y * a, -n.y), n);
}

fn to_world(f: Frame, v: vec3<f32>) -> vec3<f32> {
    return f.x * v.x + f.y * v.y + f.z * v.z;
}

fn to_local(f: Frame, v: vec3<f32>) -> vec3<f32> {
    return vec3<f32>(dot(v, f.x), dot(v, f.y), dot(v, f.z));
}

struct Params {
    resolution: u32,
    strata: u32,
    max_bounces: u32,
    flags: u32,
    seed: vec2<u32>,
    texels: u32,
    row_invocations: u32,
    first: u32,
    _pad1: u32,
    _pad0: vec2<u32>,
    env_size: vec4<u32>,
    env_tables: vec4<u32>,
    env_rotation: vec4<f32>,
    env_constant: vec4<f32>,
    perez_y: vec4<f32>,
    perez_x: vec4<f32>,
    perez_yc: vec4<f32>,
    perez_e: vec4<f32>,
    norm: vec4<f32>,
    model_sun: vec4<f32>,
    ground: vec4<f32>,
    rounds: u32,
    target_noise: f32,
    _pad2: vec2<u32>
}

struct Node {
    p: vec3<f32>,
    e_imask: u32,
    child_base: u32,
    primitive_base: u32,
    child_meta: vec2<u32>,
    x: vec4<u32>,
    y: vec4<u32>,
    z: vec4<u32>
}

struct Tri {
    v0: vec4<f32>,
    v1: vec4<f32>,
    v2: vec4<f32>,
    plane: vec4<f32>
}

struct TriAttr {
    n0: vec3<f32>,
    material: u32,
    n1: vec3<f32>,
    object: u32,
    n2: vec3<f32>,
    global: u32,
    gn: vec3<f32>,
    _pad0: u32,
    uv01: vec4<f32>,
    uv2: vec2<f32>,
    _pad1: vec2<u32>
}

struct Tex {
    kind: u32,
    width: u32,
    height: u32,
    offset: u32,
    a: vec3<f32>,
    scale: f32,
    b: vec3<f32>,
    _pad: f32
}

struct Mat {
    albedo: Tex,
    mr_texture: Tex,
    model: u32,
    metallic: f32,
    roughness: f32,
    _pad: u32,
    emission: vec3<f32>,
    has_mr_texture: u32
}

struct Light {
    position: vec3<f32>,
    kind: u32,
    direction: vec3<f32>,
    inner: f32,
    power: vec3<f32>,
    outer: f32,
    angular_radius: f32,
    _pad0: u32,
    _pad1: u32,
    _pad2: u32
}

struct Job {
    origin: vec3<f32>,
    index: u32,
    sees_objects: u32,
    _pad: array<u32, 3>
}

struct TexelOut {
    radiance: vec3<f32>,
    distance: f32,
    lum_sum: f32,
    lum_sq: f32,
    closest: u32,
    shadow_hit: u32,
    nodes: u32,
    tris: u32,
    samples: u32,
    _pad: u32
}

struct TraceRay {
    origin: vec3<f32>,
    t_max: f32,
    dir: vec3<f32>,
    flags: u32
}

struct TraceHit {
    t: f32,
    triangle: u32,
    b1: f32,
    b2: f32,
    nodes: u32,
    tris: u32,
    _pad: vec2<u32>
}

struct PreviewCamera {
    position: vec3<f32>,
    width: u32,
    right: vec3<f32>,
    height: u32,
    up: vec3<f32>,
    tan_half: f32,
    forward: vec3<f32>,
    spp: u32
}

const F32_MAX: f32 = 3.40282347e38;

const STACK: u32 = 32u;

fn gamma(n: f32) -> f32 {
    let e = 5.9604645e-8;
    return n * e / (1.0 - n * e);
}

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
    valid: bool
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
    }
    else if a.y > a.z {
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
    }
    else if kz == 1u {
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
    hit: bool
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

@group(0) @binding(9)
var<storage, read_write> out: array<TexelOut>;

const SLAB_PAD: f32 = 1e-6;

fn octant_inv4(d: vec3<f32>) -> u32 {
    return select(67372036u, 0u, d.x < 0.0) | select(33686018u, 0u, d.y < 0.0) | select(16843009u, 0u, d.z < 0.0);
}

fn intersect_node(n: Node, r: PreparedRay, t_max: f32, oct: u32) -> u32 {
    let e = vec3<u32>(n.e_imask, n.e_imask >> 8u, n.e_imask >> 16u) & vec3<u32>(255u);
    let a = bitcast<vec3<f32>>(e << vec3<u32>(23u)) * r.inv_dir;
    let o = (n.p - r.origin) * r.inv_dir;
    let pad = (abs(o) + abs(a) * 255.0) * SLAB_PAD;
    let nx = select(n.x.xy, n.x.zw, r.dir.x < 0.0);
    let fx = select(n.x.zw, n.x.xy, r.dir.x < 0.0);
    let ny = select(n.y.xy, n.y.zw, r.dir.y < 0.0);
    let fy = select(n.y.zw, n.y.xy, r.dir.y < 0.0);
    let nz = select(n.z.xy, n.z.zw, r.dir.z < 0.0);
    let fz = select(n.z.zw, n.z.xy, r.dir.z < 0.0);
    let octant = oct & 255u;
    var mask = 0u;
    for (var c = 0u; c < 8u; c++) {
        let w = c >> 2u;
        let s = (c & 3u) * 8u;
        let m = extractBits(n.child_meta[w], s, 8u);
        if m == 0u {
            continue;
        }
        let qn = vec3<f32>(vec3<u32>(extractBits(nx[w], s, 8u), extractBits(ny[w], s, 8u), extractBits(nz[w], s, 8u)));
        let qf = vec3<f32>(vec3<u32>(extractBits(fx[w], s, 8u), extractBits(fy[w], s, 8u), extractBits(fz[w], s, 8u)));
        let t0 = qn * a + o - pad;
        let t1 = qf * a + o + pad;
        let tmin = max(max(t0.x, t0.y), max(t0.z, 0.0));
        let tmax = min(min(t1.x, t1.y), min(t1.z, t_max));
        if tmin <= tmax {
            let inner = (m & (m << 1u) & 16u) != 0u;
            let bit_index = (m ^ select(0u, octant, inner)) & 31u;
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
    nodes: u32,
    tris: u32
}

fn included(tri: Tri, objects: bool) -> bool {
    return objects || tri.v1.w != 0.0;
}

var<private> stack: array<vec2<u32>, STACK>;

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
    var group = vec2<u32>(0u, 2147483648u);
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
        if (group.y & 4278190080u) != 0u {
            let bits = group.y;
            let k = firstLeadingBit(bits);
            group.y &= ~(1u << k);
            if (group.y & 4278190080u) != 0u {
                stack[top] = group;
                top += 1u;
            }
            let slot = (k - 24u) ^ (oct & 255u);
            let index = group.x + countOneBits(bits & ~(4294967295u << slot));
            let n = nodes[index];
            best.nodes += 1u;
            let hits = intersect_node(n, r, best.t, oct);
            group = vec2<u32>(n.child_base, (hits & 4278190080u) | (n.e_imask >> 24u));
            prims = vec2<u32>(n.primitive_base, hits & 16777215u);
        }
        else {
            group = vec2<u32>(0u);
        }
        if prims.y == 0u && (group.y & 4278190080u) == 0u {
            if top == 0u {
                break;
            }
            top -= 1u;
            group = stack[top];
        }
    }
    return best;
}

const ONE_MINUS_EPSILON: f32 = 0.99999994;

struct SurfaceHit {
    t: f32,
    position: vec3<f32>,
    geometric_normal: vec3<f32>,
    shading_normal: vec3<f32>,
    uv: vec2<f32>,
    material: u32,
    extent: f32
}

fn surface_hit(h: Hit) -> SurfaceHit {
    let tri = tris[h.slot];
    let a = attrs[h.slot];
    var s: SurfaceHit;
    s.t = h.t;
    let gn = a.gn;
    var sn = a.n0 * h.b.x + a.n1 * h.b.y + a.n2 * h.b.z;
    let len = length(sn);
    if len > 0.0 && len <= F32_MAX {
        sn = sn / len;
    }
    else {
        sn = gn;
    }
    if dot(sn, gn) < 0.0 {
        sn = -sn;
    }
    s.position = tri.v0.xyz * h.b.x + tri.v1.xyz * h.b.y + tri.v2.xyz * h.b.z;
    s.geometric_normal = gn;
    s.shading_normal = sn;
    s.uv = a.uv01.xy * h.b.x + a.uv01.zw * h.b.y + a.uv2 * h.b.z;
    s.material = a.material;
    s.extent = tri.v0.w;
    return s;
}

fn finite(x: f32) -> bool {
    return abs(x) <= F32_MAX;
}

fn clamp01(x: f32) -> f32 {
    if finite(x) {
        return clamp(x, 0.0, 1.0);
    }
    return 0.0;
}

fn texel_rgb(i: u32) -> vec3<f32> {
    return vec3<f32>(texels[3u * i], texels[3u * i + 1u], texels[3u * i + 2u]);
}

fn wrap(i: i32, n: u32) -> u32 {
    let m = i32(n);
    return u32(select(select(i, i - m, i >= m), i + m, i < 0));
}

fn texture_eval(t: Tex, uv_in: vec2<f32>) -> vec3<f32> {
    var uv = uv_in;
    if !(finite(uv.x) && finite(uv.y)) {
        uv = vec2<f32>(0.0);
    }
    if t.kind == TEX_CONSTANT || TEXTURE_KINDS == (1u << TEX_CONSTANT) {
        return t.a;
    }
    if present(TEXTURE_KINDS, TEX_CHECKER) && t.kind == TEX_CHECKER {
        let s = select(1.0, t.scale, finite(t.scale));
        let sum = floor(uv.x * s) + floor(uv.y * s);
        if sum - 2.0 * floor(0.5 * sum) == 0.0 {
            return t.a;
        }
        return t.b;
    }
    if !present(TEXTURE_KINDS, TEX_IMAGE) {
        return t.a;
    }
    let u = uv.x - floor(uv.x);
    let v = uv.y - floor(uv.y);
    let x = u * f32(t.width) - 0.5;
    let y = (1.0 - v) * f32(t.height) - 0.5;
    let x0 = floor(x);
    let y0 = floor(y);
    let fx = clamp(x - x0, 0.0, 1.0);
    let fy = clamp(y - y0, 0.0, 1.0);
    let ix = i32(x0);
    let iy = i32(y0);
    let c0 = wrap(ix, t.width);
    let c1 = wrap(ix + 1, t.width);
    let r0 = wrap(iy, t.height) * t.width + t.offset;
    let r1 = wrap(iy + 1, t.height) * t.width + t.offset;
    let top = mix(texel_rgb(r0 + c0), texel_rgb(r0 + c1), fx);
    let bottom = mix(texel_rgb(r1 + c0), texel_rgb(r1 + c1), fx);
    return mix(top, bottom, fy);
}

fn present(kinds: u32, kind: u32) -> bool {
    return (kinds & (1u << kind)) != 0u;
}

const TEX_CONSTANT: u32 = 0u;

const TEX_CHECKER: u32 = 1u;

const TEX_IMAGE: u32 = 2u;

const MODEL_LAMBERTIAN: u32 = 0u;

const MODEL_METALLIC_ROUGHNESS: u32 = 1u;

fn material_albedo(m: Mat, uv: vec2<f32>) -> vec3<f32> {
    let a = texture_eval(m.albedo, uv);
    return vec3<f32>(clamp01(a.x), clamp01(a.y), clamp01(a.z));
}

struct LightSample {
    dir: vec3<f32>,
    distance: f32,
    irradiance: vec3<f32>,
    valid: bool
}

const LIGHT_POINT: u32 = 0u;

const LIGHT_SPOT: u32 = 1u;

const LIGHT_SUN: u32 = 2u;

fn finite_vec(v: vec3<f32>) -> bool {
    return finite3(v);
}

fn spot_falloff(cos_psi: f32, inner: f32, outer: f32) -> f32 {
    let cos_outer = cos(outer);
    let cos_inner = cos(inner);
    let scale = 1.0 / max(cos_inner - cos_outer, 0.001);
    let t = clamp((cos_psi - cos_outer) * scale, 0.0, 1.0);
    if finite(t) {
        return t * t;
    }
    return 0.0;
}

fn safe_normalize(v: vec3<f32>) -> vec3<f32> {
    let l = length(v);
    if l > 0.0 && finite(l) && finite(1.0 / l) {
        return v / l;
    }
    return vec3<f32>(0.0);
}

fn sample_li(l: Light, p: vec3<f32>) -> LightSample {
    var s: LightSample;
    s.valid = false;
    if present(LIGHT_KINDS, LIGHT_SUN) && l.kind == LIGHT_SUN {
        let dir = safe_normalize(l.direction);
        if all(dir == vec3<f32>(0.0)) || all(l.power == vec3<f32>(0.0)) || !finite_vec(l.power) {
            return s;
        }
        s.dir = dir;
        s.distance = F32_MAX;
        s.irradiance = l.power;
        s.valid = true;
        return s;
    }
    if !present(LIGHT_KINDS, LIGHT_POINT) && !present(LIGHT_KINDS, LIGHT_SPOT) {
        return s;
    }
    let d = l.position - p;
    let r2 = dot(d, d);
    if !(r2 > 0.0 && finite(r2)) {
        return s;
    }
    let r = sqrt(r2);
    let dir = d / r;
    var e = l.power / r2;
    if present(LIGHT_KINDS, LIGHT_SPOT) && l.kind == LIGHT_SPOT {
        let axis = safe_normalize(l.direction);
        if all(axis == vec3<f32>(0.0)) {
            return s;
        }
        let a = spot_falloff(-dot(dir, axis), l.inner, l.outer);
        e = l.power * (a / r2);
    }
    if !finite_vec(e) || all(e == vec3<f32>(0.0)) {
        return s;
    }
    s.dir = dir;
    s.distance = r;
    s.irradiance = e;
    s.valid = true;
    return s;
}

fn disc_radiance(l: Light, dir: vec3<f32>) -> vec3<f32> {
    if !present(LIGHT_KINDS, LIGHT_SUN) || l.kind != LIGHT_SUN {
        return vec3<f32>(0.0);
    }
    let s = safe_normalize(l.direction);
    let a = l.angular_radius;
    if all(s == vec3<f32>(0.0)) || !(a > 0.0 && a < 0.5 * PI) || dot(dir, s) < cos(a) {
        return vec3<f32>(0.0);
    }
    let sin_a = sin(a);
    let radiance = l.power / (PI * sin_a * sin_a);
    if finite_vec(radiance) {
        return radiance;
    }
    return vec3<f32>(0.0);
}

const ENV_CONSTANT: u32 = 0u;

const ENV_LAT_LONG: u32 = 1u;

const ENV_SKY: u32 = 2u;

fn perez(c: vec4<f32>, e: f32, cos_theta_in: f32, gamma_angle: f32) -> f32 {
    let cos_theta = max(cos_theta_in, 0.01);
    let cos_gamma = cos(gamma_angle);
    return (1.0 + c.x * exp(c.y / cos_theta)) * (1.0 + c.z * exp(c.w * gamma_angle) + e * cos_gamma * cos_gamma);
}

fn eval_sky(dir: vec3<f32>) -> vec3<f32> {
    let cos_theta = clamp(dir.z, 0.0, 1.0);
    let g = acos(clamp(dot(dir, params.model_sun.xyz), -1.0, 1.0));
    let big_y = params.norm.x * perez(params.perez_y, params.perez_e.x, cos_theta, g);
    let x = params.norm.y * perez(params.perez_x, params.perez_e.y, cos_theta, g);
    let y = params.norm.z * perez(params.perez_yc, params.perez_e.z, cos_theta, g);
    if !(y > 1e-6 && big_y > 0.0) {
        return vec3<f32>(0.0);
    }
    let cx = x / y * big_y;
    let cz = (1.0 - x - y) / y * big_y;
    let r = 3.2404542 * cx - 1.5371385 * big_y - 0.4985314 * cz;
    let gr = -0.969266 * cx + 1.8760108 * big_y + 0.041556 * cz;
    let b = 0.0556434 * cx - 0.2040259 * big_y + 1.0572252 * cz;
    let c = max(vec3<f32>(r, gr, b), vec3<f32>(0.0));
    if finite_vec(c) {
        return c;
    }
    return vec3<f32>(0.0);
}

fn lat_long_uv(dir: vec3<f32>) -> vec3<f32> {
    var d = safe_normalize(dir);
    if all(d == vec3<f32>(0.0)) {
        d = vec3<f32>(0.0, 0.0, 1.0);
    }
    let c = params.env_rotation.x;
    let s = params.env_rotation.y;
    let m = vec3<f32>(c * d.x + s * d.y, -s * d.x + c * d.y, d.z);
    var u = 0.5 + atan2(m.y, m.x) * (0.5 * FRAC_1_PI);
    u = u - floor(u);
    let v = acos(clamp(m.z, -1.0, 1.0)) * FRAC_1_PI;
    let uv = clamp(vec2<f32>(u, v), vec2<f32>(0.0), vec2<f32>(ONE_MINUS_EPSILON));
    return vec3<f32>(uv, length(m.xy));
}

fn environment_eval(dir: vec3<f32>) -> vec3<f32> {
    if ENV_KIND == ENV_CONSTANT {
        return params.env_constant.xyz;
    }
    if ENV_KIND == ENV_LAT_LONG {
        let uv = lat_long_uv(dir).xy;
        let w = params.env_size.x;
        let h = params.env_size.y;
        let x = min(u32(uv.x * f32(w)), w - 1u);
        let y = min(u32(uv.y * f32(h)), h - 1u);
        return texel_rgb(params.env_size.z + y * w + x);
    }
    let d = safe_normalize(dir);
    if all(d == vec3<f32>(0.0)) {
        return vec3<f32>(0.0);
    }
    if d.z >= 0.0 {
        return eval_sky(d);
    }
    return params.ground.xyz;
}

fn sample_table(base: u32, n: u32, u_in: f32) -> vec3<f32> {
    var u = 0.0;
    if finite(u_in) {
        u = clamp(u_in, 0.0, ONE_MINUS_EPSILON);
    }
    var lo = 0u;
    var hi = n + 1u;
    while lo < hi {
        let mid = (lo + hi) / 2u;
        if env_tables[base + mid].x <= u {
            lo = mid + 1u;
        }
        else {
            hi = mid;
        }
    }
    let i = min(max(lo, 1u) - 1u, n - 1u);
    let c = env_tables[base + i];
    let width = env_tables[base + i + 1u].x - c.x;
    var du = 0.0;
    if width > 0.0 {
        du = clamp((u - c.x) / width, 0.0, ONE_MINUS_EPSILON);
    }
    let x = min((f32(i) + du) / f32(n), ONE_MINUS_EPSILON);
    return vec3<f32>(x, c.y, f32(i));
}

struct EnvSample {
    dir: vec3<f32>,
    pdf: f32
}

fn sample_environment(u: vec2<f32>) -> EnvSample {
    if ENV_KIND == ENV_CONSTANT {
        return EnvSample(sample_uniform_sphere(u), 0.25 * FRAC_1_PI);
    }
    let w = params.env_tables.x;
    let h = params.env_tables.y;
    let ys = sample_table(0u, h, u.y);
    let row = u32(ys.z);
    let xs = sample_table(h + 1u + row * (w + 1u), w, u.x);
    let pdf_uv = xs.y * ys.y;
    let theta = ys.x * PI;
    let phi = (xs.x - 0.5) * 2.0 * PI;
    let sin_theta = sin(theta);
    let m = vec3<f32>(sin_theta * cos(phi), sin_theta * sin(phi), cos(theta));
    let c = params.env_rotation.x;
    let s = params.env_rotation.y;
    let dir = vec3<f32>(c * m.x - s * m.y, s * m.x + c * m.y, m.z);
    let denom = 2.0 * PI * PI * sin_theta;
    if denom > 0.0 && pdf_uv > 0.0 {
        let pdf = pdf_uv / denom;
        if finite(pdf) {
            return EnvSample(dir, pdf);
        }
    }
    return EnvSample(dir, 0.0);
}

fn environment_pdf(dir: vec3<f32>) -> f32 {
    if ENV_KIND == ENV_CONSTANT {
        return 0.25 * FRAC_1_PI;
    }
    let uvs = lat_long_uv(dir);
    let denom = 2.0 * PI * PI * uvs.z;
    if denom <= 0.0 {
        return 0.0;
    }
    let w = params.env_tables.x;
    let h = params.env_tables.y;
    let row = min(u32(uvs.y * f32(h)), h - 1u);
    let column = min(u32(uvs.x * f32(w)), w - 1u);
    let p = env_tables[row].y * env_tables[h + 1u + row * (w + 1u) + column].y;
    let pdf = p / denom;
    if finite(pdf) {
        return pdf;
    }
    return 0.0;
}

const OFFSET_RELATIVE: f32 = 1.9073486e-6;

const RUSSIAN_ROULETTE_START: u32 = 3u;

fn power_heuristic(pdf_a: f32, pdf_b: f32) -> f32 {
    let a = pdf_a * pdf_a;
    let b = pdf_b * pdf_b;
    let s = a + b;
    if s > 0.0 && finite(s) {
        return a / s;
    }
    if pdf_a > F32_MAX {
        return 1.0;
    }
    return 0.0;
}

struct Lobe {
    model: u32,
    albedo: vec3<f32>,
    metallic: f32,
    roughness: f32
}

fn mr_alpha(l: Lobe) -> f32 {
    return ggx_alpha(l.roughness);
}

fn mr_eval(l: Lobe, n: vec3<f32>, wo: vec3<f32>, wi: vec3<f32>) -> vec3<f32> {
    let nv = dot(n, wo);
    let nl = dot(n, wi);
    if nv <= 0.0 || nl <= 0.0 {
        return vec3<f32>(0.0);
    }
    let h = safe_normalize(wo + wi);
    if all(h == vec3<f32>(0.0)) {
        return vec3<f32>(0.0);
    }
    let alpha = mr_alpha(l);
    let a2 = alpha * alpha;
    let vh = abs(dot(wo, h));
    let specular = ggx_visibility(a2, nl, nv) * ggx_distribution_at(a2, n, h);
    let k5 = fresnel_schlick_weight(vh);
    let c = l.albedo;
    let metal = specular * (c + (vec3<f32>(1.0) - c) * k5);
    let fr = fresnel_schlick(GGX_DIELECTRIC_F0, vh);
    let dielectric = c * FRAC_1_PI * (1.0 - fr) + vec3<f32>(specular * fr);
    return mix(dielectric, metal, l.metallic);
}

fn mr_pdf(l: Lobe, n: vec3<f32>, wo: vec3<f32>, wi: vec3<f32>) -> f32 {
    let nv = dot(n, wo);
    let nl = dot(n, wi);
    if nv <= 0.0 || nl <= 0.0 {
        return 0.0;
    }
    let h = safe_normalize(wo + wi);
    if all(h == vec3<f32>(0.0)) {
        return 0.0;
    }
    let alpha = mr_alpha(l);
    let a2 = alpha * alpha;
    let specular = ggx_smith_g1(a2, nv) * ggx_distribution_at(a2, n, h) / (4.0 * nv);
    let p = 0.5 + 0.5 * l.metallic;
    return p * specular + (1.0 - p) * cosine_hemisphere_pdf(nl);
}

fn is_metallic_roughness(model: u32) -> bool {
    if !present(MATERIAL_MODELS, MODEL_LAMBERTIAN) {
        return true;
    }
    return present(MATERIAL_MODELS, MODEL_METALLIC_ROUGHNESS) && model == MODEL_METALLIC_ROUGHNESS;
}

fn lobe_at(m: Mat, uv: vec2<f32>, valid: ptr<function, bool>) -> Lobe {
    var l: Lobe;
    l.model = m.model;
    l.albedo = material_albedo(m, uv);
    l.metallic = m.metallic;
    l.roughness = m.roughness;
    if is_metallic_roughness(m.model) {
        if MR_TEXTURES && m.has_mr_texture != 0u {
            let c = texture_eval(m.mr_texture, uv);
            l.metallic = clamp01(c.z);
            l.roughness = clamp01(c.y);
        }
        *valid = true;
    }
    else {
        *valid = any(l.albedo != vec3<f32>(0.0));
    }
    return l;
}

fn lobe_f(l: Lobe, ns: vec3<f32>, wo: vec3<f32>, wi: vec3<f32>) -> vec3<f32> {
    if is_metallic_roughness(l.model) {
        return mr_eval(l, ns, wo, wi);
    }
    return l.albedo * FRAC_1_PI;
}

fn lobe_pdf(l: Lobe, ns: vec3<f32>, wo: vec3<f32>, wi: vec3<f32>, cos_theta: f32) -> f32 {
    if is_metallic_roughness(l.model) {
        return mr_pdf(l, ns, wo, wi);
    }
    return cosine_hemisphere_pdf(cos_theta);
}

struct BsdfSample {
    wi: vec3<f32>,
    weight: vec3<f32>,
    pdf: f32,
    valid: bool
}

fn lobe_sample(l: Lobe, ns: vec3<f32>, wo: vec3<f32>, rng: ptr<function, Rng>) -> BsdfSample {
    var s: BsdfSample;
    s.valid = false;
    if !is_metallic_roughness(l.model) {
        let wi = to_world(frame_from_normal(ns), sample_cosine_hemisphere(rng_vec2(rng)));
        s.wi = wi;
        s.weight = l.albedo;
        s.pdf = cosine_hemisphere_pdf(dot(ns, wi));
        s.valid = true;
        return s;
    }
    let choice = rng_f32(rng);
    let u = rng_vec2(rng);
    let frame = frame_from_normal(ns);
    let v = to_local(frame, wo);
    if v.z <= 0.0 {
        return s;
    }
    var wi: vec3<f32>;
    if choice < 0.5 + 0.5 * l.metallic {
        let m = to_world(frame, ggx_sample_visible_normal(v, mr_alpha(l), u.x, u.y));
        wi = safe_normalize(2.0 * dot(wo, m) * m - wo);
        if all(wi == vec3<f32>(0.0)) {
            return s;
        }
    }
    else {
        wi = to_world(frame, sample_cosine_hemisphere(u));
    }
    let pdf = mr_pdf(l, ns, wo, wi);
    let nl = dot(ns, wi);
    if !(pdf > 0.0 && finite(pdf) && nl > 0.0) {
        return s;
    }
    let weight = mr_eval(l, ns, wo, wi) * (nl / pdf);
    if !finite_vec(weight) {
        return s;
    }
    s.wi = wi;
    s.weight = weight;
    s.pdf = pdf;
    s.valid = true;
    return s;
}

fn offset_origin(p: vec3<f32>, n: vec3<f32>, extent: f32) -> vec3<f32> {
    let delta = OFFSET_RELATIVE * max(extent, max(max(abs(p.x), abs(p.y)), abs(p.z)));
    return p + n * delta;
}

fn finite_or_zero(v: vec3<f32>) -> vec3<f32> {
    if finite_vec(v) {
        return v;
    }
    return vec3<f32>(0.0);
}

struct Counts {
    closest: u32,
    shadow: u32,
    nodes: u32,
    tris: u32
}

fn tally(h: Hit, counts: ptr<function, Counts>) {
    (*counts).nodes += h.nodes;
    (*counts).tris += h.tris;
}

fn occluded(o: vec3<f32>, d: vec3<f32>, t_max: f32, objects: bool, counts: ptr<function, Counts>) -> bool {
    (*counts).shadow += 1u;
    let h = traverse(o, d, t_max, objects, true);
    tally(h, counts);
    return h.found;
}

fn closest(o: vec3<f32>, d: vec3<f32>, objects: bool, counts: ptr<function, Counts>) -> Hit {
    (*counts).closest += 1u;
    let h = traverse(o, d, F32_MAX, objects, false);
    tally(h, counts);
    return h;
}

fn env_active() -> bool {
    return ENV_ACTIVE;
}

fn escaped(wi: vec3<f32>, pdf: f32, throughput: vec3<f32>) -> vec3<f32> {
    return throughput * environment_eval(wi) * power_heuristic(pdf, environment_pdf(wi));
}

fn last_sample(origin: vec3<f32>, wi: vec3<f32>, pdf: f32, throughput: vec3<f32>, emitters: bool, objects: bool, counts: ptr<function, Counts>) -> vec3<f32> {
    if emitters {
        let h = closest(origin, wi, objects, counts);
        if h.found {
            let mi = attrs[h.slot].material;
            if mi < arrayLength(&materials) {
                return throughput * materials[mi].emission;
            }
            return vec3<f32>(0.0);
        }
        if env_active() {
            return escaped(wi, pdf, throughput);
        }
        return vec3<f32>(0.0);
    }
    if occluded(origin, wi, F32_MAX, objects, counts) {
        return vec3<f32>(0.0);
    }
    return escaped(wi, pdf, throughput);
}

fn oriented_normals(hit: SurfaceHit, incoming: vec3<f32>) -> array<vec3<f32>, 2> {
    var ng = safe_normalize(hit.geometric_normal);
    if all(ng == vec3<f32>(0.0)) {
        ng = -incoming;
    }
    if dot(ng, incoming) > 0.0 {
        ng = -ng;
    }
    var ns = safe_normalize(hit.shading_normal);
    if all(ns == vec3<f32>(0.0)) {
        ns = ng;
    }
    if dot(ns, ng) < 0.0 {
        ns = -ns;
    }
    return array<vec3<f32>, 2>(ng, ns);
}

fn russian_roulette(throughput: ptr<function, vec3<f32>>, rng: ptr<function, Rng>) -> bool {
    let q = min(max(max((*throughput).x, (*throughput).y), (*throughput).z), 0.95);
    if !(q > 0.0) || rng_f32(rng) >= q {
        return false;
    }
    *throughput = *throughput / q;
    return true;
}

struct Path {
    radiance: vec3<f32>,
    throughput: vec3<f32>,
    hit: SurfaceHit,
    incoming: vec3<f32>,
    bounce: u32,
    origin: vec3<f32>,
    wi: vec3<f32>,
    pdf: f32
}

fn path_start(first: SurfaceHit, incoming: vec3<f32>) -> Path {
    var p: Path;
    p.radiance = vec3<f32>(0.0);
    p.throughput = vec3<f32>(1.0);
    p.hit = first;
    p.incoming = incoming;
    p.bounce = 0u;
    return p;
}

fn path_vertex(path: ptr<function, Path>, objects: bool, rng: ptr<function, Rng>, counts: ptr<function, Counts>) -> bool {
    let env_on = env_active();
    let emitters = EMITTERS;
    let hit = (*path).hit;
    let normals = oriented_normals(hit, (*path).incoming);
    let ng = normals[0];
    let ns = normals[1];
    let wo = -(*path).incoming;
    if hit.material >= arrayLength(&materials) {
        return false;
    }
    let m = materials[hit.material];
    let throughput = (*path).throughput;
    (*path).radiance += throughput * m.emission;
    var valid = false;
    let lobe = lobe_at(m, hit.uv, &valid);
    if !valid {
        return false;
    }
    let p = hit.position;
    let origin = offset_origin(p, ng, hit.extent);
    for (var i = 0u; i < LIGHT_COUNT; i++) {
        let ls = sample_li(lights[i], p);
        if !ls.valid {
            continue;
        }
        let c = dot(ns, ls.dir);
        if c <= 0.0 || dot(ng, ls.dir) <= 0.0 {
            continue;
        }
        var t_max = F32_MAX;
        if ls.distance != F32_MAX {
            t_max = ls.distance * (1.0 - 0.0001);
        }
        if !occluded(origin, ls.dir, t_max, objects, counts) {
            (*path).radiance += throughput * lobe_f(lobe, ns, wo, ls.dir) * ls.irradiance * c;
        }
    }
    if env_on {
        let es = sample_environment(rng_vec2(rng));
        let c = dot(ns, es.dir);
        if es.pdf > 0.0 && c > 0.0 && dot(ng, es.dir) > 0.0 {
            if !occluded(origin, es.dir, F32_MAX, objects, counts) {
                let le = environment_eval(es.dir);
                let w = power_heuristic(es.pdf, lobe_pdf(lobe, ns, wo, es.dir, c));
                (*path).radiance += throughput * lobe_f(lobe, ns, wo, es.dir) * le * (c * w / es.pdf);
            }
        }
    }
    let gather_next = (*path).bounce < params.max_bounces;
    if !env_on && !gather_next && !emitters {
        return false;
    }
    let bs = lobe_sample(lobe, ns, wo, rng);
    if !bs.valid {
        return false;
    }
    if bs.pdf <= 0.0 || dot(ng, bs.wi) <= 0.0 {
        return false;
    }
    (*path).throughput = throughput * bs.weight;
    if !gather_next {
        (*path).radiance += last_sample(origin, bs.wi, bs.pdf, (*path).throughput, emitters, objects, counts);
        return false;
    }
    (*path).origin = origin;
    (*path).wi = bs.wi;
    (*path).pdf = bs.pdf;
    return true;
}

fn path_next(path: ptr<function, Path>, found: bool, next: SurfaceHit, rng: ptr<function, Rng>) -> bool {
    if !found {
        if env_active() {
            (*path).radiance += escaped((*path).wi, (*path).pdf, (*path).throughput);
        }
        return false;
    }
    (*path).bounce += 1u;
    if (*path).bounce >= RUSSIAN_ROULETTE_START {
        var throughput = (*path).throughput;
        if !russian_roulette(&throughput, rng) {
            return false;
        }
        (*path).throughput = throughput;
    }
    (*path).hit = next;
    (*path).incoming = (*path).wi;
    return true;
}

fn radiance_leaving(first: SurfaceHit, incoming: vec3<f32>, objects: bool, rng: ptr<function, Rng>, counts: ptr<function, Counts>) -> vec3<f32> {
    var path = path_start(first, incoming);
    loop {
        if !path_vertex(&path, objects, rng, counts) {
            break;
        }
        let next = closest(path.origin, path.wi, objects, counts);
        if !path_next(&path, next.found, surface_hit(next), rng) {
            break;
        }
    }
    return finite_or_zero(path.radiance);
}

fn escaped_primary(dir: vec3<f32>) -> vec3<f32> {
    var l = environment_eval(dir);
    for (var i = 0u; i < LIGHT_COUNT; i++) {
        l += disc_radiance(lights[i], dir);
    }
    return finite_or_zero(l);
}

fn radiance(o: vec3<f32>, dir: vec3<f32>, objects: bool, rng: ptr<function, Rng>, counts: ptr<function, Counts>) -> vec4<f32> {
    let first = closest(o, dir, objects, counts);
    if !first.found {
        return vec4<f32>(escaped_primary(dir), F32_MAX);
    }
    return vec4<f32>(radiance_leaving(surface_hit(first), dir, objects, rng, counts), first.t);
}

const FLAG_DISTANCE: u32 = 1u;

override ENV_KIND: u32;

override ENV_ACTIVE: bool;

override EMITTERS: bool;

override LIGHT_COUNT: u32;

override LIGHT_KINDS: u32;

override MATERIAL_MODELS: u32;

override TEXTURE_KINDS: u32;

override MR_TEXTURES: bool;

@group(0) @binding(0)
var<uniform> params: Params;

@group(0) @binding(1)
var<storage, read> nodes: array<Node>;

@group(0) @binding(2)
var<storage, read> tris: array<Tri>;

@group(0) @binding(3)
var<storage, read> attrs: array<TriAttr>;

@group(0) @binding(4)
var<storage, read> materials: array<Mat>;

@group(0) @binding(5)
var<storage, read> texels: array<f32>;

@group(0) @binding(6)
var<storage, read> lights: array<Light>;

@group(0) @binding(7)
var<storage, read> env_tables: array<vec2<f32>>;

@group(0) @binding(8)
var<storage, read> jobs: array<Job>;

@group(0) @binding(10)
var<storage, read> trace_rays: array<TraceRay>;

@group(0) @binding(11)
var<storage, read_write> trace_hits: array<TraceHit>;

fn face_st_to_direction(face: u32, s: f32, t: f32) -> vec3<f32> {
    let sc = 2.0 * s - 1.0;
    let tc = 2.0 * t - 1.0;
    var d: vec3<f32>;
    switch face {
        case 0u {
            d = vec3<f32>(1.0, -tc, -sc);
        }
        case 1u {
            d = vec3<f32>(-1.0, -tc, sc);
        }
        case 2u {
            d = vec3<f32>(sc, 1.0, tc);
        }
        case 3u {
            d = vec3<f32>(sc, -1.0, -tc);
        }
        case 4u {
            d = vec3<f32>(sc, -tc, 1.0);
        }
        case default {
            d = vec3<f32>(-sc, -tc, -1.0);
        }
    }
    let len = sqrt(d.x * d.x + d.y * d.y + d.z * d.z);
    if len > 0.0 && finite(len) {
        return d / len;
    }
    return vec3<f32>(1.0, 0.0, 0.0);
}

fn rounds_after_pilot(sum: f32, sum_sq: f32, n: u32, goal: f32, round: u32, min_rounds: u32, max_rounds: u32) -> u32 {
    let nf = f32(max(n, 2u));
    let mean = sum / nf;
    let variance = max((sum_sq - nf * mean * mean) / (nf - 1.0), 0.0);
    let wanted = variance / (goal * goal * mean * mean);
    var rounds = min_rounds;
    if finite(wanted) {
        rounds = u32(min(ceil(wanted / f32(max(round, 1u))), f32(max_rounds)));
    }
    else if variance > 0.0 {
        rounds = max_rounds;
    }
    return clamp(rounds, min_rounds, max(max_rounds, min_rounds));
}

const PILOT_ROUNDS: u32 = 2u;

const MIN_ROUNDS: u32 = 2u;

override WORKGROUP: u32 = 64u;

@compute @workgroup_size(WORKGROUP)
fn capture(@builtin(workgroup_id) wg: vec3<u32>, @builtin(local_invocation_index) local: u32) {
    let id = params.first + wg.y * params.row_invocations + wg.x * WORKGROUP + local;
    if id >= params.texels {
        return;
    }
    let res = params.resolution;
    let per_face = res * res;
    let per_cube = 6u * per_face;
    let job = jobs[id / per_cube];
    let face = (id % per_cube) / per_face;
    let texel = id % per_face;
    let x = texel % res;
    let y = texel / res;
    let objects = job.sees_objects != 0u;
    let stream = hash4(params.seed, vec2<u32>(job.index, 0u), vec2<u32>(face, 0u), vec2<u32>(texel, 0u));
    var rng = rng_new(params.seed, stream);
    var counts = Counts(0u, 0u, 0u, 0u);
    let k = params.strata;
    var sum = vec3<f32>(0.0);
    var lum_sum = 0.0;
    var lum_sq = 0.0;
    var hit_any = false;
    var n = 0u;
    var planned = params.rounds;
    var round = 0u;
    var j = 0u;
    var fresh = true;
    var ray_o = job.origin;
    var ray_d = vec3<f32>(0.0);
    var path: Path;
    var first_t = F32_MAX;
    loop {
        if round >= planned {
            break;
        }
        if fresh {
            let sx = (f32(j % k) + rng_f32(&rng)) / f32(k);
            let sy = (f32(j / k) + rng_f32(&rng)) / f32(k);
            let s = (f32(x) + sx) / f32(res);
            let t = (f32(y) + sy) / f32(res);
            ray_o = job.origin;
            ray_d = face_st_to_direction(face, s, t);
        }
        let h = closest(ray_o, ray_d, objects, &counts);
        let surface = surface_hit(h);
        var going = false;
        if fresh {
            first_t = F32_MAX;
            if h.found {
                first_t = h.t;
                path = path_start(surface, ray_d);
                going = true;
            }
            else {
                path.radiance = escaped_primary(ray_d);
            }
        }
        else {
            going = path_next(&path, h.found, surface, &rng);
        }
        if going {
            going = path_vertex(&path, objects, &rng, &counts);
        }
        fresh = !going;
        if going {
            ray_o = path.origin;
            ray_d = path.wi;
            continue;
        }
        let r = finite_or_zero(path.radiance);
        sum += r;
        let l = luminance(r);
        lum_sum += l;
        lum_sq += l * l;
        hit_any = hit_any || first_t != F32_MAX;
        n += 1u;
        j += 1u;
        if j < k * k {
            continue;
        }
        j = 0u;
        if params.target_noise > 0.0 && round + 1u == PILOT_ROUNDS {
            planned = PILOT_ROUNDS + rounds_after_pilot(lum_sum, lum_sq, n, params.target_noise, k * k, MIN_ROUNDS, params.rounds - PILOT_ROUNDS);
            sum = vec3<f32>(0.0);
            lum_sum = 0.0;
            lum_sq = 0.0;
            n = 0u;
        }
        round += 1u;
    }
    var o: TexelOut;
    o.radiance = sum * (1.0 / f32(n));
    o.distance = 0.0;
    if (params.flags & FLAG_DISTANCE) != 0u {
        let n = f32(res);
        let centre = face_st_to_direction(face, (f32(x) + 0.5) / n, (f32(y) + 0.5) / n);
        let h = closest(job.origin, centre, objects, &counts);
        o.distance = select(F32_MAX, h.t, h.found);
    }
    o.lum_sum = lum_sum;
    o.lum_sq = lum_sq;
    o.closest = counts.closest;
    o.shadow_hit = (counts.shadow << 1u) | select(0u, 1u, hit_any);
    o.nodes = counts.nodes;
    o.tris = counts.tris;
    o.samples = n;
    out[id] = o;
}

@compute @workgroup_size(WORKGROUP)
fn trace(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = gid.x;
    if i >= arrayLength(&trace_rays) {
        return;
    }
    let r = trace_rays[i];
    let h = traverse(r.origin, r.dir, r.t_max, (r.flags & 1u) != 0u, (r.flags & 2u) != 0u);
    var o = TraceHit(F32_MAX, 4294967295u, 0.0, 0.0, h.nodes, h.tris, vec2<u32>(0u));
    if h.found {
        o = TraceHit(h.t, attrs[h.slot].global, h.b.y, h.b.z, h.nodes, h.tris, vec2<u32>(0u));
    }
    trace_hits[i] = o;
}

@compute @workgroup_size(WORKGROUP)
fn preview(@builtin(workgroup_id) wg: vec3<u32>, @builtin(local_invocation_index) local: u32) {
    let id = params.first + wg.y * params.row_invocations + wg.x * WORKGROUP + local;
    if id >= camera.width * camera.height {
        return;
    }
    let x = id % camera.width;
    let y = id / camera.width;
    var rng = rng_new(params.seed, hash3(params.seed, vec2<u32>(x, 0u), vec2<u32>(y, 0u)));
    var counts = Counts(0u, 0u, 0u, 0u);
    let spp = max(camera.spp, 1u);
    var sum = vec3<f32>(0.0);
    for (var s = 0u; s < spp; s++) {
        let j = stratified_2d(s, spp, &rng);
        let dir = camera_direction(f32(x) + j.x, f32(y) + j.y);
        sum += radiance(camera.position, dir, true, &rng, &counts).xyz;
    }
    pixels[id] = vec4<f32>(sum / f32(spp), 1.0);
}

@group(0) @binding(12)
var<uniform> camera: PreviewCamera;

@group(0) @binding(13)
var<storage, read_write> pixels: array<vec4<f32>>;

fn hash3(a: vec2<u32>, b: vec2<u32>, c: vec2<u32>) -> vec2<u32> {
    var h = mix64(GOLDEN ^ vec2<u32>(3u, 0u));
    h = mix64(h ^ mix64(add64(a, GOLDEN)));
    h = mix64(h ^ mix64(add64(b, GOLDEN)));
    h = mix64(h ^ mix64(add64(c, GOLDEN)));
    return h;
}

fn stratified_2d(i_in: u32, n_in: u32, rng: ptr<function, Rng>) -> vec2<f32> {
    let n = max(n_in, 1u);
    let i = i_in % n;
    var kx = u32(sqrt(f32(n)));
    while kx * kx < n {
        kx += 1u;
    }
    while kx > 1u && (kx - 1u) * (kx - 1u) >= n {
        kx -= 1u;
    }
    let ky = (n + kx - 1u) / kx;
    let j = rng_vec2(rng);
    let x = (f32(i % kx) + j.x) / f32(kx);
    let y = (f32(i / kx) + j.y) / f32(ky);
    return vec2<f32>(min(x, ONE_MINUS_EPSILON), min(y, ONE_MINUS_EPSILON));
}

fn camera_direction(px: f32, py: f32) -> vec3<f32> {
    let w = f32(max(camera.width, 1u));
    let h = f32(max(camera.height, 1u));
    let sx = (2.0 * px / w - 1.0) * (w / h) * camera.tan_half;
    let sy = (1.0 - 2.0 * py / h) * camera.tan_half;
    let d = safe_normalize(camera.forward + camera.right * sx + camera.up * sy);
    if all(d == vec3<f32>(0.0)) {
        return camera.forward;
    }
    return d;
}
