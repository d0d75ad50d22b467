//! The Ashikhmin–Shirley anisotropic Phong BRDF (thesis chapter 5; Ashikhmin & Shirley 2000)
//! for the ground-truth renders ([`crate::ground_truth`]).
//!
//! This is written from the paper's formulas, in `f64`, independently of the runtime's shader
//! (`runtime/src/shade/glossy.wgsl`), which uses the simplified estimator
//! F(⟨v,h⟩)⟨n,l⟩ / max(⟨n,v⟩, ⟨n,l⟩): the ground truth evaluates the BRDF and the density
//! separately, so a mistake in one does not hide in the other.
//!
//! Vectors are in the local shading frame: `t` along +x (the tangent, ∂x/∂u made orthogonal to
//! the normal), `b = n × t` along +y, the normal `n` along +z. `n_u` is the exponent along `t`,
//! `n_v` along `b`. The exponent of ⟨n,h⟩ is written `n_u cos²φ_h + n_v sin²φ_h` (see
//! `../NOTES`: the thesis's 5.5/5.8 print ⟨h,v⟩ where the tangent is meant), which is finite at
//! h = n, where ⟨n,h⟩ = 1 makes the power 1 whatever the exponent.

use std::f64::consts::PI;

use glam::DVec3;

/// The lobe's parameters: specular reflectance R_s and the exponents n_u, n_v (≥ 0).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AsLobe {
    pub rs: f64,
    pub nu: f64,
    pub nv: f64,
}

impl AsLobe {
    /// Schlick's Fresnel approximation (Eq. 5.7).
    pub fn fresnel(&self, cos: f64) -> f64 {
        let k = (1.0 - cos).clamp(0.0, 1.0);
        self.rs + (1.0 - self.rs) * k.powi(5)
    }

    /// `⟨n,h⟩^(n_u cos²φ_h + n_v sin²φ_h)` for a unit half vector `h` with ⟨n,h⟩ > 0.
    fn lobe_power(&self, h: DVec3) -> f64 {
        let s2 = h.x * h.x + h.y * h.y;
        if s2 <= 0.0 {
            return 1.0; // h = n
        }
        let e = (self.nu * h.x * h.x + self.nv * h.y * h.y) / s2;
        h.z.powf(e)
    }

    /// √((n_u + 1)(n_v + 1)), the normalization of Eq. 5.5 and 5.8.
    fn norm(&self) -> f64 {
        ((self.nu + 1.0) * (self.nv + 1.0)).sqrt()
    }

    /// The specular BRDF ρ_s(v, l) of Eq. 5.5 (v, l unit, local frame); 0 below the surface.
    pub fn eval(&self, v: DVec3, l: DVec3) -> f64 {
        if v.z <= 0.0 || l.z <= 0.0 {
            return 0.0;
        }
        let Some(h) = (v + l).try_normalize() else {
            return 0.0;
        };
        let vh = v.dot(h);
        if vh <= 0.0 {
            return 0.0;
        }
        self.norm() / (8.0 * PI) * self.lobe_power(h) / (vh * v.z.max(l.z)) * self.fresnel(vh)
    }

    /// Samples a half vector (Eq. 5.9): φ in the quadrant of `u.x`, θ from `u.y`.
    pub fn sample_half(&self, u: [f64; 2]) -> DVec3 {
        let xi1 = u[0].clamp(0.0, 1.0);
        let q = ((xi1 * 4.0) as u32).min(3);
        let x = xi1 * 4.0 - q as f64;
        let a = ((self.nu + 1.0) / (self.nv + 1.0)).sqrt();
        // φ in [0, π/2]: tan φ = a · tan(πx/2), without the tangent's pole.
        let half = 0.5 * PI * x;
        let mut phi = (a * half.sin()).atan2(half.cos());
        phi = match q {
            0 => phi,
            1 => PI - phi,
            2 => PI + phi,
            _ => 2.0 * PI - phi,
        };
        let e = self.nu * phi.cos().powi(2) + self.nv * phi.sin().powi(2);
        let cos_theta = (1.0 - u[1].clamp(0.0, 1.0)).powf(1.0 / (e + 1.0));
        let sin_theta = (1.0 - cos_theta * cos_theta).max(0.0).sqrt();
        DVec3::new(sin_theta * phi.cos(), sin_theta * phi.sin(), cos_theta)
    }

