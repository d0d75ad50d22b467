// Assembled by oslf_shading::wgsl::assemble from WGSL modules (root `package::composite`).
// Do not edit: edit the modules, then run this crate's tests with OSLF_BLESS=1 to write
// this file again.
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

override REVERSED: bool = false;

@group(0) @binding(0)
var shaded: texture_2d<f32>;

@group(0) @binding(1)
var object_depth: texture_depth_2d;

@group(0) @binding(2)
var<uniform> exposure: vec4<f32>;

@group(0) @binding(3)
var gb_position: texture_2d<f32>;

@group(0) @binding(4)
var gb_normal: texture_2d<f32>;

@group(0) @binding(5)
var<uniform> prepass: Prepass;

@vertex
fn vs_main(@builtin(vertex_index) i: u32) -> @builtin(position) vec4<f32> {
    let corner = vec2<f32>(f32((i << 1u) & 2u), f32(i & 2u));
    return vec4<f32>(corner * 2.0 - 1.0, 0.0, 1.0);
}

fn host_depth(d: f32, slack: f32) -> f32 {
    return select(max(d - slack, 0.0), min(1.0 - d + slack, 1.0), REVERSED);
}

struct FsOut {
    @location(0)
    color: vec4<f32>,
    @builtin(frag_depth)
    depth: f32
}

@fragment
fn fs_main(@builtin(position) p: vec4<f32>) -> FsOut {
    let xy = vec2<i32>(p.xy);
    let d = textureLoad(object_depth, xy, 0);
    if d >= 1.0 {
        discard;
    }
    var out: FsOut;
    out.color = vec4<f32>(textureLoad(shaded, xy, 0).rgb * exposure.x, 1.0);
    out.depth = host_depth(d, exposure.y);
    return out;
}

struct PrepassOut {
    @location(0)
    normal: vec4<f32>,
    @location(1)
    motion: vec2<f32>,
    @builtin(frag_depth)
    depth: f32
}

fn prepass_normal(e: vec2<f32>, normal_from_local: mat4x4<f32>) -> vec4<f32> {
    let world = (normal_from_local * vec4<f32>(oct_decode(e), 0.0)).xyz;
    let l2 = dot(world, world);
    let n = select(vec3<f32>(0.0, 0.0, 1.0), world * inverseSqrt(l2), l2 > 1e-30);
    return vec4<f32>(n * 0.5 + vec3<f32>(0.5), 1.0);
}

fn prepass_motion(x: vec4<f32>, clip_from_patch: mat4x4<f32>, previous_clip_from_patch: mat4x4<f32>) -> vec2<f32> {
    let now = clip_from_patch * x;
    let before = previous_clip_from_patch * x;
    let seen = now.w > 1e-20 && before.w > 1e-20;
    let motion = (now.xy / now.w - before.xy / before.w) * vec2<f32>(0.5, -0.5);
    return select(vec2<f32>(0.0), motion, seen);
}

@fragment
fn fs_prepass(@builtin(position) p: vec4<f32>) -> PrepassOut {
    let xy = vec2<i32>(p.xy);
    let d = textureLoad(object_depth, xy, 0);
    if d >= 1.0 {
        discard;
    }
    var out: PrepassOut;
    out.normal = prepass_normal(textureLoad(gb_normal, xy, 0).xy, prepass.normal_from_local);
    let x = vec4<f32>(textureLoad(gb_position, xy, 0).xyz, 1.0);
    out.motion = prepass_motion(x, prepass.clip_from_patch, prepass.previous_clip_from_patch);
    out.depth = host_depth(d, 0.0);
    return out;
}
