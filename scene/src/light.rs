//! Delta lights: point lights, spot lights and the sun.
//!
//! All are treated as *delta* lights for shading: a surface point receives light from them
//! only through next-event estimation (one shadow ray per light per shading point), irradiance
//! `E = I cos θ / r²` for a point light, `E = I a(ψ) cos θ / r²` for a spot light (`a` its cone
//! falloff, [`spot_falloff`]) and `E = E_sun cos θ` for the sun.
//!
//! The sun additionally has a visible disc (see [`Light::disc_radiance`]). The integrator adds
//! the disc's radiance **only** to camera / primary rays (the first segment of a path, i.e. the
//! rays shot from a camera or an OSLF sample point) that escape the scene towards the sun. Rays
//! scattered off surfaces never pick up the disc, so the sun is not counted twice (once by its
//! shadow ray, once by a BSDF-sampled ray hitting the disc). Cube maps and camera renders
//! therefore show the sun; diffuse shading sees it as the delta light only.

use std::f32::consts::PI;

use glam::Vec3;

use crate::{BakeError, Result};

/// A light source.
#[derive(Clone, Debug, PartialEq)]
pub enum Light {
    /// An isotropic point light.
    Point {
        position: Vec3,
        /// Radiant intensity per channel (W/sr).
        intensity: Vec3,
    },
    /// A point light limited to a cone (glTF's `KHR_lights_punctual` spot light): radiant
    /// intensity `intensity · a(ψ)` at angle ψ from `direction`, `a` = [`spot_falloff`] (1
    /// inside `inner_angle`, 0 outside `outer_angle`).
    Spot {
        position: Vec3,
        /// Unit vector the light shines along (the cone's axis).
        direction: Vec3,
        /// Radiant intensity on the axis, per channel (W/sr).
        intensity: Vec3,
        /// Half-angle of the full-intensity cone, radians, in `[0, outer_angle]`.
        inner_angle: f32,
        /// Half-angle beyond which the light is dark, radians, in `(0, π/2]`.
        outer_angle: f32,
    },
    /// A distant light with a visible disc.
    Sun {
        /// Unit vector from the scene towards the sun.
        direction: Vec3,
        /// Irradiance (W/m²) on a surface facing the sun.
        irradiance: Vec3,
        /// Angular radius of the visible disc in radians (the real sun: about 0.00465);
        /// 0 = no visible disc. It does not soften shadows.
        angular_radius: f32,
    },
}

/// The incident light at a point from one delta light.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightSample {
    /// Unit direction from the point towards the light.
    pub dir: Vec3,
    /// Distance to the light (`f32::MAX` for the sun): the shadow ray's extent.
    pub distance: f32,
    /// Irradiance on a surface facing the light (multiply by `cos θ` for a tilted surface).
    pub irradiance: Vec3,
}

impl Light {
    /// Errors on non-finite or negative values, a zero sun direction or an angular radius
    /// outside `[0, π/2)`.
    pub fn validate(&self) -> Result<()> {
        let non_negative = |c: Vec3, what: &str| -> Result<()> {
            if c.is_finite() && c.min_element() >= 0.0 {
                Ok(())
            } else {
                Err(BakeError::Invalid(format!(
                    "light {what} {c} must be finite and non-negative"
                )))
            }
        };
        let finite_position = |p: Vec3, what: &str| -> Result<()> {
            if p.is_finite() {
                Ok(())
            } else {
                Err(BakeError::Invalid(format!(
                    "{what} position {p} is not finite"
                )))
            }
        };
        let nonzero_direction = |d: Vec3, what: &str| -> Result<()> {
            if d.is_finite() && d.length_squared() >= 1e-12 {
                Ok(())
            } else {
                Err(BakeError::Invalid(format!(
                    "{what} direction {d} must be a finite non-zero vector"
                )))
            }
        };
        match self {
            Light::Point {
                position,
                intensity,
            } => {
                finite_position(*position, "point light")?;
                non_negative(*intensity, "intensity")
            }
            Light::Spot {
                position,
                direction,
                intensity,
                inner_angle,
                outer_angle,
            } => {
                finite_position(*position, "spot light")?;
                nonzero_direction(*direction, "spot light")?;
                if !(outer_angle.is_finite() && *outer_angle > 0.0 && *outer_angle <= 0.5 * PI) {
                    return Err(BakeError::Invalid(format!(
                        "spot light outer cone angle {outer_angle} must be in (0, π/2] radians"
                    )));
                }
                if !(inner_angle.is_finite() && *inner_angle >= 0.0 && inner_angle <= outer_angle) {
                    return Err(BakeError::Invalid(format!(
                        "spot light inner cone angle {inner_angle} must be in [0, outer angle {outer_angle}] radians"
                    )));
                }
                non_negative(*intensity, "intensity")
            }
            Light::Sun {
                direction,
                irradiance,
                angular_radius,
            } => {
                nonzero_direction(*direction, "sun")?;
                if !(angular_radius.is_finite()
                    && *angular_radius >= 0.0
                    && *angular_radius < 0.5 * PI)
                {
                    return Err(BakeError::Invalid(format!(
                        "sun angular radius {angular_radius} must be in [0, π/2) radians"
                    )));
                }
                non_negative(*irradiance, "irradiance")
            }
        }
    }

