//! The scene model: what a scene is, as plain data the bake, the path tracer and the tools
//! read: the OSLF objects, the environment geometry, lights, materials, the camera and the
//! bake settings.
//!
//! Reading a scene (TOML scene files with located errors, presets, glTF and OBJ includes) is
//! [`crate::scene_file`]'s work; this module knows nothing of file formats.
//!
//! Conventions: Z is up; lengths are in scene units; angles in degrees; colours are linear RGB.

use glam::{Affine3A, Vec2, Vec3};
use oslf_geometry::atlas::{Atlas, AtlasOptions, UvSource};
use oslf_geometry::Camera;
use std::hash::{Hash, Hasher};
use std::path::PathBuf;
use std::sync::{Arc, Mutex};

use crate::environment::Environment;
use crate::error::{BakeError, Result};
use crate::light::Light;
use crate::material::Material;
use crate::normals::NormalsUsed;
use crate::tolerance::TESSELLATION_ERROR;
use oslf_geometry::bezier::{self, BezierPatch};
use oslf_geometry::mesh::Mesh;

/// The smallest ε relative to an object's largest coordinate magnitude, 2⁻²⁰ (twice
/// [`crate::tolerance::SELF_TOLERANCE`]); see `check_epsilon`.
pub const MIN_EPSILON_RELATIVE: f32 = 2.0 * crate::tolerance::SELF_TOLERANCE;

/// The largest ε, relative to the diagonal of the object's bounding box. Bakes at 10× the
/// object's size still find points for every texel (bake/tests/extremes.rs); at 10³⁰ every
/// texel is empty, as f32 sample positions no longer resolve the object.
pub const MAX_EPSILON_RELATIVE: f32 = 100.0;

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
    /// A mesh object's normals: the file's or computed by which rule, and why (`None` for
    /// patches, whose normals are exact).
    pub normals: Option<NormalsUsed>,
    /// The object's own sample spacing (scene units), overriding the bake's density for it:
    /// a small object beside a large one gets points of its own scale.
    pub sample_spacing: Option<f32>,
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
    /// What the shape is, for messages: `[[box]] 2` (the third box of the scene file),
    /// `[[mesh]] "table.obj"`, `room.glb: nodes[3] "Table": meshes[1] "Top" primitive 0`.
    pub name: String,
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
    /// How the points are spread: evenly, or denser where the surroundings are near.
    pub placement: PointPlacement,
    /// What becomes of a point that ε brings near another surface: removed (the thesis's
    /// §3.3), or lowered towards its own.
    pub near_surface: NearSurface,
    /// Horizon tolerance of Eq. 3.10, degrees.
    pub phi_samplemap_deg: f32,
    pub cube_resolution: u32,
    pub sample_map_resolution: u32,
    /// Rays per cube-map texel (rounded up to a square number of strata); with a
    /// `target_noise`, the most a texel takes.
    pub samples_per_texel: u32,
    /// Adaptive sampling: each cube texel takes rounds of 4 stratified samples until the
    /// relative standard error of its mean is at most this (0: off, every texel takes
    /// `samples_per_texel`).
    pub target_noise: f32,
    /// Denoise each captured cube map before it is stored (`oslf_trace::denoise`): its texels
    /// averaged with the neighbours on the same surface whose difference the noise explains.
    pub denoise: bool,
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
    /// What captures the cube maps (not part of the store: CPU and GPU captures of a scene
    /// differ only by rounding, so either may resume the other's bake).
    pub device: DeviceChoice,
}

/// The preset `oslf bake` applies by itself when the cube maps are captured on a GPU and no
/// other preset is asked for: the settings a GPU makes affordable (more samples per texel,
/// say), where the scene file defines `[presets.gpu]`.
pub const GPU_PRESET: &str = "gpu";

