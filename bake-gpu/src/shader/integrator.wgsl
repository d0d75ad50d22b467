// The path tracer of trace/src/integrator.rs, step for step and drawing its random numbers in
// the same order: emission wherever the path meets a surface, one shadow ray per delta
// light, one environment sample and one BSDF sample combined by MIS (power heuristic), the
// BSDF sample continuing the path, Russian roulette from the 4th vertex. Its BRDFs are those
// of scene/src/material.rs: Lambertian and glTF metallic-roughness
// (scene/src/metallic_roughness.rs), with GGX and Fresnel from oslf-shading's WGSL.

import package::bvh::{F32_MAX, Hit, traverse};
import package::capture::{
    EMITTERS, ENV_ACTIVE, LIGHT_COUNT, MATERIAL_MODELS, MR_TEXTURES, attrs, lights, materials, params,
};
import package::layouts::{Mat};
import package::scene::{
    MODEL_LAMBERTIAN, MODEL_METALLIC_ROUGHNESS, SurfaceHit, clamp01, disc_radiance, environment_eval,
    environment_pdf, finite, finite_vec, material_albedo, present, safe_normalize,
    sample_environment, sample_li, surface_hit, texture_eval,
};
import package::shading::constants::{FRAC_1_PI, GGX_DIELECTRIC_F0};
import package::shading::fresnel::{fresnel_schlick, fresnel_schlick_weight};
import package::shading::ggx::{
    ggx_alpha, ggx_distribution_at, ggx_sample_visible_normal, ggx_smith_g1, ggx_visibility,
};
import package::shading::random::{Rng, rng_f32, rng_vec2};
import package::shading::warp::{
    cosine_hemisphere_pdf, frame_from_normal, sample_cosine_hemisphere, to_local, to_world,
};

// 2⁻¹⁹ (integrator::OFFSET_RELATIVE).
const OFFSET_RELATIVE: f32 = 1.9073486e-6;
const RUSSIAN_ROULETTE_START: u32 = 3u;

fn power_heuristic(pdf_a: f32, pdf_b: f32) -> f32 {
    let a = pdf_a * pdf_a;
    let b = pdf_b * pdf_b;
    let s = a + b;
    if s > 0.0 && finite(s) {
        return a / s;
    }
    if pdf_a > F32_MAX {
        return 1.0;
    }
    return 0.0;
}

// The BRDF at one path vertex (`Lobe`): Lambertian with `albedo`, or metallic-roughness with
// base colour `albedo`.
struct Lobe {
    model: u32,
    albedo: vec3<f32>,
    metallic: f32,
    roughness: f32,
}

// `MetallicRoughness::alpha`.
fn mr_alpha(l: Lobe) -> f32 {
    return ggx_alpha(l.roughness);
}

// `MetallicRoughness::eval`.
fn mr_eval(l: Lobe, n: vec3<f32>, wo: vec3<f32>, wi: vec3<f32>) -> vec3<f32> {
    let nv = dot(n, wo);
    let nl = dot(n, wi);
    if nv <= 0.0 || nl <= 0.0 {
        return vec3<f32>(0.0);
    }
    let h = safe_normalize(wo + wi);
    if all(h == vec3<f32>(0.0)) {
        return vec3<f32>(0.0);
    }
    let alpha = mr_alpha(l);
    let a2 = alpha * alpha;
    let vh = abs(dot(wo, h));
    let specular = ggx_visibility(a2, nl, nv) * ggx_distribution_at(a2, n, h);
    let k5 = fresnel_schlick_weight(vh);
    let c = l.albedo;
    let metal = specular * (c + (vec3<f32>(1.0) - c) * k5);
    let fr = fresnel_schlick(GGX_DIELECTRIC_F0, vh);
    let dielectric = c * FRAC_1_PI * (1.0 - fr) + vec3<f32>(specular * fr);
    return mix(dielectric, metal, l.metallic);
}

// `MetallicRoughness::pdf`.
fn mr_pdf(l: Lobe, n: vec3<f32>, wo: vec3<f32>, wi: vec3<f32>) -> f32 {
    let nv = dot(n, wo);
    let nl = dot(n, wi);
    if nv <= 0.0 || nl <= 0.0 {
        return 0.0;
    }
    let h = safe_normalize(wo + wi);
    if all(h == vec3<f32>(0.0)) {
        return 0.0;
    }
    let alpha = mr_alpha(l);
    let a2 = alpha * alpha;
    let specular = ggx_smith_g1(a2, nv) * ggx_distribution_at(a2, n, h) / (4.0 * nv);
    let p = 0.5 + 0.5 * l.metallic;
    return p * specular + (1.0 - p) * cosine_hemisphere_pdf(nl);
}

