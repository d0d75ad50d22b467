// Ashikhmin–Shirley (chapter 5) and glTF's metallic-roughness BRDF by Monte Carlo.
// Its CPU twin: reference/glossy.rs.

import package::shade::bindings::{
    BLEND, DEPTH, DIFFUSE, FILTER, INVALID, IRRADIANCE, ORDER, P, PBR_LOD_BIAS, SOURCE,
    SPLIT_SUM, TERMS, samples, slots,
};
import package::shade::blend::{blend_read, blend_weights, cand, env_dir, env_read};
import package::shade::cube::{lookup, lookup_levels, sample_lod};
import package::shade::depth::{depth_hidden, depth_iterate, depth_search, low_hit};
import package::shade::random::{filter_rows, sample_xi};
import package::shade::split_sum::{split_sum};
import package::shading::constants::{GGX_DIELECTRIC_F0, PI, SH_AS_DIFFUSE, SH_COSINE};
import package::shading::fresnel::{fresnel_schlick, fresnel_schlick_weight};
import package::shading::ggx::{
    ggx_distribution_denominator, ggx_sample_visible_normal, ggx_smith_g1,
};
import package::shading::sh::{sh_convolve, sh_fresnel_cosine_weight};

struct AsSample {
    l: vec3<f32>,
    // f_r ⟨n,l⟩ / p(l): the weight of L_i(l) in Eq. 5.12; 0 for samples below the surface.
    weight: vec3<f32>,
    // log2(M p(l)), p the solid-angle density l was drawn with: the sample's mip level
    // (`sample_lod`).
    lpdf: f32,
};

// The specular lobe's sample at (ξ1, ξ2): ξ1 picks the quadrant and φ in it (Eq. 5.9 with the
// exponent in φ), ξ2 the angle from n, reflected about h (5.10). With k = v the estimator
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
    out.weight = vec3<f32>(0.0);
    // p(h) = √((n_u+1)(n_v+1)) / 2π · ⟨n,h⟩^e (5.8), with ⟨n,h⟩^e = (1 − ξ2)^(e/(e+1)) from the
    // inversion above (finite for any exponent); p(l) = p(h) / 4⟨v,h⟩ (5.11).
    out.lpdf = log2(f32(P.m)) + 0.5 * log2((P.nu + 1.0) * (P.nv + 1.0)) - log2(2.0 * PI)
        + e / (e + 1.0) * log2(1.0 - xi2) - log2(4.0 * max(vh, 1e-30));
    let nl = dot(n, out.l);
    if (vh > 0.0 && nl > 0.0) {
        out.weight = vec3<f32>(fresnel_schlick(P.rs, vh) * nl / max(nv, nl));
    }
    return out;
}

// glTF's GGX lobe: a visible normal drawn at (ξ1, ξ2) (Heitz 2018), v reflected about it.
fn sample_ggx(xi1: f32, xi2: f32, n: vec3<f32>, t: vec3<f32>, b: vec3<f32>, v: vec3<f32>, nv: f32, base: vec3<f32>, pbr: vec2<f32>) -> AsSample {
    var out: AsSample;
    let a = pbr.y;
    let a2 = a * a;
    let vl = vec3<f32>(dot(v, t), dot(v, b), nv);
    // (ξ1, ξ2) = (φ/2π, r²) on the disc, as `filter_xi` lays its strata out.
    let hl = ggx_sample_visible_normal(vl, a, xi2, xi1);
    let h = t * hl.x + b * hl.y + n * hl.z;
    let vh = dot(v, h);
    out.l = 2.0 * vh * h - v;
    let nl = dot(n, out.l);
    // D(h) with its denominator as α²(n·h)² + |n × h|² (exact at a narrow lobe's peak).
    let d = ggx_distribution_denominator(a2, hl.z, hl.x * hl.x + hl.y * hl.y);
    let g1v = ggx_smith_g1(a2, nv);
    // p(l) = G₁(v) D(h) / (4 n·v); the lookup reads PBR_LOD_BIAS levels off its share
    // (sample_lod's ½ log2(1 / (M p)), so 2·bias off log2(M p)).
    out.lpdf = log2(f32(P.m)) + log2(max(g1v, 1e-30)) + log2(a2)
        - log2(max(PI * d * d, 1e-30))
        - log2(4.0 * max(nv, 1e-30)) - 2.0 * PBR_LOD_BIAS;
    out.weight = vec3<f32>(0.0);
    if (vh > 0.0 && nl > 0.0 && nv > 0.0) {
        // f ⟨n,l⟩ / p(l) = F(⟨v,h⟩) G₁(l): separable Smith, G = G₁(l) G₁(v).
        let g1l = ggx_smith_g1(a2, nl);
        let k5 = fresnel_schlick_weight(vh);
        let metal = base + (vec3<f32>(1.0) - base) * k5;
        let dielectric = vec3<f32>(fresnel_schlick(GGX_DIELECTRIC_F0, vh));
        out.weight = mix(dielectric, metal, pbr.x) * g1l;
    }
    return out;
}

