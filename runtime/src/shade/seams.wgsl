// Lookups filtered across face edges (for the background).
// Its CPU twin: reference/seams.rs.

import package::shade::bindings::{P, slots};
import package::shade::cube::{face_st, load_texel, place};
import package::shade::feedback::{mark_face};

// The texel of the adjacent face that texel (x, y) one texel off `face`'s edge stands for, per
// edge (left, right, top, bottom) and face 6 bits: the adjacent face (3 bits); 8: the edge's
// own coordinate runs along the adjacent face's x (else its y); 16: reversed (n − 1 − it);
// 32: the texel lies at the adjacent face's far side (n − 1, else 0). SEAM_LO holds faces 0–4,
// SEAM_HI face 5. The same texel as `face_st` of the direction through the off-face texel's
// centre extended on `face`'s plane (the edge's coordinate a lands on (a + 1)·n/(n + 1), so
// at texel a): reference/seams.rs `seam_texel` computes it that way.
const SEAM_LO = vec4<u32>(0x21e49964u, 0x00a18105u, 0x2ab1d0b2u, 0x0bf4c4e3u);
const SEAM_HI = vec4<u32>(0x20u, 0x1u, 0x1au, 0x3bu);

// Face and texel (x, y) of a level n texels wide that texel (x, y) of `face` stands for, where
// (x, y) may lie one texel off the face (not off two edges at once: a corner gets a valid
// texel of no meaning): then the texel of the adjacent face it stands for (SEAM_LO).
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

// Texel `c` (face, x, y) of mip `level` of the slot in indirection entry `entry`.
fn slot_texel(entry: u32, c: vec3<u32>, level: u32) -> vec3<f32> {
    let at = place(entry, c.x);
    return load_texel(at.x, i32(at.y), vec2<u32>((at.z >> level) + c.y, c.z), level);
}

// The four texel centres around `fst` (`face_st` of a direction: face and face coordinates) on
// a level `n` texels wide, ACROSS face edges: those off the face are the adjacent face's
// (`seam_texel`). At a corner of the cube, where three faces meet, the texel off the face in
// both directions does not exist: `corner` names it (k = column + 2 · row; 4 = none) and
// `seam_bilinear` replaces it by the mean of the other three.
struct SeamTaps {
    c0: vec3<u32>,
    c1: vec3<u32>,
    c2: vec3<u32>,
    c3: vec3<u32>,
    wx: f32,
    wy: f32,
    corner: u32,
};

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

// The bilinear blend of the four texels read at `t`'s taps (the corner's value, loaded from a
// valid address of no meaning, replaced by the mean of the other three).
fn seam_bilinear(t: SeamTaps, a0: vec3<f32>, a1: vec3<f32>, a2: vec3<f32>, a3: vec3<f32>) -> vec3<f32> {
    var t0 = a0;
    var t1 = a1;
    var t2 = a2;
    var t3 = a3;
    if (t.corner == 0u) { t0 = vec3<f32>(0.0); } else if (t.corner == 1u) { t1 = vec3<f32>(0.0); } else if (t.corner == 2u) { t2 = vec3<f32>(0.0); } else if (t.corner == 3u) { t3 = vec3<f32>(0.0); }
    let mean = (t0 + t1 + t2 + t3) * (1.0 / 3.0);
    if (t.corner == 0u) { t0 = mean; } else if (t.corner == 1u) { t1 = mean; } else if (t.corner == 2u) { t2 = mean; } else if (t.corner == 3u) { t3 = mean; }
    let top = t0 + (t1 - t0) * t.wx;
    let bottom = t2 + (t3 - t2) * t.wx;
    return top + (bottom - top) * t.wy;
}

// Radiance of mip `level` of cube `cube` at `fst`, bilinear across face edges (`seam_taps`).
// `.w` = 0 when a face it reads is not resident. Marks the faces it reads when `mark`. The
// four texels are found first and then read alike, so that an invocation at a face edge
// differs from its neighbours only in `seam_texel`'s arithmetic, not in what it loads
// (lavapipe runs every path any lane takes). Written without a local array (see
// `Candidates`).
fn seamless_level(cube: u32, entry: u32, fst: vec3<f32>, level: u32, mark: bool) -> vec4<f32> {
    let t = seam_taps(fst, i32(max(P.cube_res >> level, 1u)));
    let bits = select(1u << t.c0.x, 0u, t.corner == 0u) | select(1u << t.c1.x, 0u, t.corner == 1u)
        | select(1u << t.c2.x, 0u, t.corner == 2u) | select(1u << t.c3.x, 0u, t.corner == 3u);
    if (mark) {
        mark_face(cube, bits);
    }
    if ((entry & bits) != bits) {
        return vec4<f32>(0.0);
    }
    let c = seam_bilinear(t, slot_texel(entry, t.c0, level), slot_texel(entry, t.c1, level),
        slot_texel(entry, t.c2, level), slot_texel(entry, t.c3, level));
    return vec4<f32>(c, 1.0);
}

// `seamless_level` at level 0 without feedback marks: for the background only. `lookup`
// (reflections, reconstruction) clamps at face edges, and every published error figure
// depends on that; filtered glossy samples (`lookup_lod`) read across edges at every level.
fn seamless_read(cube: u32, dir: vec3<f32>) -> vec3<f32> {
    return seamless_level(cube, slots[cube], face_st(dir), 0u, false).rgb;
}
