//! The irradiance section (`docs/format.md`, "Irradiance section"): per cube, its radiance in
//! spherical harmonics of bands 0–2, projected from all of the cube's decoded texels, each
//! weighted by its solid angle. The runtime convolves it with the diffuse lobe at the shaded
//! normal ([`oslf_shading::sh`]), so the diffuse base is as smooth as an engine's irradiance
//! map and still varies from sample point to sample point.
//!
//! The writer projects the faces as they are stored (decoded from their frames when the store
//! is finished), so a fresh, a resumed and a merged bake of one scene write the same section,
//! and a reader can check it against the cube it came from.

use glam::Vec3;
use oslf_shading::sh::{self, COEFFS};

use crate::cube::{texel_direction, texel_solid_angle, FACES};
use crate::Error;

/// A cube's radiance in spherical harmonics: per coefficient ([`sh::basis`] order) linear RGB.
pub type CubeSh = [[f32; 3]; COEFFS];

/// Bytes of one cube's record: 27 `f32`, coefficient-major, RGB within.
pub const IRRADIANCE_CUBE_BYTES: usize = COEFFS * 3 * 4;

/// Sums a cube's projection onto the nine spherical harmonics face by face ([`Projection::face`]),
/// in `f64`, in texel order: the same faces give the same bytes on every host.
#[derive(Clone, Debug)]
pub struct Projection {
    resolution: u32,
    sums: [[f64; 3]; COEFFS],
}

impl Projection {
    /// An empty projection of a cube of `resolution` texels a side.
    pub fn new(resolution: u32) -> Self {
        Projection {
            resolution,
            sums: [[0.0; 3]; COEFFS],
        }
    }

    /// Adds face `face`'s texels (`resolution²`, row-major).
    pub fn face(&mut self, face: usize, texels: &[[f32; 3]]) {
        let n = self.resolution.max(1);
        for (i, c) in texels.iter().enumerate() {
            let (x, y) = (i as u32 % n, i as u32 / n);
            let d = Vec3::from_array(texel_direction(face, x, y, n));
            let w = f64::from(texel_solid_angle(x, y, n));
            for (k, y) in sh::basis(d).iter().enumerate() {
                let wy = w * f64::from(*y);
                for (sum, v) in self.sums[k].iter_mut().zip(c) {
                    *sum += f64::from(*v) * wy;
                }
            }
        }
    }

    /// The coefficients; `Err` names the first that is not finite as an `f32`.
    pub fn finish(&self, cube: u32) -> Result<CubeSh, Error> {
        let mut out = [[0.0f32; 3]; COEFFS];
        for (k, sum) in self.sums.iter().enumerate() {
            for ch in 0..3 {
                let v = sum[ch] as f32;
                if !v.is_finite() {
                    return Err(Error::InvalidIrradiance {
                        cube: u64::from(cube),
                        coefficient: k,
                        channel: ch,
                        offset: 0,
                        value: v,
                    });
                }
                out[k][ch] = v;
            }
        }
        Ok(out)
    }
}

/// The coefficients of a decoded cube's six faces ([`crate::CubeImage`]'s `faces`).
pub fn project(
    resolution: u32,
    faces: &[Vec<[f32; 3]>; FACES],
    cube: u32,
) -> Result<CubeSh, Error> {
    let mut p = Projection::new(resolution);
    for (face, texels) in faces.iter().enumerate() {
        p.face(face, texels);
    }
    p.finish(cube)
}

/// A cube's record as stored.
pub(crate) fn to_bytes(c: &CubeSh) -> [u8; IRRADIANCE_CUBE_BYTES] {
    let mut b = [0u8; IRRADIANCE_CUBE_BYTES];
    for (i, v) in c.iter().flatten().enumerate() {
        b[4 * i..4 * i + 4].copy_from_slice(&v.to_le_bytes());
    }
    b
}

