//! Cube-map capture at a point (thesis §3.2): six world-axis-aligned faces, in the wgpu/Vulkan
//! face order and orientation of [`oslf_format::cube`], ray traced from the point itself so the
//! surface ε below is visible.

use glam::Vec3;
use oslf_format::CubeImage;
use rayon::prelude::*;

use crate::bake::chunk_cubes;
use crate::integrator::{Integrator, RayStats};
use crate::ray::{Intersector, Ray};
use crate::sampling::{hash_u64, Rng};

/// Strata per texel side for `samples_per_texel`: the smallest k with k² ≥ the request.
pub fn strata_per_side(samples_per_texel: u32) -> u32 {
    let mut k = (samples_per_texel.max(1) as f64).sqrt().floor() as u32;
    while k * k < samples_per_texel.max(1) {
        k += 1;
    }
    k
}

/// What one capture needs besides the integrator.
#[derive(Clone, Copy, Debug)]
pub struct CaptureSettings {
    pub resolution: u32,
    pub samples_per_texel: u32,
    pub distance_channel: bool,
    pub seed: u64,
}

/// Captures the cube map seen from `origin`. `cube_index` selects the random streams, so a
/// cube's texels are the same whichever thread renders them.
pub fn capture_cube<I: Intersector>(
    integrator: &Integrator<I>,
    origin: Vec3,
    cube_index: u32,
    settings: &CaptureSettings,
) -> (CubeImage, RayStats) {
    let res = settings.resolution;
    let k = strata_per_side(settings.samples_per_texel);
    let inv_spp = 1.0 / (k * k) as f32;
    let texels = (res as usize) * (res as usize);
    let mut faces: [Vec<[f32; 3]>; 6] = Default::default();
    let mut distance: [Vec<f32>; 6] = Default::default();
    for (f, d) in faces.iter_mut().zip(distance.iter_mut()) {
        *f = vec![[0.0; 3]; texels];
        if settings.distance_channel {
            *d = vec![0.0; texels];
        }
    }
    // Rows in parallel when the bake captures fewer cubes at once than there are threads
    // (large faces, see [`chunk_cubes`]): a large cube then keeps every thread busy on its own.
    // Each texel has its own random stream, so the result does not depend on the split.
    let parallel = chunk_cubes(res, settings.distance_channel) < rayon::current_num_threads();
    type Row<'a> = (usize, u32, &'a mut [[f32; 3]], Option<&'a mut [f32]>);
    let mut rows: Vec<Row> = Vec::new();
    for (face, (out, dist)) in faces.iter_mut().zip(distance.iter_mut()).enumerate() {
        let dist_rows: Vec<Option<&mut [f32]>> = if settings.distance_channel {
            dist.chunks_mut(res as usize).map(Some).collect()
        } else {
            (0..res).map(|_| None).collect()
        };
        for (y, (row, d)) in out.chunks_mut(res as usize).zip(dist_rows).enumerate() {
            rows.push((face, y as u32, row, d));
        }
    }
    let trace_row = |(face, y, row, mut dist_row): Row| {
        let mut stats = RayStats::default();
        for x in 0..res {
            let texel = u64::from(y) * u64::from(res) + u64::from(x);
            let stream = hash_u64(&[settings.seed, cube_index as u64, face as u64, texel]);
            let mut rng = Rng::new(settings.seed, stream);
            let mut sum = Vec3::ZERO;
            for j in 0..k * k {
                let sx = ((j % k) as f32 + rng.next_f32()) / k as f32;
                let sy = ((j / k) as f32 + rng.next_f32()) / k as f32;
                let s = (x as f32 + sx) / res as f32;
                let t = (y as f32 + sy) / res as f32;
                let dir = Vec3::from_array(oslf_format::cube::face_st_to_direction(face, s, t));
                let sample = integrator.radiance(&Ray::new(origin, dir), &mut rng, &mut stats);
                sum += sample.radiance;
            }
            row[x as usize] = (sum * inv_spp).to_array();
            if let Some(d_row) = dist_row.as_deref_mut() {
                let dir = Vec3::from_array(oslf_format::cube::texel_direction(face, x, y, res));
                stats.closest += 1;
                d_row[x as usize] = integrator
                    .geometry
                    .intersect(&Ray::new(origin, dir), f32::MAX)
                    .map_or(f32::MAX, |h| h.t);
            }
        }
        stats
    };
    let sum = |mut a: RayStats, b: RayStats| {
        a.add(&b);
        a
    };
    let stats = if parallel {
        rows.into_par_iter()
            .map(trace_row)
            .reduce(RayStats::default, sum)
    } else {
        rows.into_iter()
            .map(trace_row)
            .fold(RayStats::default(), sum)
    };
    let cube = CubeImage {
        resolution: res,
        faces,
        distance: settings.distance_channel.then_some(distance),
    };
    (cube, stats)
}
