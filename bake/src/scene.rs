//! Scene files: the TOML text a user writes, parsed and validated into a [`Scene`].
//!
//! The format is documented in docs/scene-format.md; every key there is honoured by the
//! bake, and every unknown key is an error. Errors name the file, line and column.
//!
//! Conventions: Z is up; lengths are in scene units; angles in degrees; colours are linear RGB.
//! Relative paths resolve against the directory of the scene file.
//!
//! `[[gltf]]` tables include glTF 2.0 files ([`crate::gltf`]) as environment geometry, lights
//! and cameras; unsupported glTF features become [`Scene::warnings`].

use std::collections::BTreeMap;
use std::ops::Range;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use glam::{Affine3A, Quat, Vec2, Vec3};
use serde::de::Error as _;
use serde::{Deserialize, Deserializer};
use toml::Spanned;

use crate::bezier::{self, BezierPatch};
use crate::bvh::Instance;
use crate::camera::Camera;
use crate::environment::{Environment, LatLongMap, Sky};
use crate::error::{BakeError, Result};
use crate::gltf::GltfCamera;
use crate::light::Light;
use crate::material::Material;
use crate::mesh::Mesh;
use crate::ray::ENVIRONMENT_OBJECT;
use crate::surface::MeshSource;
use crate::texture::{ImageTexture, Texture};
use crate::{obj, shapes};
use oslf_geometry::atlas::UvSource;

/// The smallest ε relative to an object's largest coordinate magnitude, 2⁻²⁰ (twice
/// [`crate::bvh::SELF_TOLERANCE`]); see `check_epsilon`.
pub const MIN_EPSILON_RELATIVE: f32 = 2.0 * crate::bvh::SELF_TOLERANCE;

/// An OSLF object: the Bézier patches or the triangle mesh a light field is baked around.
#[derive(Clone, Debug)]
pub struct OslfObject {
    pub name: String,
    /// Patches in object space, as read (empty for a mesh object).
    pub object_patches: Vec<BezierPatch>,
    /// The same patches in world space (`transform` applied).
    pub patches: Vec<BezierPatch>,
    /// A triangle-mesh object: the mesh in world space and its candidate atlas uv sets.
    pub mesh: Option<MeshSource>,
    /// Object to world.
    pub transform: Affine3A,
    /// Index into [`Scene::materials`].
    pub material: u32,
    /// The material's mean albedo: the C_s of Eq. 4.12 that the store carries.
    pub base_color: Vec3,
}

impl OslfObject {
    /// Every point that defines the object's surface in world space: control points or mesh
    /// vertices.
    pub fn points(&self) -> impl Iterator<Item = Vec3> + '_ {
        let mesh = self
            .mesh
            .iter()
            .flat_map(|m| m.mesh.positions.iter().copied());
        self.patches.iter().flat_map(|p| p.cp).chain(mesh)
    }
}

/// A piece of environment geometry (everything that is not an OSLF object), in world space.
#[derive(Clone, Debug)]
pub struct Shape {
    pub mesh: Mesh,
    pub material: u32,
}

/// The bake settings after presets and defaults are applied.
#[derive(Clone, Debug, PartialEq)]
pub struct BakeSettings {
    /// Offset of the sample points above the surface (thesis ε).
    pub epsilon: f32,
    /// How many sample points to place (exact, before removal of invalid points).
    pub sample_count: SampleDensity,
    /// Horizon tolerance of Eq. 3.10, degrees.
    pub phi_samplemap_deg: f32,
    pub cube_resolution: u32,
    pub sample_map_resolution: u32,
    /// Rays per cube-map texel (rounded up to a square number of strata).
    pub samples_per_texel: u32,
    /// Diffuse bounces after the first hit (0 = direct light only).
    pub bounces: u32,
    pub seed: u64,
    pub encoding: oslf_format::Encoding,
    pub zstd_level: i32,
    /// RGB9E5 mantissa bits kept per channel, 1..=9 (9, the default, is lossless; fewer
    /// quantize the cube maps below their Monte Carlo noise so that zstd compresses them
    /// further: `oslf_format::encoding::quantize_rgb9e5`). Below 9 only with `rgb9e5`.
    pub mantissa_bits: u32,
    /// Store the first-hit distance of each cube-map texel (the thesis's RGBZ idea, §6.3).
    pub distance_channel: bool,
    /// Capture the environment-map baseline: one extra cube at the object's centre.
    pub env_cube: bool,
}

/// How densely sample points are placed.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum SampleDensity {
    /// This many points over all OSLF patches.
    Count(u32),
    /// Points roughly this far apart (scene units).
    Spacing(f32),
}

