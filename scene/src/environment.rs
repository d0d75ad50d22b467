//! Distant illumination: a constant, a lat-long HDR map, or a procedural clear sky.
//!
//! # Lat-long convention (Z up)
//! A unit direction `d = (x, y, z)` in the map's own frame has
//! `u = ½ + atan2(y, x) / 2π` and `v = acos(z) / π`: `u` grows counter-clockwise seen from
//! above, with the map's centre column (`u = ½`) looking along +x and its left/right edges
//! along −x; `v = 0` is the zenith. Pixel row 0 (the top row of the file) is therefore the
//! zenith and the last row the nadir; column `i` covers `u ∈ [i/w, (i+1)/w)`.
//!
//! A map rotated by `rotation_deg` is turned counter-clockwise about +z (seen from above): the
//! map direction `m` appears at world direction `R_z(rotation) m`.
//!
//! # Sampling
//! All densities are with respect to solid angle. Lat-long maps (and the sky's tabulation) are
//! importance sampled by a piecewise-constant 2D distribution proportional to
//! `luminance × sin θ` per pixel (θ at the row centre); the density in solid angle is
//! `p(u, v) / (2π² sin θ)`. Lat-long maps are evaluated with nearest-texel lookup, so the
//! distribution is exactly proportional to luminance. The constant environment is sampled
//! uniformly over the sphere (it has no preferred direction, and the surface normal is not
//! known here).

use std::f32::consts::{FRAC_1_PI, PI};
use std::path::Path;
use std::sync::Arc;

use glam::{Vec2, Vec3};

use crate::light::Light;
use crate::sampling::Distribution2D;
use oslf_shading::color::luminance;
use oslf_shading::random::ONE_MINUS_EPSILON;
use oslf_shading::warp::{invert_uniform_sphere, sample_uniform_sphere, uniform_sphere_pdf};

use crate::texture::load_linear_rgb;
use crate::{BakeError, Result};

/// Angular radius of the real sun seen from the earth, radians.
pub const SUN_ANGULAR_RADIUS: f32 = 0.004_65;

/// Light arriving from infinitely far away.
#[derive(Clone, Debug)]
pub enum Environment {
    /// The same radiance from every direction.
    Constant(Vec3),
    /// An HDR lat-long map.
    LatLong(Arc<LatLongMap>),
    /// A procedural clear sky (the sun itself is a separate [`Light::Sun`]).
    Sky(Arc<Sky>),
}

impl Environment {
    /// Radiance arriving from direction `dir` (unit, pointing away from the scene).
    pub fn eval(&self, dir: Vec3) -> Vec3 {
        match self {
            Environment::Constant(c) => *c,
            Environment::LatLong(map) => map.eval(dir),
            Environment::Sky(sky) => sky.eval(dir),
        }
    }

    /// Whether the environment is zero in every direction (the integrator then skips its
    /// light samples).
    pub fn is_black(&self) -> bool {
        match self {
            Environment::Constant(c) => *c == Vec3::ZERO,
            Environment::LatLong(map) => map.is_black,
            Environment::Sky(_) => false,
        }
    }

    /// A direction drawn with density roughly proportional to the radiance, and its density in
    /// solid angle (0 if the sample must be discarded).
    pub fn sample_environment(&self, u: Vec2) -> (Vec3, f32) {
        match self {
            Environment::Constant(_) => (sample_uniform_sphere(u), uniform_sphere_pdf()),
            Environment::LatLong(map) => map.sampler.sample(u),
            Environment::Sky(sky) => sky.sampler.sample(u),
        }
    }

    /// The density of [`Environment::sample_environment`] at `dir`, in solid angle.
    pub fn environment_pdf(&self, dir: Vec3) -> f32 {
        match self {
            Environment::Constant(_) => uniform_sphere_pdf(),
            Environment::LatLong(map) => map.sampler.pdf(dir),
            Environment::Sky(sky) => sky.sampler.pdf(dir),
        }
    }

