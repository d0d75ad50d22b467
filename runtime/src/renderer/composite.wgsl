// A host frame's full-screen passes over the object's G-buffer (host.rs and prepass.rs bind
// them). Pixels the object does not cover (G-buffer depth still cleared to 1) are discarded.
// - fs_main, the composite: the shaded object, scaled by the host's exposure, into the host's
//   colour target, its depth tested against and written into the host's depth target.
// - fs_prepass, the prepass: the object's depth, world normal and motion vector into the
//   host's depth prepass (Bevy's: depth, then normals and motion vectors as its prepass
//   writes them), before the host shades anything.
// Its CPU twin: reference/composite.rs, function for function.

import package::layouts::{Prepass};
import package::octahedral::{oct_decode};

// The host's depth is reversed (1 near, 0 far): the G-buffer stored 1 − depth.
override REVERSED: bool = false;

@group(0) @binding(0) var shaded: texture_2d<f32>;
@group(0) @binding(1) var object_depth: texture_depth_2d;
// x: the scale of the radiance written (the host camera's exposure); y: the depth slack
// (HostTarget::depth_slack), how much nearer the object's depth is written; zw unused.
@group(0) @binding(2) var<uniform> exposure: vec4<f32>;
@group(0) @binding(3) var gb_position: texture_2d<f32>;
@group(0) @binding(4) var gb_normal: texture_2d<f32>;
@group(0) @binding(5) var<uniform> prepass: Prepass;

@vertex
fn vs_main(@builtin(vertex_index) i: u32) -> @builtin(position) vec4<f32> {
    let corner = vec2<f32>(f32((i << 1u) & 2u), f32(i & 2u));
    return vec4<f32>(corner * 2.0 - 1.0, 0.0, 1.0);
}

// The host's depth of G-buffer depth `d`, `slack` nearer.
fn host_depth(d: f32, slack: f32) -> f32 {
    return select(max(d - slack, 0.0), min(1.0 - d + slack, 1.0), REVERSED);
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
    out.depth = host_depth(d, exposure.y);
    return out;
}

// Bevy's prepass targets, in its order: normals (n·½ + ½, world space), motion vectors.
struct PrepassOut {
    @location(0) normal: vec4<f32>,
    @location(1) motion: vec2<f32>,
    @builtin(frag_depth) depth: f32,
};

// The host's normal target of the object's normal `e` (octahedral, its own space): the world
// normal through `normal_from_local` (world_from_local's inverse transpose, so that uneven
// scales keep it perpendicular to the surface) as n·½ + ½; +z where it vanishes.
fn prepass_normal(e: vec2<f32>, normal_from_local: mat4x4<f32>) -> vec4<f32> {
    let world = (normal_from_local * vec4<f32>(oct_decode(e), 0.0)).xyz;
    let l2 = dot(world, world);
    let n = select(vec3<f32>(0.0, 0.0, 1.0), world * inverseSqrt(l2), l2 > 1e-30);
    return vec4<f32>(n * 0.5 + vec3<f32>(0.5), 1.0);
}

// The screen motion of the G-buffer point `x` since the previous frame, in UV units (y down),
// as Bevy's prepass writes it; 0 where either frame sees it behind the eye.
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