/// A parsed, validated scene.
#[derive(Clone, Debug)]
pub struct Scene {
    /// The scene file.
    pub path: PathBuf,
    /// SHA-256 of the scene file's bytes followed by the SHA-256 of every file it includes
    /// (patch files, OBJ meshes, textures, environment maps, glTF files with their buffers and
    /// images), in reading order: a store records it, and `oslf truth --store` and `oslf
    /// tables` check it, so an edited include is a different scene.
    pub hash: [u8; 32],
    pub camera: Option<Camera>,
    pub environment: Environment,
    pub lights: Vec<Light>,
    pub materials: Vec<Material>,
    pub objects: Vec<OslfObject>,
    pub shapes: Vec<Shape>,
    pub bake: BakeSettings,
    /// Name of the preset applied, if any.
    pub preset: Option<String>,
    /// What the scene asks for that the bake cannot do and ignores (unsupported glTF
    /// features, each naming the file and the node, mesh or material). Tools print them.
    pub warnings: Vec<String>,
}

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
        let bytes = std::fs::read(path).map_err(|source| BakeError::Io {
            path: path.to_path_buf(),
            source,
        })?;
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
    /// [`crate::camera::render`]. The defaults:
    /// - the file rotated from glTF's Y-up to the scene's Z-up (`rotate = [90, 0, 0]`), its
    ///   lights converted with [`crate::gltf::WATTS_PER_LUMEN`];
    /// - the camera: the file's first perspective camera, else one framing the bounds of its
    ///   meshes from the front right, above (40° vertical field of view);
    /// - the environment: uniform, radiance [`GLTF_SCENE_ENVIRONMENT`] (white);
    /// - the bake settings: the `[bake]` defaults.
    pub fn from_gltf(path: &Path) -> Result<Scene> {
        let bytes = std::fs::read(path).map_err(|source| BakeError::Io {
            path: path.to_path_buf(),
            source,
        })?;
        let options = crate::gltf::Options {
            transform: Affine3A::from_rotation_x(90f32.to_radians()),
            objects_from_extras: true,
            ..Default::default()
        };
        let mut materials = Vec::new();
        let mut import = crate::gltf::load(path, &options, &mut materials)?;
        let objects = mesh_objects(std::mem::take(&mut import.objects), &materials);
        let raw: RawScene = toml::from_str("").expect("an empty scene parses");
        let ctx = Ctx {
            text: "",
            path,
            included: Default::default(),
        };
        let (bake, _) = ctx.bake_settings(&raw, None)?;
        for object in &objects {
            if let Some(message) = epsilon_problem(bake.epsilon, object) {
                return Err(BakeError::Invalid(format!("{}: {message}", path.display())));
            }
        }
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
            camera,
            environment: Environment::Constant(Vec3::splat(GLTF_SCENE_ENVIRONMENT)),
            lights: import.lights,
            materials,
            objects,
            shapes: import.shapes,
            bake,
            preset: None,
            warnings: import.warnings,
        })
    }

    /// Every triangle of the scene for ray tracing: environment shapes and the OSLF objects
    /// tessellated finely enough that the tessellation error stays below `max_error`.
    pub fn instances(&self, include_objects: bool, max_error: f32) -> Vec<Instance> {
        let mut out: Vec<Instance> = self
            .shapes
            .iter()
            .map(|s| Instance {
                mesh: s.mesh.clone(),
                material: s.material,
                object: ENVIRONMENT_OBJECT,
            })
            .collect();
        if include_objects {
            for (i, object) in self.objects.iter().enumerate() {
                let mut mesh = Mesh::default();
                for patch in &object.patches {
                    mesh.append(&patch.tessellate(patch.tessellation_level(max_error)));
                }
                if let Some(source) = &object.mesh {
                    mesh.append(&source.mesh);
                }
                out.push(Instance {
                    mesh,
                    material: object.material,
                    object: i as u32,
                });
            }
        }
        out
    }
}

/// 1-based line and column (in characters) of a byte offset.
pub fn line_column(text: &str, offset: usize) -> (usize, usize) {
    let offset = offset.min(text.len());
    let before = &text.as_bytes()[..offset];
    let line = before.iter().filter(|&&b| b == b'\n').count() + 1;
    let line_start = before
        .iter()
        .rposition(|&b| b == b'\n')
        .map_or(0, |p| p + 1);
    let column = String::from_utf8_lossy(&before[line_start..])
        .chars()
        .count()
        + 1;
    (line, column)
}

