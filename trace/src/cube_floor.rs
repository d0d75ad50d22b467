//! The cube-map floor of the mirror term: what a store of cube maps at a given resolution
//! could reach at best, with a cube captured at every shaded point itself.
//!
//! A store reflects what its cube maps hold: each texel the mean radiance over its solid angle
//! (the bake's stratified samples), read by a bilinear lookup of the four texels around a
//! direction (`Tap`, shade.wgsl). However many sample points a bake places and however well it
//! interpolates between them, a pixel cannot be better than the lookup of a noise-free cube
//! captured at the pixel's own surface point. [`CubeFloor::direction`] draws the directions of
//! that lookup: a texel of the four with the bilinear weights, then a direction uniform over
//! the texel's face coordinates (as the capture's strata). Averaged over a pixel's paths, the
//! mirror term then estimates that lookup without bias: the error of that image against the
//! truth is the floor of any bake at that resolution (`oslf truth --cube-floor N`,
//! docs/measuring.md).

use glam::Vec3;
use oslf_format::cube::{direction_to_face_st, face_st_to_direction, Tap};
use oslf_format::MAX_CUBE_RESOLUTION;
use oslf_scene::{BakeError, Result};
use oslf_shading::random::Rng;

/// How the floor's cube is read.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FloorLookup {
    /// The four texels around the direction with bilinear weights, clamped at the face's
    /// edges: the runtime's lookup.
    Bilinear,
    /// The one texel the direction falls in.
    Nearest,
}

/// A cube resolution and the lookup that reads it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct CubeFloor {
    /// Texels along a face's side, 1..=[`MAX_CUBE_RESOLUTION`] (the bake's bound).
    pub resolution: u32,
    pub lookup: FloorLookup,
}

impl CubeFloor {
    /// Errors, naming the value, when the resolution is outside 1..=[`MAX_CUBE_RESOLUTION`].
    pub fn validate(&self) -> Result<()> {
        if (1..=MAX_CUBE_RESOLUTION).contains(&self.resolution) {
            Ok(())
        } else {
            Err(BakeError::Invalid(format!(
                "cube floor resolution {} must be in 1..={MAX_CUBE_RESOLUTION}",
                self.resolution
            )))
        }
    }

    /// One direction of the lookup of `dir` (a unit vector): a texel drawn with the lookup's
    /// weights, and a direction uniform in that texel's face coordinates. Four random numbers.
    pub fn direction(&self, dir: Vec3, rng: &mut Rng) -> Vec3 {
        let n = self.resolution.max(1);
        let (face, s, t) = direction_to_face_st(dir.to_array());
        let (tx, ty) = match self.lookup {
            FloorLookup::Bilinear => {
                let tap = Tap::new(n, s, t);
                let tx = if rng.next_f32() < tap.wx {
                    tap.x1
                } else {
                    tap.x0
                };
                let ty = if rng.next_f32() < tap.wy {
                    tap.y1
                } else {
                    tap.y0
                };
                (tx, ty)
            }
            FloorLookup::Nearest => {
                let texel = |c: f32| ((c * n as f32) as u32).min(n - 1);
                (texel(s), texel(t))
            }
        };
        let nf = n as f32;
        let s = (tx as f32 + rng.next_f32()) / nf;
        let t = (ty as f32 + rng.next_f32()) / nf;
        Vec3::from(face_st_to_direction(face, s, t))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The face and texel a direction falls in at resolution `n`.
    fn texel_of(d: Vec3, n: u32) -> (usize, u32, u32) {
        let (face, s, t) = direction_to_face_st(d.to_array());
        let c = |v: f32| ((v * n as f32) as u32).min(n - 1);
        (face, c(s), c(t))
    }

    #[test]
    fn a_nearest_floor_stays_in_the_texel_of_its_direction() {
        let mut rng = Rng::new(1, 2);
        for n in [1, 2, 7, 64, 1000] {
            let floor = CubeFloor {
                resolution: n,
                lookup: FloorLookup::Nearest,
            };
            for _ in 0..2000 {
                let d = Vec3::new(
                    rng.next_f32() - 0.5,
                    rng.next_f32() - 0.5,
                    rng.next_f32() - 0.5,
                )
                .normalize();
                let got = floor.direction(d, &mut rng);
                assert!((got.length() - 1.0).abs() < 1e-5);
                assert_eq!(texel_of(got, n), texel_of(d, n), "n {n}, d {d}");
            }
        }
    }

    #[test]
    fn a_bilinear_floor_draws_the_four_texels_with_their_weights() {
        let n = 16;
        let floor = CubeFloor {
            resolution: n,
            lookup: FloorLookup::Bilinear,
        };
        // Face 4 (+z) at s = (5.5 + 0.3) / 16, t = (9.5 + 0.8) / 16: texels x 5, 6 with
        // weights 0.7, 0.3; y 9, 10 with 0.2, 0.8.
        let d = Vec3::from(face_st_to_direction(4, 5.8 / 16.0, 10.3 / 16.0));
        let mut rng = Rng::new(7, 11);
        let draws = 40_000;
        let mut counts = std::collections::HashMap::new();
        for _ in 0..draws {
            *counts
                .entry(texel_of(floor.direction(d, &mut rng), n))
                .or_insert(0u32) += 1;
        }
        assert_eq!(counts.len(), 4, "{counts:?}");
        for ((x, wx), (y, wy)) in [(5, 0.7), (6, 0.3)]
            .into_iter()
            .flat_map(|a| [(9, 0.2), (10, 0.8)].into_iter().map(move |b| (a, b)))
        {
            let p: f64 = wx * wy;
            let got = f64::from(counts[&(4, x, y)]) / f64::from(draws);
            let sigma = (p * (1.0 - p) / f64::from(draws)).sqrt();
            assert!(
                (got - p).abs() < 5.0 * sigma,
                "texel ({x}, {y}): {got} against {p}"
            );
        }
    }

    #[test]
    fn a_floor_at_the_face_edge_stays_on_the_face() {
        // Beyond the last texel centre the lookup clamps (as the runtime's): the edge texel.
        let floor = CubeFloor {
            resolution: 8,
            lookup: FloorLookup::Bilinear,
        };
        let d = Vec3::from(face_st_to_direction(0, 0.99, 0.01));
        let mut rng = Rng::new(3, 5);
        for _ in 0..500 {
            assert_eq!(texel_of(floor.direction(d, &mut rng), 8), (0, 7, 0));
        }
    }

    #[test]
    fn resolutions_outside_the_bakes_range_are_refused() {
        for resolution in [0, MAX_CUBE_RESOLUTION + 1] {
            let err = CubeFloor {
                resolution,
                lookup: FloorLookup::Nearest,
            }
            .validate()
            .unwrap_err()
            .to_string();
            assert!(err.contains(&resolution.to_string()), "{err}");
        }
    }
}
