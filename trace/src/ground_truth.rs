//! Ray-traced ground truth for measuring the runtime (thesis chapter 6).
//!
//! Renders what each runtime mode approximates, from the scene camera, with the bake's own
//! path tracer ([`Integrator`]) in the scene the store was baked from, so that a difference
//! measures the method and not a different scene:
//!
//! | [`Term`] | the pixel | runtime mode it judges |
//! | --- | --- | --- |
//! | `Recon` | radiance leaving the (Lambertian) object towards the camera: the scene as baked | `recon` (Table 6.1) |
//! | `Mirror` | radiance arriving at the object's surface along the mirror direction r = 2⟨n,v⟩n − v (Eq. 2.4, thesis Figure 1.1a) | `mirror` (Table 6.2) |
//! | `Glossy` | the Ashikhmin–Shirley specular term ∫ ρ_s(v,l) L_i(l) ⟨n,l⟩ dl (Eq. 5.3), integrated by importance sampling the lobe ([`AsLobe`]) | `glossy` with R_d = 0 |
//! | `Pbr` | glTF's metallic-roughness reflection ∫ f(v,l) L_i(l) ⟨n,l⟩ dl with the object's base colour C_s, by the bake's own sampling of that BRDF ([`MetallicRoughness::sample`]) | `pbr` |
//!
//! [`compose`] adds a term to the reconstruction as the runtime does: F_recon + C_s · term
//! (Eq. 4.12), giving the full images of `recon-mirror` and `recon-glossy` (Figure 6.3a).
//!
//! # What is held equal to the runtime
//! - Pixels: one primary ray through each pixel centre (the runtime rasterizes one sample per
//!   pixel), against the OSLF object's patches *alone*, tessellated as for the bake (error
//!   below ε/50): the runtime draws the object and nothing else, so occluders between camera
//!   and object are ignored here too. Alpha is 1 where the object is hit, 0 elsewhere.
//! - Shading point: where the pixel's ray meets the Bézier patch itself, refined from the
//!   triangles' hit by Newton's method ([`BezierPatch::refine_hit`]), as the runtime's shading
//!   pass refines its G-buffer's; the exact normal there ([`BezierPatch::normal`]), and the
//!   tangent from ∂x/∂u made orthogonal to it, as `shade.wgsl` does.
//! - The light the reflections see is the bake's: the same scene with the object in it as a
//!   Lambertian surface (one level of self-reflection, as the OSLF represents), the same
//!   `bounces`. Reflected rays leave from the shading point offset along the tessellation's
//!   geometric normal ([`offset_origin`]) towards the viewer's side, lifted to the triangle
//!   where the patch lies below its chord.
//!
//! # Estimators
//! `spp` samples per pixel. `Recon` averages `spp` paths from the hit; `Mirror` averages `spp`
//! paths along r; `Glossy` draws `spp` stratified lobe samples and weights each path's radiance
//! by ρ_s⟨n,l⟩ / p(l), the BRDF and its density evaluated separately ([`AsLobe::eval`],
//! [`AsLobe::light_pdf`]). Surfaces seen from behind (⟨n,v⟩ ≤ 0) get no glossy light, as in the
//! runtime. Every pixel has its own random stream keyed by (seed, term, x, y): the image does
//! not depend on the number of threads. With [`GroundTruth::with_cube_floor`], `Mirror`'s paths
//! leave along directions drawn from an N² cube map's lookup of r instead of r itself: the
//! floor of any store at that resolution ([`crate::cube_floor`]).

use std::sync::Arc;
use std::time::Instant;

use glam::{DVec3, Vec3};
use rayon::prelude::*;

use crate::ashikhmin_shirley::AsLobe;
use crate::bvh::{Instance, TriangleScene};
use crate::cube_floor::CubeFloor;
use crate::integrator::{offset_origin, Integrator, RayStats};
use crate::preview::primary_ray;
use crate::progress::{self, Progress};
use crate::ray::{Intersector, Ray, SurfaceHit};
use oslf_geometry::bezier::{BezierPatch, REFINE_REACH};
use oslf_geometry::Camera;
use oslf_scene::material::Model;
use oslf_scene::metallic_roughness::MetallicRoughness;
use oslf_scene::scene::Scene;
use oslf_scene::tolerance::TESSELLATION_ERROR;
use oslf_scene::{BakeError, Result};
use oslf_shading::random::{hash_u64, stratified_2d, Rng};
use oslf_shading::warp::Frame;

