// Composite: the shaded object, scaled by the host's exposure, into a host's colour target, its depth tested against and
// written into the host's depth target (host.rs binds it). A full-screen triangle; pixels the
// object does not cover (G-buffer depth still cleared to 1) are discarded.

// The host's depth is reversed (1 near, 0 far): the G-buffer stored 1 − depth.
override REVERSED: bool = false;

@group(0) @binding(0) var shaded: texture_2d<f32>;
@group(0) @binding(1) var object_depth: texture_depth_2d;
// x: the scale of the radiance written (the host camera's exposure); y: the depth slack
// (HostTarget::depth_slack), how much nearer the object's depth is written; zw unused.
@group(0) @binding(2) var<uniform> exposure: vec4<f32>;

@vertex
fn vs_main(@builtin(vertex_index) i: u32) -> @builtin(position) vec4<f32> {
    let corner = vec2<f32>(f32((i << 1u) & 2u), f32(i & 2u));
    return vec4<f32>(corner * 2.0 - 1.0, 0.0, 1.0);
}

struct FsOut {
    @location(0) color: vec4<f32>,
    @builtin(frag_depth) depth: f32,
};

@fragment
fn fs_main(@builtin(position) p: vec4<f32>) -> FsOut {
    let xy = vec2<i32>(p.xy);
    let d = textureLoad(object_depth, xy, 0);
    if d >= 1.0 {
        discard;
    }
    var out: FsOut;
    out.color = vec4<f32>(textureLoad(shaded, xy, 0).rgb * exposure.x, 1.0);
    out.depth = select(max(d - exposure.y, 0.0), min(1.0 - d + exposure.y, 1.0), REVERSED);
    return out;
}
