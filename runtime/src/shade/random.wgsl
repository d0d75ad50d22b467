// Random numbers: PCG hash (Jarzynski & Olano 2020).
// Its CPU twin: reference/random.rs.

import package::shade::bindings::{FILTER, P, TERMS};
import package::shading::constants::{PI};

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
        return filter_xi(i, (TERMS & 16u) != 0u && k == 0u, j);
    }
    return vec2<f32>((f32(i) + rand(pixel, i, j, k)) / f32(P.m), rand(pixel, i, j, k + 1u));
}

// (ξ1, ξ2) of filtered sample i of M. For M = n² the centres of an n × n grid of strata mapped
// to the disc by Shirley & Chiu's concentric map (1997), read as polar coordinates (ξ1 = φ/2π,
// ξ2 = r²: the disc's area measure is uniform in both): every sample's cell is compact, so
// the isotropic filtered lookup of its area covers it (Hammersley's cells near the lobe's
// peak are thin wedges, and a wide lobe's peak is then read too often). Other M: the
// Hammersley set ((i + ½)/M, radical inverse of i). With `spiral` (the pbr mode's GGX
// samples) the golden-angle spiral of integration j instead, ξ1 = frac(i (2 − φ) + t),
// ξ2 = (i + ½ + s)/M: M distinct radii on the disc of visible normals, where the grid has n/2
// rings (two at M = 16, the outer one standing for the GGX lobe's whole tail), with cells as
// compact. Candidate j < 4 of a per-point integration turns it by t = j/4 and moves its radii
// by s = j/4 − 3/8 of a stratum: the four candidates' sets interleave into one of 4M
// directions, which their blend integrates for the lookups of M; integration 4 (per
// direction, the environment) t = s = 0 (measurements.md, "Mips weighted by solid angle, a
// spiral per candidate"). reference/random.rs `filter_xi` computes the same.
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
// row by row; the pbr mode's spiral in runs of n neighbouring radii), else 1 (every sample a
// row of its own). A row's later samples step once from its first one's depth.
// reference/random.rs `filter_rows` likewise.
fn filter_rows() -> u32 {
    let n = u32(round(sqrt(f32(P.m))));
    if (FILTER && n > 0u && n * n == P.m) {
        return n;
    }
    return 1u;
}
