//! Building a [`Scene`] from a parsed scene file: the lights, the environment, the glTF
//! includes, the camera, and the objects and shapes ([`super::objects`]).

use std::ops::Range;
use std::sync::Arc;

use glam::Vec3;
use toml::Spanned;

use super::context::{scene_hash, Ctx};
use super::objects::mesh_objects;
use super::raw::{RawDirectionalLight, RawEnvironment, RawGltf, RawPointLight, RawScene};
use crate::bake_defaults::choose;
use crate::environment::{Environment, LatLongMap, Sky};
use crate::error::{BakeError, Result};
use crate::gltf::GltfCamera;
use crate::light::Light;
use crate::material::Material;
use crate::scene::{OslfObject, Scene, Shape};

/// What the `[[gltf]]` includes add to the scene.
#[derive(Default)]
struct Included {
    objects: Vec<OslfObject>,
    shapes: Vec<Shape>,
    lights: Vec<Light>,
    cameras: Vec<GltfCamera>,
    warnings: Vec<String>,
}

impl Ctx<'_> {
    /// The scene of the parsed file `raw` with the named preset applied.
    pub(super) fn build(&self, mut raw: RawScene, preset: Option<&str>) -> Result<Scene> {
        let (mut bake, epsilon_span, unset) = self.bake_settings(&raw, preset)?;
        let given_epsilon = epsilon_span.map(|span| (bake.epsilon, span));
        let presets = raw.presets.keys().cloned().collect();

        let camera_spec = match raw.camera.take() {
            Some(c) => Some(self.camera(c)?),
            None => None,
        };

        let mut lights = lights(&raw.point_light, &raw.directional_light);
        let environment = match raw.environment.take() {
            None => Environment::Constant(Vec3::ZERO),
            Some(env) => self.environment(env, &mut lights)?,
        };

        let mut materials = Vec::new();
        let mut objects = self.objects(
            std::mem::take(&mut raw.object),
            &given_epsilon,
            &mut materials,
        )?;
        let mut shapes_out = self.shapes(&raw, &mut materials)?;

        let included = self.include_gltf(&raw.gltf, &given_epsilon, &mut materials)?;
        objects.extend(included.objects);
        shapes_out.extend(included.shapes);
        lights.extend(included.lights);
        let warnings = included.warnings;
        let camera = self.resolve_camera(camera_spec, &included.cameras)?;

        if objects.is_empty() {
            return Err(BakeError::Invalid(format!(
                "{}: the scene has no [[object]]: there is nothing to bake a light field around",
                self.path.display()
            )));
        }

        let bake_choices = choose(&mut objects, &shapes_out, &materials, &mut bake, unset);
        let hash = scene_hash(self.text.as_bytes(), &self.included.borrow())?;
        let files = std::iter::once(self.path.to_path_buf())
            .chain(self.included.borrow().iter().cloned())
            .collect();
        Ok(Scene {
            path: self.path.to_path_buf(),
            hash,
            files,
            camera,
            environment,
            lights,
            materials,
            objects,
            shapes: shapes_out,
            bake,
            bake_choices,
            preset: preset.map(str::to_string),
            presets,
            warnings,
        })
    }

    /// The `[environment]`; a sky adds its sun to `lights`.
    fn environment(
        &self,
        env: Spanned<RawEnvironment>,
        lights: &mut Vec<Light>,
    ) -> Result<Environment> {
        let span = env.span();
        let env = env.into_inner();
        let count =
            env.sky.is_some() as u32 + env.map.is_some() as u32 + env.uniform.is_some() as u32;
        if count != 1 {
            return Err(self.error_at(
                span,
                "[environment] needs exactly one of `sky`, `map` or `uniform`",
            ));
        }
        Ok(if let Some(sky) = env.sky {
            let direction = sky.sun_direction.0.normalize();
            let model = Sky::new(direction, sky.turbidity.0, sky.intensity.0)
                .map_err(|e| self.locate(span.clone(), e))?;
            lights
                .push(model.sun_light(sky.sun_irradiance.0, sky.sun_angular_radius.0.to_radians()));
            Environment::Sky(Arc::new(model))
        } else if let Some(map) = env.map {
            let file = self.existing_file(&map.path)?;
            let loaded = LatLongMap::load(&file, map.scale.0, map.rotation.0)?;
            Environment::LatLong(Arc::new(loaded))
        } else {
            Environment::Constant(env.uniform.map_or(Vec3::ZERO, |u| u.0))
        })
    }

    /// The `[[gltf]]` includes, in order: their OSLF objects (a given ε checked against each),
    /// shapes, lights, cameras and warnings; their files are recorded as included.
    fn include_gltf(
        &self,
        includes: &[RawGltf],
        epsilon: &Option<(f32, Range<usize>)>,
        materials: &mut Vec<Material>,
    ) -> Result<Included> {
        let mut out = Included::default();
        for g in includes {
            let file = self.existing_file(&g.path)?;
            let options = crate::gltf::Options {
                transform: g.transform.affine(),
                watts_per_lumen: g
                    .watts_per_lumen
                    .map_or(crate::gltf::WATTS_PER_LUMEN, |w| w.0),
                lights: g.lights,
                objects: g.objects.clone(),
                objects_from_extras: false,
                normals: g.normals.map(|n| n.0),
            };
            let import = crate::gltf::load(&file, &options, materials)?;
            self.included
                .borrow_mut()
                .extend(import.files.iter().cloned());
            for mut object in mesh_objects(import.objects, materials) {
                object.sample_spacing = g.sample_spacing.map(|s| s.0);
                self.check_epsilon(epsilon, &object)?;
                out.objects.push(object);
            }
            out.shapes.extend(import.shapes);
            out.lights.extend(import.lights);
            out.cameras.extend(import.cameras);
            out.warnings.extend(import.warnings);
        }
        Ok(out)
    }
}

/// The point and directional lights, in that order.
fn lights(points: &[RawPointLight], directional: &[RawDirectionalLight]) -> Vec<Light> {
    let mut lights: Vec<Light> = points
        .iter()
        .map(|l| Light::Point {
            position: l.position.0,
            intensity: l.intensity.0,
        })
        .collect();
    lights.extend(directional.iter().map(|l| Light::Sun {
        direction: l.direction.0.normalize(),
        irradiance: l.irradiance.0,
        angular_radius: l.angular_radius.0.to_radians(),
    }));
    lights
}