/// Which device captures a bake's cube maps (`[bake] device`, `oslf bake --device`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum DeviceChoice {
    /// The GPU on a hardware adapter, else the CPU (on a CPU adapter such as lavapipe the CPU
    /// path tracer is the faster of the two).
    #[default]
    Auto,
    Cpu,
    Gpu,
}

impl std::str::FromStr for DeviceChoice {
    type Err = String;
    fn from_str(s: &str) -> std::result::Result<Self, String> {
        match s {
            "auto" => Ok(DeviceChoice::Auto),
            "cpu" => Ok(DeviceChoice::Cpu),
            "gpu" => Ok(DeviceChoice::Gpu),
            _ => Err(format!(
                "unknown device {s:?} (expected \"auto\", \"cpu\" or \"gpu\")"
            )),
        }
    }
}

impl std::fmt::Display for DeviceChoice {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            DeviceChoice::Auto => "auto",
            DeviceChoice::Cpu => "cpu",
            DeviceChoice::Gpu => "gpu",
        })
    }
}

/// One bake setting chosen from the scene ([`crate::bake_defaults`]): its key, the object it is for (`None`: the whole
/// bake), its value as printed and why, in the scene's units with the digits the object's
/// size needs.
#[derive(Clone, Debug, PartialEq)]
pub struct BakeChoice {
    pub key: &'static str,
    pub object: Option<String>,
    pub value: String,
    pub why: String,
}

impl std::fmt::Display for BakeChoice {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match &self.object {
            Some(o) => write!(
                f,
                "object {o:?}: {} = {}: {}",
                self.key, self.value, self.why
            ),
            None => write!(f, "{} = {}: {}", self.key, self.value, self.why),
        }
    }
}

/// How the sample points are spread over the surfaces.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum PointPlacement {
    /// Evenly by area (the thesis's; the default where the file gives a density).
    #[default]
    Uniform,
    /// Denser where the surroundings are near: a reflection's parallax between two points
    /// grows as their spacing over the distance to what they see, so the spacing follows that
    /// distance (the harmonic mean over a hemisphere of probe rays), within 0.5 to 2 times the
    /// typical spacing; the count is the same.
    Parallax,
    /// Denser where neighbouring points predict each other's view worst: pilot cube maps
    /// captured at a coarse set of points, each predicted from its nearest neighbours' cubes
    /// through their distances (leave one out), and the spacing following that error (its
    /// inverse square root), within 0.5 to 2 times the typical spacing; the count is the same.
    Adaptive,
}

impl std::str::FromStr for PointPlacement {
    type Err = String;
    fn from_str(s: &str) -> std::result::Result<Self, String> {
        match s {
            "uniform" => Ok(PointPlacement::Uniform),
            "parallax" => Ok(PointPlacement::Parallax),
            "adaptive" => Ok(PointPlacement::Adaptive),
            _ => Err(format!(
                "unknown placement {s:?} (expected \"uniform\", \"parallax\" or \"adaptive\")"
            )),
        }
    }
}

/// What becomes of a sample point near a surface other than its object's own (`[bake]
/// near_surface`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum NearSurface {
    /// Removed where a surface lies within ε (the thesis's free-space test, §3.3; the default
    /// where the file sets `epsilon`).
    #[default]
    Remove,
    /// Lowered towards its own surface, by halves down to ε/8, until every other surface it
    /// faces lies at least three times its height away (removed only where even ε/8 fails):
    /// near a contact, such as a can on a table, the points that ε would remove or leave too
    /// high stay, at a height the gap allows.
    Lower,
}

