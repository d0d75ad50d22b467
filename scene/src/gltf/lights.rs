//! `KHR_lights_punctual` point, spot and directional lights, converted to radiometric units.

use glam::{Affine3A, Vec3};

use super::loader::{label, Loader};
use crate::light::Light;
use crate::Result;

impl<'d> Loader<'d> {
    pub(super) fn node_light(
        &mut self,
        at: &str,
        light: &gltf::khr_lights_punctual::Light,
        world: &Affine3A,
        watts_per_lumen: f32,
    ) -> Result<Light> {
        let json_at = format!("extensions.KHR_lights_punctual.lights[{}]", light.index());
        let name = label("lights", light.index(), light.name());
        let color = Vec3::from(light.color());
        let intensity = light.intensity();
        if !(color.is_finite() && color.min_element() >= 0.0) {
            return Err(self.err(
                format!("{json_at}.color"),
                format!("{color} must be finite and non-negative"),
            ));
        }
        if !(intensity.is_finite() && intensity >= 0.0) {
            return Err(self.err(
                format!("{json_at}.intensity"),
                format!("{intensity} must be finite and non-negative"),
            ));
        }
        let power = color * (intensity * watts_per_lumen);
        let position = world.transform_point3(Vec3::ZERO);
        let axis = world.transform_vector3(Vec3::NEG_Z).try_normalize();
        if light.range().is_some() {
            self.warn(format!(
                "{at}: {name}: range is not supported: the light reaches everywhere (inverse-square falloff only)"
            ));
        }
        let singular = || {
            self.err(
                json_at.to_string(),
                format!("{at}: the node's transform is singular, so the light has no direction"),
            )
        };
        let l = match light.kind() {
            gltf::khr_lights_punctual::Kind::Point => Light::Point {
                position,
                intensity: power,
            },
            gltf::khr_lights_punctual::Kind::Directional => Light::Sun {
                direction: -axis.ok_or_else(singular)?,
                irradiance: power,
                angular_radius: 0.0,
            },
            gltf::khr_lights_punctual::Kind::Spot {
                inner_cone_angle,
                outer_cone_angle,
            } => {
                let direction = axis.ok_or_else(singular)?;
                Light::Spot {
                    position,
                    direction,
                    intensity: power,
                    inner_angle: inner_cone_angle,
                    outer_angle: outer_cone_angle,
                }
            }
        };
        l.validate()
            .map_err(|e| self.err(json_at, format!("{at}: {e}")))?;
        Ok(l)
    }
}
