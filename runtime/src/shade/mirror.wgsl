// Mirror reflection (chapter 4).
// Its CPU twin: reference/mirror.rs.

import package::shade::bindings::{BLEND, DEPTH, INVALID, P, SOURCE};
import package::shade::blend::{blend_fetch, blend_read, blend_weights, cand, env_read};
import package::shade::cube::{fetch, tap};

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
            b = blend_read(w, x, r, 0.0, n, false);
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