// ---------------------------------------------------------------------------------------------
// Raw (serde) types. Every struct denies unknown keys; validated number types reject NaN,
// infinities and out-of-range values while parsing, so the error carries the value's position.

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawScene {
    camera: Option<Spanned<RawCamera>>,
    environment: Option<Spanned<RawEnvironment>>,
    #[serde(default)]
    point_light: Vec<RawPointLight>,
    #[serde(default)]
    directional_light: Vec<RawDirectionalLight>,
    #[serde(default)]
    object: Vec<Spanned<RawObject>>,
    #[serde(default)]
    plane: Vec<RawPlane>,
    #[serde(default, rename = "box")]
    boxes: Vec<RawBox>,
    #[serde(default)]
    cylinder: Vec<RawCylinder>,
    #[serde(default)]
    sphere: Vec<RawSphere>,
    #[serde(default)]
    revolution: Vec<RawRevolution>,
    #[serde(default)]
    mesh: Vec<RawMesh>,
    #[serde(default)]
    gltf: Vec<RawGltf>,
    #[serde(default)]
    bake: RawBake,
    #[serde(default)]
    presets: BTreeMap<String, RawBake>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawCamera {
    /// Required unless `gltf` names the camera.
    position: Option<Point>,
    /// Required unless `gltf` names the camera.
    target: Option<Spanned<Point>>,
    /// The name of a node (or camera) of an included glTF file whose camera to use.
    gltf: Option<Spanned<String>>,
    /// Default +Z.
    up: Option<Spanned<Direction>>,
    /// Default 40°.
    vfov: Option<Spanned<Angle>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawEnvironment {
    sky: Option<RawSky>,
    map: Option<RawMap>,
    uniform: Option<Rgb>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawSky {
    /// Towards the sun.
    sun_direction: Direction,
    /// Irradiance of the sun on a surface facing it (linear RGB).
    sun_irradiance: Rgb,
    /// Apparent radius of the sun's disc, degrees.
    #[serde(default = "default_sun_radius")]
    sun_angular_radius: Angle,
    /// Atmospheric turbidity (2 = very clear, 10 = hazy).
    #[serde(default = "default_turbidity")]
    turbidity: Positive,
    /// Multiplier on the sky's radiance.
    #[serde(default = "one")]
    intensity: NonNegative,
}

fn default_sun_radius() -> Angle {
    Angle(0.27)
}
fn default_turbidity() -> Positive {
    Positive(3.0)
}
fn one() -> NonNegative {
    NonNegative(1.0)
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawMap {
    /// A lat-long (equirectangular) OpenEXR or Radiance HDR file.
    path: Spanned<String>,
    #[serde(default = "one")]
    scale: NonNegative,
    /// Rotation about +z, degrees.
    #[serde(default)]
    rotation: Finite,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawPointLight {
    position: Point,
    /// Radiant intensity per channel.
    intensity: Rgb,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawDirectionalLight {
    /// Towards the light.
    direction: Direction,
    /// Irradiance on a surface facing the light.
    irradiance: Rgb,
    /// Apparent radius of the light's visible disc, degrees (0: invisible to camera rays).
    #[serde(default)]
    angular_radius: AngleRadius,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawObject {
    #[serde(default)]
    name: Option<String>,
    /// `"newell-teapot"` (the built-in data) or a path to a patch file. Exactly one of
    /// `patches` and `mesh`.
    patches: Option<Spanned<String>>,
    /// A Wavefront OBJ file: a triangle-mesh object, its sample maps in a UV atlas.
    mesh: Option<Spanned<String>>,
    /// Which patches to use, `[first, end)`; all by default.
    select: Option<Spanned<[u32; 2]>>,
    #[serde(default)]
    transform: RawTransform,
    material: Spanned<RawMaterial>,
}

#[derive(Deserialize, Default)]
#[serde(deny_unknown_fields)]
struct RawTransform {
    #[serde(default)]
    translate: Option<Point>,
    /// Rotations about x, then y, then z, in degrees.
    #[serde(default)]
    rotate: Option<Point>,
    #[serde(default)]
    scale: Option<Positive>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawMaterial {
    color: Option<Albedo>,
    checker: Option<RawChecker>,
    texture: Option<Spanned<String>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawChecker {
    a: Albedo,
    b: Albedo,
    /// Checks per unit of texture coordinate.
    scale: Positive,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawPlane {
    size: [Positive; 2],
    #[serde(default)]
    transform: RawTransform,
    material: Spanned<RawMaterial>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawBox {
    size: [Positive; 3],
    #[serde(default)]
    transform: RawTransform,
    material: Spanned<RawMaterial>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawCylinder {
    radius: Positive,
    height: Positive,
    #[serde(default = "default_segments")]
    segments: Segments,
    #[serde(default = "yes")]
    capped: bool,
    #[serde(default)]
    transform: RawTransform,
    material: Spanned<RawMaterial>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawSphere {
    radius: Positive,
    #[serde(default = "default_segments")]
    segments: Segments,
    #[serde(default)]
    transform: RawTransform,
    material: Spanned<RawMaterial>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawRevolution {
    /// `(radius, z)` pairs, bottom to top.
    profile: Spanned<Vec<[Finite; 2]>>,
    #[serde(default = "default_segments")]
    segments: Segments,
    #[serde(default)]
    transform: RawTransform,
    material: Spanned<RawMaterial>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawMesh {
    /// A Wavefront OBJ file.
    path: Spanned<String>,
    #[serde(default)]
    transform: RawTransform,
    material: Spanned<RawMaterial>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawGltf {
    /// A glTF 2.0 file, `.gltf` or `.glb`.
    path: Spanned<String>,
    /// Applied after the file's node transforms (e.g. `rotate = [90, 0, 0]`: Y-up to Z-up).
    #[serde(default)]
    transform: RawTransform,
    /// Converts the file's photometric light units (cd, lx) to radiometric ones (W/sr, W/m²).
    watts_per_lumen: Option<Positive>,
    /// Import the file's `KHR_lights_punctual` lights.
    #[serde(default = "yes")]
    lights: bool,
    /// Names of nodes whose meshes become OSLF objects (triangle-mesh objects, their sample
    /// maps in a UV atlas) instead of environment geometry.
    #[serde(default)]
    objects: Vec<String>,
}

fn default_segments() -> Segments {
    Segments(48)
}
fn yes() -> bool {
    true
}

#[derive(Deserialize, Default, Clone)]
#[serde(deny_unknown_fields)]
struct RawBake {
    epsilon: Option<Spanned<Positive>>,
    sample_count: Option<Spanned<u32>>,
    sample_spacing: Option<Positive>,
    phi_samplemap: Option<Spanned<Angle>>,
    cube_resolution: Option<Resolution>,
    sample_map_resolution: Option<Resolution>,
    samples_per_texel: Option<Spanned<u32>>,
    bounces: Option<Spanned<u32>>,
    seed: Option<u64>,
    encoding: Option<EncodingName>,
    zstd_level: Option<Spanned<i32>>,
    mantissa_bits: Option<Spanned<i64>>,
    distance_channel: Option<bool>,
    env_cube: Option<bool>,
}

impl RawBake {
    /// `self` with every key that `over` sets replaced.
    fn overridden_by(&self, over: &RawBake) -> RawBake {
        macro_rules! pick {
            ($($f:ident),*) => { RawBake { $($f: over.$f.clone().or_else(|| self.$f.clone())),* } };
        }
        let mut merged = pick!(
            epsilon,
            sample_count,
            sample_spacing,
            phi_samplemap,
            cube_resolution,
            sample_map_resolution,
            samples_per_texel,
            bounces,
            seed,
            encoding,
            zstd_level,
            mantissa_bits,
            distance_channel,
            env_cube
        );
        // A preset that sets one density key replaces the other.
        if over.sample_count.is_some() && over.sample_spacing.is_none() {
            merged.sample_spacing = None;
        }
        if over.sample_spacing.is_some() && over.sample_count.is_none() {
            merged.sample_count = None;
        }
        merged
    }
}

// --- validated scalar types ------------------------------------------------------------------

macro_rules! checked_f32 {
    ($name:ident, $what:literal, |$v:ident| $ok:expr) => {
        #[derive(Clone, Copy, Debug, Default, PartialEq)]
        struct $name(f32);
        impl<'de> Deserialize<'de> for $name {
            fn deserialize<D: Deserializer<'de>>(d: D) -> std::result::Result<Self, D::Error> {
                let $v = f64::deserialize(d)? as f32;
                if $v.is_finite() && $ok {
                    Ok($name($v))
                } else {
                    Err(D::Error::custom(format!("{} must be {}", $v, $what)))
                }
            }
        }
    };
}

checked_f32!(Finite, "a finite number", |v| true);
checked_f32!(Positive, "a finite number > 0", |v| v > 0.0);
checked_f32!(NonNegative, "a finite number >= 0", |v| v >= 0.0);
checked_f32!(Angle, "an angle in degrees within [0, 180]", |v| (0.0
    ..=180.0)
    .contains(&v));
checked_f32!(Unit, "within [0, 1]", |v| (0.0..=1.0).contains(&v));
// The apparent radius of a directional light's disc.
checked_f32!(AngleRadius, "an angle in degrees within [0, 90)", |v| (0.0
    ..90.0)
    .contains(&v));

macro_rules! checked_vec3 {
    ($name:ident, $elem:ident, $extra:literal, |$v:ident| $ok:expr) => {
        #[derive(Clone, Copy, Debug, PartialEq)]
        struct $name(Vec3);
        impl<'de> Deserialize<'de> for $name {
            fn deserialize<D: Deserializer<'de>>(d: D) -> std::result::Result<Self, D::Error> {
                let [x, y, z] = <[$elem; 3]>::deserialize(d)?;
                let $v = Vec3::new(x.0, y.0, z.0);
                if $ok {
                    Ok($name($v))
                } else {
                    Err(D::Error::custom($extra))
                }
            }
        }
    };
}

checked_vec3!(Point, Finite, "", |v| true);
checked_vec3!(Rgb, NonNegative, "", |v| true);
checked_vec3!(Albedo, Unit, "", |v| true);
checked_vec3!(
    Direction,
    Finite,
    "a direction must not be the zero vector",
    |v| v.length_squared() > 1e-12
);

/// An integer key within `$min..=$max`.
macro_rules! checked_u32 {
    ($name:ident, $what:literal, $min:expr, $max:expr) => {
        #[derive(Clone, Copy, Debug, PartialEq)]
        struct $name(u32);
        impl<'de> Deserialize<'de> for $name {
            fn deserialize<D: Deserializer<'de>>(d: D) -> std::result::Result<Self, D::Error> {
                let v = i64::deserialize(d)?;
                if (i64::from($min)..=i64::from($max)).contains(&v) {
                    Ok($name(v as u32))
                } else {
                    Err(D::Error::custom(format!(
                        "{} {v} is out of range {}..={}",
                        $what, $min, $max
                    )))
                }
            }
        }
    };
}

// A texture or cube-map resolution, as the store allows.
checked_u32!(
    Resolution,
    "resolution",
    1u32,
    oslf_format::MAX_CUBE_RESOLUTION
);
// Segments around a round shape.
checked_u32!(Segments, "segments", 3u32, 4096u32);

#[derive(Clone, Copy, Debug, PartialEq)]
struct EncodingName(oslf_format::Encoding);
impl<'de> Deserialize<'de> for EncodingName {
    fn deserialize<D: Deserializer<'de>>(d: D) -> std::result::Result<Self, D::Error> {
        let s = String::deserialize(d)?;
        s.parse::<oslf_format::Encoding>()
            .map(EncodingName)
            .map_err(|_| {
                D::Error::custom(format!(
                    "unknown encoding {s:?} (expected \"rgb9e5\", \"rgba16f\", \"rgba32f\" or \"bc6h\")"
                ))
            })
    }
}

// --- building the scene ----------------------------------------------------------------------

struct Ctx<'a> {
    text: &'a str,
    path: &'a Path,
    /// Every file the scene includes, in reading order (for [`Scene::hash`]).
    included: std::cell::RefCell<Vec<PathBuf>>,
}

/// A `[camera]` as written: explicit, or naming a glTF camera (resolved once the includes are
/// read).
enum CameraSpec {
    Explicit(Camera),
    Gltf(Spanned<String>),
}

impl Ctx<'_> {
    fn error_at(&self, span: Range<usize>, message: impl Into<String>) -> BakeError {
        let (line, column) = line_column(self.text, span.start);
        BakeError::Parse {
            path: self.path.to_path_buf(),
            line,
            column,
            message: message.into(),
        }
    }

    /// Located version of an error from a helper that does not know where it was called from.
    fn locate(&self, span: Range<usize>, error: BakeError) -> BakeError {
        match error {
            BakeError::Invalid(message) => self.error_at(span, message),
            other => other,
        }
    }

    fn resolve(&self, relative: &str) -> PathBuf {
        let p = Path::new(relative);
        if p.is_absolute() {
            p.to_path_buf()
        } else {
            self.path.parent().unwrap_or_else(|| Path::new(".")).join(p)
        }
    }

    fn existing_file(&self, path: &Spanned<String>) -> Result<PathBuf> {
        let resolved = self.resolve(path.get_ref());
        if resolved.is_file() {
            self.included.borrow_mut().push(resolved.clone());
            Ok(resolved)
        } else {
            Err(self.error_at(
                path.span(),
                format!("file not found: {}", resolved.display()),
            ))
        }
    }

    /// The `[camera]`, checked as the renderers need it: errors point at the key at fault
    /// (or at the table when the key was left at its default).
    fn camera(&self, raw: Spanned<RawCamera>) -> Result<CameraSpec> {
        let table = raw.span();
        let c = raw.into_inner();
        if let Some(name) = c.gltf {
            if c.position.is_some() || c.target.is_some() || c.up.is_some() || c.vfov.is_some() {
                return Err(self.error_at(
                    table,
                    "a [camera] with `gltf` takes the glTF camera as it is: give no position, target, up or vfov with it",
                ));
            }
            return Ok(CameraSpec::Gltf(name));
        }
        let (Some(position), Some(target)) = (c.position, c.target) else {
            return Err(self.error_at(
                table,
                "the [camera] needs `position` and `target` (or `gltf = \"NodeName\"`, a camera of an included glTF file)",
            ));
        };
        let vec = |v: Vec3| format!("[{}, {}, {}]", v.x, v.y, v.z);
        let camera = Camera {
            position: position.0,
            target: target.get_ref().0,
            up: c.up.as_ref().map_or(Vec3::Z, |u| u.get_ref().0).normalize(),
            vfov_deg: c.vfov.as_ref().map_or(40.0, |v| v.get_ref().0),
        };
        let Some(forward) = (camera.target - camera.position).try_normalize() else {
            return Err(self.error_at(
                target.span(),
                format!(
                    "the camera's target {} coincides with its position",
                    vec(camera.target)
                ),
            ));
        };
        if forward.cross(camera.up).length_squared() < 1e-12 {
            let (span, up) = match &c.up {
                Some(u) => (u.span(), format!("up {}", vec(u.get_ref().0))),
                None => (table.clone(), "up (default [0, 0, 1])".to_string()),
            };
            return Err(self.error_at(
                span,
                format!(
                    "the camera's {up} is parallel to its view direction {} (from position to target), so the image has no defined vertical: choose an up that is not",
                    vec(forward)
                ),
            ));
        }
        if !(camera.vfov_deg > 0.0 && camera.vfov_deg < 180.0) {
            let span = c.vfov.as_ref().map_or(table.clone(), |v| v.span());
            return Err(self.error_at(
                span,
                format!(
                    "the camera's vfov {} must be within (0, 180) degrees",
                    camera.vfov_deg
                ),
            ));
        }
        // Whatever else the renderers refuse.
        camera
            .validate()
            .map_err(|e| self.locate(table, e.into()))?;
        Ok(CameraSpec::Explicit(camera))
    }

    /// The scene camera: the `[camera]`'s, the glTF camera it names, or (without a
    /// `[camera]`) the first camera of the included glTF files.
    fn resolve_camera(
        &self,
        spec: Option<CameraSpec>,
        cameras: &[GltfCamera],
    ) -> Result<Option<Camera>> {
        Ok(match spec {
            Some(CameraSpec::Explicit(c)) => Some(c),
            Some(CameraSpec::Gltf(name)) => {
                let wanted = name.get_ref();
                let found = cameras
                    .iter()
                    .find(|c| &c.node == wanted)
                    .or_else(|| cameras.iter().find(|c| c.name.as_ref() == Some(wanted)));
                match found {
                    Some(c) => Some(c.camera),
                    None => {
                        let known: Vec<String> =
                            cameras.iter().map(|c| format!("{:?}", c.node)).collect();
                        return Err(self.error_at(
                            name.span(),
                            format!(
                                "no glTF camera named {wanted:?} (the included glTF files have {})",
                                if known.is_empty() {
                                    "no perspective camera".to_string()
                                } else {
                                    format!("cameras on nodes {}", known.join(", "))
                                }
                            ),
                        ));
                    }
                }
            }
            None => cameras.first().map(|c| c.camera),
        })
    }

    fn build(&self, raw: RawScene, preset: Option<&str>) -> Result<Scene> {
        let (bake, epsilon_span) = self.bake_settings(&raw, preset)?;

        let camera_spec = match raw.camera {
            Some(c) => Some(self.camera(c)?),
            None => None,
        };

        let mut lights: Vec<Light> = raw
            .point_light
            .iter()
            .map(|l| Light::Point {
                position: l.position.0,
                intensity: l.intensity.0,
            })
            .collect();
        lights.extend(raw.directional_light.iter().map(|l| Light::Sun {
            direction: l.direction.0.normalize(),
            irradiance: l.irradiance.0,
            angular_radius: l.angular_radius.0.to_radians(),
        }));

        let environment = match raw.environment {
            None => Environment::Constant(Vec3::ZERO),
            Some(env) => {
                let span = env.span();
                let env = env.into_inner();
                let count = env.sky.is_some() as u32
                    + env.map.is_some() as u32
                    + env.uniform.is_some() as u32;
                if count != 1 {
                    return Err(self.error_at(
                        span,
                        "[environment] needs exactly one of `sky`, `map` or `uniform`",
                    ));
                }
                if let Some(sky) = env.sky {
                    let direction = sky.sun_direction.0.normalize();
                    let model = Sky::new(direction, sky.turbidity.0, sky.intensity.0)
                        .map_err(|e| self.locate(span.clone(), e))?;
                    lights.push(
                        model
                            .sun_light(sky.sun_irradiance.0, sky.sun_angular_radius.0.to_radians()),
                    );
                    Environment::Sky(Arc::new(model))
                } else if let Some(map) = env.map {
                    let file = self.existing_file(&map.path)?;
                    let loaded = LatLongMap::load(&file, map.scale.0, map.rotation.0)?;
                    Environment::LatLong(Arc::new(loaded))
                } else {
                    Environment::Constant(env.uniform.map_or(Vec3::ZERO, |u| u.0))
                }
            }
        };

        let mut materials = Vec::new();
        let mut objects = Vec::new();
        for spanned in raw.object {
            let span = spanned.span();
            let o = spanned.into_inner();
            let transform = o.transform.affine();
            let (patches, mesh) = match (&o.patches, &o.mesh) {
                (Some(patches), None) => (self.object_patches(patches, o.select.as_ref())?, None),
                (None, Some(path)) => {
                    if let Some(select) = &o.select {
                        return Err(self.error_at(
                            select.span(),
                            "`select` picks patches; a `mesh` object has none",
                        ));
                    }
                    let file = self.existing_file(path)?;
                    let mut mesh = crate::obj::load_obj(&file)?;
                    mesh.transform(&transform);
                    // An OBJ without `vt` reads as all-zero uvs: no texture set then.
                    let uv_sets = if mesh.uvs.iter().any(|&uv| uv != Vec2::ZERO) {
                        vec![(UvSource::Texture, mesh.uvs.clone())]
                    } else {
                        Vec::new()
                    };
                    let source = MeshSource { mesh, uv_sets };
                    (Vec::new(), Some(source))
                }
                _ => {
                    return Err(self.error_at(
                        span,
                        "an [[object]] needs exactly one of `patches` (Bézier patches) or `mesh` (an OBJ file)",
                    ))
                }
            };
            let (material, base_color) = self.material(&o.material, &mut materials)?;
            let world = patches.iter().map(|p| p.transformed(&transform)).collect();
            let object = OslfObject {
                name: o.name.unwrap_or_else(|| format!("object{}", objects.len())),
                object_patches: patches,
                patches: world,
                mesh,
                transform,
                material,
                base_color,
            };
            self.check_epsilon(bake.epsilon, epsilon_span.clone(), &object, span)?;
            objects.push(object);
        }

        let mut shapes_out = Vec::new();
        let mut add = |mesh: Mesh,
                       t: &RawTransform,
                       m: &Spanned<RawMaterial>,
                       materials: &mut Vec<Material>|
         -> Result<()> {
            let mut mesh = mesh;
            mesh.transform(&t.affine());
            let (material, _) = self.material(m, materials)?;
            shapes_out.push(Shape { mesh, material });
            Ok(())
        };
        for p in &raw.plane {
            let mesh = shapes::plane(Vec2::new(p.size[0].0, p.size[1].0))
                .map_err(|e| self.locate(p.material.span(), e))?;
            add(mesh, &p.transform, &p.material, &mut materials)?;
        }
        for b in &raw.boxes {
            let mesh = shapes::cuboid(Vec3::new(b.size[0].0, b.size[1].0, b.size[2].0))
                .map_err(|e| self.locate(b.material.span(), e))?;
            add(mesh, &b.transform, &b.material, &mut materials)?;
        }
        for c in &raw.cylinder {
            let mesh = shapes::cylinder(c.radius.0, c.height.0, c.segments.0, c.capped)
                .map_err(|e| self.locate(c.material.span(), e))?;
            add(mesh, &c.transform, &c.material, &mut materials)?;
        }
        for s in &raw.sphere {
            let mesh = shapes::sphere(s.radius.0, s.segments.0)
                .map_err(|e| self.locate(s.material.span(), e))?;
            add(mesh, &s.transform, &s.material, &mut materials)?;
        }
        for r in &raw.revolution {
            let profile: Vec<Vec2> = r
                .profile
                .get_ref()
                .iter()
                .map(|[a, b]| Vec2::new(a.0, b.0))
                .collect();
            let mesh = shapes::revolution(&profile, r.segments.0)
                .map_err(|e| self.locate(r.profile.span(), e))?;
            add(mesh, &r.transform, &r.material, &mut materials)?;
        }
        for m in &raw.mesh {
            let file = self.existing_file(&m.path)?;
            let mesh = obj::load_obj(&file)?;
            add(mesh, &m.transform, &m.material, &mut materials)?;
        }

        let mut warnings = Vec::new();
        let mut gltf_cameras = Vec::new();
        for g in &raw.gltf {
            let file = self.existing_file(&g.path)?;
            let options = crate::gltf::Options {
                transform: g.transform.affine(),
                watts_per_lumen: g
                    .watts_per_lumen
                    .map_or(crate::gltf::WATTS_PER_LUMEN, |w| w.0),
                lights: g.lights,
                objects: g.objects.clone(),
                objects_from_extras: false,
            };
            let import = crate::gltf::load(&file, &options, &mut materials)?;
            self.included
                .borrow_mut()
                .extend(import.files.iter().cloned());
            for object in mesh_objects(import.objects, &materials) {
                self.check_epsilon(bake.epsilon, epsilon_span.clone(), &object, g.path.span())?;
                objects.push(object);
            }
            shapes_out.extend(import.shapes);
            lights.extend(import.lights);
            gltf_cameras.extend(import.cameras);
            warnings.extend(import.warnings);
        }
        let camera = self.resolve_camera(camera_spec, &gltf_cameras)?;

        if objects.is_empty() {
            return Err(BakeError::Invalid(format!(
                "{}: the scene has no [[object]]: there is nothing to bake a light field around",
                self.path.display()
            )));
        }

        let hash = scene_hash(self.text.as_bytes(), &self.included.borrow())?;
        Ok(Scene {
            path: self.path.to_path_buf(),
            hash,
            camera,
            environment,
            lights,
            materials,
            objects,
            shapes: shapes_out,
            bake,
            preset: preset.map(str::to_string),
            warnings,
        })
    }

    /// Adds a material, returning its index and its mean albedo.
    fn material(
        &self,
        m: &Spanned<RawMaterial>,
        materials: &mut Vec<Material>,
    ) -> Result<(u32, Vec3)> {
        let raw = m.get_ref();
        let count = raw.color.is_some() as u32
            + raw.checker.is_some() as u32
            + raw.texture.is_some() as u32;
        if count != 1 {
            return Err(self.error_at(
                m.span(),
                "a material needs exactly one of `color`, `checker` or `texture`",
            ));
        }
        let (albedo, mean) = if let Some(c) = raw.color {
            (Texture::Constant(c.0), c.0)
        } else if let Some(c) = &raw.checker {
            (
                Texture::Checker {
                    a: c.a.0,
                    b: c.b.0,
                    scale: c.scale.0,
                },
                (c.a.0 + c.b.0) * 0.5,
            )
        } else {
            let spanned = raw.texture.as_ref().expect("counted above");
            let file = self.existing_file(spanned)?;
            let image = ImageTexture::load(&file)?;
            let mean =
                image.pixels.iter().copied().sum::<Vec3>() / image.pixels.len().max(1) as f32;
            (Texture::Image(Arc::new(image)), mean)
        };
        let material = Material { albedo };
        materials.push(material);
        Ok(((materials.len() - 1) as u32, mean))
    }

    /// The bake settings and where `epsilon` was given (if it was).
    fn bake_settings(
        &self,
        raw: &RawScene,
        preset: Option<&str>,
    ) -> Result<(BakeSettings, Option<Range<usize>>)> {
        let merged = match preset {
            None => raw.bake.clone(),
            Some(name) => match raw.presets.get(name) {
                Some(p) => raw.bake.overridden_by(p),
                None => {
                    let known: Vec<&str> = raw.presets.keys().map(String::as_str).collect();
                    return Err(BakeError::Invalid(format!(
                        "{}: no preset named {name:?} (the scene defines: {})",
                        self.path.display(),
                        if known.is_empty() {
                            "none".to_string()
                        } else {
                            known.join(", ")
                        }
                    )));
                }
            },
        };
        let sample_count = match (&merged.sample_count, &merged.sample_spacing) {
            (Some(c), Some(_)) => {
                return Err(self.error_at(
                    c.span(),
                    "give either sample_count or sample_spacing, not both",
                ))
            }
            (Some(c), None) => {
                if *c.get_ref() == 0 || *c.get_ref() > 16_000_000 {
                    return Err(self.error_at(c.span(), "sample_count must be in 1..=16000000"));
                }
                SampleDensity::Count(*c.get_ref())
            }
            (None, Some(s)) => SampleDensity::Spacing(s.0),
            (None, None) => SampleDensity::Count(300),
        };
        let phi = match &merged.phi_samplemap {
            Some(p) if p.get_ref().0 <= 0.0 || p.get_ref().0 >= 90.0 => {
                return Err(self.error_at(
                    p.span(),
                    "phi_samplemap must be in (0, 90) degrees (Eq. 3.10)",
                ))
            }
            Some(p) => p.get_ref().0,
            None => 85.0,
        };
        let spp = match &merged.samples_per_texel {
            Some(s) if *s.get_ref() == 0 || *s.get_ref() > 1 << 16 => {
                return Err(self.error_at(s.span(), "samples_per_texel must be in 1..=65536"))
            }
            Some(s) => *s.get_ref(),
            None => 4,
        };
        let bounces = match &merged.bounces {
            Some(b) if *b.get_ref() > 64 => {
                return Err(self.error_at(b.span(), "bounces must be at most 64"))
            }
            Some(b) => *b.get_ref(),
            None => 1,
        };
        let zstd_level = match &merged.zstd_level {
            Some(z) if !(1..=22).contains(z.get_ref()) => {
                return Err(self.error_at(z.span(), "zstd_level must be in 1..=22"))
            }
            Some(z) => *z.get_ref(),
            None => 3,
        };
        let encoding = merged
            .encoding
            .map_or(oslf_format::Encoding::Rgb9e5, |e| e.0);
        let mantissa_bits = match &merged.mantissa_bits {
            Some(m) => {
                let bits = u32::try_from(*m.get_ref()).unwrap_or(0);
                oslf_format::meta::check_mantissa_bits(encoding, bits).map_err(|_| {
                    let problem = if (1..=9).contains(m.get_ref()) {
                        format!(
                            "mantissa_bits = {} needs encoding = \"rgb9e5\" (the encoding is {encoding}, {})",
                            m.get_ref(),
                            if encoding.is_block_compressed() {
                                "whose precision its 4×4 blocks set"
                            } else {
                                "which keeps every bit"
                            }
                        )
                    } else {
                        format!("mantissa_bits {} must be in 1..=9", m.get_ref())
                    };
                    self.error_at(m.span(), problem)
                })?;
                bits
            }
            None => oslf_format::encoding::RGB9E5_FULL_MANTISSA_BITS,
        };
        let epsilon_span = merged.epsilon.as_ref().map(Spanned::span);
        let settings = BakeSettings {
            epsilon: merged.epsilon.as_ref().map_or(0.1, |e| e.get_ref().0),
            sample_count,
            phi_samplemap_deg: phi,
            cube_resolution: merged.cube_resolution.map_or(32, |r| r.0),
            sample_map_resolution: merged.sample_map_resolution.map_or(256, |r| r.0),
            samples_per_texel: spp,
            bounces,
            seed: merged.seed.unwrap_or(0),
            encoding,
            zstd_level,
            mantissa_bits,
            distance_channel: merged.distance_channel.unwrap_or(true),
            env_cube: merged.env_cube.unwrap_or(true),
        };
        Ok((settings, epsilon_span))
    }

    /// The patches an `[[object]]` names: the built-in teapot or a patch file, cut to
    /// `select`.
    fn object_patches(
        &self,
        patches: &Spanned<String>,
        select: Option<&Spanned<[u32; 2]>>,
    ) -> Result<Vec<BezierPatch>> {
        let mut out = if patches.get_ref() == "newell-teapot" {
            bezier::newell_teapot()
        } else {
            let file = self.existing_file(patches)?;
            let text = std::fs::read_to_string(&file).map_err(|source| BakeError::Io {
                path: file.clone(),
                source,
            })?;
            bezier::parse_patch_file(&text, &file)?
        };
        if let Some(select) = select {
            let [first, end] = *select.get_ref();
            if first >= end || end as usize > out.len() {
                return Err(self.error_at(
                    select.span(),
                    format!(
                        "select = [{first}, {end}] is not a non-empty range within the {} patches",
                        out.len()
                    ),
                ));
            }
            out = out[first as usize..end as usize].to_vec();
        }
        Ok(out)
    }

    /// Refuses an ε that the bake cannot honour for `object` (located at `epsilon_span`, or at
    /// the object when ε is the default). Two limits, both reported with the smallest ε that
    /// works:
    /// - f32: a sample point must lie at least [`MIN_EPSILON_RELATIVE`] × the object's largest
    ///   coordinate magnitude above its surface, twice the ray–triangle test's self-intersection
    ///   tolerance ([`crate::bvh::SELF_TOLERANCE`]); below it, rays from a sample point pass
    ///   through the surface under it. (10⁵ units from the origin: ε ≥ 0.095.)
    /// - tessellation: the ray-traced triangles must follow the patches within ε/50
    ///   ([`crate::bake::TESSELLATION_ERROR`]), which the finest grid
    ///   ([`bezier::MAX_TESSELLATION_LEVEL`]² quads per patch) must reach. (The Newell teapot at
    ///   scale 1: ε ≥ 3.2·10⁻³.)
    fn check_epsilon(
        &self,
        epsilon: f32,
        epsilon_span: Option<Range<usize>>,
        object: &OslfObject,
        object_span: Range<usize>,
    ) -> Result<()> {
        let span = epsilon_span.unwrap_or(object_span);
        match epsilon_problem(epsilon, object) {
            Some(message) => Err(self.error_at(span, message)),
            None => Ok(()),
        }
    }
}

/// OSLF objects of the glTF nodes chosen as objects (world space, identity transform), their
/// base colour the material's mean albedo.
fn mesh_objects(
    imported: Vec<crate::gltf::ImportedObject>,
    materials: &[Material],
) -> Vec<OslfObject> {
    imported
        .into_iter()
        .map(|o| OslfObject {
            name: o.node,
            object_patches: Vec::new(),
            patches: Vec::new(),
            mesh: Some(MeshSource {
                mesh: o.mesh,
                uv_sets: o.uv_sets,
            }),
            transform: Affine3A::IDENTITY,
            material: o.material,
            base_color: materials[o.material as usize].mean_albedo(),
        })
        .collect()
}

/// Why the bake cannot honour `epsilon` for `object`, if it cannot (see `Ctx::check_epsilon`).
fn epsilon_problem(epsilon: f32, object: &OslfObject) -> Option<String> {
    let extent = object
        .points()
        .fold(0f32, |m, c| m.max(c.abs().max_element()));
    let f32_limit = MIN_EPSILON_RELATIVE * extent;
    if epsilon < f32_limit {
        let ulp = f32::EPSILON * extent;
        return Some(format!(
            "epsilon = {epsilon} is too small for object {:?}: its coordinates reach \
             {extent:.4e}, where f32 positions are up to {ulp:.2e} apart, and sample points \
             must sit at least 2^-20 of that ({f32_limit:.4e}) above the surface; use \
             epsilon >= {f32_limit:.4e} or move the object nearer the origin",
            object.name
        ));
    }
    let (worst, patch) = object
        .patches
        .iter()
        .enumerate()
        .map(|(i, p)| (p.min_tessellation_error(), i))
        .fold((0f32, 0), |a, b| if b.0 > a.0 { b } else { a });
    let tess_limit = worst / crate::bake::TESSELLATION_ERROR;
    if epsilon < tess_limit {
        return Some(format!(
            "epsilon = {epsilon} is too small for object {:?}: the ray-traced \
             triangles must follow the patches within epsilon/50, but patch {patch} \
             still deviates by up to {worst:.3e} at the finest tessellation ({}² \
             quads); use epsilon >= {tess_limit:.4e}",
            object.name,
            bezier::MAX_TESSELLATION_LEVEL
        ));
    }
    None
}

impl Scene {
    /// Checks bake settings changed after loading (tools that vary them, e.g. a sweep) against
    /// the limits the scene file's parser enforces on ε for each object.
    pub fn check_epsilon(&self) -> Result<()> {
        for object in &self.objects {
            if let Some(message) = epsilon_problem(self.bake.epsilon, object) {
                return Err(BakeError::Invalid(message));
            }
        }
        Ok(())
    }
}

impl RawTransform {
    /// Scale, then rotate about x, y, z (degrees), then translate.
    fn affine(&self) -> Affine3A {
        let scale = self.scale.map_or(1.0, |s| s.0);
        let r = self.rotate.map_or(Vec3::ZERO, |r| r.0);
        let rotation = Quat::from_rotation_z(r.z.to_radians())
            * Quat::from_rotation_y(r.y.to_radians())
            * Quat::from_rotation_x(r.x.to_radians());
        let translation = self.translate.map_or(Vec3::ZERO, |t| t.0);
        Affine3A::from_scale_rotation_translation(Vec3::splat(scale), rotation, translation)
    }
}

/// [`Scene::hash`]: SHA-256 of `text` and of the SHA-256 of each of `files`, in order.
fn scene_hash(text: &[u8], files: &[PathBuf]) -> Result<[u8; 32]> {
    use sha2::Digest;
    let mut hasher = sha2::Sha256::new();
    hasher.update(text);
    for file in files {
        let bytes = std::fs::read(file).map_err(|source| BakeError::Io {
            path: file.clone(),
            source,
        })?;
        hasher.update(sha256(&bytes));
    }
    Ok(hasher.finalize().into())
}

fn sha256(bytes: &[u8]) -> [u8; 32] {
    use sha2::Digest;
    sha2::Sha256::digest(bytes).into()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn line_column_counts_from_one() {
        let text = "a = 1\nbé = x\n";
        assert_eq!(line_column(text, 0), (1, 1));
        assert_eq!(line_column(text, 6), (2, 1));
        // 'x' sits after the two-byte 'é': byte 12, character column 6.
        assert_eq!(line_column(text, text.find('x').unwrap()), (2, 6));
    }
}