// A cosine-weighted direction at (ξ1, r²) = (φ/2π, r²) on the disc, with weight 0:
// p(l) = ⟨n,l⟩ / π.
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

// glTF's diffuse base of a dielectric, cosine-weighted: f ⟨n,l⟩ / p(l) =
// (1 − metallic)(1 − F(⟨v,h⟩)) C.
fn sample_pbr_diffuse(xi1: f32, r2: f32, n: vec3<f32>, t: vec3<f32>, b: vec3<f32>, v: vec3<f32>, base: vec3<f32>, pbr: vec2<f32>) -> AsSample {
    var out = cosine_sample(xi1, r2, n, t, b);
    let nl = dot(n, out.l);
    var h = n;
    let hv = v + out.l;
    if (dot(hv, hv) > 0.0) { h = normalize(hv); }
    let fr = fresnel_schlick(GGX_DIELECTRIC_F0, abs(dot(v, h)));
    if (nl > 0.0 && dot(n, v) > 0.0) {
        out.weight = base * ((1.0 - pbr.x) * (1.0 - fr));
    }
    return out;
}

// Cosine-weighted sample for the diffuse term 5.4: f_dr ⟨n,l⟩ / p(l) = π f_dr.
fn sample_diffuse(xi1: f32, r2: f32, n: vec3<f32>, t: vec3<f32>, b: vec3<f32>, nv: f32) -> AsSample {
    var out = cosine_sample(xi1, r2, n, t, b);
    let nl = dot(n, out.l);
    let fv = 1.0 - pow(1.0 - 0.5 * max(nv, 0.0), 5.0);
    let fl = 1.0 - pow(1.0 - 0.5 * max(nl, 0.0), 5.0);
    out.weight = vec3<f32>(select(0.0, 28.0 / 23.0 * P.rd * (1.0 - P.rs) * fv * fl, nl > 0.0)); // Eq. 5.4 × π
    return out;
}

// The radiance of sample `s` for the shaded point x: cube `cube` (depth-corrected for a
// sample point with DEPTH, parallax-corrected for the environment cube with SOURCE 2), or (per
// direction, cube = INVALID) the blend of the candidates (`low_hit`s left out; x's normal n)
// with the environment cube where none is resident; filtered at mip level `lod` (`sample_lod`) with FILTER. `.w` = 0 when a cube's
// face was not resident.
fn sample_radiance(cube: u32, entry: u32, o: vec3<f32>, wn: vec4<f32>, x: vec3<f32>, n: vec3<f32>, s: AsSample, lod: f32, fresh: bool, seed: ptr<function, f32>) -> vec4<f32> {
    let l = s.l;
    if (ORDER == 1u && cube == INVALID) {
        var w = wn;
        if (BLEND != 4u) { w = blend_weights(l); }
        let b = blend_read(w, x, l, lod, n, true);
        if (b.w > 0.0) { return b; }
        return vec4<f32>(env_read(x, l, lod), 1.0);
    }
    var d = l;
    if (cube == P.env_cube) {
        d = env_dir(x, l);
    } else if (DEPTH) {
        d = depth_iterate(cube, entry, o, l, fresh, seed);
    }
    return read_dir(cube, entry, d, lod);
}

// Cube `cube` towards `d` at mip level `lod` (with FILTER; else level 0). With FILTER every
// level through `lookup_levels`, level 0 too: lavapipe would run `lookup_lod`'s branch to
// `lookup` for every sample, lengthening FIS + depth frames (docs/measurements.md).
fn read_dir(cube: u32, entry: u32, d: vec3<f32>, lod: f32) -> vec4<f32> {
    if (FILTER) {
        return lookup_levels(cube, entry, d, lod);
    }
    return lookup(cube, d);
}

// The largest component of `w`: a sample with none above 0 adds nothing.
fn max3(w: vec3<f32>) -> f32 {
    return max(w.x, max(w.y, w.z));
}

// The specular sample of the mode: Ashikhmin–Shirley, or glTF's GGX with TERMS & 16.
fn sample_spec(xi1: f32, xi2: f32, n: vec3<f32>, t: vec3<f32>, b: vec3<f32>, v: vec3<f32>, nv: f32, base: vec3<f32>, pbr: vec2<f32>) -> AsSample {
    if ((TERMS & 16u) != 0u) { return sample_ggx(xi1, xi2, n, t, b, v, nv, base, pbr); }
    return sample_as(xi1, xi2, n, t, b, v, nv);
}

