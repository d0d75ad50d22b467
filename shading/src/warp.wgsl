// The twin of oslf-shading's warp.rs: the warps the GPU bake draws (same names, same order;
// the inverses and the densities it does not need are Rust only) and the frame about a normal.

import package::shading::constants::{FRAC_1_PI, FRAC_PI_2, FRAC_PI_4, PI};

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
    z: vec3<f32>,
}

// `Frame::from_normal` (Duff et al. 2017): n normalised first, the world frame for a zero or
// non-finite n.
fn frame_from_normal(n_in: vec3<f32>) -> Frame {
    var n = vec3<f32>(0.0, 0.0, 1.0);
    let l = length(n_in);
    if l > 0.0 && abs(l) <= 3.40282347e+38 && abs(1.0 / l) <= 3.40282347e+38 {
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