    /// Incident light at `p`, or `None` if the light contributes nothing there (a point light
    /// at `p` itself, zero power, or a degenerate sun direction).
    pub fn sample_li(&self, p: Vec3) -> Option<LightSample> {
        match self {
            Light::Point {
                position,
                intensity,
            } => {
                let (dir, r, r2) = toward(*position, p)?;
                lit(dir, r, *intensity / r2)
            }
            Light::Spot {
                position,
                direction,
                intensity,
                inner_angle,
                outer_angle,
            } => {
                let (dir, r, r2) = toward(*position, p)?;
                let axis = direction.try_normalize()?;
                // ψ is the angle between the axis and the direction from the light to `p`.
                let a = spot_falloff(-dir.dot(axis), *inner_angle, *outer_angle);
                lit(dir, r, *intensity * (a / r2))
            }
            Light::Sun {
                direction,
                irradiance,
                ..
            } => {
                let dir = direction.try_normalize()?;
                if *irradiance == Vec3::ZERO || !irradiance.is_finite() {
                    return None;
                }
                Some(LightSample {
                    dir,
                    distance: f32::MAX,
                    irradiance: *irradiance,
                })
            }
        }
    }

    /// Radiance of the sun's disc seen along `dir` (unit), zero for point and spot lights and outside
    /// the disc.
    ///
    /// The disc is uniform with radiance `L = E / (π sin²α)`, α the angular radius, so that
    /// integrating `L cos θ` over the disc seen face-on gives exactly the irradiance `E`. (The
    /// small-disc approximation `E / Ω`, `Ω = 2π(1 − cos α)`, differs by a factor
    /// `1 − tan²(α/2)`, under 10⁻⁵ for the real sun.) Added only to primary rays; see the
    /// module documentation.
    pub fn disc_radiance(&self, dir: Vec3) -> Vec3 {
        match self {
            Light::Point { .. } | Light::Spot { .. } => Vec3::ZERO,
            Light::Sun {
                direction,
                irradiance,
                angular_radius,
            } => {
                let Some(s) = direction.try_normalize() else {
                    return Vec3::ZERO;
                };
                let a = *angular_radius;
                if !(a > 0.0 && a < 0.5 * PI) {
                    return Vec3::ZERO;
                }
                if dir.dot(s) < a.cos() {
                    return Vec3::ZERO;
                }
                let sin_a = a.sin();
                let l = *irradiance / (PI * sin_a * sin_a);
                if l.is_finite() {
                    l
                } else {
                    Vec3::ZERO
                }
            }
        }
    }
}

/// The angular falloff of a spot light, `a(ψ)` for `cos_psi` = cos ψ, ψ the angle from the
/// cone's axis: the reference implementation of glTF's `KHR_lights_punctual`,
///
/// ```text
/// t = clamp((cos ψ − cos outer) / max(0.001, cos inner − cos outer), 0, 1),   a = t²
/// ```
///
/// a ramp linear in cos ψ (no smoothstep), squared: 1 inside the inner cone, 0 outside the
/// outer cone.
pub fn spot_falloff(cos_psi: f32, inner_angle: f32, outer_angle: f32) -> f32 {
    let cos_outer = outer_angle.cos();
    let cos_inner = inner_angle.cos();
    let scale = 1.0 / (cos_inner - cos_outer).max(0.001);
    let t = ((cos_psi - cos_outer) * scale).clamp(0.0, 1.0);
    if t.is_finite() {
        t * t
    } else {
        0.0
    }
}

/// The unit direction from `p` to a light at `position`, the distance and its square; `None`
/// when the light is at `p` or infinitely far.
fn toward(position: Vec3, p: Vec3) -> Option<(Vec3, f32, f32)> {
    let d = position - p;
    let r2 = d.length_squared();
    if !(r2 > 0.0 && r2.is_finite()) {
        return None;
    }
    let r = r2.sqrt();
    Some((d / r, r, r2))
}