    /// What another implementation (the GPU path tracer) needs to compute the same
    /// radiance, samples and densities.
    pub fn model(&self) -> EnvironmentModel<'_> {
        match self {
            Environment::Constant(c) => EnvironmentModel::Constant(*c),
            Environment::LatLong(map) => EnvironmentModel::LatLong {
                map,
                sampling: map.sampler.tables(),
            },
            Environment::Sky(sky) => EnvironmentModel::Sky {
                model: SkyModel {
                    perez: [sky.perez_y, sky.perez_x, sky.perez_yc]
                        .map(|p| [p.a, p.b, p.c, p.d, p.e]),
                    norm: sky.norm,
                    model_sun: sky.model_sun,
                    ground: sky.ground,
                },
                sampling: sky.sampler.tables(),
            },
        }
    }

    /// Inverse of [`Environment::sample_environment`]: the `u` that maps to `dir`.
    pub fn invert_environment(&self, dir: Vec3) -> Vec2 {
        match self {
            Environment::Constant(_) => invert_uniform_sphere(dir),
            Environment::LatLong(map) => map.sampler.invert(dir),
            Environment::Sky(sky) => sky.sampler.invert(dir),
        }
    }
}

/// An [`Environment`] as data ([`Environment::model`]).
#[derive(Clone, Copy, Debug)]
pub enum EnvironmentModel<'a> {
    Constant(Vec3),
    /// The map (nearest-texel lookup in its lat-long convention, see the module
    /// documentation) and its sampling tables.
    LatLong {
        map: &'a LatLongMap,
        sampling: SamplingTables<'a>,
    },
    Sky {
        model: SkyModel,
        sampling: SamplingTables<'a>,
    },
}

/// A lat-long sampling distribution: the map's rotation about z, and the distribution over
/// `(u, v)` (density in solid angle `p(u, v) / (2π² sin θ)`).
#[derive(Clone, Copy, Debug)]
pub struct SamplingTables<'a> {
    pub cos_rot: f32,
    pub sin_rot: f32,
    pub distribution: &'a Distribution2D,
}

/// The constants of [`Sky::eval`]: the Perez coefficients `[A, B, C, D, E]` of Y, x and y,
/// their normalisation (zenith value over the Perez function there), the sun direction the
/// model uses and the ground's radiance.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SkyModel {
    pub perez: [[f32; 5]; 3],
    pub norm: Vec3,
    pub model_sun: Vec3,
    pub ground: Vec3,
}

/// The lat-long parameterisation with a rotation about z, and a luminance-based sampling
/// distribution over it.
#[derive(Clone, Debug)]
struct LatLongSampler {
    cos_rot: f32,
    sin_rot: f32,
    distribution: Distribution2D,
}

impl LatLongSampler {
    /// `values`: per-pixel importance (already including `sin θ`).
    fn new(width: u32, height: u32, values: &[f32], rotation_deg: f32) -> Result<Self> {
        let r = rotation_deg.to_radians();
        Ok(LatLongSampler {
            cos_rot: r.cos(),
            sin_rot: r.sin(),
            distribution: Distribution2D::new(values, width as usize, height as usize)?,
        })
    }