/// Parses the section (`bytes`, at byte offset `offset`; its size already checked against the
/// cube count): every coefficient must be finite.
pub(crate) fn parse(bytes: &[u8], offset: u64) -> Result<Vec<CubeSh>, Error> {
    bytes
        .chunks_exact(IRRADIANCE_CUBE_BYTES)
        .enumerate()
        .map(|(cube, rec)| {
            let mut c = [[0.0f32; 3]; COEFFS];
            for (i, v) in rec.chunks_exact(4).enumerate() {
                let value = f32::from_le_bytes([v[0], v[1], v[2], v[3]]);
                if !value.is_finite() {
                    return Err(Error::InvalidIrradiance {
                        cube: cube as u64,
                        coefficient: i / 3,
                        channel: i % 3,
                        offset: offset + (cube * IRRADIANCE_CUBE_BYTES + 4 * i) as u64,
                        value,
                    });
                }
                c[i / 3][i % 3] = value;
            }
            Ok(c)
        })
        .collect()
}

/// The irradiance ÷ π at unit normal `n` of coefficients `c`: `∫ L(l) max(⟨n,l⟩, 0) dl / π`
/// ([`sh::convolve`] with the cosine lobe).
pub fn irradiance(c: &CubeSh, n: Vec3) -> Vec3 {
    sh::convolve(&c.map(Vec3::from_array), sh::COSINE, n)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cube::CubeImage;

    fn cube(n: u32, f: impl Fn(Vec3) -> Vec3) -> CubeImage {
        let mut c = CubeImage::black(n, false);
        for (face, texels) in c.faces.iter_mut().enumerate() {
            for (i, t) in texels.iter_mut().enumerate() {
                let d = Vec3::from_array(texel_direction(face, i as u32 % n, i as u32 / n, n));
                *t = f(d).to_array();
            }
        }
        c
    }

    #[test]
    fn texels_sum_to_the_sphere() {
        for n in [1, 2, 3, 8, 64] {
            let total: f64 = (0..FACES)
                .flat_map(|_| {
                    (0..n * n).map(move |i| f64::from(texel_solid_angle(i % n, i / n, n)))
                })
                .sum();
            assert!(
                (total - 4.0 * std::f64::consts::PI).abs() < 1e-5,
                "{n}: {total}"
            );
        }
    }

    #[test]
    fn a_furnace_and_a_gradient_give_their_irradiance() {
        // Uniform radiance 2: irradiance ÷ π is 2 everywhere (within the texels' solid-angle
        // sum). L = 1 + z: 5/3 facing up, 1 sideways, 1/3 facing down, up to the projection's
        // quadrature error at 16 texels a side.
        let flat = cube(16, |_| Vec3::splat(2.0));
        let c = project(16, &flat.faces, 0).unwrap();
        for n in [Vec3::X, Vec3::NEG_Y, Vec3::new(0.6, 0.0, 0.8)] {
            assert!((irradiance(&c, n) - Vec3::splat(2.0)).abs().max_element() < 1e-5);
        }
        let grad = cube(16, |d| Vec3::splat(1.0 + d.z));
        let c = project(16, &grad.faces, 0).unwrap();
        assert!(
            (irradiance(&c, Vec3::Z).x - 5.0 / 3.0).abs() < 2e-3,
            "{}",
            irradiance(&c, Vec3::Z)
        );
        assert!(
            (irradiance(&c, Vec3::Y).x - 1.0).abs() < 2e-3,
            "{}",
            irradiance(&c, Vec3::Y)
        );
        assert!((irradiance(&c, -Vec3::Z).x - 1.0 / 3.0).abs() < 2e-3);
    }

    #[test]
    fn records_round_trip_and_refuse_non_finite_values() {
        let grad = cube(4, |d| Vec3::new(1.0 + d.z, 0.5, d.x.abs()));
        let c = project(4, &grad.faces, 0).unwrap();
        let mut bytes = to_bytes(&c).to_vec();
        bytes.extend_from_slice(&to_bytes(&c));
        assert_eq!(parse(&bytes, 1000).unwrap(), vec![c, c]);
        bytes[IRRADIANCE_CUBE_BYTES + 4 * 7..IRRADIANCE_CUBE_BYTES + 4 * 8]
            .copy_from_slice(&f32::NAN.to_le_bytes());
        let e = parse(&bytes, 1000).unwrap_err().to_string();
        assert!(
            e.contains("cube 1, coefficient 2, channel 1 (byte offset 1136)"),
            "{e}"
        );
    }
}
