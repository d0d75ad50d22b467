//! Pilot cube maps for adaptive placement (`[bake] placement = "adaptive"`): small cubes
//! captured at a coarse set of points over the objects, and how badly each is predicted from
//! its nearest neighbours' cubes with the one left out. The prediction reprojects through the
//! distances as the runtime's depth-corrected lookup does: the point's view ray meets what it
//! sees at its pilot distance, and each neighbour is looked up towards that place, its
//! lookups blended by inverse distance. Where the prediction is poor (near surroundings,
//! bright and sharp features that move between points) the placement puts points closer
//! together; where it is good (far, smooth surroundings) further apart.

use glam::Vec3;
use kiddo::{ImmutableKdTree, SquaredEuclidean};
use oslf_format::cube::{texel_direction, texel_solid_angle, FACES};
use oslf_format::CubeImage;
use oslf_trace::capture::CaptureSettings;
use oslf_trace::noise::luminance;
use rayon::prelude::*;

/// Texels per pilot cube edge: an 8² cube's texels span about 11°.
pub const PILOT_RESOLUTION: u32 = 8;
/// Samples per pilot texel.
pub const PILOT_SAMPLES: u32 = 32;
/// Pilot points as a fraction of the points the placement asks for (a coarse start).
pub const PILOT_FRACTION: f32 = 0.5;
/// Fewest pilot points of a placement group.
pub const MIN_PILOTS: usize = 16;

/// The pilot points of a placement group of `count` points, before the free-space tests.
pub fn pilot_count(count: usize) -> usize {
    ((count as f32 * PILOT_FRACTION).ceil() as usize).max(MIN_PILOTS)
}
/// Neighbours a pilot's view is predicted from (the runtime blends four points).
pub const PILOT_NEIGHBOURS: usize = 4;
/// The pilot cubes' random streams, apart from the store's cubes'.
const PILOT_SEED: u64 = 0x9170_7c0b_e5a1_0001;

/// Captures a pilot cube (with its distance channel) at a position, its random streams chosen
/// by the index; returns it, its relative standard error (`NoiseStats::relative_error`, 0
/// where unknown) and the rays it traced.
pub type PilotCapture<'a> = dyn Fn(Vec3, u32) -> (CubeImage, f32, u64) + Sync + 'a;

/// The capture of a pilot cube for a bake whose cubes are captured with `bake`: small, with
/// distances, not denoised, every texel taking [`PILOT_SAMPLES`].
pub fn capture_settings(bake: &CaptureSettings) -> CaptureSettings {
    CaptureSettings {
        resolution: PILOT_RESOLUTION,
        samples_per_texel: PILOT_SAMPLES,
        target_noise: 0.0,
        distance_channel: true,
        seed: bake.seed ^ PILOT_SEED,
        denoise: false,
    }
}

/// A pilot point: where its cube was captured, the normal of its face, its object, its cube
/// and that cube's relative standard error.
pub struct Pilot {
    pub position: Vec3,
    pub normal: Vec3,
    pub object: u32,
    pub cube: CubeImage,
    pub noise: f32,
}

/// Each pilot's leave-one-out prediction error: over the hemisphere its face's normal faces,
/// the solid-angle-weighted root mean square difference in luminance between its cube and the
/// prediction from its [`PILOT_NEIGHBOURS`] nearest pilots of the same object facing the same
/// side (see the module), relative to its cube's RMS luminance there, less what the cubes'
/// own Monte Carlo noise explains (their relative standard errors, the prediction's averaged
/// down by its weights; at least a tenth of the error is kept). A pilot with no such neighbour,
/// which nothing predicts, gets 1 (as poor as a prediction of black); a black view 0.
pub fn prediction_errors(pilots: &[Pilot]) -> Vec<f32> {
    if pilots.is_empty() {
        return Vec::new();
    }
    let positions: Vec<[f32; 3]> = pilots.iter().map(|p| p.position.to_array()).collect();
    let tree: ImmutableKdTree<f32, 3> = ImmutableKdTree::new_from_slice(&positions);
    let candidates = std::num::NonZero::new((4 * PILOT_NEIGHBOURS + 1).min(pilots.len()))
        .expect("at least one pilot");
    pilots
        .par_iter()
        .enumerate()
        .map(|(i, pilot)| {
            let neighbours: Vec<(&Pilot, f32)> = tree
                .nearest_n::<SquaredEuclidean>(&positions[i], candidates)
                .into_iter()
                .map(|nb| (nb.item as usize, nb.distance.sqrt()))
                .filter(|&(j, d)| {
                    j != i
                        && d > 0.0
                        && pilots[j].object == pilot.object
                        && pilots[j].normal.dot(pilot.normal) > 0.0
                })
                .take(PILOT_NEIGHBOURS)
                .map(|(j, d)| (&pilots[j], d))
                .collect();
            if neighbours.is_empty() {
                1.0
            } else {
                leave_one_out(pilot, &neighbours)
            }
        })
        .collect()
}

/// [`prediction_errors`] of one pilot from `neighbours` (each with its distance).
fn leave_one_out(pilot: &Pilot, neighbours: &[(&Pilot, f32)]) -> f32 {
    // Inverse-distance weights, normalized.
    let inverse: f64 = neighbours.iter().map(|&(_, d)| 1.0 / f64::from(d)).sum();
    let weights: Vec<f64> = neighbours
        .iter()
        .map(|&(_, d)| 1.0 / f64::from(d) / inverse)
        .collect();
    let res = pilot.cube.resolution;
    let (mut difference, mut total) = (0.0f64, 0.0f64);
    for face in 0..FACES {
        for y in 0..res {
            for x in 0..res {
                let dir = Vec3::from_array(texel_direction(face, x, y, res));
                if dir.dot(pilot.normal) <= 0.0 {
                    continue;
                }
                let k = (y * res + x) as usize;
                let own = luminance(pilot.cube.faces[face][k]);
                let t = pilot
                    .cube
                    .distance
                    .as_ref()
                    .map_or(f32::MAX, |d| d[face][k]);
                // What the view ray meets; an escaped ray's is at infinity (direction only).
                let seen = (t.is_finite() && t < f32::MAX).then(|| pilot.position + dir * t);
                let predicted: f64 = neighbours
                    .iter()
                    .zip(&weights)
                    .map(|(&(n, _), w)| {
                        let towards = seen.map_or(dir, |p| p - n.position);
                        w * luminance(n.cube.bilinear(towards.to_array()))
                    })
                    .sum();
                let omega = f64::from(texel_solid_angle(x, y, res));
                difference += omega * (own - predicted).powi(2);
                total += omega * own * own;
            }
        }
    }
    if !(total > 0.0 && difference.is_finite()) {
        return 0.0;
    }
    let predicted_noise: f64 = neighbours
        .iter()
        .zip(&weights)
        .map(|(&(n, _), w)| (f64::from(n.noise) * w).powi(2))
        .sum();
    let error = difference / total;
    let signal = error - f64::from(pilot.noise).powi(2) - predicted_noise;
    signal.max(0.01 * error).sqrt() as f32
}
