//! What a glTF file contributes to a scene, and how it is placed there.

use std::path::PathBuf;

use glam::{Affine3A, Vec2, Vec3};
use oslf_geometry::atlas::UvSource;
use oslf_geometry::Camera;

use crate::light::Light;
use crate::normals::{NormalRule, NormalsUsed};
use crate::scene::Shape;
use oslf_geometry::mesh::Mesh;

/// Watts per lumen at 555 nm, the peak of the photopic luminous efficiency: the default
/// conversion of glTF's photometric light units to the scene's radiometric ones.
pub const WATTS_PER_LUMEN: f32 = 1.0 / 683.0;

/// The extensions this importer understands; any other in `extensionsUsed` is warned about.
pub const SUPPORTED_EXTENSIONS: [&str; 3] = [
    "KHR_lights_punctual",
    "KHR_texture_transform",
    "KHR_materials_emissive_strength",
];

/// How a glTF file is placed into a scene.
#[derive(Clone, Debug, PartialEq)]
pub struct Options {
    /// glTF world space to scene space, applied after every node transform.
    pub transform: Affine3A,
    /// Converts light intensities: candela (lm/sr) to W/sr for point and spot lights, lux
    /// (lm/m²) to W/m² for directional lights. Default [`WATTS_PER_LUMEN`].
    pub watts_per_lumen: f32,
    /// Import the file's `KHR_lights_punctual` lights.
    pub lights: bool,
    /// Names of nodes whose meshes are OSLF objects ([`Import::objects`]) rather than
    /// environment shapes. Each must name a node with a mesh.
    pub objects: Vec<String>,
    /// Also make OSLF objects of the nodes whose `extras` hold `"oslf": true` (how a `.glb`
    /// given as the whole scene names its objects).
    pub objects_from_extras: bool,
    /// How every primitive's normals are computed, replacing its `NORMAL`; `None`: the
    /// file's `NORMAL`, else flat normals (the glTF specification's rule).
    pub normals: Option<NormalRule>,
}

impl Default for Options {
    fn default() -> Self {
        Self {
            transform: Affine3A::IDENTITY,
            watts_per_lumen: WATTS_PER_LUMEN,
            lights: true,
            objects: Vec::new(),
            objects_from_extras: false,
            normals: None,
        }
    }
}

/// A perspective camera of a glTF file, placed in scene space.
#[derive(Clone, Debug, PartialEq)]
pub struct GltfCamera {
    /// The node's name (`nodes[i]` where it has none).
    pub node: String,
    /// The camera's own name, if it has one.
    pub name: Option<String>,
    pub camera: Camera,
    /// The aspect ratio the file gives (width / height), if any; renders take their size from
    /// the command line, so this is informational.
    pub aspect_ratio: Option<f32>,
}

/// A node chosen as an OSLF object ([`Options::objects`]).
#[derive(Clone, Debug)]
pub struct ImportedObject {
    /// The node's name.
    pub node: String,
    /// The node's mesh (all primitives) in scene space; `uvs` are the base-colour texture's.
    pub mesh: Mesh,
    /// Raw `TEXCOORD_1` (lightmap) and `TEXCOORD_0`, where every primitive has the set.
    pub uv_sets: Vec<(UvSource, Vec<Vec2>)>,
    /// The first primitive's material (an index into the materials passed to [`crate::gltf::load`]).
    pub material: u32,
    /// Which normals the primitives got and why.
    pub normals: NormalsUsed,
}

/// What a glTF file contributes to a scene.
#[derive(Clone, Debug, Default)]
pub struct Import {
    /// Triangle meshes in scene space; `material` indexes the materials passed to [`crate::gltf::load`].
    pub shapes: Vec<Shape>,
    /// The nodes named in [`Options::objects`], in traversal order.
    pub objects: Vec<ImportedObject>,
    pub lights: Vec<Light>,
    /// Perspective cameras in the order of the scene traversal (depth first, children in
    /// file order).
    pub cameras: Vec<GltfCamera>,
    /// Unsupported features met, each naming the file and the node, mesh or material.
    pub warnings: Vec<String>,
    /// The external files the document refers to and that were read (buffers, images), in
    /// reading order: with the file itself, everything the import depends on.
    pub files: Vec<PathBuf>,
}

impl Import {
    /// Axis-aligned bounds of every shape, `None` without shapes.
    pub fn bounds(&self) -> Option<(Vec3, Vec3)> {
        self.shapes
            .iter()
            .filter(|s| !s.mesh.positions.is_empty())
            .map(|s| s.mesh.bounds())
            .reduce(|(a, b), (c, d)| (a.min(c), b.max(d)))
    }
}
