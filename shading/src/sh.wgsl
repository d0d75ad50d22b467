// The twin of oslf-shading's sh.rs (sh_ + its names): spherical harmonics of bands 0–2. The
// normalisations SH_Y* and the band factors SH_COSINE, SH_AS_DIFFUSE are generated from sh.rs.

import package::shading::constants::{SH_Y0, SH_Y1, SH_Y2, SH_Y20, SH_Y22};

// The nine real spherical harmonics at the unit direction d, in sh.rs's order.
fn sh_basis(d: vec3<f32>) -> array<f32, 9> {
    return array<f32, 9>(
        SH_Y0,
        SH_Y1 * d.y,
        SH_Y1 * d.z,
        SH_Y1 * d.x,
        SH_Y2 * d.x * d.y,
        SH_Y2 * d.y * d.z,
        SH_Y20 * (3.0 * d.z * d.z - 1.0),
        SH_Y2 * d.x * d.z,
        SH_Y22 * (d.x * d.x - d.y * d.y),
    );
}

// The band of coefficient i (0, 1 or 2).
fn sh_band(i: u32) -> u32 {
    if (i == 0u) { return 0u; }
    if (i <= 3u) { return 1u; }
    return 2u;
}

// ∫ L(l) k(⟨n,l⟩) dl / π for coefficients c and the lobe of band factors `bands`, clamped at 0.
fn sh_convolve(c: array<vec3<f32>, 9>, bands: vec3<f32>, n: vec3<f32>) -> vec3<f32> {
    let y = sh_basis(n);
    var e = vec3<f32>(0.0);
    for (var i = 0u; i < 9u; i++) {
        e += c[i] * (y[i] * bands[sh_band(i)]);
    }
    return max(e, vec3<f32>(0.0));
}

// 1 − W(⟨n,v⟩): the share of a cosine lobe the dielectric Fresnel weight leaves (sh.rs).
fn sh_fresnel_cosine_weight(nv: f32) -> f32 {
    let s = 1.0 - clamp(nv, 0.0, 1.0);
    let w = 8.280397e-5 + s * (2.0117674e-3 + s * (9.362331e-3 + s * (7.705992e-3 + s * 9.002511e-3)));
    return 1.0 - w;
}