    fn tables(&self) -> SamplingTables<'_> {
        SamplingTables {
            cos_rot: self.cos_rot,
            sin_rot: self.sin_rot,
            distribution: &self.distribution,
        }
    }

    fn to_map(&self, d: Vec3) -> Vec3 {
        Vec3::new(
            self.cos_rot * d.x + self.sin_rot * d.y,
            -self.sin_rot * d.x + self.cos_rot * d.y,
            d.z,
        )
    }

    fn to_world(&self, m: Vec3) -> Vec3 {
        Vec3::new(
            self.cos_rot * m.x - self.sin_rot * m.y,
            self.sin_rot * m.x + self.cos_rot * m.y,
            m.z,
        )
    }

    /// `(uv, sin θ)` of a world direction.
    fn uv(&self, dir: Vec3) -> (Vec2, f32) {
        let m = self.to_map(dir.try_normalize().unwrap_or(Vec3::Z));
        let u = 0.5 + m.y.atan2(m.x) * (0.5 * FRAC_1_PI);
        let u = u - u.floor();
        let v = m.z.clamp(-1.0, 1.0).acos() * FRAC_1_PI;
        let uv = Vec2::new(u, v).clamp(Vec2::ZERO, Vec2::splat(ONE_MINUS_EPSILON));
        (uv, Vec2::new(m.x, m.y).length())
    }

    fn sample(&self, u: Vec2) -> (Vec3, f32) {
        let (uv, pdf_uv) = self.distribution.sample_continuous(u);
        let theta = uv.y * PI;
        let phi = (uv.x - 0.5) * 2.0 * PI;
        let sin_theta = theta.sin();
        let m = Vec3::new(sin_theta * phi.cos(), sin_theta * phi.sin(), theta.cos());
        let dir = self.to_world(m);
        let denom = 2.0 * PI * PI * sin_theta;
        if denom > 0.0 && pdf_uv > 0.0 {
            let pdf = pdf_uv / denom;
            if pdf.is_finite() {
                return (dir, pdf);
            }
        }
        (dir, 0.0)
    }

    fn pdf(&self, dir: Vec3) -> f32 {
        let (uv, sin_theta) = self.uv(dir);
        let denom = 2.0 * PI * PI * sin_theta;
        if denom <= 0.0 {
            return 0.0;
        }
        let pdf = self.distribution.pdf(uv) / denom;
        if pdf.is_finite() {
            pdf
        } else {
            0.0
        }
    }

    fn invert(&self, dir: Vec3) -> Vec2 {
        self.distribution.invert(self.uv(dir).0)
    }
}

/// Per-pixel sampling weights `luminance × sin θ_row` of a lat-long image.
fn importance(width: u32, height: u32, luminance_of: impl Fn(usize) -> f32) -> Vec<f32> {
    let mut values = Vec::with_capacity(width as usize * height as usize);
    for y in 0..height {
        let sin_theta = ((y as f32 + 0.5) / height as f32 * PI).sin();
        for x in 0..width {
            let i = y as usize * width as usize + x as usize;
            values.push(luminance_of(i) * sin_theta);
        }
    }
    values
}

/// An HDR environment map in the lat-long layout (see the module documentation).
#[derive(Clone, Debug)]
pub struct LatLongMap {
    pub width: u32,
    pub height: u32,
    /// Texels already multiplied by `scale`, row 0 = zenith.
    pub pixels: Vec<Vec3>,
    pub scale: f32,
    pub rotation_deg: f32,
    is_black: bool,
    sampler: LatLongSampler,
}

impl LatLongMap {
    /// Loads an EXR / HDR (or PNG / JPEG, sRGB-decoded) lat-long map, multiplies it by `scale`
    /// and rotates it by `rotation_deg` about +z.
    pub fn load(path: &Path, scale: f32, rotation_deg: f32) -> Result<LatLongMap> {
        let (w, h, pixels) = load_linear_rgb(path)?;
        Self::from_pixels(w, h, pixels, scale, rotation_deg).map_err(|e| match e {
            BakeError::Invalid(message) => BakeError::Image {
                path: path.to_path_buf(),
                message,
            },
            other => other,
        })
    }