// Whether a lobe of `model` is metallic-roughness: decided by the scene's models alone where
// it holds one model.
fn is_metallic_roughness(model: u32) -> bool {
    if !present(MATERIAL_MODELS, MODEL_LAMBERTIAN) {
        return true;
    }
    return present(MATERIAL_MODELS, MODEL_METALLIC_ROUGHNESS) && model == MODEL_METALLIC_ROUGHNESS;
}

// The lobe of material `m` at `uv` (`Lobe::at`); `valid` false for a black Lambertian one.
fn lobe_at(m: Mat, uv: vec2<f32>, valid: ptr<function, bool>) -> Lobe {
    var l: Lobe;
    l.model = m.model;
    l.albedo = material_albedo(m, uv);
    l.metallic = m.metallic;
    l.roughness = m.roughness;
    if is_metallic_roughness(m.model) {
        if MR_TEXTURES && m.has_mr_texture != 0u {
            let c = texture_eval(m.mr_texture, uv);
            l.metallic = clamp01(c.z);
            l.roughness = clamp01(c.y);
        }
        *valid = true;
    } else {
        *valid = any(l.albedo != vec3<f32>(0.0));
    }
    return l;
}

fn lobe_f(l: Lobe, ns: vec3<f32>, wo: vec3<f32>, wi: vec3<f32>) -> vec3<f32> {
    if is_metallic_roughness(l.model) {
        return mr_eval(l, ns, wo, wi);
    }
    return l.albedo * FRAC_1_PI;
}

fn lobe_pdf(l: Lobe, ns: vec3<f32>, wo: vec3<f32>, wi: vec3<f32>, cos_theta: f32) -> f32 {
    if is_metallic_roughness(l.model) {
        return mr_pdf(l, ns, wo, wi);
    }
    return cosine_hemisphere_pdf(cos_theta);
}

struct BsdfSample {
    wi: vec3<f32>,
    weight: vec3<f32>,
    pdf: f32,
    valid: bool,
}

// `Lobe::sample`.
fn lobe_sample(l: Lobe, ns: vec3<f32>, wo: vec3<f32>, rng: ptr<function, Rng>) -> BsdfSample {
    var s: BsdfSample;
    s.valid = false;
    if !is_metallic_roughness(l.model) {
        let wi = to_world(frame_from_normal(ns), sample_cosine_hemisphere(rng_vec2(rng)));
        s.wi = wi;
        s.weight = l.albedo;
        s.pdf = cosine_hemisphere_pdf(dot(ns, wi));
        s.valid = true;
        return s;
    }
    let choice = rng_f32(rng);
    let u = rng_vec2(rng);
    let frame = frame_from_normal(ns);
    let v = to_local(frame, wo);
    if v.z <= 0.0 {
        return s;
    }
    var wi: vec3<f32>;
    if choice < 0.5 + 0.5 * l.metallic {
        let m = to_world(frame, ggx_sample_visible_normal(v, mr_alpha(l), u.x, u.y));
        wi = safe_normalize(2.0 * dot(wo, m) * m - wo);
        if all(wi == vec3<f32>(0.0)) {
            return s;
        }
    } else {
        wi = to_world(frame, sample_cosine_hemisphere(u));
    }
    let pdf = mr_pdf(l, ns, wo, wi);
    let nl = dot(ns, wi);
    if !(pdf > 0.0 && finite(pdf) && nl > 0.0) {
        return s;
    }
    let weight = mr_eval(l, ns, wo, wi) * (nl / pdf);
    if !finite_vec(weight) {
        return s;
    }
    s.wi = wi;
    s.weight = weight;
    s.pdf = pdf;
    s.valid = true;
    return s;
}

fn offset_origin(p: vec3<f32>, n: vec3<f32>, extent: f32) -> vec3<f32> {
    let delta = OFFSET_RELATIVE * max(extent, max(max(abs(p.x), abs(p.y)), abs(p.z)));
    return p + n * delta;
}

fn finite_or_zero(v: vec3<f32>) -> vec3<f32> {
    if finite_vec(v) {
        return v;
    }
    return vec3<f32>(0.0);
}

// Rays traced for one texel, by kind, and the nodes and triangles they tested (`RayStats`).
struct Counts {
    closest: u32,
    shadow: u32,
    nodes: u32,
    tris: u32,
}

fn tally(h: Hit, counts: ptr<function, Counts>) {
    (*counts).nodes += h.nodes;
    (*counts).tris += h.tris;
}