// The diffuse sample of the mode: the term 5.4, or glTF's diffuse base with TERMS & 16.
fn sample_diff(xi1: f32, xi2: f32, n: vec3<f32>, t: vec3<f32>, b: vec3<f32>, v: vec3<f32>, nv: f32, base: vec3<f32>, pbr: vec2<f32>) -> AsSample {
    if ((TERMS & 16u) != 0u) { return sample_pbr_diffuse(xi1, xi2, n, t, b, v, base, pbr); }
    return sample_diffuse(xi1, xi2, n, t, b, nv);
}

// Per-cube sums of an integration (Eq. 5.12), by component: entry k belongs to `cubes[k]`.
struct Sums {
    r: vec4<f32>,
    g: vec4<f32>,
    b: vec4<f32>,
    // 0 where a face that entry needed was not resident.
    ok: vec4<f32>,
};

// Per point visible (ORDER 2), the entry whose cube sample `s` of entry k reads: k itself where
// its sample point sees the sample's ray (`depth_hidden`) or it is the environment cube, else
// the used entry of largest blend weight `w` whose point sees it (k where none does).
fn stand_in(k: u32, cubes: vec4<u32>, entries: vec4<u32>, used: vec4<bool>, ox: vec4<f32>, oy: vec4<f32>, oz: vec4<f32>, w: vec4<f32>, s: AsSample) -> u32 {
    var best = k;
    var best_w = 0.0;
    let hidden = cubes[k] != P.env_cube && depth_hidden(cubes[k], entries[k], vec3<f32>(ox[k], oy[k], oz[k]), s.l);
    // A loop no invocation enters where k sees the sample: lavapipe runs an if's body whatever
    // its condition, but skips a loop that no invocation enters.
    for (var j = select(4u, 0u, hidden); j < 4u; j++) {
        if (j == k || !used[j] || !(w[j] > best_w)) { continue; }
        if (depth_hidden(cubes[j], entries[j], vec3<f32>(ox[j], oy[j], oz[j]), s.l)) { continue; }
        best = j;
        best_w = w[j];
    }
    return best;
}

// Per point searched (ORDER 3), where sample `s` of entry k is read: where k's sample point
// sees the sample's ray meet the scene (`depth_search`), or where k's cannot (the search's
// w < 0), where the used entry of largest blend weight `w` whose point sees it does (k's own
// search where none does). `e`: the entry whose cube is read, or 4 for a hit of k's that is a
// `low_hit` (x's normal n): there the sample is read as per point reads it. `d`: the direction
// from its point.
struct Seen {
    e: u32,
    d: vec3<f32>,
};

fn searched(k: u32, cubes: vec4<u32>, used: vec4<bool>, x: vec3<f32>, n: vec3<f32>, w: vec4<f32>, s: AsSample) -> Seen {
    let p = samples[cubes[k]].xyz;
    let h = depth_search(cubes[k], x, s.l);
    if (low_hit(p, h, x, s.l, n)) {
        return Seen(4u, s.l);
    }
    var best = Seen(k, h.xyz);
    var best_w = 0.0;
    // A loop no invocation enters where k sees the sample, as in `stand_in`.
    for (var j = select(4u, 0u, h.w < 0.0); j < 4u; j++) {
        if (j == k || !used[j] || !(w[j] > best_w)) { continue; }
        let q = depth_search(cubes[j], x, s.l);
        if (q.w < 0.0) { continue; }
        best = Seen(j, q.xyz);
        best_w = w[j];
    }
    return best;
}

// Adds sample `s`'s radiance × weight to entry k of `sums`: `sample_radiance` of entry k's cube,
// or with ORDER 2, where k's point cannot see the sample, of its `stand_in`'s, read as a fresh
// sample that leaves k's row as it was; with ORDER 3 where `searched` sees it (x's normal n),
// unless its hit is too low. `fresh` and `seeds`: per entry, this kind of sample's row state of
// `depth_iterate`; `w`: the entries' blend weights, which choose the stand-in.
// A function, not a loop over the two kinds of sample: lavapipe ran FIS frames markedly
// slower with even a one-pass loop around the read (docs/measurements.md).
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
        if (ORDER == 2u && DEPTH) { e = stand_in(k, cubes, entries, used, ox, oy, oz, w, s); }
        let own = e == k;
        var seed = select(0.0, (*seeds)[k], own);
        l = sample_radiance(cubes[e], entries[e], vec3<f32>(ox[e], oy[e], oz[e]), wn, x, n, s, lod, (*fresh)[k] || !own, &seed);
        (*seeds)[k] = select((*seeds)[k], seed, own);
        (*fresh)[k] = (*fresh)[k] && !own;
    }
    if (l.w == 0.0) { (*sums).ok[k] = 0.0; }
    (*sums).r[k] += l.r * s.weight.r;
    (*sums).g[k] += l.g * s.weight.g;
    (*sums).b[k] += l.b * s.weight.b;
}