    /// Density of [`Self::sample_half`] over solid angle of h.
    pub fn half_pdf(&self, h: DVec3) -> f64 {
        if h.z <= 0.0 {
            return 0.0;
        }
        self.norm() / (2.0 * PI) * self.lobe_power(h)
    }

    /// The `u` that [`Self::sample_half`] maps to `h` (upper hemisphere).
    pub fn invert_half(&self, h: DVec3) -> [f64; 2] {
        let mut phi = h.y.atan2(h.x);
        if phi < 0.0 {
            phi += 2.0 * PI;
        }
        let q = ((phi / (0.5 * PI)) as u32).min(3);
        let local = match q {
            0 => phi,
            1 => PI - phi,
            2 => phi - PI,
            _ => 2.0 * PI - phi,
        };
        let a = ((self.nu + 1.0) / (self.nv + 1.0)).sqrt();
        // tan(πx/2) = tan φ / a
        let half = local.sin().atan2(a * local.cos());
        let x = half / (0.5 * PI);
        let e = self.nu * phi.cos().powi(2) + self.nv * phi.sin().powi(2);
        let u1 = 1.0 - h.z.clamp(0.0, 1.0).powf(e + 1.0);
        [(q as f64 + x) / 4.0, u1]
    }

    /// Samples a light direction l by reflecting v about a sampled half vector (Eq. 5.10).
    /// `None` when l falls below the surface.
    pub fn sample_light(&self, v: DVec3, u: [f64; 2]) -> Option<DVec3> {
        let h = self.sample_half(u);
        let l = 2.0 * v.dot(h) * h - v;
        (l.z > 0.0 && v.dot(h) > 0.0).then_some(l)
    }

    /// Density of [`Self::sample_light`] over solid angle of l (Eq. 5.11): p_h / (4⟨v,h⟩).
    pub fn light_pdf(&self, v: DVec3, l: DVec3) -> f64 {
        let Some(h) = (v + l).try_normalize() else {
            return 0.0;
        };
        let vh = v.dot(h);
        if vh <= 0.0 {
            return 0.0;
        }
        self.half_pdf(h) / (4.0 * vh)
    }

    /// The `u` that [`Self::sample_light`] maps to `l` from `v`.
    pub fn invert_light(&self, v: DVec3, l: DVec3) -> Option<[f64; 2]> {
        let h = (v + l).try_normalize()?;
        Some(self.invert_half(h))
    }