impl std::str::FromStr for NearSurface {
    type Err = String;
    fn from_str(s: &str) -> std::result::Result<Self, String> {
        match s {
            "remove" => Ok(NearSurface::Remove),
            "lower" => Ok(NearSurface::Lower),
            _ => Err(format!(
                "unknown near_surface {s:?} (expected \"remove\" or \"lower\")"
            )),
        }
    }
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
    /// Every file the scene was read from: the scene file, then each file it includes, in
    /// reading order (what a command that reads the scene declares as its inputs).
    pub files: Vec<PathBuf>,
    pub camera: Option<Camera>,
    pub environment: Environment,
    pub lights: Vec<Light>,
    pub materials: Vec<Material>,
    pub objects: Vec<OslfObject>,
    pub shapes: Vec<Shape>,
    pub bake: BakeSettings,
    /// The bake settings the scene file leaves unset, as chosen from the scene, and why
    /// ([`crate::bake_defaults`]): empty where the file sets them all.
    pub bake_choices: Vec<BakeChoice>,
    /// Name of the preset applied, if any.
    pub preset: Option<String>,
    /// Names of the presets the scene file defines (`[presets.NAME]`), sorted.
    pub presets: Vec<String>,
    /// What the scene asks for that the bake cannot do and ignores (unsupported glTF
    /// features, each naming the file and the node, mesh or material). Tools print them.
    pub warnings: Vec<String>,
}

/// A triangle-mesh OSLF object as the scene gives it.
#[derive(Clone, Debug)]
pub struct MeshSource {
    /// World space. `uvs` are the material's texture coordinates (for the object's own
    /// appearance in the scene), not the atlas.
    pub mesh: Mesh,
    /// Candidate atlas uv sets, most preferred first: the lightmap set (glTF `TEXCOORD_1`),
    /// then the texture set (`TEXCOORD_0`, OBJ `vt`). Unusable sets are skipped by the atlas.
    pub uv_sets: Vec<(UvSource, Vec<Vec2>)>,
    /// The last atlas built from this source (see [`MeshSource::atlas`]).
    built: AtlasMemo,
}

/// The last atlas built from a mesh source, with what it was built from: the preflight's atlas
/// is the bake's, built once.
#[derive(Clone, Debug, Default)]
struct AtlasMemo(Arc<Mutex<Option<KeyedAtlas>>>);

/// An atlas and the hash of what it was built from.
type KeyedAtlas = (u64, Arc<Atlas>);

impl MeshSource {
    /// A mesh object's source: world-space mesh and candidate atlas uv sets.
    pub fn new(mesh: Mesh, uv_sets: Vec<(UvSource, Vec<Vec2>)>) -> MeshSource {
        MeshSource {
            mesh,
            uv_sets,
            built: AtlasMemo::default(),
        }
    }

    /// The atlas of this mesh at `options` ([`Atlas::build`] over the uv sets in order). The
    /// last one built is kept, keyed by a hash of the mesh, the uv sets and the options, so the
    /// preflight and the bake build it once between them, and a changed mesh is rebuilt.
    pub fn atlas(&self, options: &AtlasOptions) -> oslf_geometry::Result<Arc<Atlas>> {
        let key = self.atlas_key(options);
        let mut memo = self
            .built
            .0
            .lock()
            .unwrap_or_else(|poisoned| poisoned.into_inner());
        if let Some((k, atlas)) = memo.as_ref() {
            if *k == key {
                return Ok(Arc::clone(atlas));
            }
        }
        let sets: Vec<(UvSource, &[Vec2])> = self
            .uv_sets
            .iter()
            .map(|(s, uv)| (*s, uv.as_slice()))
            .collect();
        let atlas = Arc::new(Atlas::build(&self.mesh, &sets, options)?);
        *memo = Some((key, Arc::clone(&atlas)));
        Ok(atlas)
    }

    /// What an atlas is built from, hashed: every position, normal, triangle and uv bit, and
    /// the options.
    fn atlas_key(&self, options: &AtlasOptions) -> u64 {
        let mut h = std::collections::hash_map::DefaultHasher::new();
        let floats = |h: &mut std::collections::hash_map::DefaultHasher, v: &[f32]| {
            v.iter().for_each(|f| f.to_bits().hash(h));
        };
        for p in self.mesh.positions.iter().chain(&self.mesh.normals) {
            floats(&mut h, &p.to_array());
        }
        self.mesh.triangles.hash(&mut h);
        for (source, uvs) in &self.uv_sets {
            source.hash(&mut h);
            uvs.iter().for_each(|uv| floats(&mut h, &uv.to_array()));
        }
        options.page_resolution.hash(&mut h);
        options.texel_size.to_bits().hash(&mut h);
        options.max_grid.hash(&mut h);
        h.finish()
    }
}

