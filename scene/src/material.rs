//! Materials: two-sided reflectors, Lambertian or glTF metallic-roughness.

use glam::{Vec2, Vec3};

use crate::metallic_roughness::MetallicRoughness;
use crate::texture::Texture;
use crate::{BakeError, Result};

/// A material reflecting on both sides of the surface: Lambertian (perfectly diffuse, BRDF
/// `albedo / π`) or glTF's metallic-roughness model with `albedo` as its base colour
/// ([`crate::metallic_roughness`]).
///
/// Albedo components must lie in `[0, 1]` for energy conservation. Constant and checker
/// albedos are checked by [`Material::validate`]; image albedos (an EXR may legitimately hold
/// values a hair above 1) are clamped to `[0, 1]` texel by texel in [`Material::eval`], and
/// [`Material::clamped_texels`] counts the texels affected so the scene loader can warn.
#[derive(Clone, Debug)]
pub struct Material {
    /// The Lambertian albedo, or the metallic-roughness base colour.
    pub albedo: Texture,
    pub model: Model,
    /// Radiance the surface emits, on both sides (linear RGB, finite, ≥ 0): glTF's
    /// `emissiveFactor` × `KHR_materials_emissive_strength`.
    pub emission: Vec3,
    /// A metallic-roughness model's texture, as glTF's `metallicRoughnessTexture` times the
    /// factors: roughness in green, metallic in blue (each clamped to [0, 1] where read). With
    /// it, the model's factors are not used again.
    pub metallic_roughness_texture: Option<Texture>,
    /// glTF's `normalTexture` (data, `2c − 1` per channel) and its scale: the shading normal
    /// of a mesh object, in the MikkTSpace frame of its texture coordinates
    /// ([`Material::mapped_normal`]).
    pub normal_texture: Option<NormalTexture>,
    /// glTF's `emissiveTexture` (sRGB decoded): an OSLF mesh object emits `emission` times it
    /// ([`Material::emission_at`]); environment geometry emits `emission` alone.
    pub emissive_texture: Option<Texture>,
    /// glTF's `occlusionTexture` (data, occlusion in red) and its strength: an OSLF mesh
    /// object reflects [`Material::occlusion_at`] of the light that reaches it; environment
    /// geometry has its occlusion from the path tracer alone.
    pub occlusion_texture: Option<OcclusionTexture>,
}

/// A tangent-space normal texture with its scale (glTF `normalTexture.scale`).
#[derive(Clone, Debug)]
pub struct NormalTexture {
    pub texture: Texture,
    pub scale: f32,
}

/// An occlusion texture with its strength (glTF `occlusionTexture.strength`, in `[0, 1]`).
#[derive(Clone, Debug)]
pub struct OcclusionTexture {
    pub texture: Texture,
    pub strength: f32,
}

/// How a [`Material`] reflects.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Model {
    /// BRDF `albedo / π`.
    Lambertian,
    /// glTF's metallic-roughness BRDF with the albedo as base colour; factors in `[0, 1]`.
    MetallicRoughness { metallic: f32, roughness: f32 },
}

impl Material {
    /// A constant-albedo Lambertian material.
    pub fn lambertian(albedo: Vec3) -> Self {
        Material {
            albedo: Texture::Constant(albedo),
            model: Model::Lambertian,
            emission: Vec3::ZERO,
            metallic_roughness_texture: None,
            normal_texture: None,
            emissive_texture: None,
            occlusion_texture: None,
        }
    }

    /// The factor a mesh object with this material scales the light it reflects at `uv` by:
    /// `1 + strength · (occlusion − 1)`, the occlusion texture's red channel clamped to
    /// [0, 1] (format docs, "Object textures"; glTF's `occlusionTexture`); 1 without one.
    pub fn occlusion_at(&self, uv: Vec2) -> f32 {
        match &self.occlusion_texture {
            Some(o) => 1.0 + o.strength * (clamp01(o.texture.eval(uv).x) - 1.0),
            None => 1.0,
        }
    }

    /// The radiance a mesh object with this material emits at `uv`: `emission` times the
    /// emissive texture, where there is one (format docs, "Object textures").
    pub fn emission_at(&self, uv: Vec2) -> Vec3 {
        match &self.emissive_texture {
            Some(t) => self.emission * t.eval(uv),
            None => self.emission,
        }
    }

