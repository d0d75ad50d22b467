//! Reading scene files: the TOML text a user writes, parsed and validated into a
//! [`Scene`] (the model, [`crate::scene`]), and glTF files read as scenes of their own.
//!
//! The format is documented in docs/scene-format.md; every key there is honoured by the
//! bake, and every unknown key is an error. Errors name the file, line and column.
//!
//! Conventions: Z is up; lengths are in scene units; angles in degrees; colours are linear RGB.
//! Relative paths resolve against the directory of the scene file.
//!
//! `[[gltf]]` tables include glTF 2.0 files ([`crate::gltf`]) as environment geometry, lights
//! and cameras; unsupported glTF features become [`Scene::warnings`].
//!
//! Submodules: [`location`] (line and column of a byte offset), `raw` (the serde types, as
//! written), `context` (one file being read: located errors, included files), `settings`
//! (`[bake]` and presets), `camera`, `objects` (objects, shapes, materials), `build` (the
//! scene from them all).

mod build;
mod camera;
mod context;
pub mod location;
mod objects;
mod raw;
mod settings;

use std::path::Path;

use glam::{Affine3A, Vec3};
use oslf_geometry::Camera;

use crate::bake_defaults::choose;
use crate::environment::Environment;
use crate::error::{BakeError, Result};
use crate::input::{read_input, InputKind};
use crate::scene::Scene;
use context::{scene_hash, Ctx};
pub use location::line_column;
use objects::mesh_objects;
use raw::RawScene;

/// Whether `path` names a glTF file (`.gltf` or `.glb`, any case) rather than a TOML scene.
pub fn is_gltf_path(path: &Path) -> bool {
    path.extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("gltf") || e.eq_ignore_ascii_case("glb"))
}

/// The uniform environment radiance of a scene made from a glTF file alone
/// ([`Scene::from_gltf`]).
pub const GLTF_SCENE_ENVIRONMENT: f32 = 1.0;

impl Scene {
    /// Reads and validates a scene file, applying the named preset (from its `[presets.NAME]`).
    ///
    /// A `.gltf` / `.glb` path is read with [`Scene::from_gltf`]: its OSLF objects are the
    /// nodes marked `"extras": {"oslf": true}`; a file without one is refused (there would be
    /// nothing to bake), as is a preset (a glTF file has none).
    pub fn load(path: &Path, preset: Option<&str>) -> Result<Scene> {
        if is_gltf_path(path) {
            let scene = Scene::from_gltf(path)?;
            if let Some(name) = preset {
                return Err(BakeError::Invalid(format!(
                    "{}: a glTF file given as the scene has no presets (asked for {name:?}); \
                     include it from a TOML scene with [[gltf]] to choose bake settings",
                    path.display()
                )));
            }
            if scene.objects.is_empty() {
                let warned = if scene.warnings.is_empty() {
                    String::new()
                } else {
                    format!(" (its warnings: {})", scene.warnings.join("; "))
                };
                return Err(BakeError::Invalid(format!(
                    "{}: no node is marked as an OSLF object: there is nothing to bake a light \
                     field around. Mark the nodes to bake with \"extras\": {{\"oslf\": true}}, \
                     or include the file from a TOML scene with [[gltf]] path = {:?} and \
                     objects = [\"NODE\", ...] (docs/scene-format.md, \"glTF scenes\"){warned}",
                    path.display(),
                    path.file_name()
                        .map(|n| n.to_string_lossy())
                        .unwrap_or_default()
                )));
            }
            return Ok(scene);
        }
        let bytes = read_input(path, InputKind::Text)?;
        let text = String::from_utf8(bytes).map_err(|e| {
            let (line, column) = line_column(
                &String::from_utf8_lossy(e.as_bytes()),
                e.utf8_error().valid_up_to(),
            );
            BakeError::Parse {
                path: path.to_path_buf(),
                line,
                column,
                message: "the scene file is not valid UTF-8".into(),
            }
        })?;
        Scene::from_str(&text, path, preset)
    }

    /// Parses scene text. `path` names the file in errors and anchors relative paths.
    pub fn from_str(text: &str, path: &Path, preset: Option<&str>) -> Result<Scene> {
        let raw: RawScene = toml::from_str(text).map_err(|e| {
            let (line, column) = e
                .span()
                .map(|s| line_column(text, s.start))
                .unwrap_or((1, 1));
            BakeError::Parse {
                path: path.to_path_buf(),
                line,
                column,
                message: e.message().to_string(),
            }
        })?;
        let ctx = Ctx {
            text,
            path,
            included: Default::default(),
        };
        ctx.build(raw, preset)
    }

    /// A scene made from a glTF file alone, with defaults for the rest. Its OSLF objects are
    /// the mesh nodes whose `extras` hold `"oslf": true` (triangle-mesh objects); without one
    /// it cannot be baked ([`Scene::load`] refuses it) but serves path-traced views such as
    /// `oslf_trace::preview::render`. The defaults:
    /// - the file rotated from glTF's Y-up to the scene's Z-up (`rotate = [90, 0, 0]`), its
    ///   lights converted with [`crate::gltf::WATTS_PER_LUMEN`];
    /// - the camera: the file's first perspective camera, else one framing the bounds of its
    ///   meshes from the front right, above (40° vertical field of view);
    /// - the environment: uniform, radiance [`GLTF_SCENE_ENVIRONMENT`] (white);
    /// - the bake settings: the `[bake]` defaults.
    pub fn from_gltf(path: &Path) -> Result<Scene> {
        let bytes = read_input(path, InputKind::Mesh)?;
        let options = crate::gltf::Options {
            transform: Affine3A::from_rotation_x(90f32.to_radians()),
            objects_from_extras: true,
            ..Default::default()
        };
        let mut materials = Vec::new();
        let mut import = crate::gltf::load(path, &options, &mut materials)?;
        let mut objects = mesh_objects(std::mem::take(&mut import.objects), &materials);
        let raw: RawScene = toml::from_str("").expect("an empty scene parses");
        let ctx = Ctx {
            text: "",
            path,
            included: Default::default(),
        };
        let (mut bake, _, unset) = ctx.bake_settings(&raw, None)?;
        let bake_choices = choose(&mut objects, &import.shapes, &materials, &mut bake, unset);
        let camera = match import.cameras.first() {
            Some(c) => Some(c.camera),
            None => import.bounds().map(|(lo, hi)| {
                let target = 0.5 * (lo + hi);
                let radius = (0.5 * (hi - lo).length()).max(1e-3);
                let vfov_deg = 40.0f32;
                let distance = 1.1 * radius / (0.5 * vfov_deg).to_radians().sin();
                let dir = Vec3::new(1.0, -1.6, 0.9).normalize();
                Camera {
                    position: target + distance * dir,
                    target,
                    up: Vec3::Z,
                    vfov_deg,
                }
            }),
        };
        Ok(Scene {
            path: path.to_path_buf(),
            hash: scene_hash(&bytes, &import.files)?,
            files: std::iter::once(path.to_path_buf())
                .chain(import.files.iter().cloned())
                .collect(),
            camera,
            environment: Environment::Constant(Vec3::splat(GLTF_SCENE_ENVIRONMENT)),
            lights: import.lights,
            materials,
            objects,
            shapes: import.shapes,
            bake,
            bake_choices,
            preset: None,
            presets: Vec::new(),
            warnings: import.warnings,
        })
    }
}
