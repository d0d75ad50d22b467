// The scene the path tracer shades: surface hits, textures, materials, delta lights and the
// environment, each the CPU's function of the same name (trace/src/ray.rs,
// scene/src/{texture,material,light,environment}.rs) on the data of scene.rs.

import package::bvh::{F32_MAX, Hit, finite3};
import package::capture::{
    ENV_KIND, LIGHT_KINDS, TEXTURE_KINDS, attrs, env_tables, params, texels, tris,
};
import package::integrator::{radiance};
import package::layouts::{Light, Mat, Tex};
import package::shading::constants::{FRAC_1_PI, PI};
import package::shading::warp::{sample_uniform_sphere};

const ONE_MINUS_EPSILON: f32 = 0.99999994;

struct SurfaceHit {
    t: f32,
    position: vec3<f32>,
    geometric_normal: vec3<f32>,
    shading_normal: vec3<f32>,
    uv: vec2<f32>,
    material: u32,
    extent: f32,
}

// `TriangleScene::surface_hit`.
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
    } else {
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

// `i.rem_euclid(n)` for i in [−n, 2n), where a bilinear tap's column or row lies (from −1
// to n): without an integer division, which SIMD units lack (a CPU adapter divides lane by
// lane).
fn wrap(i: i32, n: u32) -> u32 {
    let m = i32(n);
    return u32(select(select(i, i - m, i >= m), i + m, i < 0));
}

// `Texture::eval`.
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
        return t.a; // no path reaches this
    }
    // A linear RGB image, bilinear, wrapping (`ImageTexture::eval`).
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

// Whether bit 1 << `kind` is set in `kinds` (the overrides LIGHT_KINDS, MATERIAL_MODELS and
// TEXTURE_KINDS).
fn present(kinds: u32, kind: u32) -> bool {
    return (kinds & (1u << kind)) != 0u;
}

const TEX_CONSTANT: u32 = 0u;
const TEX_CHECKER: u32 = 1u;
const TEX_IMAGE: u32 = 2u;
const MODEL_LAMBERTIAN: u32 = 0u;
const MODEL_METALLIC_ROUGHNESS: u32 = 1u;

// `Material::eval`: the albedo at `uv`, clamped to [0, 1].
fn material_albedo(m: Mat, uv: vec2<f32>) -> vec3<f32> {
    let a = texture_eval(m.albedo, uv);
    return vec3<f32>(clamp01(a.x), clamp01(a.y), clamp01(a.z));
}

struct LightSample {
    dir: vec3<f32>,
    distance: f32,
    irradiance: vec3<f32>,
    valid: bool,
}

const LIGHT_POINT: u32 = 0u;
const LIGHT_SPOT: u32 = 1u;
const LIGHT_SUN: u32 = 2u;

fn finite_vec(v: vec3<f32>) -> bool {
    return finite3(v);
}

// `spot_falloff`.
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

// `Light::sample_li`.
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
        return s; // no path reaches this
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

// `Light::disc_radiance`.
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

// `Perez::f`.
fn perez(c: vec4<f32>, e: f32, cos_theta_in: f32, gamma_angle: f32) -> f32 {
    let cos_theta = max(cos_theta_in, 0.01);
    let cos_gamma = cos(gamma_angle);
    return (1.0 + c.x * exp(c.y / cos_theta)) * (1.0 + c.z * exp(c.w * gamma_angle) + e * cos_gamma * cos_gamma);
}

// `Sky::eval_sky`.
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

// `LatLongSampler::uv`: (u, v, sin θ) of a world direction.
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

// `Environment::eval`.
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

// `sample_tables` on a table of `n + 1` entries [cdf, pdf] from `base`: (x, pdf, bin).
fn sample_table(base: u32, n: u32, u_in: f32) -> vec3<f32> {
    var u = 0.0;
    if finite(u_in) {
        u = clamp(u_in, 0.0, ONE_MINUS_EPSILON);
    }
    // count = the number of entries with cdf ≤ u (the cdf does not decrease).
    var lo = 0u;
    var hi = n + 1u;
    while lo < hi {
        let mid = (lo + hi) / 2u;
        if env_tables[base + mid].x <= u {
            lo = mid + 1u;
        } else {
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
    pdf: f32,
}

// `Environment::sample_environment`.
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

// `Environment::environment_pdf`.
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
