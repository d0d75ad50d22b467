//! What a packed scene holds that the capture shader is specialized on: the values of
//! shader/capture.wgsl's pipeline overrides `ENV_KIND` … `MR_TEXTURES`, fixed when the
//! capture's pipelines are built. With them the shader compiler drops the environment models,
//! light kinds, material models and texture kinds the scene lacks, and the loops over its
//! delta lights have a known count: less code per path vertex, which a CPU adapter (lavapipe
//! runs both sides of every branch under a mask of its SIMD lanes) pays for in full and a GPU
//! in registers.

use crate::error::{GpuBakeError, Result};
use crate::scene::GpuScene;

/// The overrides' values for one scene ([`SceneFeatures::of`]); the kinds are bit sets, bit
/// `1 << kind` per kind present.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SceneFeatures {
    /// `EnvironmentParams::kind`.
    pub env_kind: u32,
    /// Whether the environment shines (it is not black).
    pub env_active: bool,
    /// Whether any material emits.
    pub emitters: bool,
    pub light_count: u32,
    /// The delta lights' kinds (`LIGHT_*`).
    pub light_kinds: u32,
    /// The materials' models (`MODEL_*`).
    pub material_models: u32,
    /// The kinds (`TEX_*`) of the materials' albedo textures and of their metallic-roughness
    /// textures where they have one.
    pub texture_kinds: u32,
    /// Whether any material has a metallic-roughness texture.
    pub mr_textures: bool,
}

impl SceneFeatures {
    /// What `scene` holds.
    pub fn of(scene: &GpuScene) -> Result<Self> {
        let light_count = u32::try_from(scene.lights.len()).map_err(|_| {
            GpuBakeError::Scene(format!(
                "the scene has {} delta lights; the GPU path takes at most {}",
                scene.lights.len(),
                u32::MAX
            ))
        })?;
        let bits = |kinds: &mut dyn Iterator<Item = u32>| kinds.fold(0, |b, k| b | (1 << k));
        let materials = &scene.materials;
        Ok(SceneFeatures {
            env_kind: scene.environment.kind,
            env_active: scene.environment.active,
            emitters: scene.emitters,
            light_count,
            light_kinds: bits(&mut scene.lights.iter().map(|l| l.kind)),
            material_models: bits(&mut materials.iter().map(|m| m.model)),
            texture_kinds: bits(&mut materials.iter().flat_map(|m| {
                std::iter::once(m.albedo.kind)
                    .chain((m.has_mr_texture != 0).then_some(m.mr_texture.kind))
            })),
            mr_textures: materials.iter().any(|m| m.has_mr_texture != 0),
        })
    }

    /// The pipeline constants, by override name.
    pub fn constants(&self) -> [(&'static str, f64); 8] {
        let flag = |b: bool| f64::from(u8::from(b));
        [
            ("ENV_KIND", f64::from(self.env_kind)),
            ("ENV_ACTIVE", flag(self.env_active)),
            ("EMITTERS", flag(self.emitters)),
            ("LIGHT_COUNT", f64::from(self.light_count)),
            ("LIGHT_KINDS", f64::from(self.light_kinds)),
            ("MATERIAL_MODELS", f64::from(self.material_models)),
            ("TEXTURE_KINDS", f64::from(self.texture_kinds)),
            ("MR_TEXTURES", flag(self.mr_textures)),
        ]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::{
        GpuLight, Mat, ENV_SKY, LIGHT_SPOT, LIGHT_SUN, MODEL_LAMBERTIAN, MODEL_METALLIC_ROUGHNESS,
        TEX_CHECKER, TEX_CONSTANT, TEX_IMAGE,
    };
    use bytemuck::Zeroable;

    fn material(model: u32, albedo: u32, mr_texture: Option<u32>) -> Mat {
        let mut m = Mat::zeroed();
        m.model = model;
        m.albedo.kind = albedo;
        if let Some(kind) = mr_texture {
            m.mr_texture.kind = kind;
            m.has_mr_texture = 1;
        }
        m
    }

    #[test]
    fn features_name_each_kind_the_scene_holds_and_no_other() {
        let mut scene = GpuScene::default();
        let bare = SceneFeatures::of(&scene).unwrap();
        assert_eq!(
            (bare.light_count, bare.light_kinds, bare.material_models),
            (0, 0, 0)
        );
        assert_eq!((bare.texture_kinds, bare.mr_textures), (0, false));

        scene.environment.kind = ENV_SKY;
        scene.environment.active = true;
        scene.emitters = true;
        for kind in [LIGHT_SUN, LIGHT_SPOT, LIGHT_SUN] {
            let mut l = GpuLight::zeroed();
            l.kind = kind;
            scene.lights.push(l);
        }
        scene.materials = vec![
            material(MODEL_LAMBERTIAN, TEX_CHECKER, None),
            // The unused metallic-roughness slot of a material without one is not counted.
            material(MODEL_LAMBERTIAN, TEX_CONSTANT, None),
        ];
        let f = SceneFeatures::of(&scene).unwrap();
        assert_eq!(
            f,
            SceneFeatures {
                env_kind: ENV_SKY,
                env_active: true,
                emitters: true,
                light_count: 3,
                light_kinds: (1 << LIGHT_SUN) | (1 << LIGHT_SPOT),
                material_models: 1 << MODEL_LAMBERTIAN,
                texture_kinds: (1 << TEX_CHECKER) | (1 << TEX_CONSTANT),
                mr_textures: false,
            }
        );
        scene.materials.push(material(
            MODEL_METALLIC_ROUGHNESS,
            TEX_CONSTANT,
            Some(TEX_IMAGE),
        ));
        let f = SceneFeatures::of(&scene).unwrap();
        assert_eq!(f.material_models, 0b11);
        assert_eq!(f.texture_kinds, 0b111);
        assert!(f.mr_textures);
        let constants = f.constants();
        assert!(constants.contains(&("LIGHT_COUNT", 3.0)));
        assert!(constants.contains(&("ENV_KIND", f64::from(ENV_SKY))));
        assert!(constants.contains(&("MR_TEXTURES", 1.0)));
    }
}
