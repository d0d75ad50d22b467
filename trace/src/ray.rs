//! Rays, surface hits and the `Intersector` interface the integrator traces against.

use glam::{Vec2, Vec3};

/// A ray `origin + t * dir`, `dir` of unit length.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ray {
    pub origin: Vec3,
    pub dir: Vec3,
}

impl Ray {
    pub fn new(origin: Vec3, dir: Vec3) -> Self {
        Self { origin, dir }
    }
    pub fn at(&self, t: f32) -> Vec3 {
        self.origin + self.dir * t
    }
}

/// Object index of geometry that is not part of an OSLF object (table, gazebo, ...).
pub const ENVIRONMENT_OBJECT: u32 = u32::MAX;

/// The closest intersection of a ray with the scene.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurfaceHit {
    /// Ray parameter of the hit (distance, as ray directions are unit length).
    pub t: f32,
    /// World-space hit position.
    pub position: Vec3,
    /// Unit normal of the hit triangle's plane, oriented by the triangle's winding.
    pub geometric_normal: Vec3,
    /// Unit interpolated (shading) normal, on the same side as `geometric_normal`.
    pub shading_normal: Vec3,
    /// Texture coordinates at the hit.
    pub uv: Vec2,
    /// Index into the scene's material list.
    pub material: u32,
    /// OSLF object index, or [`ENVIRONMENT_OBJECT`].
    pub object: u32,
    /// Global triangle index (for tests and debugging).
    pub triangle: u32,
    /// The largest coordinate magnitude of the points that define the hit primitive (a
    /// triangle's corners). `position` is interpolated from them, so its rounding error is a
    /// few ulps of this (not of `position` itself, which may lie near the origin on a large
    /// triangle); secondary rays are offset by a multiple of it
    /// ([`crate::integrator::offset_origin`]).
    pub extent: f32,
}

/// Number of shadow-ray streams of [`Intersector::occluded_in_stream`]; stream 0 is the
/// general one (what [`Intersector::occluded`] uses).
pub const OCCLUSION_STREAMS: usize = 32;

/// Anything the integrator can trace rays against.
pub trait Intersector: Sync {
    /// Closest hit with `t` in `(0, t_max)`.
    fn intersect(&self, ray: &Ray, t_max: f32) -> Option<SurfaceHit>;
    /// Whether any surface is hit with `t` in `(0, t_max)`.
    fn occluded(&self, ray: &Ray, t_max: f32) -> bool;
    /// [`Intersector::occluded`] for a shadow ray of `stream` (below
    /// [`OCCLUSION_STREAMS`]): the caller's label for a series of similar shadow rays (those
    /// towards one light from one path depth, say), which an intersector may use to guess
    /// where to look first. The answer is that of `occluded`, whatever the stream.
    fn occluded_in_stream(&self, ray: &Ray, t_max: f32, stream: usize) -> bool {
        let _ = stream;
        self.occluded(ray, t_max)
    }
    /// [`Intersector::intersect`] of every ray of `rays` into the same slot of `hits` (of the
    /// same length). Intersectors that can trace coherent rays together (packets, see
    /// [`crate::bvh`]) override this; the answers are those of `intersect`.
    fn intersect_packet(&self, rays: &[Ray], t_max: f32, hits: &mut [Option<SurfaceHit>]) {
        assert_eq!(rays.len(), hits.len(), "one hit slot per ray");
        for (ray, hit) in rays.iter().zip(hits) {
            *hit = self.intersect(ray, t_max);
        }
    }
}

/// A scene with no surfaces: every ray escapes. (The environment-map baseline of a scene whose
/// only geometry is the OSLF object sees nothing but the environment.)
#[derive(Clone, Copy, Debug, Default)]
pub struct EmptyScene;

impl Intersector for EmptyScene {
    fn intersect(&self, _: &Ray, _: f32) -> Option<SurfaceHit> {
        None
    }
    fn occluded(&self, _: &Ray, _: f32) -> bool {
        false
    }
}
