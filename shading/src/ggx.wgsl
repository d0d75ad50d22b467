// The twin of oslf-shading's ggx.rs, function for function (ggx_ + its names): GGX D, Smith
// masking, visible-normal sampling. GGX_MIN_ALPHA and GGX_DIELECTRIC_F0 are generated from
// the Rust constants (wgsl.rs).

import package::shading::constants::{GGX_MIN_ALPHA, PI};

// α = roughness², at least GGX_MIN_ALPHA.
fn ggx_alpha(roughness: f32) -> f32 {
    return max(roughness * roughness, GGX_MIN_ALPHA);
}

// α²(n·h)² + |n × h|², sin2 = |n × h|² computed by the caller without cancellation.
fn ggx_distribution_denominator(a2: f32, nh: f32, sin2: f32) -> f32 {
    return a2 * nh * nh + sin2;
}

// Trowbridge–Reitz D for α², n·h and |n × h|²; 0 where n·h ≤ 0.
fn ggx_distribution(a2: f32, nh: f32, sin2: f32) -> f32 {
    if (nh <= 0.0) {
        return 0.0;
    }
    let d = ggx_distribution_denominator(a2, nh, sin2);
    return a2 / (PI * d * d);
}

// ggx_distribution at the half vector h about the normal n (both unit, in any frame).
fn ggx_distribution_at(a2: f32, n: vec3<f32>, h: vec3<f32>) -> f32 {
    let c = cross(n, h);
    return ggx_distribution(a2, dot(n, h), dot(c, c));
}

// Smith's Λ(c) = c + √(α² + (1 − α²) c²).
fn ggx_smith_lambda(a2: f32, c: f32) -> f32 {
    return c + sqrt(a2 + (1.0 - a2) * c * c);
}

// Smith's masking G₁ = 2c / Λ(c).
fn ggx_smith_g1(a2: f32, c: f32) -> f32 {
    return 2.0 * c / ggx_smith_lambda(a2, c);
}

// The separable Smith visibility V = 1 / (Λ(n·l) Λ(n·v)).
fn ggx_visibility(a2: f32, nl: f32, nv: f32) -> f32 {
    return 1.0 / (ggx_smith_lambda(a2, nl) * ggx_smith_lambda(a2, nv));
}

// A microfacet normal drawn from the normals visible from v (Heitz 2018, listing 1), local
// frame, at radius √r2 and angle 2π·phi_fraction on the unit disc; the normal itself where
// the draw degenerates.
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

// n·h of a half vector drawn from D(h) (n·h) at ξ.
fn ggx_sample_distribution_cos(a2: f32, xi: f32) -> f32 {
    return sqrt(max((1.0 - xi) / (1.0 + (a2 - 1.0) * xi), 0.0));
}