    /// A map from linear texels (row-major, row 0 = zenith). Errors on a size mismatch,
    /// NaN / infinite / negative texels, a negative or non-finite scale, or a non-finite
    /// rotation.
    pub fn from_pixels(
        width: u32,
        height: u32,
        pixels: Vec<Vec3>,
        scale: f32,
        rotation_deg: f32,
    ) -> Result<LatLongMap> {
        if !(scale.is_finite() && scale >= 0.0) {
            return Err(BakeError::Invalid(format!(
                "environment scale {scale} must be finite and non-negative"
            )));
        }
        if !rotation_deg.is_finite() {
            return Err(BakeError::Invalid(format!(
                "environment rotation {rotation_deg} is not finite"
            )));
        }
        if width == 0 || height == 0 || width as usize * height as usize != pixels.len() {
            return Err(BakeError::Invalid(format!(
                "lat-long map: {} pixels for {width} × {height}",
                pixels.len()
            )));
        }
        let mut scaled = pixels;
        for (i, p) in scaled.iter_mut().enumerate() {
            if !p.is_finite() || p.min_element() < 0.0 {
                return Err(BakeError::Invalid(format!(
                    "lat-long map pixel ({}, {}) is {p} (must be finite and non-negative)",
                    i % width as usize,
                    i / width as usize
                )));
            }
            *p *= scale;
            if !p.is_finite() {
                return Err(BakeError::Invalid(format!(
                    "lat-long map pixel ({}, {}) overflows when scaled by {scale}",
                    i % width as usize,
                    i / width as usize
                )));
            }
        }
        let values = importance(width, height, |i| luminance(scaled[i]));
        let is_black = scaled.iter().all(|p| *p == Vec3::ZERO);
        Ok(LatLongMap {
            width,
            height,
            sampler: LatLongSampler::new(width, height, &values, rotation_deg)?,
            pixels: scaled,
            scale,
            rotation_deg,
            is_black,
        })
    }

    /// The `(u, v)` lat-long coordinates of a world direction (rotation applied).
    pub fn direction_to_uv(&self, dir: Vec3) -> Vec2 {
        self.sampler.uv(dir).0
    }

    /// The world direction at lat-long coordinates `(u, v)`.
    pub fn uv_to_direction(&self, uv: Vec2) -> Vec3 {
        let theta = uv.y * PI;
        let phi = (uv.x - 0.5) * 2.0 * PI;
        self.sampler.to_world(Vec3::new(
            theta.sin() * phi.cos(),
            theta.sin() * phi.sin(),
            theta.cos(),
        ))
    }

    /// Radiance from `dir` (nearest texel).
    pub fn eval(&self, dir: Vec3) -> Vec3 {
        let uv = self.direction_to_uv(dir);
        let x = ((uv.x * self.width as f32) as usize).min(self.width as usize - 1);
        let y = ((uv.y * self.height as f32) as usize).min(self.height as usize - 1);
        self.pixels[y * self.width as usize + x]
    }
}

/// Perez et al. (1993) sky luminance distribution coefficients.
#[derive(Clone, Copy, Debug)]
struct Perez {
    a: f32,
    b: f32,
    c: f32,
    d: f32,
    e: f32,
}

impl Perez {
    /// `F(θ, γ) = (1 + A e^{B / cos θ}) (1 + C e^{D γ} + E cos² γ)`; `cos θ` is clamped to at
    /// least 0.01 (the model is singular at the horizon).
    fn f(&self, cos_theta: f32, gamma: f32) -> f32 {
        let cos_theta = cos_theta.max(0.01);
        let cos_gamma = gamma.cos();
        (1.0 + self.a * (self.b / cos_theta).exp())
            * (1.0 + self.c * (self.d * gamma).exp() + self.e * cos_gamma * cos_gamma)
    }
}

/// Resolution of the sky's sampling table.
const SKY_TABLE_WIDTH: u32 = 256;
const SKY_TABLE_HEIGHT: u32 = 128;
/// Albedo of the grey ground below the horizon.
const SKY_GROUND_ALBEDO: f32 = 0.2;

/// A procedural clear sky: the Preetham, Shirley & Smits (1999) analytic model ("A practical
/// analytic model for daylight", Appendix A: Perez distributions of luminance Y and
/// chromaticity x, y as functions of turbidity T; converted through CIE XYZ to linear sRGB).
///
/// - It is bright and whitish near the horizon, blue at the zenith and brighter around the sun
///   (circumsolar region); the sun's disc itself is not part of the sky (see
///   [`Sky::sun_light`]).
/// - Absolute scale: the zenith has luminance `sky_intensity` (the model's own absolute zenith
///   luminance is replaced by this user value).
/// - The model holds for the sun above the horizon; a sun below it is treated as on the horizon
///   for the sky's colours.
/// - Below the horizon is a uniform grey ground of albedo 0.2 lit by the sky (not the sun):
///   radiance `0.2 · E_sky / π`, with `E_sky` the sky's irradiance on a horizontal surface.
///
/// [`Sky::eval`] evaluates the model analytically; a 256 × 128 lat-long tabulation (no
/// rotation) drives importance sampling.
#[derive(Clone, Debug)]
pub struct Sky {
    pub sun_direction: Vec3,
    pub turbidity: f32,
    pub sky_intensity: f32,
    /// The sun direction the model uses: `sun_direction` with its elevation clamped to ≥ 0.
    model_sun: Vec3,
    perez_y: Perez,
    perez_x: Perez,
    perez_yc: Perez,
    /// `Y_z / F_Y(0, θ_s)` etc.: the zenith values divided by the Perez function at the zenith.
    norm: Vec3,
    ground: Vec3,
    sampler: LatLongSampler,
}