    /// The directional albedo ∫ ρ_s(v, l) ⟨n,l⟩ dl by a midpoint rule over `n_theta × n_phi`
    /// cells of (θ, φ): a deterministic reference for the sampler (the cells must resolve the
    /// lobe, about 1/√n wide).
    pub fn albedo_quadrature(&self, v: DVec3, n_theta: usize, n_phi: usize) -> f64 {
        let (dt, dp) = (0.5 * PI / n_theta as f64, 2.0 * PI / n_phi as f64);
        let mut sum = 0.0;
        for i in 0..n_theta {
            let t = (i as f64 + 0.5) * dt;
            for j in 0..n_phi {
                let p = (j as f64 + 0.5) * dp;
                let l = DVec3::new(t.sin() * p.cos(), t.sin() * p.sin(), t.cos());
                sum += self.eval(v, l) * l.z * t.sin() * dt * dp;
            }
        }
        sum
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn dir(theta_deg: f64, phi_deg: f64) -> DVec3 {
        let (t, p) = (theta_deg.to_radians(), phi_deg.to_radians());
        DVec3::new(t.sin() * p.cos(), t.sin() * p.sin(), t.cos())
    }

    /// Stratified Monte Carlo estimate of the same integral through the sampler and its pdf.
    fn albedo_monte_carlo(lobe: &AsLobe, v: DVec3, n: usize) -> f64 {
        let mut sum = 0.0;
        for i in 0..n {
            for j in 0..n {
                let u = [(i as f64 + 0.5) / n as f64, (j as f64 + 0.5) / n as f64];
                if let Some(l) = lobe.sample_light(v, u) {
                    let pdf = lobe.light_pdf(v, l);
                    if pdf > 0.0 {
                        sum += lobe.eval(v, l) * l.z / pdf;
                    }
                }
            }
        }
        sum / (n * n) as f64
    }

    #[test]
    fn sampler_and_pdf_integrate_to_the_albedo() {
        for (lobe, v, grid) in [
            (
                AsLobe {
                    rs: 1.0,
                    nu: 10.0,
                    nv: 10.0,
                },
                dir(30.0, 0.0),
                (800, 1600),
            ),
            (
                AsLobe {
                    rs: 0.5,
                    nu: 100.0,
                    nv: 100.0,
                },
                dir(60.0, 40.0),
                (1600, 3200),
            ),
            (
                AsLobe {
                    rs: 1.0,
                    nu: 1000.0,
                    nv: 1000.0,
                },
                dir(10.0, 0.0),
                (4000, 4000),
            ),
            (
                AsLobe {
                    rs: 1.0,
                    nu: 10.0,
                    nv: 1000.0,
                },
                dir(45.0, 20.0),
                (3000, 6000),
            ),
        ] {
            let q = lobe.albedo_quadrature(v, grid.0, grid.1);
            let mc = albedo_monte_carlo(&lobe, v, 400);
            assert!(q > 0.05 && q < 1.2, "{lobe:?}: albedo {q}");
            assert!(
                (mc - q).abs() < 0.01 * q,
                "{lobe:?} at {v:?}: MC {mc} vs quadrature {q}"
            );
        }
    }

    #[test]
    fn the_half_vector_density_integrates_to_one() {
        for lobe in [
            AsLobe {
                rs: 1.0,
                nu: 0.0,
                nv: 0.0,
            },
            AsLobe {
                rs: 1.0,
                nu: 10.0,
                nv: 300.0,
            },
        ] {
            let (nt, np) = (2000, 2000);
            let (dt, dp) = (0.5 * PI / nt as f64, 2.0 * PI / np as f64);
            let mut sum = 0.0;
            for i in 0..nt {
                let t = (i as f64 + 0.5) * dt;
                for j in 0..np {
                    let p = (j as f64 + 0.5) * dp;
                    let h = DVec3::new(t.sin() * p.cos(), t.sin() * p.sin(), t.cos());
                    sum += lobe.half_pdf(h) * t.sin() * dt * dp;
                }
            }
            // Eq. 5.9's density is normalized for cos-weighted... check: ∫ p_h dω = 1.
            assert!((sum - 1.0).abs() < 2e-3, "{lobe:?}: {sum}");
        }
    }

    #[test]
    fn invert_undoes_sample() {
        let lobe = AsLobe {
            rs: 1.0,
            nu: 30.0,
            nv: 700.0,
        };
        for &u in &[
            [0.1, 0.2],
            [0.3, 0.9],
            [0.55, 0.5],
            [0.8, 0.01],
            [0.99, 0.7],
        ] {
            let h = lobe.sample_half(u);
            let back = lobe.invert_half(h);
            assert!(
                (back[0] - u[0]).abs() < 1e-9 && (back[1] - u[1]).abs() < 1e-9,
                "{u:?} -> {back:?}"
            );
        }
    }

    #[test]
    fn extremes_stay_finite() {
        // h = n exactly (the exponent's 0/0), huge and anisotropic exponents, grazing v.
        let lobe = AsLobe {
            rs: 1.0,
            nu: 1e6,
            nv: 1.0,
        };
        let n = DVec3::Z;
        assert_eq!(lobe.half_pdf(n), lobe.norm() / (2.0 * PI));
        assert!(lobe.eval(n, n).is_finite());
        let v = dir(89.999, 0.0);
        for k in 0..100 {
            let u = [(k as f64 + 0.5) / 100.0, 0.5];
            let h = lobe.sample_half(u);
            assert!(h.is_finite() && (h.length() - 1.0).abs() < 1e-9);
            if let Some(l) = lobe.sample_light(v, u) {
                assert!(lobe.eval(v, l).is_finite() && lobe.light_pdf(v, l).is_finite());
            }
        }
        assert_eq!(lobe.fresnel(1.0), 1.0);
        let f = AsLobe {
            rs: 0.04,
            nu: 1.0,
            nv: 1.0,
        };
        assert!((f.fresnel(0.0) - 1.0).abs() < 1e-12 && (f.fresnel(1.0) - 0.04).abs() < 1e-12);
    }
}