/// Which term a ground-truth image holds (see the module documentation).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Term {
    Recon,
    Mirror,
    Glossy(AsLobe),
    /// glTF's metallic-roughness BRDF with the object's base colour C_s: `metallic` and
    /// `roughness`, each in [0, 1]; with `object_material`, an object whose own material is
    /// metallic-roughness is drawn with its factors instead (as the store records them).
    Pbr {
        metallic: f32,
        roughness: f32,
        object_material: bool,
    },
}

/// The largest Ashikhmin–Shirley exponent a term takes: the runtime's bound on n_u and n_v
/// (`ShadingParams::validate`), beyond which the lobe is a mirror within f32.
pub const MAX_AS_EXPONENT: f64 = 1e7;

impl Term {
    /// Errors, naming the values, when the term's material is out of range: metallic and
    /// roughness in [0, 1]; R_s in [0, 1] and n_u, n_v in [0, [`MAX_AS_EXPONENT`]]. A command
    /// checks its terms with it before any work; [`GroundTruth::render`] checks again.
    pub fn validate(&self) -> Result<()> {
        match *self {
            Term::Pbr {
                metallic,
                roughness,
                ..
            } if !((0.0..=1.0).contains(&metallic) && (0.0..=1.0).contains(&roughness)) => {
                Err(BakeError::Invalid(format!(
                    "metallic {metallic} and roughness {roughness} must be in [0, 1]"
                )))
            }
            Term::Glossy(lobe) => {
                let exponent_ok = |n: f64| (0.0..=MAX_AS_EXPONENT).contains(&n);
                if (0.0..=1.0).contains(&lobe.rs) && exponent_ok(lobe.nu) && exponent_ok(lobe.nv) {
                    Ok(())
                } else {
                    Err(BakeError::Invalid(format!(
                        "Ashikhmin–Shirley lobe {lobe:?}: R_s must be in [0, 1] and n_u, n_v in [0, {MAX_AS_EXPONENT:e}]"
                    )))
                }
            }
            _ => Ok(()),
        }
    }
}

impl Term {
    fn tag(&self) -> u64 {
        match self {
            Term::Recon => 1,
            Term::Mirror => 2,
            Term::Glossy(_) => 3,
            Term::Pbr { .. } => 5,
        }
    }
}

/// The random-stream tag of [`GroundTruth::render_background`] (between the terms' 1, 2, 3
/// and 5).
const BACKGROUND_TAG: u64 = 4;

/// Image size and sampling of a ground-truth render.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TruthSettings {
    pub width: u32,
    pub height: u32,
    /// Samples per pixel (0 is treated as 1).
    pub spp: u32,
    pub seed: u64,
}

impl Default for TruthSettings {
    /// The thesis's 655×460 at 256 samples per pixel.
    fn default() -> Self {
        Self {
            width: 655,
            height: 460,
            spp: 256,
            seed: 0,
        }
    }
}

/// A ground-truth image.
#[derive(Clone, Debug)]
pub struct TruthImage {
    pub width: u32,
    pub height: u32,
    /// Linear RGB and the object mask in alpha, row-major, top row first.
    pub pixels: Vec<[f32; 4]>,
    /// C_s of the object under each pixel (zero off the object), for [`compose`].
    pub base_color: Vec<Vec3>,
    pub rays: RayStats,
    pub seconds: f64,
}

/// The scene prepared for ground-truth renders.
pub struct GroundTruth<'s> {
    scene: &'s Scene,
    /// Everything, the object included: what reflected rays and paths see.
    geometry: TriangleScene,
    /// The OSLF objects alone, `SurfaceHit::object` = an index into `patches` and `colors`:
    /// one per Bézier patch (store order), one per mesh object.
    object: TriangleScene,
    /// The Bézier patch hit (its normal and ∂x/∂u are evaluated exactly), or `None` for a
    /// mesh, shaded with its interpolated normal and a frame built from it alone (as the
    /// runtime does).
    patches: Vec<Option<BezierPatch>>,
    colors: Vec<Vec3>,
    /// Per entry of `patches`: a mesh object's MikkTSpace tangents where its material has a
    /// normal texture, which then turns its shading normal.
    tangents: Vec<Option<MeshTangents>>,
    camera: Camera,
    /// The patches' tessellation tolerance: how far a primary hit on the triangles may lie
    /// from the patch itself (`BezierPatch::refine_hit` looks within a multiple of it).
    max_error: f32,
    /// Where the renders report their rows (`None`: nowhere).
    progress: Option<Arc<dyn Progress>>,
    /// The mirror term read from a cube map at the shaded point ([`Self::with_cube_floor`]).
    cube_floor: Option<CubeFloor>,
}

