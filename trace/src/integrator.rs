//! A unidirectional path tracer with next-event estimation.
//!
//! # Estimator
//! At every surface vertex (two-sided; Lambertian, BRDF `albedo / π`, or glTF's
//! metallic-roughness, [`oslf_scene::metallic_roughness`], whose BRDF and sampling density replace
//! the Lambertian ones below):
//! - **Delta lights** (point, sun): one shadow ray each, contribution `f · E · cos θ`.
//!   Delta lights cannot be hit by scattered rays, so this is their only path.
//! - **Environment**: one light sample from [`Environment::sample_environment`] plus the
//!   BSDF sample (cosine-weighted for a Lambertian surface) that also continues the path,
//!   combined by multiple importance sampling with the power heuristic (Veach 1997).
//! - **Emission**: a surface's emission ([`Material::emission`]) is added with the path's
//!   throughput wherever the path meets it: the primary hit and every BSDF sample's hit, the
//!   last vertex's too (whose sample is then a closest-hit query, in scenes with emitters).
//!   Emitters are not light-sampled, so this is their only estimator (no MIS weight).
//! - **Continuation**: the BSDF sample. If it escapes, it contributes the environment with its
//!   MIS weight and the path ends. If it hits a surface, that surface's direct lighting is
//!   gathered only while the bounce budget lasts (below).
//!
//! The sun's visible disc ([`Light::disc_radiance`]) is added only when the *primary* ray
//! escapes, never to scattered rays (it is already counted by the sun's shadow rays).
//!
//! # `max_bounces`
//! The number of bounces *after the first hit* whose light is gathered. With 0, only
//! direct lighting at the first hit is computed (delta lights + environment). With `k`, direct
//! lighting is gathered at the first `k + 1` surface vertices of the path: radiance that has
//! been reflected up to `k` times before the reflection towards the ray. In a closed sphere of
//! albedo `a` lit by a light inside it, the leaving radiance is
//! `L_direct · (1 + a + … + a^k)`.
//!
//! Russian roulette starts at the 4th vertex (`bounce ≥ 3`), with survival probability
//! `min(max component of throughput, 0.95)`; it draws from the path's own [`Rng`], so it is
//! deterministic.
//!
//! # Ray spawning
//! Primary rays are traced exactly from their origin (the bake shoots them from OSLF sample
//! points ε above the surface). Secondary rays start at `p + n_g · δ` on the side of the
//! geometric normal facing the outgoing direction, with
//! `δ = 2⁻¹⁹ · e`, `e` = [`SurfaceHit::extent`], the largest coordinate magnitude of the hit
//! triangle's corners:
//! - the hit position is interpolated from those corners, so its rounding error is a few ulps
//!   of `e` (pbrt's bound is γ₇·e ≈ 2⁻²¹·e); δ is 4× that bound (8–16 ulps of `e`), and the
//!   ray–triangle test adds its own guard (a hit is accepted only at a `t` provably above its
//!   rounding error, and not on the plane of a triangle through the origin, `bvh`);
//! - δ is *relative* only: the bake of a scene scaled by s is the bake of the unscaled scene
//!   scaled by s (tested from s = 10⁻³ to 10³ in `tests/extremes.rs`). An absolute term (this
//!   crate had 10⁻⁴) is as large as ε for an object of a few thousandths of a unit and lets
//!   light leak into its creases. Using `e` rather than `|p|` covers hit points near the origin
//!   on a triangle whose corners are far from it (a ground plane 100 units wide);
//! - far from the origin δ grows with the coordinates: 0.19 units at 10⁵, where one ulp is
//!   0.0078. That is what f32 resolves there; the scene validation refuses an ε that f32 cannot
//!   resolve at the object's distance from the origin (`scene::min_epsilon`).
//!
//! Back faces: the geometric normal is flipped towards the incoming ray and the shading normal
//! onto the same side. Directions below the geometric surface (possible with shading normals)
//! carry no light.
//!
//! # Numbers
//! Accumulation is in f32. No value is clamped; every density is checked before dividing, so
//! no NaN or infinity is produced from finite scene data.

use std::f32::consts::FRAC_1_PI;

use glam::Vec3;

