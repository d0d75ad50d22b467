// G-buffer pass: rasterizes the tessellated Bézier patches and the triangle meshes
// (geometry.rs) and writes, per pixel, the world position with the sample-map id, and the
// octahedral-encoded shading normal with the map parameters (u, v). shade.wgsl reads these.
// Bindings in the order of `GBufferPipeline::bind_group_layout` (pipelines.rs).

struct Params {
    view_proj: mat4x4<f32>,
    camera_pos: vec4<f32>,
};

// One vertex: position and map id + 1 (as f32, exact below 2^24); normal and u; v and the
// atlas grid k (0 for a Bézier patch; for a mesh the id is its first map and (u, v) its atlas
// uv, made page-local per fragment).
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
    @location(4) @interpolate(flat) grid: f32,
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