impl<'s> GroundTruth<'s> {
    /// Builds both BVHs. `camera` is the view (the scene's `[camera]` for measurement).
    pub fn new(scene: &'s Scene, camera: Camera) -> Result<Self> {
        camera.validate()?;
        let max_error = scene.bake.epsilon * TESSELLATION_ERROR;
        let geometry = TriangleScene::build(crate::bvh::scene_instances(scene, true, max_error))?;
        let mut instances = Vec::new();
        let mut patches = Vec::new();
        let mut colors = Vec::new();
        let mut tangents = Vec::new();
        let mut first_triangle = 0u32;
        for object in &scene.objects {
            for patch in &object.patches {
                instances.push(Instance {
                    name: format!("object {:?}", object.name),
                    mesh: patch.tessellate(patch.tessellation_level(max_error)),
                    material: object.material,
                    object: patches.len() as u32,
                });
                first_triangle += instances
                    .last()
                    .map_or(0, |i: &Instance| i.mesh.triangles.len() as u32);
                patches.push(Some(*patch));
                colors.push(object.base_color);
                tangents.push(None);
            }
            if let Some(source) = &object.mesh {
                instances.push(Instance {
                    name: format!("object {:?}", object.name),
                    mesh: source.mesh.clone(),
                    material: object.material,
                    object: patches.len() as u32,
                });
                let mapped = scene
                    .materials
                    .get(object.material as usize)
                    .is_some_and(|m| m.normal_texture.is_some());
                tangents.push(mapped.then(|| MeshTangents {
                    first: first_triangle,
                    triangles: source.mesh.triangles.clone(),
                    positions: source.mesh.positions.clone(),
                    corners: oslf_geometry::tangents::corner_tangents(&source.mesh),
                }));
                first_triangle += source.mesh.triangles.len() as u32;
                patches.push(None);
                colors.push(object.base_color);
            }
        }
        let object = TriangleScene::build(instances)?;
        Ok(Self {
            scene,
            geometry,
            object,
            patches,
            colors,
            tangents,
            camera,
            max_error,
            progress: None,
            cube_floor: None,
        })
    }

    /// Reports the rows of every render to `progress` (by default nowhere).
    pub fn with_progress(mut self, progress: Option<Arc<dyn Progress>>) -> Self {
        self.progress = progress;
        self
    }

    /// Renders the mirror term as a cube map of `floor`'s resolution captured at each shaded
    /// point would give it (see [`crate::cube_floor`]): the floor of any store at that
    /// resolution. [`Self::render`] refuses the other terms while it is set. Errors, naming it,
    /// for a resolution outside the bake's range.
    pub fn with_cube_floor(mut self, floor: Option<CubeFloor>) -> Result<Self> {
        if let Some(f) = &floor {
            f.validate()?;
        }
        self.cube_floor = floor;
        Ok(self)
    }