    /// The shading normal at `uv` with the normal texture (format docs, "Object textures";
    /// as the runtime's `mapped_normal`): `tangent` (xyz, and the bitangent's sign in w) made
    /// orthogonal to the unit normal `n`, the bitangent `w·(n × t)`, the texel's `2c − 1`
    /// scaled in x and y. `n` without a normal texture or where the frame degenerates.
    pub fn mapped_normal(&self, uv: Vec2, n: Vec3, tangent: glam::Vec4) -> Vec3 {
        let Some(map) = &self.normal_texture else {
            return n;
        };
        let c = map.texture.eval(uv) * 2.0 - Vec3::ONE;
        let Some(t) = (tangent.truncate() - n * n.dot(tangent.truncate())).try_normalize() else {
            return n;
        };
        let b = if tangent.w >= 0.0 { 1.0 } else { -1.0 } * n.cross(t);
        (t * (c.x * map.scale) + b * (c.y * map.scale) + n * c.z)
            .try_normalize()
            .unwrap_or(n)
    }

    /// The metallic-roughness BRDF at `uv` (`None` for a Lambertian material).
    pub fn metallic_roughness(&self, uv: Vec2) -> Option<MetallicRoughness> {
        match self.model {
            Model::Lambertian => None,
            Model::MetallicRoughness {
                metallic,
                roughness,
            } => {
                let (metallic, roughness) = match &self.metallic_roughness_texture {
                    Some(t) => {
                        let c = t.eval(uv);
                        (clamp01(c.z), clamp01(c.y))
                    }
                    None => (metallic, roughness),
                };
                Some(MetallicRoughness {
                    base_color: self.eval(uv),
                    metallic,
                    roughness,
                })
            }
        }
    }

    /// Errors if a constant or checker albedo component is outside `[0, 1]` or not finite, a
    /// checker scale is not finite and positive, a metallic or roughness factor is outside
    /// `[0, 1]`, or the emission is negative or not finite.
    pub fn validate(&self) -> Result<()> {
        if !(self.emission.is_finite() && self.emission.min_element() >= 0.0) {
            return Err(BakeError::Invalid(format!(
                "emission {} must be finite and ≥ 0",
                self.emission
            )));
        }
        if let Model::MetallicRoughness {
            metallic,
            roughness,
        } = self.model
        {
            for (name, v) in [("metallic", metallic), ("roughness", roughness)] {
                if !(0.0..=1.0).contains(&v) {
                    return Err(BakeError::Invalid(format!("{name} {v} must be in [0, 1]")));
                }
            }
        }
        let check = |c: Vec3, what: &str| -> Result<()> {
            if c.is_finite() && c.min_element() >= 0.0 && c.max_element() <= 1.0 {
                Ok(())
            } else {
                Err(BakeError::Invalid(format!(
                    "{what} albedo {c} must have components in [0, 1]"
                )))
            }
        };
        match &self.albedo {
            Texture::Constant(c) => check(*c, "constant"),
            Texture::Checker { a, b, scale } => {
                check(*a, "checker")?;
                check(*b, "checker")?;
                if scale.is_finite() && *scale > 0.0 {
                    Ok(())
                } else {
                    Err(BakeError::Invalid(format!(
                        "checker scale {scale} must be finite and positive"
                    )))
                }
            }
            Texture::Image(_) => Ok(()),
        }
    }

    /// Number of image texels with a component above 1 (which [`Material::eval`] clamps).
    pub fn clamped_texels(&self) -> usize {
        match &self.albedo {
            Texture::Image(img) => img.count_above(1.0),
            _ => 0,
        }
    }

    /// The mean albedo over the texture's domain (a checker's two colours equally, an image's
    /// texels clamped as [`Material::eval`] clamps them): the C_s of Eq. 4.12 a store carries.
    pub fn mean_albedo(&self) -> Vec3 {
        match &self.albedo {
            Texture::Constant(c) => *c,
            Texture::Checker { a, b, .. } => (*a + *b) * 0.5,
            Texture::Image(img) => {
                let sum: Vec3 = img
                    .pixels
                    .iter()
                    .map(|p| Vec3::new(clamp01(p.x), clamp01(p.y), clamp01(p.z)))
                    .sum();
                sum / img.pixels.len().max(1) as f32
            }
        }
    }

    /// The albedo at `uv`, clamped to `[0, 1]` (a non-finite component reads as 0).
    pub fn eval(&self, uv: Vec2) -> Vec3 {
        let a = self.albedo.eval(uv);
        Vec3::new(clamp01(a.x), clamp01(a.y), clamp01(a.z))
    }
}

fn clamp01(x: f32) -> f32 {
    if x.is_finite() {
        x.clamp(0.0, 1.0)
    } else {
        0.0
    }
}
