// The shader's root module, with its three entry points: the cube-map capture of
// trace/src/capture.rs (one invocation per texel of a batch of cubes, its samples stratified
// k × k, its random stream keyed by (seed, cube, face, texel) as on the CPU); `trace`, the
// closest-hit queries the traversal tests compare with the CPU's BVH; and `preview`.
//
// The structs the host fills (Params, Node, Tri, TriAttr, Tex, Mat, Light, Job, TexelOut,
// TraceRay, TraceHit and the preview's PreviewCamera) are generated from their Rust
// definitions (layouts.rs and scene.rs, whose docs say what each field holds): the module
// `layouts` (shader.rs).

import package::bvh::{F32_MAX, traverse};
import package::integrator::{
    Counts, Path, closest, escaped_primary, finite_or_zero, path_next, path_start, path_vertex,
    radiance,
};
import package::layouts::{
    Job, Light, Mat, Node, Params, TexelOut, TraceHit, TraceRay, Tri, TriAttr,
};
import package::preview::{camera, camera_direction, hash3, pixels, stratified_2d};
import package::scene::{finite, surface_hit};
import package::shading::color::{luminance};
import package::shading::random::{hash4, rng_f32, rng_new};

// `Params::flags`: each texel's distance is traced too.
const FLAG_DISTANCE: u32 = 1u;

// What the scene holds, fixed when the pipelines are built (features.rs `SceneFeatures`): the
// environment's kind (ENV_*) and whether it shines, whether any material emits, the delta
// lights' count, and bits 1 << kind of the light kinds (LIGHT_*), material models (MODEL_*)
// and texture kinds (TEX_*) present, and whether any material has a metallic-roughness
// texture. The compiler drops every branch no path of this scene can take: a CPU adapter,
// which runs both sides of every branch under a mask of its SIMD lanes, gains the most.
override ENV_KIND: u32;
override ENV_ACTIVE: bool;
override EMITTERS: bool;
override LIGHT_COUNT: u32;
override LIGHT_KINDS: u32;
override MATERIAL_MODELS: u32;
override TEXTURE_KINDS: u32;
override MR_TEXTURES: bool;

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<storage, read> nodes: array<Node>;
@group(0) @binding(2) var<storage, read> tris: array<Tri>;
@group(0) @binding(3) var<storage, read> attrs: array<TriAttr>;
@group(0) @binding(4) var<storage, read> materials: array<Mat>;
@group(0) @binding(5) var<storage, read> texels: array<f32>;
@group(0) @binding(6) var<storage, read> lights: array<Light>;
@group(0) @binding(7) var<storage, read> env_tables: array<vec2<f32>>;
@group(0) @binding(8) var<storage, read> jobs: array<Job>;
@group(0) @binding(9) var<storage, read_write> out: array<TexelOut>;
@group(0) @binding(10) var<storage, read> trace_rays: array<TraceRay>;
@group(0) @binding(11) var<storage, read_write> trace_hits: array<TraceHit>;

// `oslf_format::cube::face_st_to_direction`.
fn face_st_to_direction(face: u32, s: f32, t: f32) -> vec3<f32> {
    let sc = 2.0 * s - 1.0;
    let tc = 2.0 * t - 1.0;
    var d: vec3<f32>;
    switch face {
        case 0u: { d = vec3<f32>(1.0, -tc, -sc); }
        case 1u: { d = vec3<f32>(-1.0, -tc, sc); }
        case 2u: { d = vec3<f32>(sc, 1.0, tc); }
        case 3u: { d = vec3<f32>(sc, -1.0, -tc); }
        case 4u: { d = vec3<f32>(sc, -tc, 1.0); }
        default: { d = vec3<f32>(-sc, -tc, -1.0); }
    }
    let len = sqrt(d.x * d.x + d.y * d.y + d.z * d.z);
    if len > 0.0 && finite(len) {
        return d / len;
    }
    return vec3<f32>(1.0, 0.0, 0.0);
}

// Rounds of `round` samples an adaptive capture's texel takes after its pilot of n samples
// (oslf_trace::noise::rounds_after_pilot, in f32), within min_rounds..=max_rounds.
fn rounds_after_pilot(sum: f32, sum_sq: f32, n: u32, goal: f32, round: u32, min_rounds: u32, max_rounds: u32) -> u32 {
    let nf = f32(max(n, 2u));
    let mean = sum / nf;
    let variance = max((sum_sq - nf * mean * mean) / (nf - 1.0), 0.0);
    let wanted = variance / (goal * goal * mean * mean);
    var rounds = min_rounds;
    if finite(wanted) {
        rounds = u32(min(ceil(wanted / f32(max(round, 1u))), f32(max_rounds)));
    } else if variance > 0.0 {
        rounds = max_rounds;
    }
    return clamp(rounds, min_rounds, max(max_rounds, min_rounds));
}

// The pilot's rounds and the fewest after it (capture.rs PILOT_ROUNDS, MIN_ROUNDS).
const PILOT_ROUNDS: u32 = 2u;
const MIN_ROUNDS: u32 = 2u;

// Invocations per workgroup, chosen per adapter (capture.rs `workgroup_size`).
override WORKGROUP: u32 = 64u;

