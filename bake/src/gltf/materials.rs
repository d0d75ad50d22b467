//! Materials: glTF's metallic-roughness model from its base colour (factor and texture) and
//! its metallic and roughness factors; what else a material uses is warned about.

use std::sync::Arc;

use glam::Vec3;

use super::loader::{label, material_label, Loader};
use super::textures::{wrapped_image, UvMap};
use crate::material::{Material, Model};
use crate::texture::Texture;
use crate::Result;

impl<'d> Loader<'d> {
    /// The scene material for a glTF material, and how the primitive's texture coordinates
    /// map into its texture (`None`: the material has no texture).
    pub(super) fn material(
        &mut self,
        m: &gltf::Material,
        materials: &mut Vec<Material>,
    ) -> Result<(u32, Option<UvMap>)> {
        let pbr = m.pbr_metallic_roughness();
        let info = pbr.base_color_texture();
        let transform = info.as_ref().and_then(|i| i.texture_transform());
        let set = match (&info, &transform) {
            (Some(i), Some(t)) => t.tex_coord().unwrap_or(i.tex_coord()),
            (Some(i), None) => i.tex_coord(),
            _ => 0,
        };
        let key = (m.index(), set);
        let uv_map = match &info {
            None => None,
            Some(info) => Some(self.uv_map(m, info, transform.as_ref(), set)?),
        };
        if let Some(&index) = self.materials.get(&key) {
            return Ok((index, uv_map));
        }
        let at = match m.index() {
            Some(i) => format!("materials[{i}]"),
            None => "materials".into(),
        };
        let name = material_label(m);
        let factor = pbr.base_color_factor();
        let rgb = Vec3::new(factor[0], factor[1], factor[2]);
        if !factor
            .iter()
            .all(|c| c.is_finite() && (0.0..=1.0).contains(c))
        {
            return Err(self.err(
                format!("{at}.pbrMetallicRoughness.baseColorFactor"),
                format!("{factor:?}: components must be in [0, 1]"),
            ));
        }
        self.warn_material(m, &name);
        let albedo = match &info {
            None => Texture::Constant(rgb),
            Some(info) => {
                let texture = info.texture();
                let image = self.image(&texture.source())?;
                let sampler = texture.sampler();
                let (ws, wt) = (sampler.wrap_s(), sampler.wrap_t());
                if let Some(ext) = texture.extensions() {
                    let names: Vec<String> = ext.keys().cloned().collect();
                    for e in names {
                        self.warn(format!(
                            "{}: extension {e} is not supported",
                            label("textures", texture.index(), texture.name())
                        ));
                    }
                }
                Texture::Image(Arc::new(wrapped_image(&image, ws, wt, rgb)))
            }
        };
        let model = match m.index() {
            // glTF's default material: drawn white Lambertian, as documented.
            None => Model::Lambertian,
            Some(_) => {
                let (metallic, roughness) = (pbr.metallic_factor(), pbr.roughness_factor());
                for (name, v) in [("metallicFactor", metallic), ("roughnessFactor", roughness)] {
                    if !(0.0..=1.0).contains(&v) {
                        return Err(self.err(
                            format!("{at}.pbrMetallicRoughness.{name}"),
                            format!("{v}: must be in [0, 1]"),
                        ));
                    }
                }
                Model::MetallicRoughness {
                    metallic,
                    roughness,
                }
            }
        };
        let strength = m.emissive_strength().unwrap_or(1.0);
        let emission = Vec3::from(m.emissive_factor()) * strength;
        if !(emission.is_finite() && emission.min_element() >= 0.0) {
            return Err(self.err(
                format!("{at}.emissiveFactor"),
                format!(
                    "{:?} × emissive strength {strength}: must be finite and ≥ 0",
                    m.emissive_factor()
                ),
            ));
        }
        materials.push(Material {
            albedo,
            model,
            emission,
        });
        let index = (materials.len() - 1) as u32;
        self.materials.insert(key, index);
        Ok((index, uv_map))
    }

    pub(super) fn warn_material(&mut self, m: &gltf::Material, name: &str) {
        let pbr = m.pbr_metallic_roughness();
        let mut ignored = Vec::new();
        if pbr.metallic_roughness_texture().is_some() {
            ignored.push(format!(
                "metallicRoughnessTexture (drawn with metallicFactor {} and roughnessFactor {} \
                 alone)",
                pbr.metallic_factor(),
                pbr.roughness_factor()
            ));
        }
        if m.emissive_texture().is_some() {
            ignored.push("emissiveTexture (drawn with emissiveFactor alone)".into());
        }
        if m.normal_texture().is_some() {
            ignored.push("normalTexture".into());
        }
        if m.occlusion_texture().is_some() {
            ignored.push("occlusionTexture".into());
        }
        if m.alpha_mode() != gltf::material::AlphaMode::Opaque {
            ignored.push(format!("alphaMode {:?} (drawn opaque)", m.alpha_mode()));
        }
        if let Some(ext) = m.extensions() {
            for e in ext.keys() {
                ignored.push(format!("extension {e}"));
            }
        }
        if !ignored.is_empty() {
            self.warn(format!(
                "{name}: not supported, ignored: {}",
                ignored.join("; ")
            ));
        }
    }
}
