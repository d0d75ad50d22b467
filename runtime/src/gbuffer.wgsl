// G-buffer pass: rasterizes the tessellated Bézier patches and the triangle meshes
// (geometry.rs) and writes, per pixel, the world position with the sample-map id, and the
// octahedral-encoded shading normal with the map parameters (u, v). shade.wgsl reads these.
// A store with textured objects draws with fs_textured instead, which also
// writes each pixel's material from the object's textures (group 1, bound per object; the
// functions below fs_main have their CPU twins in reference/material.rs, in the same order).
// Bindings in the order of `GBufferPipeline::bind_group_layout` and `ObjectTextures`
// (pipelines.rs, textures.rs).

import package::layouts::{GVertex, Params, TextureParams};
import package::octahedral::{oct_encode};
import package::shading::color::{linear_to_srgb, srgb_to_linear};

// `struct Params` (the shading pass's uniform; this pass reads view_proj and camera_pos),
// `struct GVertex` and `struct TextureParams` are generated from the Rust `ShadeUniform`,
// `GVertex` and `TextureParams` (params.rs, geometry.rs, textures.rs) and placed before this
// file (pipelines.rs).


@group(0) @binding(0) var<uniform> P: Params;
@group(0) @binding(1) var<storage, read> vertices: array<GVertex>;

struct VsOut {
    @builtin(position) @invariant clip: vec4<f32>,
    @location(0) world: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) uv: vec2<f32>,
    @location(3) @interpolate(flat) patch_id: f32,
    @location(4) @interpolate(flat) grid: f32,
    @location(5) texcoord: vec2<f32>,
    @location(6) tangent: vec4<f32>,
};

@vertex
fn vs_main(@builtin(vertex_index) index: u32) -> VsOut {
    let vert = vertices[index];
    var out: VsOut;
    out.clip = P.view_proj * vec4<f32>(vert.position_patch.xyz, 1.0);
    out.world = vert.position_patch.xyz;
    out.normal = vert.normal_u.xyz;
    out.uv = vec2<f32>(vert.normal_u.w, vert.v.x);
    out.patch_id = vert.position_patch.w;
    out.grid = vert.v.y;
    out.texcoord = vert.v.zw;
    out.tangent = vert.tangent;
    return out;
}

struct FsOut {
    @location(0) position_patch: vec4<f32>,
    @location(1) normal_uv: vec4<f32>,
};

@fragment
fn fs_main(in: VsOut) -> FsOut {
    return gbuffer(in);
}

fn gbuffer(in: VsOut) -> FsOut {
    var n = in.normal;
    let l2 = dot(n, n);
    if (l2 > 1e-20) { n = n * inverseSqrt(l2); } else { n = vec3<f32>(0.0, 0.0, 1.0); }
    var id = in.patch_id;
    var uv = in.uv;
    if (in.grid > 0.0) {
        // A mesh's atlas of k×k pages (format docs, "Triangle-mesh objects"): page
        // (px, py) = clamp(floor(uv·k), 0, k−1) is map base + py·k + px, at local uv·k − page.
        let k = in.grid;
        let page = clamp(floor(uv * k), vec2<f32>(0.0), vec2<f32>(k - 1.0));
        uv = uv * k - page;
        id = id + page.y * k + page.x;
    }
    var out: FsOut;
    out.position_patch = vec4<f32>(in.world, id);
    out.normal_uv = vec4<f32>(oct_encode(n), clamp(uv, vec2<f32>(0.0), vec2<f32>(1.0)));
    return out;
}


// The object's textures: which it has (bit i: BOUND_KINDS[i] of textures.rs: base colour,
// metallic-roughness, normal, emissive, occlusion), and one texture per kind
// (1×1 where it has none).

@group(1) @binding(0) var<uniform> T: TextureParams;
@group(1) @binding(1) var tex_base_color: texture_2d<f32>;
@group(1) @binding(2) var tex_metallic_roughness: texture_2d<f32>;
@group(1) @binding(3) var tex_normal: texture_2d<f32>;
@group(1) @binding(4) var tex_emissive: texture_2d<f32>;
@group(1) @binding(5) var tex_occlusion: texture_2d<f32>;

struct FsTexturedOut {
    @location(0) position_patch: vec4<f32>,
    @location(1) normal_uv: vec4<f32>,
    @location(2) material: vec4<u32>,
};

// Texel (x, y) of `t` with repeat, its RGB decoded from sRGB when `srgb`.
fn texel(t: texture_2d<f32>, x: i32, y: i32, srgb: bool) -> vec3<f32> {
    let size = vec2<i32>(textureDimensions(t));
    let p = vec2<i32>(((x % size.x) + size.x) % size.x, ((y % size.y) + size.y) % size.y);
    let c = textureLoad(t, p, 0).rgb;
    if (!srgb) { return c; }
    return vec3<f32>(srgb_to_linear(c.x), srgb_to_linear(c.y), srgb_to_linear(c.z));
}