use crate::ray::{Intersector, Ray, SurfaceHit, OCCLUSION_STREAMS};
use oslf_scene::environment::Environment;
use oslf_scene::light::Light;
use oslf_scene::material::Material;
use oslf_scene::metallic_roughness::MetallicRoughness;
use oslf_shading::random::Rng;
use oslf_shading::warp::{cosine_hemisphere_pdf, sample_cosine_hemisphere, Frame};

/// Vertex index from which Russian roulette may end a path.
const RUSSIAN_ROULETTE_START: u32 = 3;
/// The ray-origin offset relative to the hit triangle's extent, 2⁻¹⁹ (see the module
/// documentation).
pub const OFFSET_RELATIVE: f32 = 1.0 / (1u32 << 19) as f32;

/// Rays traced, by kind.
#[derive(Default, Clone, Copy, Debug, PartialEq, Eq)]
pub struct RayStats {
    /// Closest-hit queries (primary and continuation rays).
    pub closest: u64,
    /// Any-hit (shadow) queries.
    pub shadow: u64,
    /// BVH nodes tested by those queries, where the tracer counts them (the GPU path
    /// tracer; 0 where it does not).
    pub nodes: u64,
    /// Triangles tested by those queries, where the tracer counts them (as `nodes`).
    pub triangles: u64,
}

impl RayStats {
    /// Adds another tally to this one.
    pub fn add(&mut self, other: &RayStats) {
        self.closest += other.closest;
        self.shadow += other.shadow;
        self.nodes += other.nodes;
        self.triangles += other.triangles;
    }

    /// All rays traced.
    pub fn total(&self) -> u64 {
        self.closest + self.shadow
    }
}

/// The result of tracing one primary ray.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sample {
    /// Radiance arriving at the ray origin along `-dir`.
    pub radiance: Vec3,
    /// Distance to the first hit, `f32::MAX` if the ray escaped.
    pub distance: f32,
}

/// The light transport of a scene: geometry, materials, lights and environment.
pub struct Integrator<'a, I: Intersector> {
    pub geometry: &'a I,
    /// Indexed by [`SurfaceHit::material`]; a hit with an out-of-range index is black.
    pub materials: &'a [Material],
    pub lights: &'a [Light],
    pub environment: &'a Environment,
    /// See the module documentation.
    pub max_bounces: u32,
    /// Whether a material emits: then the last vertex's BSDF sample must learn what it hits.
    emitters: bool,
}

/// The origin for a ray leaving the hit point `p` on the side of `n` (unit); `extent` is the
/// hit's [`SurfaceHit::extent`] (see the module documentation).
pub fn offset_origin(p: Vec3, n: Vec3, extent: f32) -> Vec3 {
    let delta = OFFSET_RELATIVE * extent.max(p.abs().max_element());
    p + n * delta
}

/// The power heuristic with β = 2 for one sample of each strategy.
fn power_heuristic(pdf_a: f32, pdf_b: f32) -> f32 {
    let a = pdf_a * pdf_a;
    let b = pdf_b * pdf_b;
    let s = a + b;
    if s > 0.0 && s.is_finite() {
        a / s
    } else if pdf_a.is_infinite() {
        1.0
    } else {
        0.0
    }
}

impl<'a, I: Intersector> Integrator<'a, I> {
    /// The integrator of `scene` (its materials, lights, environment and bounces) over
    /// `geometry`.
    pub fn for_scene(scene: &'a oslf_scene::scene::Scene, geometry: &'a I) -> Self {
        Self::new(
            geometry,
            &scene.materials,
            &scene.lights,
            &scene.environment,
            scene.bake.bounces,
        )
    }

    /// The light transport of `materials` (indexed by [`SurfaceHit::material`]), `lights`
    /// and `environment` over `geometry`, gathering `max_bounces` bounces.
    pub fn new(
        geometry: &'a I,
        materials: &'a [Material],
        lights: &'a [Light],
        environment: &'a Environment,
        max_bounces: u32,
    ) -> Self {
        Integrator {
            geometry,
            materials,
            lights,
            environment,
            max_bounces,
            emitters: materials.iter().any(|m| m.emission != Vec3::ZERO),
        }
    }