    fn integrator(&self) -> Integrator<'_, TriangleScene> {
        Integrator::for_scene(self.scene, &self.geometry)
    }

    /// Renders one term. Rows run in parallel; the result does not depend on the thread count.
    pub fn render(&self, term: Term, settings: &TruthSettings) -> Result<TruthImage> {
        let (w, h) = (settings.width, settings.height);
        if w == 0 || h == 0 {
            return Err(BakeError::Invalid(format!(
                "ground-truth image size {w}x{h} must be at least 1x1"
            )));
        }
        term.validate()?;
        if self.cube_floor.is_some() && term != Term::Mirror {
            return Err(BakeError::Invalid(format!(
                "the cube-map floor is the mirror term's; {term:?} has none"
            )));
        }
        let start = Instant::now();
        let progress = progress::or_silent(&self.progress);
        progress.start("rows", u64::from(h), 0);
        let integrator = self.integrator();
        let rows: Vec<(Vec<[f32; 4]>, Vec<Vec3>, RayStats)> = (0..h)
            .into_par_iter()
            .map(|y| {
                let mut stats = RayStats::default();
                let mut row = Vec::with_capacity(w as usize);
                let mut colors = Vec::with_capacity(w as usize);
                for x in 0..w {
                    let mut rng = Rng::new(
                        settings.seed,
                        hash_u64(&[settings.seed, term.tag(), u64::from(x), u64::from(y)]),
                    );
                    let (px, c) =
                        self.pixel(&integrator, term, x, y, settings, &mut rng, &mut stats);
                    row.push(px);
                    colors.push(c);
                }
                progress.advance(1);
                (row, colors, stats)
            })
            .collect();
        progress.finish();
        let mut pixels = Vec::with_capacity(w as usize * h as usize);
        let mut base_color = Vec::with_capacity(pixels.capacity());
        let mut rays = RayStats::default();
        for (row, colors, stats) in rows {
            pixels.extend(row);
            base_color.extend(colors);
            rays.add(&stats);
        }
        Ok(TruthImage {
            width: w,
            height: h,
            pixels,
            base_color,
            rays,
            seconds: start.elapsed().as_secs_f64(),
        })
    }

    /// The scene behind the object: for every pixel whose centre does not see the object, the
    /// radiance along `spp` camera rays jittered in strata of the pixel (paths through the whole
    /// scene, the object included, as the bake's preview); `[0; 4]` on the object. Alpha is 0
    /// everywhere, so adding it to a term's image keeps that image's object mask.
    ///
    /// What `oslf truth --background scene` puts behind the object: the true scene seen from the
    /// camera, where `oslf render --background env` shows the environment cube captured at the
    /// object's centre.
    pub fn render_background(&self, settings: &TruthSettings) -> Result<TruthImage> {
        let (w, h) = (settings.width, settings.height);
        if w == 0 || h == 0 {
            return Err(BakeError::Invalid(format!(
                "ground-truth image size {w}x{h} must be at least 1x1"
            )));
        }
        let start = Instant::now();
        let progress = progress::or_silent(&self.progress);
        progress.start("rows", u64::from(h), 0);
        let integrator = self.integrator();
        let spp = settings.spp.max(1);
        let rows: Vec<(Vec<[f32; 4]>, RayStats)> = (0..h)
            .into_par_iter()
            .map(|y| {
                let mut stats = RayStats::default();
                let mut row = Vec::with_capacity(w as usize);
                for x in 0..w {
                    stats.closest += 1;
                    if self.primary_hit(x, y, w, h).is_some() {
                        row.push([0.0; 4]);
                        continue;
                    }
                    let mut rng = Rng::new(
                        settings.seed,
                        hash_u64(&[settings.seed, BACKGROUND_TAG, u64::from(x), u64::from(y)]),
                    );
                    let mut sum = Vec3::ZERO;
                    for s in 0..spp {
                        let j = stratified_2d(s, spp, &mut rng);
                        let ray = primary_ray(&self.camera, x as f32 + j.x, y as f32 + j.y, w, h);
                        sum += integrator.radiance(&ray, &mut rng, &mut stats).radiance;
                    }
                    let c = sum / spp as f32;
                    let c = if c.is_finite() { c } else { Vec3::ZERO };
                    row.push([c.x, c.y, c.z, 0.0]);
                }
                progress.advance(1);
                (row, stats)
            })
            .collect();
        progress.finish();
        let mut pixels = Vec::with_capacity(w as usize * h as usize);
        let mut rays = RayStats::default();
        for (row, stats) in rows {
            pixels.extend(row);
            rays.add(&stats);
        }
        Ok(TruthImage {
            width: w,
            height: h,
            base_color: vec![Vec3::ZERO; pixels.len()],
            pixels,
            rays,
            seconds: start.elapsed().as_secs_f64(),
        })
    }

    /// The object hit through pixel `(x, y)`'s centre, if any.
    pub fn primary_hit(
        &self,
        x: u32,
        y: u32,
        width: u32,
        height: u32,
    ) -> Option<(Ray, SurfaceHit)> {
        let ray = primary_ray(&self.camera, x as f32 + 0.5, y as f32 + 0.5, width, height);
        self.object.intersect(&ray, f32::MAX).map(|hit| (ray, hit))
    }

    /// A mesh hit's shading normal: the interpolated one, turned by the object's normal texture
    /// in the frame of its MikkTSpace tangents interpolated at the hit (as the runtime's
    /// G-buffer does).
    fn mapped_normal(&self, pid: usize, hit: &SurfaceHit) -> Vec3 {
        let n = hit.shading_normal;
        let Some(Some(m)) = self.tangents.get(pid) else {
            return n;
        };
        let Some(local) = hit.triangle.checked_sub(m.first).map(|l| l as usize) else {
            return n;
        };
        let (Some(tri), Some(corners)) = (m.triangles.get(local), m.corners.get(local)) else {
            return n;
        };
        let [a, b, c] = tri.map(|i| m.positions[i as usize]);
        let w = barycentric(hit.position, a, b, c);
        let tangent = corners[0] * w.x + corners[1] * w.y + corners[2] * w.z;
        let tangent = tangent.truncate().extend(corners[0].w);
        match self.scene.materials.get(hit.material as usize) {
            Some(material) => material.mapped_normal(hit.uv, n, tangent),
            None => n,
        }
    }

    /// The pbr term's BRDF at `hit`: the flags' factors, or with `object_material` the
    /// object's own (a mesh object's metallic-roughness texture read at the hit, as the store's
    /// texture record has the runtime do: format docs, "Object textures"); the base colour C_s,
    /// or a mesh object's base colour texture at the hit.
    fn pbr_brdf(
        &self,
        hit: &SurfaceHit,
        mesh: bool,
        color: Vec3,
        (metallic, roughness): (f32, f32),
        object_material: bool,
    ) -> MetallicRoughness {
        let own = self.scene.materials.get(hit.material as usize);
        let textured = |t: Option<&oslf_scene::texture::Texture>| {
            mesh && matches!(t, Some(oslf_scene::texture::Texture::Image(_)))
        };
        let base_color = match own {
            Some(m) if textured(Some(&m.albedo)) => m.eval(hit.uv),
            _ => color,
        };
        let (metallic, roughness) = match own {
            Some(m) if object_material => match (m.model, m.metallic_roughness(hit.uv)) {
                (_, Some(mr)) if textured(m.metallic_roughness_texture.as_ref()) => {
                    (mr.metallic, mr.roughness)
                }
                (
                    Model::MetallicRoughness {
                        metallic,
                        roughness,
                    },
                    _,
                ) => (metallic, roughness),
                _ => (metallic, roughness),
            },
            _ => (metallic, roughness),
        };
        MetallicRoughness {
            base_color,
            metallic,
            roughness,
        }
    }

    #[allow(clippy::too_many_arguments)]
    fn pixel(
        &self,
        integrator: &Integrator<'_, TriangleScene>,
        term: Term,
        x: u32,
        y: u32,
        settings: &TruthSettings,
        rng: &mut Rng,
        stats: &mut RayStats,
    ) -> ([f32; 4], Vec3) {
        stats.closest += 1;
        let Some((ray, hit)) = self.primary_hit(x, y, settings.width, settings.height) else {
            return ([0.0; 4], Vec3::ZERO);
        };
        let pid = hit.object as usize;
        let (Some(patch), Some(&color)) = (self.patches.get(pid), self.colors.get(pid)) else {
            return ([0.0; 4], Vec3::ZERO);
        };
        let spp = settings.spp.max(1);
        // A patch is shaded where the pixel's ray meets the patch itself, not its tessellation
        // (as the runtime's shading pass does: `surface_hit` in shade/patch.wgsl).
        let (u, v, position) = patch
            .and_then(|p| {
                let uv = (hit.uv.x, hit.uv.y);
                p.refine_hit(hit.position, ray.dir, uv, REFINE_REACH * self.max_error)
            })
            .unwrap_or((hit.uv.x, hit.uv.y, hit.position));
        let n = match patch {
            Some(patch) => patch.normal(u, v),
            None => self.mapped_normal(pid, &hit),
        };
        let view = -ray.dir;
        let mut ng = hit.geometric_normal;
        if ng.dot(view) < 0.0 {
            ng = -ng;
        }
        // Leave from above the triangles too, where the surface dips below its chord.
        let lift = (hit.position - position).dot(ng).max(0.0);
        let origin = offset_origin(position + ng * lift, ng, hit.extent);
        let mut sum = Vec3::ZERO;
        match term {
            Term::Recon => {
                for _ in 0..spp {
                    sum += integrator.radiance_leaving(&hit, ray.dir, rng, stats);
                }
            }
            Term::Mirror => {
                let r = (2.0 * n.dot(view) * n - view).normalize_or(n); // Eq. 2.4
                for _ in 0..spp {
                    let d = self.cube_floor.map_or(r, |floor| floor.direction(r, rng));
                    sum += integrator
                        .radiance(&Ray::new(origin, d), rng, stats)
                        .radiance;
                }
            }
            Term::Pbr {
                metallic,
                roughness,
                object_material,
            } => {
                let brdf = self.pbr_brdf(
                    &hit,
                    patch.is_none(),
                    color,
                    (metallic, roughness),
                    object_material,
                );
                for s in 0..spp {
                    let xi = stratified_2d(s, spp, rng);
                    let lobe = rng.next_f32();
                    let Some(sample) = brdf.sample(n, view, lobe, xi) else {
                        continue;
                    };
                    let li = integrator.radiance(&Ray::new(origin, sample.wi), rng, stats);
                    sum += li.radiance * sample.weight;
                }
            }
            Term::Glossy(lobe) => {
                let du = patch.as_ref().map_or(Vec3::ZERO, |p| p.partials(u, v).0);
                let t = (du - n * n.dot(du))
                    .try_normalize()
                    .unwrap_or_else(|| Frame::from_normal(n).x);
                let b = n.cross(t);
                let local = |d: Vec3| DVec3::new(d.dot(t).into(), d.dot(b).into(), d.dot(n).into());
                let v_local = local(view);
                if v_local.z > 0.0 {
                    for s in 0..spp {
                        let xi = stratified_2d(s, spp, rng);
                        let Some(l) = lobe.sample_light(v_local, [xi.x.into(), xi.y.into()]) else {
                            continue;
                        };
                        let pdf = lobe.light_pdf(v_local, l);
                        if !(pdf > 0.0 && pdf.is_finite()) {
                            continue;
                        }
                        let weight = lobe.eval(v_local, l) * l.z / pdf; // Eq. 5.12
                        let dir =
                            (t * l.x as f32 + b * l.y as f32 + n * l.z as f32).normalize_or(n);
                        let li = integrator.radiance(&Ray::new(origin, dir), rng, stats);
                        sum += li.radiance * weight as f32;
                    }
                }
            }
        }
        let mut c = sum / spp as f32;
        if let Term::Pbr { .. } = term {
            // The pbr mode scales the reflected light by a mesh object's occlusion texture
            // and adds the object's own emission (its emissive texture read at the hit), as
            // the runtime does.
            if let Some(m) = self.scene.materials.get(hit.material as usize) {
                c = if patch.is_none() {
                    c * m.occlusion_at(hit.uv) + m.emission_at(hit.uv)
                } else {
                    c + m.emission
                };
            }
        }
        let c = if c.is_finite() { c } else { Vec3::ZERO };
        ([c.x, c.y, c.z, 1.0], color)
    }
}

