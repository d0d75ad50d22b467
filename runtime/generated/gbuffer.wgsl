// Assembled by oslf_shading::wgsl::assemble from WGSL modules (root `package::gbuffer`).
// Do not edit: edit the modules, then run this crate's tests with OSLF_BLESS=1 to write
// this file again.
fn srgb_to_linear(c: f32) -> f32 {
    if (c <= 0.04045) {
        return c / 12.92;
    }
    return pow((c + 0.055) / 1.055, 2.4);
}

fn linear_to_srgb(c: f32) -> f32 {
    let x = select(clamp(c, 0.0, 1.0), 0.0, c != c);
    if (x <= 0.0031308) {
        return 12.92 * x;
    }
    return 1.055 * pow(x, 1.0 / 2.4) - 0.055;
}

fn aces(x_in: f32) -> f32 {
    if (!(x_in > 0.0)) {
        return 0.0;
    }
    let x = min(x_in, 1000000.0);
    return clamp((x * (2.51 * x + 0.03)) / (x * (2.43 * x + 0.59) + 0.14), 0.0, 1.0);
}

fn luminance(c: vec3<f32>) -> f32 {
    return 0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z;
}

struct Params {
    view_proj: mat4x4<f32>,
    camera_pos: vec4<f32>,
    size: vec2<u32>,
    terms: u32,
    blend: u32,
    blend_n: f32,
    source: u32,
    m: u32,
    order: u32,
    rs: f32,
    rd: f32,
    nu: f32,
    nv: f32,
    cos_phi_shader: f32,
    seed: u32,
    sample_count: u32,
    env_cube: u32,
    map_res: u32,
    index16: u32,
    cube_res: u32,
    slots_per_texture: u32,
    cam_right: vec4<f32>,
    cam_up: vec4<f32>,
    cam_forward: vec4<f32>,
    bg_color: vec4<f32>,
    background: u32,
    mip_levels: u32,
    depth_steps: u32,
    depth_thickness: f32,
    probe_pos: vec4<f32>,
    box_min: vec4<f32>,
    box_max: vec4<f32>,
    metallic: f32,
    alpha: f32,
    object_material: u32,
    min_metallic: f32,
    split_sum: u32,
    irradiance: u32,
    surface_error: f32,
    pad2: u32
}

struct GVertex {
    position_patch: vec4<f32>,
    normal_u: vec4<f32>,
    v: vec4<f32>,
    tangent: vec4<f32>
}

struct TextureParams {
    flags: u32,
    normal_scale: f32,
    occlusion_strength: f32,
    pad: u32
}

struct Prepass {
    clip_from_patch: mat4x4<f32>,
    previous_clip_from_patch: mat4x4<f32>,
    normal_from_local: mat4x4<f32>
}

fn oct_encode(n: vec3<f32>) -> vec2<f32> {
    let p = n.xy / (abs(n.x) + abs(n.y) + abs(n.z));
    if (n.z < 0.0) {
        let sx = select(-1.0, 1.0, p.x >= 0.0);
        let sy = select(-1.0, 1.0, p.y >= 0.0);
        return vec2<f32>((1.0 - abs(p.y)) * sx, (1.0 - abs(p.x)) * sy);
    }
    return p;
}

fn oct_decode(e: vec2<f32>) -> vec3<f32> {
    var n = vec3<f32>(e.x, e.y, 1.0 - abs(e.x) - abs(e.y));
    if (n.z < 0.0) {
        let sx = select(-1.0, 1.0, n.x >= 0.0);
        let sy = select(-1.0, 1.0, n.y >= 0.0);
        n = vec3<f32>((1.0 - abs(n.y)) * sx, (1.0 - abs(n.x)) * sy, n.z);
    }
    return normalize(n);
}

@group(0) @binding(0)
var<uniform> P: Params;

@group(0) @binding(1)
var<storage, read> vertices: array<GVertex>;

struct VsOut {
    @builtin(position) @invariant
    clip: vec4<f32>,
    @location(0)
    world: vec3<f32>,
    @location(1)
    normal: vec3<f32>,
    @location(2)
    uv: vec2<f32>,
    @location(3) @interpolate(flat)
    patch_id: f32,
    @location(4) @interpolate(flat)
    grid: f32,
    @location(5)
    texcoord: vec2<f32>,
    @location(6)
    tangent: vec4<f32>
}

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
    @location(0)
    position_patch: vec4<f32>,
    @location(1)
    normal_uv: vec4<f32>
}

@fragment
fn fs_main(in: VsOut) -> FsOut {
    return gbuffer(in);
}