/// The sample of a light at distance `r` along `dir` giving irradiance `e`; `None` when `e` is
/// zero or not finite.
fn lit(dir: Vec3, r: f32, e: Vec3) -> Option<LightSample> {
    if !e.is_finite() || e == Vec3::ZERO {
        return None;
    }
    Some(LightSample {
        dir,
        distance: r,
        irradiance: e,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn spot() -> Light {
        Light::Spot {
            position: Vec3::new(0.0, 0.0, 2.0),
            direction: Vec3::NEG_Z,
            intensity: Vec3::new(8.0, 4.0, 2.0),
            inner_angle: 20f32.to_radians(),
            outer_angle: 40f32.to_radians(),
        }
    }

    #[test]
    fn spot_validates() {
        assert!(spot().validate().is_ok());
        let with = |inner: f32, outer: f32, dir: Vec3| Light::Spot {
            position: Vec3::ZERO,
            direction: dir,
            intensity: Vec3::ONE,
            inner_angle: inner,
            outer_angle: outer,
        };
        assert!(with(0.0, 0.5 * PI, Vec3::Z).validate().is_ok());
        assert!(with(0.3, 0.3, Vec3::Z).validate().is_ok());
        assert!(with(0.4, 0.3, Vec3::Z).validate().is_err());
        assert!(with(0.0, 0.0, Vec3::Z).validate().is_err());
        assert!(with(0.0, 2.0, Vec3::Z).validate().is_err());
        assert!(with(-0.1, 0.3, Vec3::Z).validate().is_err());
        assert!(with(0.0, f32::NAN, Vec3::Z).validate().is_err());
        assert!(with(0.0, 0.3, Vec3::ZERO).validate().is_err());
        let mut bad = spot();
        if let Light::Spot { intensity, .. } = &mut bad {
            *intensity = Vec3::new(1.0, -1.0, 0.0);
        }
        assert!(bad.validate().is_err());
    }

    #[test]
    fn spot_sample_li_follows_the_cone() {
        let light = spot();
        // On the axis, 2 below the light: I / r².
        let s = light.sample_li(Vec3::ZERO).unwrap();
        assert!((s.dir - Vec3::Z).length() < 1e-6);
        assert!((s.distance - 2.0).abs() < 1e-6);
        assert!((s.irradiance - Vec3::new(2.0, 1.0, 0.5)).length() < 1e-6);
        // Inside the inner cone (ψ = 10°): full intensity, r = 2 / cos 10°.
        let psi = 10f32.to_radians();
        let p = Vec3::new(2.0 * psi.tan(), 0.0, 0.0);
        let s = light.sample_li(p).unwrap();
        let r2 = 4.0 + p.x * p.x;
        assert!((s.irradiance.x - 8.0 / r2).abs() < 1e-5);
        // Half-way in cos between the cones: (½)² = ¼ of the intensity.
        let (ci, co) = (20f32.to_radians().cos(), 40f32.to_radians().cos());
        let psi = (0.5 * (ci + co)).acos();
        let p = Vec3::new(2.0 * psi.tan(), 0.0, 0.0);
        let s = light.sample_li(p).unwrap();
        let r2 = 4.0 + p.x * p.x;
        assert!(
            (s.irradiance.x - 0.25 * 8.0 / r2).abs() < 1e-4,
            "{}",
            s.irradiance
        );
        // Outside the outer cone and behind the light: nothing.
        let psi = 41f32.to_radians();
        assert!(light
            .sample_li(Vec3::new(2.0 * psi.tan(), 0.0, 0.0))
            .is_none());
        assert!(light.sample_li(Vec3::new(0.0, 0.0, 3.0)).is_none());
        // At the light itself: nothing, and never a visible disc.
        assert!(light.sample_li(Vec3::new(0.0, 0.0, 2.0)).is_none());
        assert_eq!(light.disc_radiance(Vec3::NEG_Z), Vec3::ZERO);
    }

    #[test]
    fn spot_falloff_reference_values() {
        let (i, o) = (0.2f32, 0.6f32);
        assert_eq!(spot_falloff(1.0, i, o), 1.0);
        assert_eq!(spot_falloff(i.cos(), i, o), 1.0);
        assert!(spot_falloff(o.cos(), i, o).abs() < 1e-6);
        assert_eq!(spot_falloff(0.0, i, o), 0.0);
        let mid = 0.5 * (i.cos() + o.cos());
        assert!((spot_falloff(mid, i, o) - 0.25).abs() < 1e-5);
        // Equal angles: a hard edge, no NaN.
        assert_eq!(spot_falloff(1.0, 0.3, 0.3), 1.0);
        assert_eq!(spot_falloff(0.9, 0.3, 0.3), 0.0);
        assert_eq!(spot_falloff(f32::NAN, 0.3, 0.5), 0.0);
    }
}