impl Sky {
    /// A clear sky for a sun in direction `sun_direction` (towards the sun, Z up), turbidity
    /// in `[1.7, 10]` (2 = very clear, 3 = clear, 6 = hazy) and zenith luminance
    /// `sky_intensity ≥ 0`.
    pub fn new(sun_direction: Vec3, turbidity: f32, sky_intensity: f32) -> Result<Sky> {
        let Some(sun) = sun_direction.try_normalize() else {
            return Err(BakeError::Invalid(format!(
                "sky sun direction {sun_direction} must be a finite non-zero vector"
            )));
        };
        if !(1.7..=10.0).contains(&turbidity) {
            return Err(BakeError::Invalid(format!(
                "sky turbidity {turbidity} must be in [1.7, 10]"
            )));
        }
        if !(sky_intensity.is_finite() && sky_intensity >= 0.0) {
            return Err(BakeError::Invalid(format!(
                "sky intensity {sky_intensity} must be finite and non-negative"
            )));
        }
        let t = turbidity;
        let theta_s = sun.z.clamp(0.0, 1.0).acos();
        let perez_y = Perez {
            a: 0.1787 * t - 1.4630,
            b: -0.3554 * t + 0.4275,
            c: -0.0227 * t + 5.3251,
            d: 0.1206 * t - 2.5771,
            e: -0.0670 * t + 0.3703,
        };
        let perez_x = Perez {
            a: -0.0193 * t - 0.2592,
            b: -0.0665 * t + 0.0008,
            c: -0.0004 * t + 0.2125,
            d: -0.0641 * t - 0.8989,
            e: -0.0033 * t + 0.0452,
        };
        let perez_yc = Perez {
            a: -0.0167 * t - 0.2608,
            b: -0.0950 * t + 0.0092,
            c: -0.0079 * t + 0.2102,
            d: -0.0441 * t - 1.6537,
            e: -0.0109 * t + 0.0529,
        };
        let (s, s2, s3) = (theta_s, theta_s * theta_s, theta_s * theta_s * theta_s);
        let t2 = t * t;
        let xz = t2 * (0.00166 * s3 - 0.00375 * s2 + 0.00209 * s)
            + t * (-0.02903 * s3 + 0.06377 * s2 - 0.03202 * s + 0.00394)
            + (0.11693 * s3 - 0.21196 * s2 + 0.06052 * s + 0.25886);
        let yz = t2 * (0.00275 * s3 - 0.00610 * s2 + 0.00317 * s)
            + t * (-0.04214 * s3 + 0.08970 * s2 - 0.04153 * s + 0.00516)
            + (0.15346 * s3 - 0.26756 * s2 + 0.06670 * s + 0.26688);
        let safe_div = |a: f32, b: f32| if b.abs() > 1e-12 { a / b } else { 0.0 };
        let norm = Vec3::new(
            safe_div(sky_intensity, perez_y.f(1.0, theta_s)),
            safe_div(xz, perez_x.f(1.0, theta_s)),
            safe_div(yz, perez_yc.f(1.0, theta_s)),
        );
        let mut sky = Sky {
            sun_direction: sun,
            turbidity,
            sky_intensity,
            model_sun: Vec3::new(sun.x, sun.y, 0.0).normalize_or(Vec3::X) * theta_s.sin()
                + Vec3::Z * theta_s.cos(),
            perez_y,
            perez_x,
            perez_yc,
            norm,
            ground: Vec3::ZERO,
            sampler: LatLongSampler::new(1, 1, &[1.0], 0.0)?,
        };

        // Tabulate the upper hemisphere at pixel centres; integrate the horizontal irradiance.
        let (w, h) = (SKY_TABLE_WIDTH, SKY_TABLE_HEIGHT);
        let mut table = Vec::with_capacity((w * h) as usize);
        let mut irradiance = Vec3::ZERO;
        let d_omega_base = (2.0 * PI / w as f32) * (PI / h as f32);
        for y in 0..h {
            let theta = (y as f32 + 0.5) / h as f32 * PI;
            for x in 0..w {
                let phi = ((x as f32 + 0.5) / w as f32 - 0.5) * 2.0 * PI;
                let dir = Vec3::new(
                    theta.sin() * phi.cos(),
                    theta.sin() * phi.sin(),
                    theta.cos(),
                );
                let l = if dir.z >= 0.0 {
                    sky.eval_sky(dir)
                } else {
                    Vec3::ZERO
                };
                irradiance += l * dir.z.max(0.0) * theta.sin() * d_omega_base;
                table.push(l);
            }
        }
        sky.ground = SKY_GROUND_ALBEDO * irradiance * FRAC_1_PI;
        let max_lum = table.iter().map(|&c| luminance(c)).fold(0.0f32, f32::max);
        let floor = (max_lum * 1e-4).max(f32::MIN_POSITIVE);
        let ground = sky.ground;
        let values = importance(w, h, |i| {
            let row = i / w as usize;
            let c = if row >= (h / 2) as usize {
                ground
            } else {
                table[i]
            };
            luminance(c).max(floor)
        });
        sky.sampler = LatLongSampler::new(w, h, &values, 0.0)?;
        Ok(sky)
    }