// The M samples' sums of radiance × weight (Eq. 5.12, before ÷ M) from up to four sources at
// once: entry k integrates over `cubes[k]` where `used[k]`, with the random numbers of
// integration j0 + k; cube INVALID is the blend of the candidates per direction. With FILTER
// the diffuse and Ashikhmin–Shirley samples are one fixed set for every source, drawn once for
// all of them; the pbr mode's GGX samples are each candidate's own spiral. The diffuse term
// 5.4 is compiled in only when R_d > 0 (override DIFFUSE). One loop with one call site:
// lavapipe pays for every inlined copy whether it runs or not. `w`: the entries' blend weights
// (ORDER 2's `stand_in`s, ORDER 3's `searched`).
fn integrate(cubes: vec4<u32>, used: vec4<bool>, j0: u32, pixel: u32, x: vec3<f32>, n: vec3<f32>, t: vec3<f32>, b: vec3<f32>, v: vec3<f32>, nv: f32, base: vec3<f32>, pbr: vec2<f32>, w: vec4<f32>) -> Sums {
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
    // converged to, and whether the row has had its fresh sample (its first one above the
    // surface) yet.
    var spec_seed = vec4<f32>(0.0);
    var diff_seed = vec4<f32>(0.0);
    var spec_fresh = vec4<bool>(true);
    var diff_fresh = vec4<bool>(true);
    let rows = filter_rows();
    // Random samples differ per candidate, and so do the pbr mode's filtered GGX spirals
    // (`filter_xi`); the other filtered samples are drawn once, for the first candidate.
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
            if (!used[k]) { continue; }
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

// Entry k of `integrate`'s sums as the estimate (÷ M).
fn estimate(s: Sums, k: u32) -> vec3<f32> {
    return vec3<f32>(s.r[k], s.g[k], s.b[k]) / f32(max(P.m, 1u));
}

// Cube `cube`'s stored spherical-harmonic coefficients (IRRADIANCE).
fn cube_sh(cube: u32) -> array<vec3<f32>, 9> {
    var c: array<vec3<f32>, 9>;
    for (var i = 0u; i < 9u; i++) {
        c[i] = samples[P.irradiance + 9u * cube + i].xyz;
    }
    return c;
}

// The diffuse part read from the stored irradiance (IRRADIANCE): each candidate's coefficients
// convolved with the mode's diffuse lobe at n and blended with the weights B at n (always
// resident, so every candidate takes part); the environment cube's with `use_env` or without
// candidates. Times the lobe's constant factors: the term 5.4's 28/23 R_d (1 − R_s) f(⟨n,v⟩),
// or glTF's (1 − metallic) C (1 − F₀) with the Fresnel share of the cosine lobe.
fn diffuse_irradiance(use_env: bool, n: vec3<f32>, nv: f32, base: vec3<f32>, pbr: vec2<f32>) -> vec3<f32> {
    var bands = SH_AS_DIFFUSE;
    if ((TERMS & 16u) != 0u) { bands = SH_COSINE; }
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
    } else if (P.env_cube != INVALID) {
        e = sh_convolve(cube_sh(P.env_cube), bands, n);
    }
    if ((TERMS & 16u) != 0u) {
        if (!(nv > 0.0)) { return vec3<f32>(0.0); }
        return e * base * ((1.0 - pbr.x) * (1.0 - GGX_DIELECTRIC_F0) * sh_fresnel_cosine_weight(nv));
    }
    let fv = 1.0 - pow(1.0 - 0.5 * max(nv, 0.0), 5.0);
    return e * (28.0 / 23.0 * P.rd * (1.0 - P.rs) * fv); // Eq. 5.4 × π
}

// Per point (order A): integrate at each candidate with its own random vectors, then blend
// (4.7); the environment cube (integration 4) when no candidate is usable; per point visible
// (ORDER 2) alike, a hidden sample read from a `stand_in`, and per point searched (ORDER 3)
// each sample read where `searched` sees it. Per direction (order B): one
// integration over the blend. Both passes through one `integrate` call. With
// SPLIT_SUM (the pbr mode's engine baseline) no Monte Carlo: `split_sum`.
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
        let sums = integrate(cubes, used, select(0u, 4u, phase == 1u), pixel, x, n, t, b, v, nv, base, pbr, wp);
        for (var k = 0u; k < 4u; k++) {
            if (used[k] && (sums.ok[k] > 0.0 || phase == 1u)) {
                acc += estimate(sums, k) * wp[k];
                wsum += wp[k];
            }
        }
    }
    if (wsum > 0.0) { return acc / wsum + diffuse; }
    return diffuse;
}