fn occluded(o: vec3<f32>, d: vec3<f32>, t_max: f32, objects: bool, counts: ptr<function, Counts>) -> bool {
    (*counts).shadow += 1u;
    let h = traverse(o, d, t_max, objects, true);
    tally(h, counts);
    return h.found;
}

fn closest(o: vec3<f32>, d: vec3<f32>, objects: bool, counts: ptr<function, Counts>) -> Hit {
    (*counts).closest += 1u;
    let h = traverse(o, d, F32_MAX, objects, false);
    tally(h, counts);
    return h;
}

fn env_active() -> bool {
    return ENV_ACTIVE;
}

// `Integrator::escaped`.
fn escaped(wi: vec3<f32>, pdf: f32, throughput: vec3<f32>) -> vec3<f32> {
    return throughput * environment_eval(wi) * power_heuristic(pdf, environment_pdf(wi));
}

// `Integrator::last_sample`: what the last vertex's BSDF sample from `origin` towards `wi`
// (density `pdf`) adds with `throughput`.
fn last_sample(origin: vec3<f32>, wi: vec3<f32>, pdf: f32, throughput: vec3<f32>, emitters: bool, objects: bool, counts: ptr<function, Counts>) -> vec3<f32> {
    if emitters {
        let h = closest(origin, wi, objects, counts);
        if h.found {
            let mi = attrs[h.slot].material;
            if mi < arrayLength(&materials) {
                return throughput * materials[mi].emission;
            }
            return vec3<f32>(0.0);
        }
        if env_active() {
            return escaped(wi, pdf, throughput);
        }
        return vec3<f32>(0.0);
    }
    if occluded(origin, wi, F32_MAX, objects, counts) {
        return vec3<f32>(0.0);
    }
    return escaped(wi, pdf, throughput);
}

// `oriented_normals`: the geometric and shading normals of `hit` facing the incoming ray.
fn oriented_normals(hit: SurfaceHit, incoming: vec3<f32>) -> array<vec3<f32>, 2> {
    var ng = safe_normalize(hit.geometric_normal);
    if all(ng == vec3<f32>(0.0)) {
        ng = -incoming;
    }
    if dot(ng, incoming) > 0.0 {
        ng = -ng;
    }
    var ns = safe_normalize(hit.shading_normal);
    if all(ns == vec3<f32>(0.0)) {
        ns = ng;
    }
    if dot(ns, ng) < 0.0 {
        ns = -ns;
    }
    return array<vec3<f32>, 2>(ng, ns);
}

// `russian_roulette`: whether the path survives (probability q, the throughput's largest
// channel up to 0.95), its throughput then divided by q.
fn russian_roulette(throughput: ptr<function, vec3<f32>>, rng: ptr<function, Rng>) -> bool {
    let q = min(max(max((*throughput).x, (*throughput).y), (*throughput).z), 0.95);
    if !(q > 0.0) || rng_f32(rng) >= q {
        return false;
    }
    *throughput = *throughput / q;
    return true;
}

// A path in flight: `Integrator::radiance_leaving`'s loop state, so that a caller may trace
// each vertex's continuation itself (the capture interleaves its samples' paths, capture.wgsl).
struct Path {
    radiance: vec3<f32>,
    throughput: vec3<f32>,
    hit: SurfaceHit,
    incoming: vec3<f32>,
    bounce: u32,
    // The continuation after `path_vertex` returned true: its origin, direction and density.
    origin: vec3<f32>,
    wi: vec3<f32>,
    pdf: f32,
}

// A path at its first hit `first`, reached along `incoming`.
fn path_start(first: SurfaceHit, incoming: vec3<f32>) -> Path {
    var p: Path;
    p.radiance = vec3<f32>(0.0);
    p.throughput = vec3<f32>(1.0);
    p.hit = first;
    p.incoming = incoming;
    p.bounce = 0u;
    return p;
}