@compute @workgroup_size(WORKGROUP)
fn capture(@builtin(workgroup_id) wg: vec3<u32>, @builtin(local_invocation_index) local: u32) {
    let id = params.first + wg.y * params.row_invocations + wg.x * WORKGROUP + local;
    if id >= params.texels {
        return;
    }
    let res = params.resolution;
    let per_face = res * res;
    let per_cube = 6u * per_face;
    let job = jobs[id / per_cube];
    let face = (id % per_cube) / per_face;
    let texel = id % per_face;
    let x = texel % res;
    let y = texel / res;
    let objects = job.sees_objects != 0u;
    let stream = hash4(params.seed, vec2<u32>(job.index, 0u), vec2<u32>(face, 0u), vec2<u32>(texel, 0u));
    var rng = rng_new(params.seed, stream);
    var counts = Counts(0u, 0u, 0u, 0u);
    let k = params.strata;
    var sum = vec3<f32>(0.0);
    var lum_sum = 0.0;
    var lum_sq = 0.0;
    var hit_any = false;
    var n = 0u;
    // Rounds of k × k stratified samples: one without a target; with one, a pilot that
    // chooses how many follow, whose samples alone make the texel (capture.rs
    // `sampling_plan`). The samples' paths are interleaved, one traced ray per turn of the
    // loop: an invocation whose path ended starts its next sample at once instead of idling
    // while its neighbours' paths go on. Each sample draws its random numbers in the order
    // `radiance` would, so the texel's value is the same.
    var planned = params.rounds;
    var round = 0u;
    var j = 0u;
    // The next ray to trace: a sample's first (`fresh`), or its path's continuation.
    var fresh = true;
    var ray_o = job.origin;
    var ray_d = vec3<f32>(0.0);
    var path: Path;
    var first_t = F32_MAX;
    loop {
        if round >= planned {
            break;
        }
        if fresh {
            let sx = (f32(j % k) + rng_f32(&rng)) / f32(k);
            let sy = (f32(j / k) + rng_f32(&rng)) / f32(k);
            let s = (f32(x) + sx) / f32(res);
            let t = (f32(y) + sy) / f32(res);
            ray_o = job.origin;
            ray_d = face_st_to_direction(face, s, t);
        }
        let h = closest(ray_o, ray_d, objects, &counts);
        // The hit's surface, read once for either use (a CPU adapter would read it twice).
        let surface = surface_hit(h);
        var going = false;
        if fresh {
            first_t = F32_MAX;
            if h.found {
                first_t = h.t;
                path = path_start(surface, ray_d);
                going = true;
            } else {
                path.radiance = escaped_primary(ray_d);
            }
        } else {
            going = path_next(&path, h.found, surface, &rng);
        }
        if going {
            going = path_vertex(&path, objects, &rng, &counts);
        }
        fresh = !going;
        if going {
            ray_o = path.origin;
            ray_d = path.wi;
            continue;
        }
        // The sample is done.
        let r = finite_or_zero(path.radiance);
        sum += r;
        let l = luminance(r);
        lum_sum += l;
        lum_sq += l * l;
        hit_any = hit_any || first_t != F32_MAX;
        n += 1u;
        j += 1u;
        if j < k * k {
            continue;
        }
        j = 0u;
        if params.target_noise > 0.0 && round + 1u == PILOT_ROUNDS {
            planned = PILOT_ROUNDS + rounds_after_pilot(lum_sum, lum_sq, n, params.target_noise, k * k, MIN_ROUNDS, params.rounds - PILOT_ROUNDS);
            sum = vec3<f32>(0.0);
            lum_sum = 0.0;
            lum_sq = 0.0;
            n = 0u;
        }
        round += 1u;
    }
    var o: TexelOut;
    o.radiance = sum * (1.0 / f32(n));
    o.distance = 0.0;
    if (params.flags & FLAG_DISTANCE) != 0u {
        let n = f32(res);
        let centre = face_st_to_direction(face, (f32(x) + 0.5) / n, (f32(y) + 0.5) / n);
        let h = closest(job.origin, centre, objects, &counts);
        o.distance = select(F32_MAX, h.t, h.found);
    }
    o.lum_sum = lum_sum;
    o.lum_sq = lum_sq;
    o.closest = counts.closest;
    o.shadow_hit = (counts.shadow << 1u) | select(0u, 1u, hit_any);
    o.nodes = counts.nodes;
    o.tris = counts.tris;
    o.samples = n;
    out[id] = o;
}

@compute @workgroup_size(WORKGROUP)
fn trace(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = gid.x;
    if i >= arrayLength(&trace_rays) {
        return;
    }
    let r = trace_rays[i];
    let h = traverse(r.origin, r.dir, r.t_max, (r.flags & 1u) != 0u, (r.flags & 2u) != 0u);
    var o = TraceHit(F32_MAX, 0xffffffffu, 0.0, 0.0, h.nodes, h.tris, vec2<u32>(0u));
    if h.found {
        o = TraceHit(h.t, attrs[h.slot].global, h.b.y, h.b.z, h.nodes, h.tris, vec2<u32>(0u));
    }
    trace_hits[i] = o;
}

// The bake's preview: the scene camera's image path traced with the capture's integrator, one
// invocation per pixel (preview.wgsl).
@compute @workgroup_size(WORKGROUP)
fn preview(@builtin(workgroup_id) wg: vec3<u32>, @builtin(local_invocation_index) local: u32) {
    let id = params.first + wg.y * params.row_invocations + wg.x * WORKGROUP + local;
    if id >= camera.width * camera.height {
        return;
    }
    let x = id % camera.width;
    let y = id / camera.width;
    var rng = rng_new(params.seed, hash3(params.seed, vec2<u32>(x, 0u), vec2<u32>(y, 0u)));
    var counts = Counts(0u, 0u, 0u, 0u);
    let spp = max(camera.spp, 1u);
    var sum = vec3<f32>(0.0);
    for (var s = 0u; s < spp; s++) {
        let j = stratified_2d(s, spp, &rng);
        let dir = camera_direction(f32(x) + j.x, f32(y) + j.y);
        sum += radiance(camera.position, dir, true, &rng, &counts).xyz;
    }
    pixels[id] = vec4<f32>(sum / f32(spp), 1.0);
}
