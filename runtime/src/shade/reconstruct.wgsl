// Surface reconstruction (3.11–3.12, §6.3).
// Its CPU twin: reference/reconstruct.rs.

import package::shade::bindings::{DEPTH, INVALID, P, samples, slots};
import package::shade::blend::{cand, cand_s, is_resident};
import package::shade::cube::{lookup};
import package::shade::depth::{depth_lookup, depth_missing, depth_toward};

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