// One vertex of `radiance_leaving`'s loop at `(*path).hit`: its emission, one shadow ray per
// delta light, the environment sample and the BSDF sample. True when the path goes on along
// `(*path).origin`, `(*path).wi`: trace that ray's closest hit and give it to `path_next`.
fn path_vertex(path: ptr<function, Path>, objects: bool, rng: ptr<function, Rng>, counts: ptr<function, Counts>) -> bool {
    let env_on = env_active();
    let emitters = EMITTERS;
    let hit = (*path).hit;
    let normals = oriented_normals(hit, (*path).incoming);
    let ng = normals[0];
    let ns = normals[1];
    let wo = -(*path).incoming;
    if hit.material >= arrayLength(&materials) {
        return false;
    }
    let m = materials[hit.material];
    let throughput = (*path).throughput;
    (*path).radiance += throughput * m.emission;
    var valid = false;
    let lobe = lobe_at(m, hit.uv, &valid);
    if !valid {
        return false;
    }
    let p = hit.position;
    let origin = offset_origin(p, ng, hit.extent);

    // Delta lights.
    for (var i = 0u; i < LIGHT_COUNT; i++) {
        let ls = sample_li(lights[i], p);
        if !ls.valid {
            continue;
        }
        let c = dot(ns, ls.dir);
        if c <= 0.0 || dot(ng, ls.dir) <= 0.0 {
            continue;
        }
        var t_max = F32_MAX;
        if ls.distance != F32_MAX {
            t_max = ls.distance * (1.0 - 1e-4);
        }
        if !occluded(origin, ls.dir, t_max, objects, counts) {
            (*path).radiance += throughput * lobe_f(lobe, ns, wo, ls.dir) * ls.irradiance * c;
        }
    }

    // Environment light sample (MIS with the BSDF sample below).
    if env_on {
        let es = sample_environment(rng_vec2(rng));
        let c = dot(ns, es.dir);
        if es.pdf > 0.0 && c > 0.0 && dot(ng, es.dir) > 0.0 {
            if !occluded(origin, es.dir, F32_MAX, objects, counts) {
                let le = environment_eval(es.dir);
                let w = power_heuristic(es.pdf, lobe_pdf(lobe, ns, wo, es.dir, c));
                (*path).radiance += throughput * lobe_f(lobe, ns, wo, es.dir) * le * (c * w / es.pdf);
            }
        }
    }

    // BSDF sample: environment MIS partner and path continuation.
    let gather_next = (*path).bounce < params.max_bounces;
    if !env_on && !gather_next && !emitters {
        return false;
    }
    let bs = lobe_sample(lobe, ns, wo, rng);
    if !bs.valid {
        return false;
    }
    if bs.pdf <= 0.0 || dot(ng, bs.wi) <= 0.0 {
        return false;
    }
    (*path).throughput = throughput * bs.weight;
    if !gather_next {
        (*path).radiance += last_sample(origin, bs.wi, bs.pdf, (*path).throughput, emitters, objects, counts);
        return false;
    }
    (*path).origin = origin;
    (*path).wi = bs.wi;
    (*path).pdf = bs.pdf;
    return true;
}

// The closest hit of the continuation `path_vertex` asked for (`found`, and its surface
// `next`): the environment where it escapes, else Russian roulette from the 4th vertex. True
// when the path goes on at `next` (`path_vertex` again).
fn path_next(path: ptr<function, Path>, found: bool, next: SurfaceHit, rng: ptr<function, Rng>) -> bool {
    if !found {
        if env_active() {
            (*path).radiance += escaped((*path).wi, (*path).pdf, (*path).throughput);
        }
        return false;
    }
    (*path).bounce += 1u;
    if (*path).bounce >= RUSSIAN_ROULETTE_START {
        var throughput = (*path).throughput;
        if !russian_roulette(&throughput, rng) {
            return false;
        }
        (*path).throughput = throughput;
    }
    (*path).hit = next;
    (*path).incoming = (*path).wi;
    return true;
}

// `Integrator::radiance_leaving` from the first hit `first` of a ray along `incoming`.
fn radiance_leaving(first: SurfaceHit, incoming: vec3<f32>, objects: bool, rng: ptr<function, Rng>, counts: ptr<function, Counts>) -> vec3<f32> {
    var path = path_start(first, incoming);
    loop {
        if !path_vertex(&path, objects, rng, counts) {
            break;
        }
        let next = closest(path.origin, path.wi, objects, counts);
        if !path_next(&path, next.found, surface_hit(next), rng) {
            break;
        }
    }
    return finite_or_zero(path.radiance);
}

// What a ray along `dir` that escapes the scene brings: the environment and the discs of the
// distant lights.
fn escaped_primary(dir: vec3<f32>) -> vec3<f32> {
    var l = environment_eval(dir);
    for (var i = 0u; i < LIGHT_COUNT; i++) {
        l += disc_radiance(lights[i], dir);
    }
    return finite_or_zero(l);
}

// `Integrator::radiance_from`: radiance arriving at `o` from `-dir`, and the first hit's
// distance (F32_MAX when the ray escapes).
fn radiance(o: vec3<f32>, dir: vec3<f32>, objects: bool, rng: ptr<function, Rng>, counts: ptr<function, Counts>) -> vec4<f32> {
    let first = closest(o, dir, objects, counts);
    if !first.found {
        return vec4<f32>(escaped_primary(dir), F32_MAX);
    }
    return vec4<f32>(radiance_leaving(surface_hit(first), dir, objects, rng, counts), first.t);
}
