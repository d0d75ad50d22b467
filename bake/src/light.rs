//! Delta lights: point lights and the sun.
//!
//! Both are treated as *delta* lights for shading: a surface point receives light from them
//! only through next-event estimation (one shadow ray per light per shading point), irradiance
//! `E = I cos θ / r²` for a point light and `E = E_sun cos θ` for the sun.
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
        match self {
            Light::Point {
                position,
                intensity,
            } => {
                if !position.is_finite() {
                    return Err(BakeError::Invalid(format!(
                        "point light position {position} is not finite"
                    )));
                }
                non_negative(*intensity, "intensity")
            }
            Light::Sun {
                direction,
                irradiance,
                angular_radius,
            } => {
                if !direction.is_finite() || direction.length_squared() < 1e-12 {
                    return Err(BakeError::Invalid(format!(
                        "sun direction {direction} must be a finite non-zero vector"
                    )));
                }
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
                let d = *position - p;
                let r2 = d.length_squared();
                if !(r2 > 0.0 && r2.is_finite()) {
                    return None;
                }
                let r = r2.sqrt();
                let e = *intensity / r2;
                if !e.is_finite() || e == Vec3::ZERO {
                    return None;
                }
                Some(LightSample {
                    dir: d / r,
                    distance: r,
                    irradiance: e,
                })
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

    /// Radiance of the sun's disc seen along `dir` (unit), zero for point lights and outside
    /// the disc.
    ///
    /// The disc is uniform with radiance `L = E / (π sin²α)`, α the angular radius, so that
    /// integrating `L cos θ` over the disc seen face-on gives exactly the irradiance `E`. (The
    /// small-disc approximation `E / Ω`, `Ω = 2π(1 − cos α)`, differs by a factor
    /// `1 − tan²(α/2)`, under 10⁻⁵ for the real sun.) Added only to primary rays; see the
    /// module documentation.
    pub fn disc_radiance(&self, dir: Vec3) -> Vec3 {
        match self {
            Light::Point { .. } => Vec3::ZERO,
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