/// Why the bake cannot honour `epsilon` for `object`, if it cannot. ε must be at most
/// [`MAX_EPSILON_RELATIVE`] × the diagonal of the object's bounding box, and at least two
/// limits, both reported with the smallest ε that works:
/// - f32: a sample point must lie at least [`MIN_EPSILON_RELATIVE`] × the object's largest
///   coordinate magnitude above its surface, twice the ray–triangle test's self-intersection
///   tolerance ([`crate::tolerance::SELF_TOLERANCE`]); below it, rays from a sample point pass
///   through the surface under it. (10⁵ units from the origin: ε ≥ 0.095.)
/// - tessellation: the ray-traced triangles must follow the patches within ε/50
///   ([`TESSELLATION_ERROR`]), which the finest grid ([`bezier::MAX_TESSELLATION_LEVEL`]²
///   quads per patch) must reach. (The Newell teapot at scale 1: ε ≥ 3.2·10⁻³.)
pub fn epsilon_problem(epsilon: f32, object: &OslfObject) -> Option<String> {
    let (lo, hi) = object
        .points()
        .fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), c| {
            (lo.min(c), hi.max(c))
        });
    let size = (hi - lo).length();
    let max_epsilon = MAX_EPSILON_RELATIVE * size;
    if size.is_finite() && epsilon > max_epsilon {
        return Some(format!(
            "epsilon = {epsilon} is too large for object {:?}: it is more than {MAX_EPSILON_RELATIVE} \
             times the diagonal of its bounding box ({size:.4e}), so far out that f32 \
             positions lose the object's shape; use epsilon <= {max_epsilon:.4e} (typically \
             a hundredth of the object's size)",
            object.name
        ));
    }
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
    let tess_limit = worst / TESSELLATION_ERROR;
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
    /// Sets the bake's sample density and drops the spacings chosen for objects where the
    /// scene file left it unset ([`crate::bake_defaults`]), so that `density` holds for them
    /// (spacings the file gives an object are kept).
    pub fn set_sample_density(&mut self, density: SampleDensity) {
        self.bake.sample_count = density;
        let chosen: Vec<&str> = self
            .bake_choices
            .iter()
            .filter(|c| c.key == "sample_spacing")
            .filter_map(|c| c.object.as_deref())
            .collect();
        for object in &mut self.objects {
            if chosen.contains(&object.name.as_str()) {
                object.sample_spacing = None;
            }
        }
        self.bake_choices.retain(|c| c.key != "sample_spacing");
    }

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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_mesh_source_builds_its_atlas_once_and_again_when_the_mesh_changes() {
        let options = AtlasOptions {
            page_resolution: 32,
            texel_size: 0.1,
            max_grid: 4,
        };
        let mut source = MeshSource::new(Mesh::icosphere(1), Vec::new());
        let first = source.atlas(&options).unwrap();
        assert!(Arc::ptr_eq(&first, &source.atlas(&options).unwrap()));
        // Other options, or a moved vertex: built anew.
        let finer = AtlasOptions {
            texel_size: 0.05,
            ..options
        };
        assert!(!Arc::ptr_eq(&first, &source.atlas(&finer).unwrap()));
        source.mesh.positions[0] *= 1.5;
        let moved = source.atlas(&options).unwrap();
        assert!(!Arc::ptr_eq(&first, &moved));
        assert_ne!(first.mesh.positions[0], moved.mesh.positions[0]);
    }
}