// Bilinear lookup at texture coordinates `uv` (v up), repeating; as the bake's
// ImageTexture::eval.
fn bilinear(t: texture_2d<f32>, uv: vec2<f32>, srgb: bool) -> vec3<f32> {
    let size = vec2<f32>(textureDimensions(t));
    let u = uv.x - floor(uv.x);
    let v = uv.y - floor(uv.y);
    let x = u * size.x - 0.5;
    let y = (1.0 - v) * size.y - 0.5;
    let x0 = floor(x);
    let y0 = floor(y);
    let fx = clamp(x - x0, 0.0, 1.0);
    let fy = clamp(y - y0, 0.0, 1.0);
    let ix = i32(x0);
    let iy = i32(y0);
    let top = mix(texel(t, ix, iy, srgb), texel(t, ix + 1, iy, srgb), fx);
    let bottom = mix(texel(t, ix, iy + 1, srgb), texel(t, ix + 1, iy + 1, srgb), fx);
    return mix(top, bottom, fy);
}

// The pixel's material, packed for shade.wgsl (`surface_of` there): base colour RGB,
// metallic, roughness, occlusion as 16-bit unorm pairs; the texture flags in w's low byte and
// the emissive texture's RGB, sRGB-encoded to 8 bits, above them. A kind the object lacks
// reads 0 (occlusion 1) and shade.wgsl takes the object's own value for it. Occlusion is
// 1 + strength·(R − 1) (format docs, "Object textures").
fn material_texel(uv: vec2<f32>) -> vec4<u32> {
    var base = vec3<f32>(0.0);
    var mr = vec3<f32>(0.0);
    var glow = vec3<f32>(0.0);
    if ((T.flags & 1u) != 0u) { base = bilinear(tex_base_color, uv, true); }
    if ((T.flags & 2u) != 0u) { mr = bilinear(tex_metallic_roughness, uv, false); }
    if ((T.flags & 8u) != 0u) { glow = bilinear(tex_emissive, uv, true); }
    var occlusion = 1.0;
    if ((T.flags & 16u) != 0u) {
        let ao = clamp(bilinear(tex_occlusion, uv, false).x, 0.0, 1.0);
        occlusion = 1.0 + T.occlusion_strength * (ao - 1.0);
    }
    let code = vec3<u32>(round(vec3<f32>(linear_to_srgb(glow.x), linear_to_srgb(glow.y), linear_to_srgb(glow.z)) * 255.0));
    return vec4<u32>(
        pack2x16unorm(base.xy),
        pack2x16unorm(vec2<f32>(base.z, mr.z)),
        pack2x16unorm(vec2<f32>(mr.y, occlusion)),
        T.flags | (code.x << 8u) | (code.y << 16u) | (code.z << 24u),
    );
}

// The shading normal with the normal texture at `uv`: the tangent made orthogonal to the
// interpolated unit normal `n`, the bitangent w·(n × t), the texel's 2c − 1 scaled in x and y
// by the texture's scale. `n` itself where the object has no normal texture or the frame
// degenerates.
fn mapped_normal(uv: vec2<f32>, n: vec3<f32>, tangent: vec4<f32>) -> vec3<f32> {
    if ((T.flags & 4u) == 0u) { return n; }
    let c = bilinear(tex_normal, uv, false) * 2.0 - vec3<f32>(1.0);
    let t0 = tangent.xyz - n * dot(n, tangent.xyz);
    let lt = dot(t0, t0);
    if (!(lt > 1.0e-12)) { return n; }
    let t = t0 * inverseSqrt(lt);
    let b = select(-1.0, 1.0, tangent.w >= 0.0) * cross(n, t);
    let m = t * (c.x * T.normal_scale) + b * (c.y * T.normal_scale) + n * c.z;
    let lm = dot(m, m);
    if (!(lm > 1.0e-12)) { return n; }
    return m * inverseSqrt(lm);
}

@fragment
fn fs_textured(in: VsOut) -> FsTexturedOut {
    let g = gbuffer(in);
    var uv = in.texcoord;
    if (!(abs(uv.x) < 1.0e30 && abs(uv.y) < 1.0e30)) { uv = vec2<f32>(0.0); }
    var out: FsTexturedOut;
    out.position_patch = g.position_patch;
    out.normal_uv = g.normal_uv;
    if ((T.flags & 4u) != 0u) {
        var n = in.normal;
        let l2 = dot(n, n);
        if (l2 > 1e-20) { n = n * inverseSqrt(l2); } else { n = vec3<f32>(0.0, 0.0, 1.0); }
        out.normal_uv = vec4<f32>(oct_encode(mapped_normal(uv, n, in.tangent)), g.normal_uv.zw);
    }
    out.material = material_texel(uv);
    return out;
}
