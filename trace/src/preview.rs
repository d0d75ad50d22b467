//! The path-traced preview: images rendered through the shared pinhole [`Camera`] by the
//! path tracer ([`crate::integrator`]), deterministic and parallel (`oslf bake --preview`,
//! `oslf truth`'s references).

use glam::Vec3;
use rayon::prelude::*;

use crate::integrator::{Integrator, RayStats};
use crate::ray::{Intersector, Ray};
use oslf_shading::random::{hash_u64, stratified_2d, Rng};

use oslf_geometry::Camera;

/// The primary ray of `camera` through image position `(px, py)` (see [`Camera::direction`]).
pub fn primary_ray(camera: &Camera, px: f32, py: f32, width: u32, height: u32) -> Ray {
    Ray::new(camera.position, camera.direction(px, py, width, height))
}

/// Renders `width × height` pixels (row-major, row 0 at the top) with `spp` samples per pixel
/// (0 is treated as 1), returning the mean radiance per pixel and the rays traced.
///
/// Each pixel's samples are jittered in `spp` strata of the pixel ([`stratified_2d`]) and use
/// their own generator `Rng::new(seed, hash_u64(&[seed, x, y]))`, so the image depends only on
/// the scene, the camera, `spp` and `seed`: never on the number of threads. Rows are rendered
/// in parallel with rayon.
pub fn render<I: Intersector>(
    integrator: &Integrator<I>,
    camera: &Camera,
    width: u32,
    height: u32,
    spp: u32,
    seed: u64,
) -> (Vec<glam::Vec3>, RayStats) {
    let spp = spp.max(1);
    let rows: Vec<(Vec<Vec3>, RayStats)> = (0..height)
        .into_par_iter()
        .map(|y| {
            let mut stats = RayStats::default();
            let mut row = Vec::with_capacity(width as usize);
            for x in 0..width {
                let mut rng = Rng::new(seed, hash_u64(&[seed, x as u64, y as u64]));
                let mut sum = Vec3::ZERO;
                for s in 0..spp {
                    let j = stratified_2d(s, spp, &mut rng);
                    let ray = primary_ray(camera, x as f32 + j.x, y as f32 + j.y, width, height);
                    sum += integrator.radiance(&ray, &mut rng, &mut stats).radiance;
                }
                row.push(sum / spp as f32);
            }
            (row, stats)
        })
        .collect();
    let mut image = Vec::with_capacity(width as usize * height as usize);
    let mut stats = RayStats::default();
    for (row, s) in rows {
        image.extend(row);
        stats.add(&s);
    }
    (image, stats)
}
