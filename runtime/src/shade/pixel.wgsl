// The entry point: one invocation per pixel.
// Its CPU twin: reference/pixel.rs.

import package::octahedral::{oct_decode};
import package::shade::background::{background};
import package::shade::bindings::{
    P, TERMS, TEXTURED, gb_depth, gb_material, gb_normal, gb_position, out_image, patches,
};
import package::shade::blend::{cand, candidates};
import package::shade::feedback::{flush_marks, mark_bits, mark_cube, mark_env};
import package::shade::glossy::{glossy};
import package::shade::mirror::{mirror};
import package::shade::patch::{patch_du, patch_normal, surface_hit, tangent_frame};
import package::shade::random::{pcg};
import package::shade::reconstruct::{recon};
import package::shading::color::{srgb_to_linear};
import package::shading::ggx::{ggx_alpha};

// Replaces NaN and infinities by 0 so that nothing non-finite reaches a pixel.
fn finite3(c: vec3<f32>) -> vec3<f32> {
    var o = c;
    for (var k = 0u; k < 3u; k++) {
        let x = c[k];
        if (!(x == x) || abs(x) > 3.0e38) { o[k] = 0.0; }
    }
    return o;
}

// The emissive texture's RGB that gb_material's w holds above the flags, decoded.
fn emissive_of(w: u32) -> vec3<f32> {
    let c = vec3<f32>(vec3<u32>((w >> 8u) & 255u, (w >> 16u) & 255u, (w >> 24u) & 255u)) / 255.0;
    return vec3<f32>(srgb_to_linear(c.x), srgb_to_linear(c.y), srgb_to_linear(c.z));
}

// The pbr mode's metallic and GGX α on map `pid`: its object's material's where the store has
// one and the parameters take it (P.object_material), else the parameters'.
fn pbr_material(pid: u32) -> vec2<f32> {
    let m = patches[pid].material;
    if (P.object_material != 0u && m.z > 0.5) { return m.xy; }
    return vec2<f32>(P.metallic, P.alpha);
}

// The pixel's base colour, pbr material (metallic, GGX α), emission and occlusion: its
// object's, with what the object's textures give (gb_material, TEXTURED) in their place.
struct Surface {
    base: vec3<f32>,
    pbr: vec2<f32>,
    emission: vec3<f32>,
    occlusion: f32,
};

fn surface_of(pid: u32, px: vec2<i32>) -> Surface {
    var s: Surface;
    s.base = patches[pid].color.rgb;
    s.pbr = pbr_material(pid);
    s.emission = patches[pid].emission.rgb;
    s.occlusion = 1.0;
    if (TEXTURED) {
        let m = textureLoad(gb_material, px, 0);
        let rg = unpack2x16unorm(m.x);
        let bm = unpack2x16unorm(m.y);
        let ro = unpack2x16unorm(m.z);
        if ((m.w & 1u) != 0u) { s.base = vec3<f32>(rg.x, rg.y, bm.x); }
        if ((m.w & 2u) != 0u && P.object_material != 0u && patches[pid].material.z > 0.5) {
            s.pbr = vec2<f32>(bm.y, ggx_alpha(ro.x));
        }
        if ((m.w & 8u) != 0u) { s.emission = s.emission * emissive_of(m.w); }
        if ((m.w & 16u) != 0u) { s.occlusion = ro.y; }
    }
    return s;
}

@compute @workgroup_size(8, 8, 1)
fn shade(@builtin(global_invocation_id) gid: vec3<u32>) {
    if (gid.x >= P.size.x || gid.y >= P.size.y) { return; }
    let px = vec2<i32>(i32(gid.x), i32(gid.y));
    let g0 = textureLoad(gb_position, px, 0);
    let g1 = textureLoad(gb_normal, px, 0);
    if (!(textureLoad(gb_depth, px, 0) < 1.0) || g0.w < 0.5) {
        textureStore(out_image, px, background(gid.xy));
        return;
    }
    let pid = u32(g0.w - 0.5);
    // The point on the patch itself, not on its triangles (the truth's shading point).
    let hit = surface_hit(pid, g0.xyz, g1.z, g1.w, normalize(g0.xyz - P.camera_pos.xyz));
    let x = hit.x;
    let u = hit.u;
    let v_param = hit.v;
    let n = patch_normal(pid, u, v_param, oct_decode(g1.xy));
    candidates(pid, u, v_param, x, n);
    mark_cube = cand.idx;
    mark_bits = vec4<u32>(0u);
    mark_env = 0u;
    let v = normalize(P.camera_pos.xyz - x);
    let r = 2.0 * dot(n, v) * n - v; // Eq. 2.4
    let pixel = pcg(gid.x + pcg(gid.y + pcg(P.seed)));

    let surface = surface_of(pid, px);
    let base = surface.base;
    var spec = vec3<f32>(0.0);
    if ((TERMS & 2u) != 0u) {
        spec = mirror(x, n, r);
    } else if ((TERMS & 4u) != 0u) {
        let t = tangent_frame(n, patch_du(pid, u, v_param));
        spec = glossy(pixel, x, n, t, v, r, base, surface.pbr);
    }
    if ((TERMS & 8u) != 0u) {
        spec *= base;
    }
    var color = spec;
    if ((TERMS & 1u) != 0u) {
        color += recon(x, n); // Eq. 3.12, 4.12
    }
    if ((TERMS & 16u) != 0u) {
        // The pbr mode draws the object's occlusion texture and its own emission.
        color = color * surface.occlusion + surface.emission;
    }
    flush_marks();
    textureStore(out_image, px, vec4<f32>(finite3(color), 1.0));
}
