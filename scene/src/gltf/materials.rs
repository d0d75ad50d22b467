//! Materials: glTF's metallic-roughness model from its base colour (factor and texture), its
//! metallic and roughness factors and texture, and its normal texture; what else a material
//! uses is warned about.

use std::sync::Arc;

use glam::Vec3;

use super::loader::{label, material_label, Loader};
use super::textures::{wrapped_image, UvMap};
use crate::material::{Material, Model, NormalTexture, OcclusionTexture};
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
        let color_map = match &info {
            None => None,
            Some(i) => {
                let set = tex_coord(i, transform.as_ref());
                Some(self.uv_map(m, "baseColorTexture", true, i, transform.as_ref(), set)?)
            }
        };
        // The metallic-roughness texture (of a material of the file's own) is drawn where it
        // maps texture coordinates as the base colour texture does, or where that is absent.
        let mr_info = pbr
            .metallic_roughness_texture()
            .filter(|_| m.index().is_some());
        let mr_transform = mr_info.as_ref().and_then(|i| i.texture_transform());
        let mr_map = match &mr_info {
            None => None,
            Some(i) => {
                let set = tex_coord(i, mr_transform.as_ref());
                let map = "metallicRoughnessTexture";
                Some(self.uv_map(m, map, false, i, mr_transform.as_ref(), set)?)
            }
        };
        let (uv_map, mr_drawn) = join(color_map, mr_map);
        // The normal texture likewise, where it maps as the others do (and has no transform).
        let normal_map = match m.normal_texture().filter(|_| m.index().is_some()) {
            Some(nt) if nt.extension_value("KHR_texture_transform").is_none() => {
                Some(self.plain_uv_map(&nt.texture(), nt.tex_coord())?)
            }
            _ => None,
        };
        let (uv_map, normal_drawn) = join(uv_map, normal_map);
        // And the emissive texture.
        let glow_info = m.emissive_texture().filter(|_| m.index().is_some());
        let glow_transform = glow_info.as_ref().and_then(|i| i.texture_transform());
        let glow_map = match &glow_info {
            None => None,
            Some(i) => {
                let set = tex_coord(i, glow_transform.as_ref());
                Some(self.uv_map(m, "emissiveTexture", true, i, glow_transform.as_ref(), set)?)
            }
        };
        let (uv_map, glow_drawn) = join(uv_map, glow_map);
        // And the occlusion texture (like the normal texture, without a transform).
        let occlusion_map = match m.occlusion_texture().filter(|_| m.index().is_some()) {
            Some(ot) if ot.extension_value("KHR_texture_transform").is_none() => {
                Some(self.plain_uv_map(&ot.texture(), ot.tex_coord())?)
            }
            _ => None,
        };
        let (uv_map, occlusion_drawn) = join(uv_map, occlusion_map);
        let key = (m.index(), uv_map.as_ref().map_or(0, |u| u.set));
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
        let drawn = [mr_drawn, normal_drawn, glow_drawn, occlusion_drawn];
        self.warn_material(m, &name, drawn);
        let albedo = match &info {
            None => Texture::Constant(rgb),
            Some(info) => self.colour_texture(info, rgb)?,
        };
        let metallic_roughness_texture = match mr_info.filter(|_| mr_drawn) {
            None => None,
            Some(info) => Some(self.metallic_roughness_texture(&info, &pbr)?),
        };
        let normal_texture = match m.normal_texture().filter(|_| normal_drawn) {
            None => None,
            Some(nt) => Some(self.normal_texture(&nt, &at)?),
        };
        let emissive_texture = match glow_info.filter(|_| glow_drawn) {
            None => None,
            Some(info) => Some(self.colour_texture(&info, Vec3::ONE)?),
        };
        let occlusion_texture = match m.occlusion_texture().filter(|_| occlusion_drawn) {
            None => None,
            Some(ot) => Some(self.occlusion_texture(&ot, &at)?),
        };
        let model = self.model(m, &at)?;
        let emission = self.emission(m, &at)?;
        materials.push(Material {
            albedo,
            model,
            emission,
            metallic_roughness_texture,
            normal_texture,
            emissive_texture,
            occlusion_texture,
        });
        let index = (materials.len() - 1) as u32;
        self.materials.insert(key, index);
        Ok((index, uv_map))
    }

    /// An sRGB colour texture (`baseColorTexture`, `emissiveTexture`) `info` decoded to linear,
    /// times `factor`, resampled for its wraps; the texture's extensions are warned about.
    fn colour_texture(&mut self, info: &gltf::texture::Info, factor: Vec3) -> Result<Texture> {
        let texture = info.texture();
        let image = self.image(&texture.source(), true)?;
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
        Ok(Texture::Image(Arc::new(wrapped_image(
            &image, ws, wt, factor,
        ))))
    }

    /// glTF's `metallicRoughnessTexture` `info` as data (roughness in green, metallic in
    /// blue), each times its factor, resampled for its wraps.
    fn metallic_roughness_texture(
        &mut self,
        info: &gltf::texture::Info,
        pbr: &gltf::material::PbrMetallicRoughness,
    ) -> Result<Texture> {
        let texture = info.texture();
        let image = self.image(&texture.source(), false)?;
        let sampler = texture.sampler();
        let (ws, wt) = (sampler.wrap_s(), sampler.wrap_t());
        let factor = Vec3::new(1.0, pbr.roughness_factor(), pbr.metallic_factor());
        Ok(Texture::Image(Arc::new(wrapped_image(
            &image, ws, wt, factor,
        ))))
    }

    /// glTF's `normalTexture` `nt` (of the material at JSON path `at`) as data, resampled for
    /// its wraps, with its scale (finite).
    fn normal_texture(
        &mut self,
        nt: &gltf::material::NormalTexture,
        at: &str,
    ) -> Result<NormalTexture> {
        let scale = nt.scale();
        if !scale.is_finite() {
            return Err(self.err(
                format!("{at}.normalTexture.scale"),
                format!("{scale}: must be finite"),
            ));
        }
        Ok(NormalTexture {
            texture: self.data_texture(&nt.texture())?,
            scale,
        })
    }

    /// A data texture (`normalTexture`, `occlusionTexture`) as stored, not sRGB-decoded,
    /// resampled for its sampler's wraps.
    fn data_texture(&mut self, texture: &gltf::Texture) -> Result<Texture> {
        let image = self.image(&texture.source(), false)?;
        let sampler = texture.sampler();
        let (ws, wt) = (sampler.wrap_s(), sampler.wrap_t());
        Ok(Texture::Image(Arc::new(wrapped_image(
            &image,
            ws,
            wt,
            Vec3::ONE,
        ))))
    }

    /// glTF's `occlusionTexture` `ot` (of the material at JSON path `at`) as data (occlusion in
    /// red), resampled for its wraps, with its strength (in [0, 1]).
    fn occlusion_texture(
        &mut self,
        ot: &gltf::material::OcclusionTexture,
        at: &str,
    ) -> Result<OcclusionTexture> {
        let strength = ot.strength();
        if !(0.0..=1.0).contains(&strength) {
            return Err(self.err(
                format!("{at}.occlusionTexture.strength"),
                format!("{strength}: must be in [0, 1]"),
            ));
        }
        Ok(OcclusionTexture {
            texture: self.data_texture(&ot.texture())?,
            strength,
        })
    }

    /// The reflection model of `m` (at JSON path `at`): its metallic and roughness factors,
    /// each in [0, 1]; glTF's default material (no index) is drawn white Lambertian.
    fn model(&self, m: &gltf::Material, at: &str) -> Result<Model> {
        if m.index().is_none() {
            return Ok(Model::Lambertian);
        }
        let pbr = m.pbr_metallic_roughness();
        let (metallic, roughness) = (pbr.metallic_factor(), pbr.roughness_factor());
        for (name, v) in [("metallicFactor", metallic), ("roughnessFactor", roughness)] {
            if !(0.0..=1.0).contains(&v) {
                return Err(self.err(
                    format!("{at}.pbrMetallicRoughness.{name}"),
                    format!("{v}: must be in [0, 1]"),
                ));
            }
        }
        Ok(Model::MetallicRoughness {
            metallic,
            roughness,
        })
    }

    /// The radiance `m` (at JSON path `at`) emits: `emissiveFactor` ×
    /// `KHR_materials_emissive_strength`, finite and ≥ 0.
    fn emission(&self, m: &gltf::Material, at: &str) -> Result<Vec3> {
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
        Ok(emission)
    }

    /// Warns about what material `m` uses that is not drawn; `drawn`: whether its
    /// metallic-roughness, normal, emissive and occlusion textures are.
    pub(super) fn warn_material(&mut self, m: &gltf::Material, name: &str, drawn: [bool; 4]) {
        let [mr_drawn, normal_drawn, glow_drawn, occlusion_drawn] = drawn;
        let pbr = m.pbr_metallic_roughness();
        let mut ignored = Vec::new();
        if pbr.metallic_roughness_texture().is_some() && m.index().is_some() && !mr_drawn {
            ignored.push(format!(
                "metallicRoughnessTexture, which maps texture coordinates unlike \
                 baseColorTexture (its TEXCOORD set, KHR_texture_transform or sampler wrap \
                 differs; drawn with metallicFactor {} and roughnessFactor {} alone)",
                pbr.metallic_factor(),
                pbr.roughness_factor()
            ));
        }
        if m.emissive_texture().is_some() && !glow_drawn {
            ignored.push(
                "emissiveTexture, which maps texture coordinates unlike the material's other \
                 textures (drawn with emissiveFactor alone)"
                    .into(),
            );
        }
        if m.normal_texture().is_some() && !normal_drawn {
            ignored.push(
                "normalTexture, which maps texture coordinates unlike the material's other \
                 textures (its TEXCOORD set, KHR_texture_transform or sampler wrap differs)"
                    .into(),
            );
        }
        if m.occlusion_texture().is_some() && !occlusion_drawn {
            ignored.push(
                "occlusionTexture, which maps texture coordinates unlike the material's other \
                 textures (its TEXCOORD set, KHR_texture_transform or sampler wrap differs)"
                    .into(),
            );
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

/// The material's texture mapping so far, `uv_map`, with texture mapping `map`: `map` is drawn
/// where it maps texture coordinates as `uv_map` does, or where there is none yet.
fn join(uv_map: Option<UvMap>, map: Option<UvMap>) -> (Option<UvMap>, bool) {
    let drawn = map
        .as_ref()
        .is_some_and(|m| uv_map.as_ref().is_none_or(|u| u == m));
    (uv_map.or(if drawn { map } else { None }), drawn)
}

/// The texture coordinate set `info` reads: `KHR_texture_transform`'s `texCoord` where given.
fn tex_coord(
    info: &gltf::texture::Info,
    transform: Option<&gltf::texture::TextureTransform>,
) -> u32 {
    transform
        .and_then(|t| t.tex_coord())
        .unwrap_or(info.tex_coord())
}