/// F_recon + C_s · `term` per pixel (Eq. 4.12): the full image of `recon-mirror` or
/// `recon-glossy`. Both images must be of the same view and size.
pub fn compose(recon: &TruthImage, term: &TruthImage) -> Result<TruthImage> {
    if (recon.width, recon.height) != (term.width, term.height)
        || recon.pixels.len() != term.pixels.len()
    {
        return Err(BakeError::Invalid(format!(
            "cannot compose a {}x{} and a {}x{} image",
            recon.width, recon.height, term.width, term.height
        )));
    }
    let pixels = recon
        .pixels
        .iter()
        .zip(&term.pixels)
        .zip(&recon.base_color)
        .map(|((a, b), c)| {
            [
                a[0] + c.x * b[0],
                a[1] + c.y * b[1],
                a[2] + c.z * b[2],
                a[3].max(b[3]),
            ]
        })
        .collect();
    let mut rays = recon.rays;
    rays.add(&term.rays);
    Ok(TruthImage {
        width: recon.width,
        height: recon.height,
        pixels,
        base_color: recon.base_color.clone(),
        rays,
        seconds: recon.seconds + term.seconds,
    })
}

/// A mesh object's MikkTSpace tangents, per triangle corner, for the truth's normal mapping.
struct MeshTangents {
    /// `SurfaceHit::triangle` of the object's first triangle.
    first: u32,
    triangles: Vec<[u32; 3]>,
    positions: Vec<Vec3>,
    corners: Vec<[glam::Vec4; 3]>,
}

/// Barycentric weights of `p` in triangle `(a, b, c)` (projected onto its plane); equal
/// thirds for a degenerate triangle.
fn barycentric(p: Vec3, a: Vec3, b: Vec3, c: Vec3) -> Vec3 {
    let (e0, e1, ep) = (b - a, c - a, p - a);
    let (d00, d01, d11) = (e0.dot(e0), e0.dot(e1), e1.dot(e1));
    let (d20, d21) = (ep.dot(e0), ep.dot(e1));
    let den = d00 * d11 - d01 * d01;
    if den.abs() <= f32::MIN_POSITIVE || den.is_nan() {
        return Vec3::splat(1.0 / 3.0);
    }
    let v = (d11 * d20 - d01 * d21) / den;
    let w = (d00 * d21 - d01 * d20) / den;
    Vec3::new(1.0 - v - w, v, w)
}
