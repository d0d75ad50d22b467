// G-buffer pass: rasterizes the tessellated Bézier patches (geometry.rs) and writes, per pixel,
// the world position with the patch id, and the octahedral-encoded shading normal with the
// patch parameters (u, v). shade.wgsl reads these. Bindings in the order of
// `GBufferPipeline::bind_group_layout` (pipelines.rs).

struct Params {
    view_proj: mat4x4<f32>,
    camera_pos: vec4<f32>,
};

// One vertex: position and patch id + 1 (as f32, exact below 2^24); normal and u; v.
struct GVertex {
    position_patch: vec4<f32>,
    normal_u: vec4<f32>,
    v: vec4<f32>,
};

@group(0) @binding(0) var<uniform> P: Params;
@group(0) @binding(1) var<storage, read> vertices: array<GVertex>;

struct VsOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) world: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) uv: vec2<f32>,
    @location(3) @interpolate(flat) patch_id: f32,
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
    return out;
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

struct FsOut {
    @location(0) position_patch: vec4<f32>,
    @location(1) normal_uv: vec4<f32>,
};

@fragment
fn fs_main(in: VsOut) -> FsOut {
    var n = in.normal;
    let l2 = dot(n, n);
    if (l2 > 1e-20) { n = n * inverseSqrt(l2); } else { n = vec3<f32>(0.0, 0.0, 1.0); }
    var out: FsOut;
    out.position_patch = vec4<f32>(in.world, in.patch_id);
    out.normal_uv = vec4<f32>(oct_encode(n), clamp(in.uv, vec2<f32>(0.0), vec2<f32>(1.0)));
    return out;
}