fn gbuffer(in: VsOut) -> FsOut {
    var n = in.normal;
    let l2 = dot(n, n);
    if (l2 > 1e-20) {
        n = n * inverseSqrt(l2);
    }
    else {
        n = vec3<f32>(0.0, 0.0, 1.0);
    }
    var id = in.patch_id;
    var uv = in.uv;
    if (in.grid > 0.0) {
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

@group(1) @binding(0)
var<uniform> T: TextureParams;

@group(1) @binding(1)
var tex_base_color: texture_2d<f32>;

@group(1) @binding(2)
var tex_metallic_roughness: texture_2d<f32>;

@group(1) @binding(3)
var tex_normal: texture_2d<f32>;

@group(1) @binding(4)
var tex_emissive: texture_2d<f32>;

@group(1) @binding(5)
var tex_occlusion: texture_2d<f32>;

struct FsTexturedOut {
    @location(0)
    position_patch: vec4<f32>,
    @location(1)
    normal_uv: vec4<f32>,
    @location(2)
    material: vec4<u32>
}

fn texel(t: texture_2d<f32>, x: i32, y: i32, srgb: bool) -> vec3<f32> {
    let size = vec2<i32>(textureDimensions(t));
    let p = vec2<i32>(((x % size.x) + size.x) % size.x, ((y % size.y) + size.y) % size.y);
    let c = textureLoad(t, p, 0).rgb;
    if (!srgb) {
        return c;
    }
    return vec3<f32>(srgb_to_linear(c.x), srgb_to_linear(c.y), srgb_to_linear(c.z));
}

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

fn material_texel(uv: vec2<f32>) -> vec4<u32> {
    var base = vec3<f32>(0.0);
    var mr = vec3<f32>(0.0);
    var glow = vec3<f32>(0.0);
    if ((T.flags & 1u) != 0u) {
        base = bilinear(tex_base_color, uv, true);
    }
    if ((T.flags & 2u) != 0u) {
        mr = bilinear(tex_metallic_roughness, uv, false);
    }
    if ((T.flags & 8u) != 0u) {
        glow = bilinear(tex_emissive, uv, true);
    }
    var occlusion = 1.0;
    if ((T.flags & 16u) != 0u) {
        let ao = clamp(bilinear(tex_occlusion, uv, false).x, 0.0, 1.0);
        occlusion = 1.0 + T.occlusion_strength * (ao - 1.0);
    }
    let code = vec3<u32>(round(vec3<f32>(linear_to_srgb(glow.x), linear_to_srgb(glow.y), linear_to_srgb(glow.z)) * 255.0));
    return vec4<u32>(pack2x16unorm(base.xy), pack2x16unorm(vec2<f32>(base.z, mr.z)), pack2x16unorm(vec2<f32>(mr.y, occlusion)), T.flags | (code.x << 8u) | (code.y << 16u) | (code.z << 24u));
}

fn mapped_normal(uv: vec2<f32>, n: vec3<f32>, tangent: vec4<f32>) -> vec3<f32> {
    if ((T.flags & 4u) == 0u) {
        return n;
    }
    let c = bilinear(tex_normal, uv, false) * 2.0 - vec3<f32>(1.0);
    let t0 = tangent.xyz - n * dot(n, tangent.xyz);
    let lt = dot(t0, t0);
    if (!(lt > 1e-12)) {
        return n;
    }
    let t = t0 * inverseSqrt(lt);
    let b = select(-1.0, 1.0, tangent.w >= 0.0) * cross(n, t);
    let m = t * (c.x * T.normal_scale) + b * (c.y * T.normal_scale) + n * c.z;
    let lm = dot(m, m);
    if (!(lm > 1e-12)) {
        return n;
    }
    return m * inverseSqrt(lm);
}

@fragment
fn fs_textured(in: VsOut) -> FsTexturedOut {
    let g = gbuffer(in);
    var uv = in.texcoord;
    if (!(abs(uv.x) < 1e30 && abs(uv.y) < 1e30)) {
        uv = vec2<f32>(0.0);
    }
    var out: FsTexturedOut;
    out.position_patch = g.position_patch;
    out.normal_uv = g.normal_uv;
    if ((T.flags & 4u) != 0u) {
        var n = in.normal;
        let l2 = dot(n, n);
        if (l2 > 1e-20) {
            n = n * inverseSqrt(l2);
        }
        else {
            n = vec3<f32>(0.0, 0.0, 1.0);
        }
        out.normal_uv = vec4<f32>(oct_encode(mapped_normal(uv, n, in.tangent)), g.normal_uv.zw);
    }
    out.material = material_texel(uv);
    return out;
}