    /// The same integrator over other geometry.
    pub fn with_geometry<J: Intersector>(&self, geometry: &'a J) -> Integrator<'a, J> {
        Integrator {
            geometry,
            materials: self.materials,
            lights: self.lights,
            environment: self.environment,
            max_bounces: self.max_bounces,
            emitters: self.emitters,
        }
    }
}

impl<I: Intersector> Integrator<'_, I> {
    /// Radiance arriving at `ray.origin` from direction `-ray.dir` (`ray.dir` unit length).
    /// The first segment starts exactly at `ray.origin`. Every ray traced is counted in `stats`.
    pub fn radiance(&self, ray: &Ray, rng: &mut Rng, stats: &mut RayStats) -> Sample {
        stats.closest += 1;
        let first = self.geometry.intersect(ray, f32::MAX);
        self.radiance_from(ray, first.as_ref(), rng, stats)
    }

    /// [`Integrator::radiance`] for a primary ray whose closest hit (`None`: it escaped),
    /// `self.geometry.intersect(ray, f32::MAX)`, the caller has already traced and counted (a
    /// cube-map capture traces a tile's primary rays as one packet). The same result, with
    /// the same random numbers drawn.
    pub fn radiance_from(
        &self,
        ray: &Ray,
        first: Option<&SurfaceHit>,
        rng: &mut Rng,
        stats: &mut RayStats,
    ) -> Sample {
        let Some(first) = first else {
            let mut l = self.environment.eval(ray.dir);
            for light in self.lights {
                l += light.disc_radiance(ray.dir);
            }
            return Sample {
                radiance: finite_or_zero(l),
                distance: f32::MAX,
            };
        };
        Sample {
            radiance: self.radiance_leaving(first, ray.dir, rng, stats),
            distance: first.t,
        }
    }

    /// Radiance leaving the surface at `first` towards `-incoming`: the path tracer of
    /// [`Integrator::radiance`] from its first hit on. The ground-truth renders start here at
    /// hits they found themselves (on the OSLF object alone).
    pub fn radiance_leaving(
        &self,
        first: &SurfaceHit,
        incoming: Vec3,
        rng: &mut Rng,
        stats: &mut RayStats,
    ) -> Vec3 {
        let env_active = !self.environment.is_black();
        // Emitting surfaces are found by the BSDF samples alone (no light samples aim at
        // them), so the last vertex's sample must learn what it hits, not only whether.
        let emitters = self.emitters;
        let mut radiance = Vec3::ZERO;
        let mut throughput = Vec3::ONE;
        let mut hit: SurfaceHit = *first;
        let mut incoming = incoming;
        let mut bounce = 0u32;
        loop {
            let (ng, ns) = oriented_normals(&hit, incoming);
            let wo = -incoming;
            let material = self.materials.get(hit.material as usize);
            if let Some(m) = material {
                radiance += throughput * m.emission;
            }
            let Some(lobe) = material.and_then(|m| Lobe::at(m, hit.uv)) else {
                break;
            };
            let p = hit.position;
            let origin = offset_origin(p, ng, hit.extent);

            // Delta lights.
            for (i, light) in self.lights.iter().enumerate() {
                // Irradiance at the shading point itself; the shadow ray leaves from the
                // offset origin.
                let Some(ls) = light.sample_li(p) else {
                    continue;
                };
                let cos = ns.dot(ls.dir);
                if cos <= 0.0 || ng.dot(ls.dir) <= 0.0 {
                    continue;
                }
                stats.shadow += 1;
                let t_max = if ls.distance == f32::MAX {
                    f32::MAX
                } else {
                    ls.distance * (1.0 - 1e-4)
                };
                let stream = stream::light(i, bounce);
                if !self
                    .geometry
                    .occluded_in_stream(&Ray::new(origin, ls.dir), t_max, stream)
                {
                    radiance += throughput * lobe.f(ns, wo, ls.dir) * ls.irradiance * cos;
                }
            }

            // Environment light sample (MIS with the BSDF sample below).
            if env_active {
                let (wi, pdf_light) = self.environment.sample_environment(rng.next_vec2());
                let cos = ns.dot(wi);
                if pdf_light > 0.0 && cos > 0.0 && ng.dot(wi) > 0.0 {
                    stats.shadow += 1;
                    if !self.geometry.occluded_in_stream(
                        &Ray::new(origin, wi),
                        f32::MAX,
                        stream::environment(wi, bounce),
                    ) {
                        let le = self.environment.eval(wi);
                        let w = power_heuristic(pdf_light, lobe.pdf(ns, wo, wi, cos));
                        radiance += throughput * lobe.f(ns, wo, wi) * le * (cos * w / pdf_light);
                    }
                }
            }

            // BSDF sample: environment MIS partner and path continuation.
            let gather_next = bounce < self.max_bounces;
            if !env_active && !gather_next && !emitters {
                break;
            }
            let Some((wi, weight, pdf_bsdf)) = lobe.sample(ns, wo, rng) else {
                break;
            };
            if pdf_bsdf <= 0.0 || ng.dot(wi) <= 0.0 {
                break;
            }
            throughput *= weight;
            let next_ray = Ray::new(origin, wi);
            if !gather_next {
                radiance += self.last_sample(&next_ray, wi, pdf_bsdf, throughput, emitters, stats);
                break;
            }
            stats.closest += 1;
            let Some(next) = self.geometry.intersect(&next_ray, f32::MAX) else {
                if env_active {
                    radiance += self.escaped(wi, pdf_bsdf, throughput);
                }
                break;
            };
            bounce += 1;
            if bounce >= RUSSIAN_ROULETTE_START && !russian_roulette(&mut throughput, rng) {
                break;
            }
            hit = next;
            incoming = wi;
        }
        finite_or_zero(radiance)
    }
}