    /// The sky above the horizon (no ground), by the Preetham model.
    fn eval_sky(&self, dir: Vec3) -> Vec3 {
        let cos_theta = dir.z.clamp(0.0, 1.0);
        let gamma = dir.dot(self.model_sun).clamp(-1.0, 1.0).acos();
        let big_y = self.norm.x * self.perez_y.f(cos_theta, gamma);
        let x = self.norm.y * self.perez_x.f(cos_theta, gamma);
        let y = self.norm.z * self.perez_yc.f(cos_theta, gamma);
        if !(y > 1e-6 && big_y > 0.0) {
            return Vec3::ZERO;
        }
        let cx = x / y * big_y;
        let cz = (1.0 - x - y) / y * big_y;
        let r = 3.240_454_2 * cx - 1.537_138_5 * big_y - 0.498_531_4 * cz;
        let g = -0.969_266 * cx + 1.876_010_8 * big_y + 0.041_556 * cz;
        let b = 0.055_643_4 * cx - 0.204_025_9 * big_y + 1.057_225_2 * cz;
        let c = Vec3::new(r.max(0.0), g.max(0.0), b.max(0.0));
        if c.is_finite() {
            c
        } else {
            Vec3::ZERO
        }
    }

    /// Radiance from `dir`: the sky above the horizon, the grey ground below.
    pub fn eval(&self, dir: Vec3) -> Vec3 {
        let Some(d) = dir.try_normalize() else {
            return Vec3::ZERO;
        };
        if d.z >= 0.0 {
            self.eval_sky(d)
        } else {
            self.ground
        }
    }

    /// Radiance of the ground below the horizon.
    pub fn ground_radiance(&self) -> Vec3 {
        self.ground
    }

    /// The sun belonging to this sky, as a delta light with a visible disc of angular radius
    /// `angular_radius` (use [`SUN_ANGULAR_RADIUS`] for the real sun) and the given irradiance
    /// on a surface facing it.
    pub fn sun_light(&self, irradiance: Vec3, angular_radius: f32) -> Light {
        Light::Sun {
            direction: self.sun_direction,
            irradiance,
            angular_radius,
        }
    }
}
