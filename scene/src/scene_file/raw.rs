//! The raw (serde) types of a scene file, as written. Every struct denies unknown keys;
//! validated number types reject NaN, infinities and out-of-range values while parsing, so
//! the error carries the value's position.

use std::collections::BTreeMap;

use glam::{Affine3A, Quat, Vec3};
use serde::de::Error as _;
use serde::{Deserialize, Deserializer};
use toml::Spanned;

use crate::normals::NormalRule;

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawScene {
    pub(super) camera: Option<Spanned<RawCamera>>,
    pub(super) environment: Option<Spanned<RawEnvironment>>,
    #[serde(default)]
    pub(super) point_light: Vec<RawPointLight>,
    #[serde(default)]
    pub(super) directional_light: Vec<RawDirectionalLight>,
    #[serde(default)]
    pub(super) object: Vec<Spanned<RawObject>>,
    #[serde(default)]
    pub(super) plane: Vec<RawPlane>,
    #[serde(default, rename = "box")]
    pub(super) boxes: Vec<RawBox>,
    #[serde(default)]
    pub(super) cylinder: Vec<RawCylinder>,
    #[serde(default)]
    pub(super) sphere: Vec<RawSphere>,
    #[serde(default)]
    pub(super) revolution: Vec<RawRevolution>,
    #[serde(default)]
    pub(super) mesh: Vec<RawMesh>,
    #[serde(default)]
    pub(super) gltf: Vec<RawGltf>,
    #[serde(default)]
    pub(super) bake: RawBake,
    #[serde(default)]
    pub(super) presets: BTreeMap<String, RawBake>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawCamera {
    /// Required unless `gltf` names the camera.
    pub(super) position: Option<Point>,
    /// Required unless `gltf` names the camera.
    pub(super) target: Option<Spanned<Point>>,
    /// The name of a node (or camera) of an included glTF file whose camera to use.
    pub(super) gltf: Option<Spanned<String>>,
    /// Default +Z.
    pub(super) up: Option<Spanned<Direction>>,
    /// Default 40°.
    pub(super) vfov: Option<Spanned<Angle>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawEnvironment {
    pub(super) sky: Option<RawSky>,
    pub(super) map: Option<RawMap>,
    pub(super) uniform: Option<Rgb>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawSky {
    /// Towards the sun.
    pub(super) sun_direction: Direction,
    /// Irradiance of the sun on a surface facing it (linear RGB).
    pub(super) sun_irradiance: Rgb,
    /// Apparent radius of the sun's disc, degrees.
    #[serde(default = "default_sun_radius")]
    pub(super) sun_angular_radius: Angle,
    /// Atmospheric turbidity (2 = very clear, 10 = hazy).
    #[serde(default = "default_turbidity")]
    pub(super) turbidity: Positive,
    /// Multiplier on the sky's radiance.
    #[serde(default = "one")]
    pub(super) intensity: NonNegative,
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
pub(super) struct RawMap {
    /// A lat-long (equirectangular) OpenEXR or Radiance HDR file.
    pub(super) path: Spanned<String>,
    #[serde(default = "one")]
    pub(super) scale: NonNegative,
    /// Rotation about +z, degrees.
    #[serde(default)]
    pub(super) rotation: Finite,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawPointLight {
    pub(super) position: Point,
    /// Radiant intensity per channel.
    pub(super) intensity: Rgb,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawDirectionalLight {
    /// Towards the light.
    pub(super) direction: Direction,
    /// Irradiance on a surface facing the light.
    pub(super) irradiance: Rgb,
    /// Apparent radius of the light's visible disc, degrees (0: invisible to camera rays).
    #[serde(default)]
    pub(super) angular_radius: AngleRadius,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawObject {
    #[serde(default)]
    pub(super) name: Option<String>,
    /// `"newell-teapot"` (the built-in data) or a path to a patch file. Exactly one of
    /// `patches` and `mesh`.
    pub(super) patches: Option<Spanned<String>>,
    /// A Wavefront OBJ file: a triangle-mesh object, its sample maps in a UV atlas.
    pub(super) mesh: Option<Spanned<String>>,
    /// Which patches to use, `[first, end)`; all by default.
    pub(super) select: Option<Spanned<[u32; 2]>>,
    /// How a `mesh` object's normals are computed (`"smooth"`, `"flat"`, `{ crease_deg }`).
    pub(super) normals: Option<Spanned<RawNormals>>,
    /// The object's own sample spacing, overriding `[bake]`'s density for it.
    pub(super) sample_spacing: Option<Positive>,
    #[serde(default)]
    pub(super) transform: RawTransform,
    pub(super) material: Spanned<RawMaterial>,
}

#[derive(Deserialize, Default)]
#[serde(deny_unknown_fields)]
pub(super) struct RawTransform {
    #[serde(default)]
    pub(super) translate: Option<Point>,
    /// Rotations about x, then y, then z, in degrees.
    #[serde(default)]
    pub(super) rotate: Option<Point>,
    #[serde(default)]
    pub(super) scale: Option<Positive>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawMaterial {
    pub(super) color: Option<Albedo>,
    pub(super) checker: Option<RawChecker>,
    pub(super) texture: Option<Spanned<String>>,
    /// glTF's metallic-roughness model (both or neither).
    pub(super) metallic: Option<Unit>,
    pub(super) roughness: Option<Unit>,
    /// Emitted radiance, linear RGB.
    pub(super) emission: Option<Rgb>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawChecker {
    pub(super) a: Albedo,
    pub(super) b: Albedo,
    /// Checks per unit of texture coordinate.
    pub(super) scale: Positive,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawPlane {
    pub(super) size: [Positive; 2],
    #[serde(default)]
    pub(super) transform: RawTransform,
    pub(super) material: Spanned<RawMaterial>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawBox {
    pub(super) size: [Positive; 3],
    #[serde(default)]
    pub(super) transform: RawTransform,
    pub(super) material: Spanned<RawMaterial>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawCylinder {
    pub(super) radius: Positive,
    pub(super) height: Positive,
    #[serde(default = "default_segments")]
    pub(super) segments: Segments,
    #[serde(default = "yes")]
    pub(super) capped: bool,
    #[serde(default)]
    pub(super) transform: RawTransform,
    pub(super) material: Spanned<RawMaterial>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawSphere {
    pub(super) radius: Positive,
    #[serde(default = "default_segments")]
    pub(super) segments: Segments,
    #[serde(default)]
    pub(super) transform: RawTransform,
    pub(super) material: Spanned<RawMaterial>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawRevolution {
    /// `(radius, z)` pairs, bottom to top.
    pub(super) profile: Spanned<Vec<[Finite; 2]>>,
    #[serde(default = "default_segments")]
    pub(super) segments: Segments,
    #[serde(default)]
    pub(super) transform: RawTransform,
    pub(super) material: Spanned<RawMaterial>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawMesh {
    /// A Wavefront OBJ file.
    pub(super) path: Spanned<String>,
    /// How its normals are computed (the default: the file's, else a 30° crease).
    pub(super) normals: Option<RawNormals>,
    #[serde(default)]
    pub(super) transform: RawTransform,
    pub(super) material: Spanned<RawMaterial>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawGltf {
    /// A glTF 2.0 file, `.gltf` or `.glb`.
    pub(super) path: Spanned<String>,
    /// Applied after the file's node transforms (e.g. `rotate = [90, 0, 0]`: Y-up to Z-up).
    #[serde(default)]
    pub(super) transform: RawTransform,
    /// Converts the file's photometric light units (cd, lx) to radiometric ones (W/sr, W/m²).
    pub(super) watts_per_lumen: Option<Positive>,
    /// Import the file's `KHR_lights_punctual` lights.
    #[serde(default = "yes")]
    pub(super) lights: bool,
    /// Names of nodes whose meshes become OSLF objects (triangle-mesh objects, their sample
    /// maps in a UV atlas) instead of environment geometry.
    #[serde(default)]
    pub(super) objects: Vec<String>,
    /// How the normals of every primitive are computed (the default: the file's `NORMAL`,
    /// else flat, as glTF specifies).
    pub(super) normals: Option<RawNormals>,
    /// The sample spacing of each of its `objects`, overriding `[bake]`'s density for them.
    pub(super) sample_spacing: Option<Positive>,
}

/// `normals = "smooth" | "flat" | { crease_deg = 30.0 }`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct RawNormals(pub(super) NormalRule);

impl<'de> Deserialize<'de> for RawNormals {
    fn deserialize<D: Deserializer<'de>>(d: D) -> std::result::Result<Self, D::Error> {
        struct Visitor;
        const EXPECTED: &str = "\"smooth\", \"flat\" or { crease_deg = DEGREES }";
        impl<'de> serde::de::Visitor<'de> for Visitor {
            type Value = RawNormals;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                write!(f, "normals = {EXPECTED}")
            }
            fn visit_str<E: serde::de::Error>(self, v: &str) -> std::result::Result<RawNormals, E> {
                match v {
                    "smooth" => Ok(RawNormals(NormalRule::Smooth)),
                    "flat" => Ok(RawNormals(NormalRule::Flat)),
                    other => Err(E::custom(format!(
                        "unknown normals {other:?} (expected {EXPECTED})"
                    ))),
                }
            }
            fn visit_map<A: serde::de::MapAccess<'de>>(
                self,
                map: A,
            ) -> std::result::Result<RawNormals, A::Error> {
                #[derive(Deserialize)]
                #[serde(deny_unknown_fields)]
                struct Crease {
                    crease_deg: Angle,
                }
                let c = Crease::deserialize(serde::de::value::MapAccessDeserializer::new(map))?;
                Ok(RawNormals(NormalRule::Crease {
                    crease_deg: c.crease_deg.0,
                }))
            }
        }
        d.deserialize_any(Visitor)
    }
}

fn default_segments() -> Segments {
    Segments(48)
}
fn yes() -> bool {
    true
}

#[derive(Deserialize, Default, Clone)]
#[serde(deny_unknown_fields)]
pub(super) struct RawBake {
    pub(super) epsilon: Option<Spanned<Positive>>,
    pub(super) sample_count: Option<Spanned<u32>>,
    pub(super) sample_spacing: Option<Positive>,
    pub(super) placement: Option<Named<crate::scene::PointPlacement>>,
    pub(super) near_surface: Option<Named<crate::scene::NearSurface>>,
    pub(super) phi_samplemap: Option<Spanned<Angle>>,
    pub(super) cube_resolution: Option<Resolution>,
    pub(super) sample_map_resolution: Option<Resolution>,
    pub(super) samples_per_texel: Option<Spanned<u32>>,
    /// The relative standard error each cube texel samples down to (adaptive sampling).
    pub(super) target_noise: Option<Spanned<f64>>,
    /// Denoise the captured cube maps.
    pub(super) denoise: Option<bool>,
    pub(super) bounces: Option<Spanned<u32>>,
    pub(super) seed: Option<u64>,
    pub(super) encoding: Option<EncodingName>,
    pub(super) zstd_level: Option<Spanned<i32>>,
    pub(super) mantissa_bits: Option<Spanned<i64>>,
    pub(super) distance_channel: Option<bool>,
    pub(super) env_cube: Option<bool>,
    pub(super) device: Option<Named<crate::scene::DeviceChoice>>,
    /// The store size (MB) the settings the scene chooses must fit.
    pub(super) store_budget_mb: Option<Positive>,
}

impl RawBake {
    /// `self` with every key that `over` sets replaced.
    pub(super) fn overridden_by(&self, over: &RawBake) -> RawBake {
        macro_rules! pick {
            ($($f:ident),*) => { RawBake { $($f: over.$f.clone().or_else(|| self.$f.clone())),* } };
        }
        let mut merged = pick!(
            epsilon,
            sample_count,
            sample_spacing,
            placement,
            near_surface,
            phi_samplemap,
            cube_resolution,
            sample_map_resolution,
            samples_per_texel,
            target_noise,
            denoise,
            bounces,
            seed,
            encoding,
            zstd_level,
            mantissa_bits,
            distance_channel,
            env_cube,
            device,
            store_budget_mb
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
        pub(super) struct $name(pub(super) f32);
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
        pub(super) struct $name(pub(super) Vec3);
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
        pub(super) struct $name(pub(super) u32);
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
pub(super) struct EncodingName(pub(super) oslf_format::Encoding);
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

/// A setting named by a string in the file (`placement = "parallax"`): whatever `T` parses,
/// its error the message.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Named<T>(pub(super) T);
impl<'de, T: std::str::FromStr<Err = String>> Deserialize<'de> for Named<T> {
    fn deserialize<D: Deserializer<'de>>(d: D) -> std::result::Result<Self, D::Error> {
        let s = String::deserialize(d)?;
        s.parse().map(Named).map_err(D::Error::custom)
    }
}

impl RawTransform {
    /// Scale, then rotate about x, y, z (degrees), then translate.
    pub(super) fn affine(&self) -> Affine3A {
        let scale = self.scale.map_or(1.0, |s| s.0);
        let r = self.rotate.map_or(Vec3::ZERO, |r| r.0);
        let rotation = Quat::from_rotation_z(r.z.to_radians())
            * Quat::from_rotation_y(r.y.to_radians())
            * Quat::from_rotation_x(r.x.to_radians());
        let translation = self.translate.map_or(Vec3::ZERO, |t| t.0);
        Affine3A::from_scale_rotation_translation(Vec3::splat(scale), rotation, translation)
    }
}