impl<I: Intersector> Integrator<'_, I> {
    /// The environment's light along `wi`, reached by a BSDF sample of density `pdf` with
    /// `throughput`, MIS-weighted against the environment's own samples.
    #[inline(always)]
    fn escaped(&self, wi: Vec3, pdf: f32, throughput: Vec3) -> Vec3 {
        let le = self.environment.eval(wi);
        let w = power_heuristic(pdf, self.environment.environment_pdf(wi));
        throughput * le * w
    }

    /// What the last vertex's BSDF sample `ray` (towards `wi`, density `pdf`) adds with
    /// `throughput`. Without emitters only whether it escapes matters (a surface hit adds
    /// nothing and ends the path), so an any-hit query answers it, counted as what it is; with
    /// emitters the surface it hits adds its emission, so it is a closest-hit query.
    fn last_sample(
        &self,
        ray: &Ray,
        wi: Vec3,
        pdf: f32,
        throughput: Vec3,
        emitters: bool,
        stats: &mut RayStats,
    ) -> Vec3 {
        if emitters {
            stats.closest += 1;
            return match self.geometry.intersect(ray, f32::MAX) {
                Some(h) => self
                    .materials
                    .get(h.material as usize)
                    .map_or(Vec3::ZERO, |m| throughput * m.emission),
                None if !self.environment.is_black() => self.escaped(wi, pdf, throughput),
                None => Vec3::ZERO,
            };
        }
        stats.shadow += 1;
        if self
            .geometry
            .occluded_in_stream(ray, f32::MAX, stream::last_bsdf(wi))
        {
            Vec3::ZERO
        } else {
            self.escaped(wi, pdf, throughput)
        }
    }
}

/// The BRDF at one path vertex.
enum Lobe {
    /// A Lambertian albedo (not black).
    Lambertian(Vec3),
    MetallicRoughness(MetallicRoughness),
}

impl Lobe {
    /// The lobe of `material` at `uv`; `None` for a black Lambertian surface (nothing to
    /// gather; the path ends).
    #[inline(always)]
    fn at(material: &Material, uv: glam::Vec2) -> Option<Self> {
        match material.metallic_roughness(uv) {
            Some(mr) => Some(Lobe::MetallicRoughness(mr)),
            None => {
                let albedo = material.eval(uv);
                (albedo != Vec3::ZERO).then_some(Lobe::Lambertian(albedo))
            }
        }
    }

    /// The BRDF for `wo` and `wi` (unit, away from the surface) about `ns`. The Lambertian
    /// lobe's callers check that `wi` is above the surface.
    #[inline(always)]
    fn f(&self, ns: Vec3, wo: Vec3, wi: Vec3) -> Vec3 {
        match self {
            Lobe::Lambertian(albedo) => *albedo * FRAC_1_PI,
            Lobe::MetallicRoughness(mr) => mr.eval(ns, wo, wi),
        }
    }

    /// The density of [`Lobe::sample`] drawing `wi`; `cos = ns·wi`.
    #[inline(always)]
    fn pdf(&self, ns: Vec3, wo: Vec3, wi: Vec3, cos: f32) -> f32 {
        match self {
            Lobe::Lambertian(_) => cosine_hemisphere_pdf(cos),
            Lobe::MetallicRoughness(mr) => mr.pdf(ns, wo, wi),
        }
    }

    /// A direction `wi` with its weight `f · cos / pdf` and density `pdf`: cosine-weighted
    /// for the Lambertian lobe (weight = albedo), [`MetallicRoughness::sample`] otherwise.
    #[inline(always)]
    fn sample(&self, ns: Vec3, wo: Vec3, rng: &mut Rng) -> Option<(Vec3, Vec3, f32)> {
        match self {
            Lobe::Lambertian(albedo) => {
                let wi = Frame::from_normal(ns).to_world(sample_cosine_hemisphere(rng.next_vec2()));
                Some((wi, *albedo, cosine_hemisphere_pdf(ns.dot(wi))))
            }
            Lobe::MetallicRoughness(mr) => {
                let lobe = rng.next_f32();
                let s = mr.sample(ns, wo, lobe, rng.next_vec2())?;
                Some((s.wi, s.weight, s.pdf))
            }
        }
    }
}

/// The geometric and shading normals of `hit`, oriented towards the incoming ray
/// (two-sided surfaces): `(ng, ns)`.
#[inline(always)]
fn oriented_normals(hit: &SurfaceHit, incoming: Vec3) -> (Vec3, Vec3) {
    let mut ng = hit.geometric_normal.try_normalize().unwrap_or(-incoming);
    if ng.dot(incoming) > 0.0 {
        ng = -ng;
    }
    let mut ns = hit.shading_normal.try_normalize().unwrap_or(ng);
    if ns.dot(ng) < 0.0 {
        ns = -ns;
    }
    (ng, ns)
}

/// Russian roulette: whether the path survives (with probability `q`, the throughput's
/// largest channel up to 0.95), its throughput then divided by `q`.
#[inline(always)]
fn russian_roulette(throughput: &mut Vec3, rng: &mut Rng) -> bool {
    let q = throughput.max_element().min(0.95);
    if q.is_nan() || q <= 0.0 || rng.next_f32() >= q {
        return false;
    }
    *throughput /= q;
    true
}

/// Shadow-ray streams ([`Intersector::occluded_in_stream`]): similar shadow rays share a
/// stream so that the intersector's guess (the triangle that blocked the stream's last
/// blocked ray) is often right. Streams 1–7: the rays towards one delta light from the first
/// vertex (neighbouring texels' first hits lie close together and their rays towards the sun
/// are parallel, so the stream's last blocker usually blocks the next one too:
/// docs/measurements.md, "Preflight constants") or from a deeper vertex; 8–15 and 16–23: environment samples from the first
/// and from deeper vertices, 24–31: the last vertex's BSDF rays, each by the octant of the
/// direction (rays up hit the roof, rays down the floor). Only the queries' speed depends on
/// this, never their answers.
mod stream {
    use glam::Vec3;

    /// The stream of the shadow rays towards light `light` from path vertex `bounce`.
    pub fn light(light: usize, bounce: u32) -> usize {
        if light < 3 {
            1 + 2 * light + bounce.min(1) as usize
        } else {
            7
        }
    }

    /// The stream of an environment sample towards `dir` from path vertex `bounce`.
    pub fn environment(dir: Vec3, bounce: u32) -> usize {
        8 + 8 * bounce.min(1) as usize + octant(dir)
    }

    /// The stream of the last vertex's BSDF ray towards `dir`.
    pub fn last_bsdf(dir: Vec3) -> usize {
        24 + octant(dir)
    }

    fn octant(d: Vec3) -> usize {
        usize::from(d.x < 0.0) | (usize::from(d.y < 0.0) << 1) | (usize::from(d.z < 0.0) << 2)
    }

    const _: () = assert!(super::OCCLUSION_STREAMS >= 32);
}

/// Guards the final result: finite scene data never produce NaN/Inf here, but a pathological
/// intersector (NaN normals, say) must not poison an image.
fn finite_or_zero(v: Vec3) -> Vec3 {
    if v.is_finite() {
        v
    } else {
        Vec3::ZERO
    }
}
