//! glTF 2.0 scenes: `.gltf` (JSON with external or data-URI buffers and images) and `.glb`
//! (binary) files read into what a scene file's shapes become: triangle meshes with Lambertian
//! materials, point, spot and directional lights, and perspective cameras.
//!
//! The JSON document is parsed and validated by the `gltf` crate (which names the JSON path of
//! what is wrong); the GLB container, buffers, accessors and images are read here, every
//! offset, length, index and value checked, so that a damaged file gives an error naming the
//! file and the JSON path or accessor index, and never a panic.
//!
//! What is read:
//! - the default scene (else the first; else every root node), its node hierarchy with TRS or
//!   matrix transforms, composed with the include's own transform ([`Options::transform`]);
//! - triangle primitives (`TRIANGLES`, and `TRIANGLE_STRIP` / `TRIANGLE_FAN` converted to
//!   lists), indexed or not: `POSITION`, `NORMAL` (flat normals where absent), the
//!   `TEXCOORD_n` set the material's base-colour texture uses;
//! - materials: `baseColorFactor` and `baseColorTexture` (sRGB decoded to linear), with
//!   `KHR_texture_transform` and the sampler's wrap modes, as a Lambertian albedo;
//! - `KHR_lights_punctual` point, spot and directional lights, photometric units converted
//!   with [`Options::watts_per_lumen`];
//! - perspective cameras.
//!
//! Everything else the file uses (skins, morph targets, animations, emission, metallic-roughness,
//! normal and occlusion maps, alpha, vertex colours, other extensions, orthographic cameras,
//! points and lines, light ranges) is reported in [`Import::warnings`], naming the node,
//! mesh or material, and otherwise ignored.
//!
//! Conventions: glTF is Y-up, right-handed, in metres; nothing here converts axes or units:
//! the include's transform does (`rotate = [90, 0, 0]` turns glTF's +Y into the scene's +Z).
//! glTF's texture coordinate origin is the image's top-left corner; the crate's textures put
//! `v = 0` at the bottom ([`crate::texture`]), so `v` is flipped on import.

use std::borrow::Cow;
use std::collections::{HashMap, HashSet};
use std::path::{Path, PathBuf};
use std::sync::Arc;

use glam::{Affine3A, Mat4, Quat, Vec2, Vec3};
use gltf::accessor::{DataType, Dimensions};
use gltf::json::validation::Validate;
use gltf::mesh::Mode;
use gltf::texture::WrappingMode;
use gltf::Semantic;

use oslf_geometry::atlas::UvSource;

use crate::light::Light;
use crate::material::Material;
use crate::mesh::Mesh;
use crate::scene::Shape;
use crate::texture::{srgb_to_linear, ImageTexture, Texture};
use crate::{BakeError, Result};
use oslf_geometry::Camera;

/// Watts per lumen at 555 nm, the peak of the photopic luminous efficiency: the default
/// conversion of glTF's photometric light units to the scene's radiometric ones.
pub const WATTS_PER_LUMEN: f32 = 1.0 / 683.0;

/// The extensions this importer understands; any other in `extensionsUsed` is warned about.
pub const SUPPORTED_EXTENSIONS: [&str; 2] = ["KHR_lights_punctual", "KHR_texture_transform"];

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
}

/// Whether a node's `extras` hold `"oslf": true`.
fn marked_oslf(node: &gltf::Node) -> bool {
    node.extras().as_ref().is_some_and(|raw| {
        serde_json::from_str::<serde_json::Value>(raw.get())
            .is_ok_and(|v| v.get("oslf") == Some(&serde_json::Value::Bool(true)))
    })
}

impl Default for Options {
    fn default() -> Self {
        Self {
            transform: Affine3A::IDENTITY,
            watts_per_lumen: WATTS_PER_LUMEN,
            lights: true,
            objects: Vec::new(),
            objects_from_extras: false,
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
    /// The first primitive's material (an index into the materials passed to [`load`]).
    pub material: u32,
}

/// What a glTF file contributes to a scene.
#[derive(Clone, Debug, Default)]
pub struct Import {
    /// Triangle meshes in scene space; `material` indexes the materials passed to [`load`].
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

/// Reads a `.gltf` or `.glb` file (recognised by content: GLB starts with `glTF`). New
/// materials are appended to `materials`; the shapes index into it.
pub fn load(path: &Path, options: &Options, materials: &mut Vec<Material>) -> Result<Import> {
    let bytes = std::fs::read(path).map_err(|source| BakeError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    // The checks below are meant to leave the crate nothing to panic on; should one slip
    // through, it is still an error naming the file, not a crash.
    let outcome = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        load_bytes(path, &bytes, options, materials)
    }));
    match outcome {
        Ok(result) => result,
        Err(_) => Err(error(
            path,
            "glTF",
            "the file could not be read (the glTF parser failed on it)",
        )),
    }
}

fn error(path: &Path, at: impl Into<String>, message: impl Into<String>) -> BakeError {
    BakeError::Gltf {
        path: path.to_path_buf(),
        at: at.into(),
        message: message.into(),
    }
}

const GLB_MAGIC: &[u8; 4] = b"glTF";
const CHUNK_JSON: u32 = 0x4E4F_534A;
const CHUNK_BIN: u32 = 0x004E_4942;

fn le_u32(b: &[u8], at: usize) -> Option<u32> {
    let s = b.get(at..at.checked_add(4)?)?;
    Some(u32::from_le_bytes([s[0], s[1], s[2], s[3]]))
}

/// Splits a GLB container into its JSON chunk and its BIN chunk (if any).
fn split_glb<'b>(path: &Path, bytes: &'b [u8]) -> Result<(&'b [u8], Option<&'b [u8]>)> {
    let bad = |message: String| error(path, "GLB header", message);
    let version = le_u32(bytes, 4).ok_or_else(|| bad("the file ends inside the header".into()))?;
    if version != 2 {
        return Err(bad(format!("version {version}; only glTF 2 is supported")));
    }
    let length =
        le_u32(bytes, 8).ok_or_else(|| bad("the file ends inside the header".into()))? as usize;
    if length > bytes.len() || length < 12 {
        return Err(bad(format!(
            "the header gives a length of {length} bytes, the file has {}",
            bytes.len()
        )));
    }
    let bytes = &bytes[..length];
    let mut offset = 12;
    let mut json = None;
    let mut bin = None;
    let mut chunk = 0;
    while offset + 8 <= length {
        let at = format!("GLB chunk {chunk}");
        let chunk_length = le_u32(bytes, offset).unwrap_or(0) as usize;
        let kind = le_u32(bytes, offset + 4).unwrap_or(0);
        let start = offset + 8;
        let end = start
            .checked_add(chunk_length)
            .filter(|&e| e <= length)
            .ok_or_else(|| {
                error(
                    path,
                    at.clone(),
                    format!(
                        "{chunk_length} bytes from byte {start} run past the end of the file ({length} bytes)"
                    ),
                )
            })?;
        let data = &bytes[start..end];
        match (chunk, kind) {
            (0, CHUNK_JSON) => json = Some(data),
            (0, _) => {
                return Err(error(
                    path,
                    at,
                    format!("the first chunk must be JSON (type 0x4E4F534A), not 0x{kind:08X}"),
                ))
            }
            (1, CHUNK_BIN) => bin = Some(data),
            _ => {} // other chunks: ignored, as the specification says
        }
        offset = end.next_multiple_of(4);
        chunk += 1;
    }
    let json = json.ok_or_else(|| bad("the file has no JSON chunk".into()))?;
    Ok((json, bin))
}

fn load_bytes(
    path: &Path,
    bytes: &[u8],
    options: &Options,
    materials: &mut Vec<Material>,
) -> Result<Import> {
    let (json, bin) = if bytes.starts_with(GLB_MAGIC) {
        split_glb(path, bytes)?
    } else {
        (bytes, None)
    };
    let root: gltf::json::Root = gltf::json::deserialize::from_slice(json)
        .map_err(|e| error(path, "JSON", format!("not a glTF document: {e}")))?;
    // gltf-json's validation indexes the accessor a POSITION attribute names without checking
    // it first: check it here.
    for (m, mesh) in root.meshes.iter().enumerate() {
        for (p, prim) in mesh.primitives.iter().enumerate() {
            for (semantic, index) in &prim.attributes {
                if index.value() >= root.accessors.len() {
                    let name = match semantic {
                        gltf::json::validation::Checked::Valid(s) => s.to_string(),
                        gltf::json::validation::Checked::Invalid => "?".into(),
                    };
                    return Err(error(
                        path,
                        format!("meshes[{m}].primitives[{p}].attributes.{name}"),
                        format!(
                            "accessor {} does not exist (the file has {} accessors)",
                            index.value(),
                            root.accessors.len()
                        ),
                    ));
                }
            }
        }
    }
    // `Camera::projection` unwraps the projection its type names; validation only asks for one.
    for (i, camera) in root.cameras.iter().enumerate() {
        use gltf::json::camera::Type;
        use gltf::json::validation::Checked;
        let (missing, key) = match camera.type_ {
            Checked::Valid(Type::Perspective) => (camera.perspective.is_none(), "perspective"),
            Checked::Valid(Type::Orthographic) => (camera.orthographic.is_none(), "orthographic"),
            Checked::Invalid => (false, ""),
        };
        if missing {
            return Err(error(
                path,
                format!("cameras[{i}].{key}"),
                format!("is missing, but the camera's type is {key}"),
            ));
        }
    }
    let mut problems: Vec<(String, String)> = Vec::new();
    root.validate(&root, gltf::json::Path::new, &mut |at, e| {
        problems.push((at().to_string(), e.to_string()))
    });
    if let Some((at, what)) = problems.first() {
        let more = match problems.len() {
            1 => String::new(),
            n => format!(" (and {} more problems)", n - 1),
        };
        let what = match what.as_str() {
            "Index out of bounds" => {
                "refers to something the file does not have (index out of range)"
            }
            "Missing data" => "is required but missing",
            "Unsupported extension" => {
                "names an extension this importer does not support, which the file requires"
            }
            "Invalid value" => "has an invalid value",
            other => other,
        };
        return Err(error(
            path,
            at.replace("[\"", ".").replace("\"]", ""),
            format!("{what}{more}"),
        ));
    }
    if !root.asset.version.starts_with("2.") {
        return Err(error(
            path,
            "asset.version",
            format!("{:?}: only glTF 2.x is supported", root.asset.version),
        ));
    }
    let doc = gltf::Document::from_json_without_validation(root);
    let mut loader = Loader {
        path,
        dir: path
            .parent()
            .unwrap_or_else(|| Path::new("."))
            .to_path_buf(),
        doc: &doc,
        buffers: Vec::new(),
        images: HashMap::new(),
        materials: HashMap::new(),
        warnings: Vec::new(),
        file: path.file_name().map_or_else(
            || path.display().to_string(),
            |n| n.to_string_lossy().into_owned(),
        ),
        files: Default::default(),
    };
    loader.load_buffers(bin)?;
    loader.check_views()?;
    loader.warn_document();
    let mut import = Import::default();
    loader.traverse(options, materials, &mut import)?;
    for name in &options.objects {
        if !import.objects.iter().any(|o| &o.node == name) {
            return Err(error(
                path,
                "nodes",
                format!("objects names {name:?}, but no node of the scene with that name has a triangle mesh"),
            ));
        }
    }
    import.warnings = std::mem::take(&mut loader.warnings);
    import.files = loader.files.take();
    Ok(import)
}

struct Loader<'d> {
    path: &'d Path,
    dir: PathBuf,
    doc: &'d gltf::Document,
    buffers: Vec<Cow<'d, [u8]>>,
    /// Decoded images (linear RGB), by image index.
    images: HashMap<usize, Arc<ImageTexture>>,
    /// Scene material index, by (glTF material index, texture coordinate set).
    materials: HashMap<(Option<usize>, u32), u32>,
    warnings: Vec<String>,
    /// The file's name, for warnings.
    file: String,
    /// External files read (buffers, images), in reading order.
    files: std::cell::RefCell<Vec<PathBuf>>,
}

/// `nodes[3] "Arm"` or `nodes[3]`.
fn label(kind: &str, index: usize, name: Option<&str>) -> String {
    match name {
        Some(n) => format!("{kind}[{index}] {n:?}"),
        None => format!("{kind}[{index}]"),
    }
}

fn material_label(m: &gltf::Material) -> String {
    match m.index() {
        Some(i) => label("materials", i, m.name()),
        None => "the default material".into(),
    }
}

impl<'d> Loader<'d> {
    fn err(&self, at: impl Into<String>, message: impl Into<String>) -> BakeError {
        error(self.path, at, message)
    }

    fn warn(&mut self, what: impl AsRef<str>) {
        self.warnings
            .push(format!("{}: {}", self.file, what.as_ref()));
    }

    // --- buffers and views ---------------------------------------------------------------

    fn load_buffers(&mut self, bin: Option<&'d [u8]>) -> Result<()> {
        for buffer in self.doc.buffers() {
            let i = buffer.index();
            let data: Cow<'d, [u8]> = match buffer.source() {
                gltf::buffer::Source::Bin => match bin {
                    Some(b) => Cow::Borrowed(b),
                    None => return Err(self.err(
                        format!("buffers[{i}]"),
                        "has no uri, so it is the GLB's BIN chunk, which the file does not have",
                    )),
                },
                gltf::buffer::Source::Uri(uri) => {
                    Cow::Owned(self.read_uri(uri, &format!("buffers[{i}].uri"))?)
                }
            };
            if data.len() < buffer.length() {
                return Err(self.err(
                    format!("buffers[{i}]"),
                    format!(
                        "byteLength is {} but the data has only {} bytes",
                        buffer.length(),
                        data.len()
                    ),
                ));
            }
            self.buffers.push(data);
        }
        Ok(())
    }

    /// The bytes of a data URI or of a file relative to the glTF file.
    fn read_uri(&self, uri: &str, at: &str) -> Result<Vec<u8>> {
        if let Some(rest) = uri.strip_prefix("data:") {
            let Some((_, data)) = rest.split_once(";base64,") else {
                return Err(self.err(at, "a data URI must be base64-encoded (\";base64,\")"));
            };
            return base64_decode(data)
                .ok_or_else(|| self.err(at, "the data URI is not valid base64"));
        }
        if uri.contains("://") {
            return Err(self.err(
                at,
                format!("{uri:?}: only relative file references and data URIs are supported"),
            ));
        }
        let relative = percent_decode(uri)
            .ok_or_else(|| self.err(at, format!("{uri:?} is not a valid percent-encoded URI")))?;
        let file = self.dir.join(relative);
        let bytes = std::fs::read(&file)
            .map_err(|e| self.err(at, format!("cannot read {}: {e}", file.display())))?;
        self.files.borrow_mut().push(file);
        Ok(bytes)
    }

    /// Every buffer view within its buffer.
    fn check_views(&self) -> Result<()> {
        for view in self.doc.views() {
            let buffer = view.buffer();
            let end = view.offset().checked_add(view.length());
            if end.is_none_or(|e| e > buffer.length()) {
                return Err(self.err(
                    format!("bufferViews[{}]", view.index()),
                    format!(
                        "bytes {}..{} lie outside buffer {}, which has {} bytes",
                        view.offset(),
                        view.offset().saturating_add(view.length()),
                        buffer.index(),
                        buffer.length()
                    ),
                ));
            }
            if let Some(stride) = view.stride() {
                if !(4..=252).contains(&stride) || stride % 4 != 0 {
                    return Err(self.err(
                        format!("bufferViews[{}].byteStride", view.index()),
                        format!("{stride} must be a multiple of 4 in 4..=252"),
                    ));
                }
            }
        }
        Ok(())
    }

    fn view_bytes(&self, view: &gltf::buffer::View) -> &[u8] {
        // Checked by `check_views`.
        &self.buffers[view.buffer().index()][view.offset()..view.offset() + view.length()]
    }

    // --- accessors -----------------------------------------------------------------------

    /// The accessor's elements as `f32`, `count × components` values, normalized integers
    /// mapped to [0, 1] or [-1, 1]. `allowed` lists the component types accepted (`true`:
    /// normalized); `expected` describes them for the error.
    fn read_floats(
        &self,
        accessor: &gltf::Accessor,
        at: &str,
        dims: Dimensions,
        allowed: &[(DataType, bool)],
        expected: &str,
    ) -> Result<Vec<f32>> {
        let ty = accessor.data_type();
        if accessor.dimensions() != dims
            || !allowed.contains(&(ty, accessor.normalized() || ty == DataType::F32))
        {
            return Err(self.err(
                at,
                format!(
                    "accessor {} has {} components of type {}{}, expected {expected}",
                    accessor.index(),
                    accessor.dimensions().multiplicity(),
                    type_name(ty),
                    if accessor.normalized() {
                        " (normalized)"
                    } else {
                        ""
                    }
                ),
            ));
        }
        let raw = self.read_raw(accessor, at)?;
        Ok(raw
            .into_iter()
            .map(|v| match (ty, accessor.normalized()) {
                (DataType::F32, _) => f32::from_bits(v as u32),
                (DataType::U8, true) => v as f32 / 255.0,
                (DataType::U16, true) => v as f32 / 65535.0,
                (DataType::I8, true) => (v as i8 as f32 / 127.0).max(-1.0),
                (DataType::I16, true) => (v as i16 as f32 / 32767.0).max(-1.0),
                (DataType::I8, false) => v as i8 as f32,
                (DataType::I16, false) => v as i16 as f32,
                _ => v as f32,
            })
            .collect())
    }

    /// Vertex indices: unsigned scalars.
    fn read_indices(&self, accessor: &gltf::Accessor, at: &str) -> Result<Vec<u32>> {
        let ty = accessor.data_type();
        if accessor.dimensions() != Dimensions::Scalar
            || !matches!(ty, DataType::U8 | DataType::U16 | DataType::U32)
            || accessor.normalized()
        {
            return Err(self.err(
                at,
                format!(
                    "accessor {} has {} components of type {}, expected scalar u8, u16 or u32",
                    accessor.index(),
                    accessor.dimensions().multiplicity(),
                    type_name(ty)
                ),
            ));
        }
        Ok(self
            .read_raw(accessor, at)?
            .into_iter()
            .map(|v| v as u32)
            .collect())
    }

    /// Every component of every element as raw little-endian bits (zero-extended), the sparse
    /// substitution applied. Checks that every byte read lies within its buffer view.
    fn read_raw(&self, accessor: &gltf::Accessor, at: &str) -> Result<Vec<u64>> {
        let index = accessor.index();
        let components = accessor.dimensions().multiplicity();
        let size = accessor.data_type().size();
        let element = components * size;
        let count = accessor.count();
        let read = |bytes: &[u8], offset: usize| -> u64 {
            let mut v = [0u8; 8];
            v[..size].copy_from_slice(&bytes[offset..offset + size]);
            u64::from_le_bytes(v)
        };
        // The elements' bytes, checked before anything is allocated: then the count is
        // bounded by the file's size.
        let source = match accessor.view() {
            None => {
                // Zeros (then the sparse values): nothing in the file bounds the count.
                const MAX_ELEMENTS: usize = 1 << 24;
                if count > MAX_ELEMENTS {
                    return Err(self.err(
                        at,
                        format!("accessor {index}: {count} elements without a bufferView is more than the {MAX_ELEMENTS} supported"),
                    ));
                }
                None
            }
            Some(view) => {
                let stride = view.stride().unwrap_or(element);
                if stride < element {
                    return Err(self.err(
                        at,
                        format!(
                            "accessor {index}: bufferView {} has a byteStride of {stride}, less than the element's {element} bytes",
                            view.index()
                        ),
                    ));
                }
                let bytes = self.view_bytes(&view);
                let end = if count == 0 {
                    Some(0)
                } else {
                    (count - 1)
                        .checked_mul(stride)
                        .and_then(|e| e.checked_add(element))
                        .and_then(|e| e.checked_add(accessor.offset()))
                };
                if end.is_none_or(|e| e > bytes.len()) {
                    return Err(self.err(
                        at,
                        format!(
                            "accessor {index} ({count} elements of {element} bytes, stride {stride}, from byte {}) runs past the end of bufferView {}, which has {} bytes",
                            accessor.offset(),
                            view.index(),
                            bytes.len()
                        ),
                    ));
                }
                Some((bytes, stride))
            }
        };
        let mut out = vec![0u64; count * components];
        if let Some((bytes, stride)) = source {
            for e in 0..count {
                let base = accessor.offset() + e * stride;
                for c in 0..components {
                    out[e * components + c] = read(bytes, base + c * size);
                }
            }
        }
        if let Some(sparse) = accessor.sparse() {
            let n = sparse.count();
            let indices = sparse.indices();
            let values = sparse.values();
            let isize = match indices.index_type() {
                gltf::accessor::sparse::IndexType::U8 => 1,
                gltf::accessor::sparse::IndexType::U16 => 2,
                gltf::accessor::sparse::IndexType::U32 => 4,
            };
            let ibytes = self.view_bytes(&indices.view());
            let vbytes = self.view_bytes(&values.view());
            let fits = |bytes: &[u8], offset: usize, each: usize| {
                n.checked_mul(each)
                    .and_then(|l| l.checked_add(offset))
                    .is_some_and(|e| e <= bytes.len())
            };
            if !fits(ibytes, indices.offset(), isize) || !fits(vbytes, values.offset(), element) {
                return Err(self.err(
                    format!("accessors[{index}].sparse"),
                    format!("{n} sparse indices or values run past the end of their buffer view"),
                ));
            }
            for k in 0..n {
                let mut v = [0u8; 4];
                let o = indices.offset() + k * isize;
                v[..isize].copy_from_slice(&ibytes[o..o + isize]);
                let target = u32::from_le_bytes(v) as usize;
                if target >= count {
                    return Err(self.err(
                        format!("accessors[{index}].sparse.indices"),
                        format!("index {target} (entry {k}) is out of range: the accessor has {count} elements"),
                    ));
                }
                let base = values.offset() + k * element;
                for c in 0..components {
                    out[target * components + c] = read(vbytes, base + c * size);
                }
            }
        }
        Ok(out)
    }

    // --- document-level warnings ----------------------------------------------------------

    fn warn_document(&mut self) {
        let used: Vec<String> = self
            .doc
            .extensions_used()
            .filter(|e| !SUPPORTED_EXTENSIONS.contains(e))
            .map(str::to_string)
            .collect();
        for e in used {
            self.warn(format!(
                "extension {e} is not supported: what it adds is ignored"
            ));
        }
        let animations: Vec<String> = self
            .doc
            .animations()
            .map(|a| label("animations", a.index(), a.name()))
            .collect();
        if !animations.is_empty() {
            self.warn(format!(
                "animations are not supported: the scene is loaded at rest ({})",
                animations.join(", ")
            ));
        }
    }

    // --- the node hierarchy ---------------------------------------------------------------

    fn traverse(
        &mut self,
        options: &Options,
        materials: &mut Vec<Material>,
        import: &mut Import,
    ) -> Result<()> {
        let doc = self.doc;
        let scene = doc.default_scene().or_else(|| doc.scenes().next());
        let roots: Vec<gltf::Node> = match &scene {
            Some(s) => {
                if doc.scenes().len() > 1 {
                    self.warn(format!(
                        "the file has {} scenes; only {} is loaded",
                        doc.scenes().len(),
                        label("scenes", s.index(), s.name())
                    ));
                }
                s.nodes().collect()
            }
            None => {
                let children: HashSet<usize> = doc
                    .nodes()
                    .flat_map(|n| n.children().map(|c| c.index()).collect::<Vec<_>>())
                    .collect();
                doc.nodes()
                    .filter(|n| !children.contains(&n.index()))
                    .collect()
            }
        };
        let mut seen = HashSet::new();
        let mut stack: Vec<(gltf::Node, Mat4)> = roots
            .into_iter()
            .rev()
            .map(|n| (n, Mat4::IDENTITY))
            .collect();
        while let Some((node, parent)) = stack.pop() {
            let at = label("nodes", node.index(), node.name());
            if !seen.insert(node.index()) {
                return Err(self.err(
                    format!("nodes[{}]", node.index()),
                    "the node is reached twice: the node hierarchy must be a set of trees",
                ));
            }
            let local = self.local_transform(&node)?;
            let global = parent * local;
            let world = Affine3A::from_mat4(global);
            let world = options.transform * world;
            if let Some(mesh) = node.mesh() {
                let object = node
                    .name()
                    .is_some_and(|n| options.objects.iter().any(|o| o == n))
                    || (options.objects_from_extras && marked_oslf(&node));
                self.node_mesh(&node, &at, &mesh, &world, object, materials, import)?;
            }
            if node.skin().is_some() {
                self.warn(format!(
                    "{at}: skins are not supported: the mesh is drawn unskinned"
                ));
            }
            if let Some(camera) = node.camera() {
                self.node_camera(&node, &at, &camera, &world, import);
            }
            if let Some(light) = node.light() {
                if options.lights {
                    let l = self.node_light(&at, &light, &world, options.watts_per_lumen)?;
                    import.lights.push(l);
                }
            }
            if let Some(ext) = node.extensions() {
                let names: Vec<String> = ext.keys().cloned().collect();
                for e in names {
                    self.warn(format!("{at}: extension {e} is not supported"));
                }
            }
            let children: Vec<gltf::Node> = node.children().collect();
            for child in children.into_iter().rev() {
                stack.push((child, global));
            }
        }
        Ok(())
    }

    fn local_transform(&self, node: &gltf::Node) -> Result<Mat4> {
        let i = node.index();
        let m = match node.transform() {
            gltf::scene::Transform::Matrix { matrix } => {
                let m = Mat4::from_cols_array_2d(&matrix);
                if !m.is_finite() {
                    return Err(self.err(format!("nodes[{i}].matrix"), "has a non-finite element"));
                }
                if m.row(3) != glam::Vec4::W {
                    return Err(self.err(
                        format!("nodes[{i}].matrix"),
                        format!(
                            "the last row is {}, not [0, 0, 0, 1]: a node matrix must be affine",
                            m.row(3)
                        ),
                    ));
                }
                m
            }
            gltf::scene::Transform::Decomposed {
                translation,
                rotation,
                scale,
            } => {
                let t = Vec3::from(translation);
                let s = Vec3::from(scale);
                let q = Quat::from_array(rotation);
                if !t.is_finite() {
                    return Err(self.err(format!("nodes[{i}].translation"), "is not finite"));
                }
                if !s.is_finite() {
                    return Err(self.err(format!("nodes[{i}].scale"), "is not finite"));
                }
                if !q.is_finite() || q.length_squared() < 1e-12 {
                    return Err(self.err(
                        format!("nodes[{i}].rotation"),
                        format!("{rotation:?} is not a unit quaternion"),
                    ));
                }
                Mat4::from_scale_rotation_translation(s, q.normalize(), t)
            }
        };
        Ok(m)
    }

    fn node_camera(
        &mut self,
        node: &gltf::Node,
        at: &str,
        camera: &gltf::Camera,
        world: &Affine3A,
        import: &mut Import,
    ) {
        let cam = label("cameras", camera.index(), camera.name());
        let gltf::camera::Projection::Perspective(p) = camera.projection() else {
            self.warn(format!(
                "{at}: {cam} is orthographic, which is not supported: skipped"
            ));
            return;
        };
        let position = world.transform_point3(Vec3::ZERO);
        let forward = world.transform_vector3(Vec3::NEG_Z).try_normalize();
        let up = world.transform_vector3(Vec3::Y).try_normalize();
        let vfov_deg = p.yfov().to_degrees();
        let (Some(forward), Some(up)) = (forward, up) else {
            self.warn(format!(
                "{at}: {cam}: the node's transform is singular, so the camera has no view direction: skipped"
            ));
            return;
        };
        let c = Camera {
            position,
            target: position + forward,
            up,
            vfov_deg,
        };
        if !(vfov_deg > 0.0 && vfov_deg < 180.0) || c.validate().is_err() {
            self.warn(format!(
                "{at}: {cam}: yfov {} rad is not a usable field of view: skipped",
                p.yfov()
            ));
            return;
        }
        import.cameras.push(GltfCamera {
            node: node
                .name()
                .map_or_else(|| format!("nodes[{}]", node.index()), str::to_string),
            name: camera.name().map(str::to_string),
            camera: c,
            aspect_ratio: p.aspect_ratio(),
        });
    }

    fn node_light(
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

    // --- meshes ----------------------------------------------------------------------------

    /// Reads `node`'s mesh into `import.shapes`, or, when `object` is set, into one
    /// `import.objects` entry (its primitives merged, with their raw `TEXCOORD_1` and
    /// `TEXCOORD_0` as atlas candidates where every primitive has them).
    #[allow(clippy::too_many_arguments)]
    fn node_mesh(
        &mut self,
        node: &gltf::Node,
        at: &str,
        mesh: &gltf::Mesh,
        world: &Affine3A,
        object: bool,
        materials: &mut Vec<Material>,
        import: &mut Import,
    ) -> Result<()> {
        let mut merged: Option<ImportedObject> = None;
        let (mut lightmap, mut texture): (Option<Vec<Vec2>>, Option<Vec<Vec2>>) =
            (Some(Vec::new()), Some(Vec::new()));
        let mesh_label = label("meshes", mesh.index(), mesh.name());
        if node.weights().is_some() || mesh.weights().is_some() {
            self.warn(format!(
                "{at}: {mesh_label}: morph target weights are not supported: the base mesh is drawn"
            ));
        }
        if let Some(ext) = mesh.extensions() {
            let names: Vec<String> = ext.keys().cloned().collect();
            for e in names {
                self.warn(format!("{mesh_label}: extension {e} is not supported"));
            }
        }
        for prim in mesh.primitives() {
            let json_at = format!("meshes[{}].primitives[{}]", mesh.index(), prim.index());
            let what = format!("{mesh_label} primitive {}", prim.index());
            let triangles_from = match prim.mode() {
                Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan => prim.mode(),
                other => {
                    self.warn(format!(
                        "{what}: mode {other:?} is not supported (triangles only): skipped"
                    ));
                    continue;
                }
            };
            if prim.morph_targets().next().is_some() {
                self.warn(format!(
                    "{what}: morph targets are not supported: the base mesh is drawn"
                ));
            }
            for (semantic, _) in prim.attributes() {
                if let Semantic::Colors(n) = semantic {
                    self.warn(format!(
                        "{what}: vertex colours (COLOR_{n}) are not supported: ignored"
                    ));
                }
            }
            if let Some(ext) = prim.extensions() {
                let names: Vec<String> = ext.keys().cloned().collect();
                for e in names {
                    self.warn(format!("{what}: extension {e} is not supported"));
                }
            }
            let material = prim.material();
            let (material_index, uv_map) = self.material(&material, materials)?;
            let PrimitiveMesh {
                mesh: mut m,
                vertices,
                split,
            } = self.primitive_mesh(&prim, &json_at, &what, triangles_from, uv_map.as_ref())?;
            if m.triangles.is_empty() {
                continue;
            }
            m.transform(world);
            if let Some(i) = m.positions.iter().position(|p| !p.is_finite()) {
                return Err(self.err(
                    format!("{json_at}.attributes.POSITION"),
                    format!(
                        "vertex {i} is not finite once the node transforms of {at} are applied"
                    ),
                ));
            }
            if !object {
                import.shapes.push(Shape {
                    mesh: m,
                    material: material_index,
                });
                continue;
            }
            for (set, uvs) in [(1, &mut lightmap), (0, &mut texture)] {
                match (
                    self.texcoords(&prim, set, &json_at, vertices)?,
                    uvs.as_mut(),
                ) {
                    // Flat-shaded primitives were split per triangle corner: follow the split.
                    (Some(read), Some(all)) => match &split {
                        None => all.extend(read),
                        Some(source) => all.extend(source.iter().map(|&i| read[i as usize])),
                    },
                    _ => *uvs = None,
                }
            }
            match &mut merged {
                None => {
                    merged = Some(ImportedObject {
                        node: node.name().unwrap_or_default().to_string(),
                        mesh: m,
                        uv_sets: Vec::new(),
                        material: material_index,
                    })
                }
                Some(o) => {
                    if o.material != material_index {
                        self.warn(format!(
                            "{at}: an OSLF object has one material: {what} keeps the first primitive's"
                        ));
                    }
                    o.mesh.append(&m);
                }
            }
        }
        if let Some(mut o) = merged {
            o.uv_sets = [(UvSource::Lightmap, lightmap), (UvSource::Texture, texture)]
                .into_iter()
                .filter_map(|(s, uvs)| Some((s, uvs?)))
                .collect();
            import.objects.push(o);
        }
        Ok(())
    }

    /// The primitive's `TEXCOORD_{set}` as read (no texture transform), `None` if absent;
    /// `n` is its vertex count.
    fn texcoords(
        &mut self,
        prim: &gltf::Primitive,
        set: u32,
        json_at: &str,
        n: usize,
    ) -> Result<Option<Vec<Vec2>>> {
        let Some(acc) = prim.get(&Semantic::TexCoords(set)) else {
            return Ok(None);
        };
        let at = format!("{json_at}.attributes.TEXCOORD_{set}");
        let flat = self.read_floats(
            &acc,
            &at,
            Dimensions::Vec2,
            &[
                (DataType::F32, true),
                (DataType::U8, true),
                (DataType::U16, true),
            ],
            "vec2 of f32, normalized u8 or normalized u16",
        )?;
        if flat.len() != 2 * n {
            return Err(self.err(
                at,
                format!(
                    "accessor {} has {} elements, POSITION has {n}",
                    acc.index(),
                    flat.len() / 2
                ),
            ));
        }
        let uvs: Vec<Vec2> = flat.chunks_exact(2).map(Vec2::from_slice).collect();
        if let Some(i) = uvs.iter().position(|p| !p.is_finite()) {
            return Err(self.err(
                at,
                format!("accessor {}: element {i} is not finite", acc.index()),
            ));
        }
        Ok(Some(uvs))
    }

    fn primitive_mesh(
        &mut self,
        prim: &gltf::Primitive,
        json_at: &str,
        what: &str,
        mode: Mode,
        uv_map: Option<&UvMap>,
    ) -> Result<PrimitiveMesh> {
        let pos_at = format!("{json_at}.attributes.POSITION");
        let accessor = prim
            .get(&Semantic::Positions)
            .ok_or_else(|| self.err(&pos_at, "missing"))?;
        let flat = self.read_floats(
            &accessor,
            &pos_at,
            Dimensions::Vec3,
            &[(DataType::F32, true)],
            "f32 vec3",
        )?;
        let positions: Vec<Vec3> = flat.chunks_exact(3).map(Vec3::from_slice).collect();
        if let Some(i) = positions.iter().position(|p| !p.is_finite()) {
            return Err(self.err(
                pos_at,
                format!(
                    "accessor {}: vertex {i} is {} (not finite)",
                    accessor.index(),
                    positions[i]
                ),
            ));
        }
        let n = positions.len();
        let indices: Vec<u32> = match prim.indices() {
            Some(acc) => {
                let at = format!("{json_at}.indices");
                let idx = self.read_indices(&acc, &at)?;
                if let Some((e, v)) = idx.iter().enumerate().find(|(_, &v)| v as usize >= n) {
                    return Err(self.err(
                        at,
                        format!(
                            "accessor {}: index {v} (element {e}) is out of range: POSITION has {n} vertices",
                            acc.index()
                        ),
                    ));
                }
                idx
            }
            None => (0..n as u32).collect(),
        };
        let mut triangles: Vec<[u32; 3]> = Vec::new();
        match mode {
            Mode::TriangleStrip => {
                for i in 0..indices.len().saturating_sub(2) {
                    let t = if i % 2 == 0 {
                        [indices[i], indices[i + 1], indices[i + 2]]
                    } else {
                        [indices[i + 1], indices[i], indices[i + 2]]
                    };
                    triangles.push(t);
                }
            }
            Mode::TriangleFan => {
                for i in 1..indices.len().saturating_sub(1) {
                    triangles.push([indices[i], indices[i + 1], indices[0]]);
                }
            }
            _ => {
                if !indices.len().is_multiple_of(3) {
                    self.warn(format!(
                        "{what}: {} indices is not a multiple of 3: the last {} are ignored",
                        indices.len(),
                        indices.len() % 3
                    ));
                }
                triangles.extend(indices.chunks_exact(3).map(|t| [t[0], t[1], t[2]]));
            }
        }
        let uvs: Vec<Vec2> = match uv_map {
            None => vec![Vec2::ZERO; n],
            Some(map) => {
                let semantic = Semantic::TexCoords(map.set);
                match prim.get(&semantic) {
                    None => {
                        self.warn(format!(
                            "{what}: the material's texture uses TEXCOORD_{}, which the primitive does not have: the texture is read at uv (0, 0)",
                            map.set
                        ));
                        vec![map.apply(Vec2::ZERO); n]
                    }
                    Some(_) => {
                        let uvs = self
                            .texcoords(prim, map.set, json_at, n)?
                            .expect("the attribute is present");
                        if uvs.iter().any(|&uv| map.beyond_clamp(uv)) {
                            self.warn(format!(
                                "{what}: texture coordinates beyond [0, 1] along a CLAMP_TO_EDGE axis are not supported: the texture repeats there"
                            ));
                        }
                        uvs.into_iter().map(|uv| map.apply(uv)).collect()
                    }
                }
            }
        };
        let normals: Option<Vec<Vec3>> = match prim.get(&Semantic::Normals) {
            None => None,
            Some(acc) => {
                let at = format!("{json_at}.attributes.NORMAL");
                let flat = self.read_floats(
                    &acc,
                    &at,
                    Dimensions::Vec3,
                    &[(DataType::F32, true)],
                    "f32 vec3",
                )?;
                if flat.len() != 3 * n {
                    return Err(self.err(
                        at,
                        format!(
                            "accessor {} has {} elements, POSITION has {n}",
                            acc.index(),
                            flat.len() / 3
                        ),
                    ));
                }
                let normals: Vec<Vec3> = flat.chunks_exact(3).map(Vec3::from_slice).collect();
                if normals
                    .iter()
                    .all(|v| v.is_finite() && v.length_squared() > 0.0)
                {
                    Some(normals.into_iter().map(|v| v.normalize()).collect())
                } else {
                    self.warn(format!(
                        "{what}: some normals are zero or not finite: flat normals are used"
                    ));
                    None
                }
            }
        };
        let vertices = positions.len();
        let (mesh, split) = match normals {
            Some(normals) => (
                Mesh {
                    positions,
                    normals,
                    uvs,
                    triangles,
                },
                None,
            ),
            None => {
                let split = triangles.iter().flatten().copied().collect();
                (flat_shaded(&positions, &uvs, &triangles), Some(split))
            }
        };
        mesh.validate()
            .map_err(|e| self.err(json_at.to_string(), e.to_string()))?;
        Ok(PrimitiveMesh {
            mesh,
            vertices,
            split,
        })
    }

    // --- materials and textures -------------------------------------------------------------

    /// The scene material for a glTF material, and how the primitive's texture coordinates
    /// map into its texture (`None`: the material has no texture).
    fn material(
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
        materials.push(Material { albedo });
        let index = (materials.len() - 1) as u32;
        self.materials.insert(key, index);
        Ok((index, uv_map))
    }

    fn warn_material(&mut self, m: &gltf::Material, name: &str) {
        let pbr = m.pbr_metallic_roughness();
        let mut ignored = Vec::new();
        // The default material (no `material`) is metallic by the specification's defaults,
        // which no one asked for: no warning for it.
        let metallic = m.index().is_some() && pbr.metallic_factor() > 0.0;
        if metallic || pbr.metallic_roughness_texture().is_some() {
            ignored.push(format!(
                "metallic-roughness (metallicFactor {}; drawn as Lambertian with the base colour)",
                pbr.metallic_factor()
            ));
        }
        if m.emissive_factor().iter().any(|&c| c != 0.0) || m.emissive_texture().is_some() {
            ignored.push("emission (the surface does not glow)".into());
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

    fn uv_map(
        &mut self,
        m: &gltf::Material,
        info: &gltf::texture::Info,
        transform: Option<&gltf::texture::TextureTransform>,
        set: u32,
    ) -> Result<UvMap> {
        let texture = info.texture();
        let image = self.image(&texture.source())?;
        let sampler = texture.sampler();
        let (offset, rotation, scale) = match transform {
            Some(t) => (Vec2::from(t.offset()), t.rotation(), Vec2::from(t.scale())),
            None => (Vec2::ZERO, 0.0, Vec2::ONE),
        };
        if !(offset.is_finite() && rotation.is_finite() && scale.is_finite()) {
            let at = match m.index() {
                Some(i) => format!("materials[{i}]"),
                None => "materials".into(),
            };
            return Err(self.err(
                format!(
                    "{at}.pbrMetallicRoughness.baseColorTexture.extensions.KHR_texture_transform"
                ),
                "offset, rotation and scale must be finite",
            ));
        }
        Ok(UvMap {
            set,
            offset,
            rotation,
            scale,
            wrap: [
                axis_map(sampler.wrap_s(), image.width),
                axis_map(sampler.wrap_t(), image.height),
            ],
        })
    }

    /// An image decoded to linear RGB (sRGB-encoded PNG or JPEG), cached by index.
    fn image(&mut self, image: &gltf::Image) -> Result<Arc<ImageTexture>> {
        if let Some(img) = self.images.get(&image.index()) {
            return Ok(img.clone());
        }
        let i = image.index();
        let at = format!("images[{i}]");
        // From the JSON: `Image::source` unwraps a missing mimeType or uri.
        let json = &self.doc.as_json().images[i];
        let bytes: Cow<[u8]> = match (&json.buffer_view, &json.uri) {
            (Some(view), _) => {
                let view = self.doc.views().nth(view.value()).ok_or_else(|| {
                    self.err(
                        format!("{at}.bufferView"),
                        "refers to a missing buffer view",
                    )
                })?;
                Cow::Borrowed(self.view_bytes(&view))
            }
            (None, Some(uri)) => Cow::Owned(self.read_uri(uri, &format!("{at}.uri"))?),
            (None, None) => return Err(self.err(&at, "has neither a uri nor a bufferView")),
        };
        let decoded = image::load_from_memory(&bytes)
            .map_err(|e| self.err(&at, format!("cannot decode the image: {e}")))?;
        let rgb = decoded.to_rgb32f();
        let (w, h) = rgb.dimensions();
        let pixels: Vec<Vec3> = rgb
            .pixels()
            .map(|p| {
                Vec3::new(
                    srgb_to_linear(p.0[0]),
                    srgb_to_linear(p.0[1]),
                    srgb_to_linear(p.0[2]),
                )
            })
            .collect();
        let img = ImageTexture::from_pixels(w, h, pixels)
            .map_err(|e| self.err(&at, format!("unusable image: {e}")))?;
        let img = Arc::new(img);
        self.images.insert(i, img.clone());
        Ok(img)
    }
}

/// How a wrap mode is realised along one axis of a texture that always repeats: the image
/// is resampled (see [`wrapped_image`]) and the coordinate mapped into it.
#[derive(Clone, Copy, Debug, PartialEq)]
enum AxisMap {
    /// REPEAT: as is.
    Repeat,
    /// MIRRORED_REPEAT: the image followed by its mirror image, coordinates halved.
    Mirror,
    /// CLAMP_TO_EDGE: the image with a one-texel border copying its edge, so that bilinear
    /// lookups within [0, 1] clamp: exact where texture coordinates lie within [0, 1]; beyond,
    /// the image repeats (warned about).
    Clamp { texels: u32 },
}

fn axis_map(mode: WrappingMode, texels: u32) -> AxisMap {
    match mode {
        WrappingMode::Repeat => AxisMap::Repeat,
        WrappingMode::MirroredRepeat => AxisMap::Mirror,
        WrappingMode::ClampToEdge => AxisMap::Clamp { texels },
    }
}

impl AxisMap {
    fn apply(self, t: f32) -> f32 {
        match self {
            AxisMap::Repeat => t,
            AxisMap::Mirror => 0.5 * t,
            AxisMap::Clamp { texels } => {
                let n = texels as f32;
                (t * n + 1.0) / (n + 2.0)
            }
        }
    }

    /// Resampled size and the source texel of each resampled texel.
    fn source(self, size: u32) -> (u32, Box<dyn Fn(u32) -> u32>) {
        match self {
            AxisMap::Repeat => (size, Box::new(|x| x)),
            AxisMap::Mirror => (
                2 * size,
                Box::new(move |x| if x < size { x } else { 2 * size - 1 - x }),
            ),
            AxisMap::Clamp { .. } => (
                size + 2,
                Box::new(move |x| x.saturating_sub(1).min(size - 1)),
            ),
        }
    }
}

/// How a primitive's glTF texture coordinates become the crate's: `KHR_texture_transform`,
/// then the wrap modes ([`AxisMap`]), then `v` flipped (glTF's origin is the top-left).
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct UvMap {
    set: u32,
    offset: Vec2,
    rotation: f32,
    scale: Vec2,
    wrap: [AxisMap; 2],
}

impl UvMap {
    /// Whether `uv` (as in the file) falls outside [0, 1] along a clamped axis, where the
    /// import cannot clamp (see [`AxisMap::Clamp`]).
    fn beyond_clamp(&self, uv: Vec2) -> bool {
        const SLACK: f32 = 1e-4;
        let t = texture_transform(uv, self.offset, self.rotation, self.scale);
        [t.x, t.y]
            .iter()
            .zip(&self.wrap)
            .any(|(c, w)| matches!(w, AxisMap::Clamp { .. }) && !(-SLACK..=1.0 + SLACK).contains(c))
    }

    fn apply(&self, uv: Vec2) -> Vec2 {
        let uv = texture_transform(uv, self.offset, self.rotation, self.scale);
        let u = self.wrap[0].apply(uv.x);
        let v = self.wrap[1].apply(uv.y);
        Vec2::new(u, 1.0 - v)
    }
}

/// `KHR_texture_transform`: scale, then rotate, then offset:
/// `u' = offset.x + cos r · s.x·u + sin r · s.y·v`, `v' = offset.y − sin r · s.x·u + cos r · s.y·v`
/// (the rotation as the extension's example and three.js, Blender and the sample models have
/// it: `offset = [0, 1]`, `rotation = π/2`, `scale = [½, ½]` maps the unit square onto the
/// image's lower-left quadrant).
pub fn texture_transform(uv: Vec2, offset: Vec2, rotation: f32, scale: Vec2) -> Vec2 {
    let s = uv * scale;
    let (sin, cos) = rotation.sin_cos();
    offset + Vec2::new(cos * s.x + sin * s.y, -sin * s.x + cos * s.y)
}

/// The image resampled for the wrap modes (see [`AxisMap`]), multiplied by `factor`.
fn wrapped_image(
    img: &ImageTexture,
    s: WrappingMode,
    t: WrappingMode,
    factor: Vec3,
) -> ImageTexture {
    let (w, fx) = axis_map(s, img.width).source(img.width);
    let (h, fy) = axis_map(t, img.height).source(img.height);
    let mut pixels = Vec::with_capacity(w as usize * h as usize);
    for y in 0..h {
        let sy = fy(y) as usize;
        for x in 0..w {
            let sx = fx(x) as usize;
            pixels.push(img.pixels[sy * img.width as usize + sx] * factor);
        }
    }
    ImageTexture {
        width: w,
        height: h,
        pixels,
    }
}

/// A mesh with one vertex per triangle corner and the face normal at each (glTF's rule for
/// primitives without normals). Degenerate triangles get +z.
/// A primitive read into a mesh.
struct PrimitiveMesh {
    mesh: Mesh,
    /// Elements of the primitive's `POSITION` accessor.
    vertices: usize,
    /// Where the mesh was flat-shaded (split per triangle corner): the accessor element of
    /// each mesh vertex.
    split: Option<Vec<u32>>,
}

fn flat_shaded(positions: &[Vec3], uvs: &[Vec2], triangles: &[[u32; 3]]) -> Mesh {
    let mut m = Mesh::new();
    for t in triangles {
        let [a, b, c] = t.map(|i| positions[i as usize]);
        let n = (b - a).cross(c - a).try_normalize().unwrap_or(Vec3::Z);
        let base = m.positions.len() as u32;
        for &i in t {
            m.positions.push(positions[i as usize]);
            m.uvs.push(uvs[i as usize]);
            m.normals.push(n);
        }
        m.triangles.push([base, base + 1, base + 2]);
    }
    m
}

fn type_name(t: DataType) -> &'static str {
    match t {
        DataType::I8 => "i8",
        DataType::U8 => "u8",
        DataType::I16 => "i16",
        DataType::U16 => "u16",
        DataType::U32 => "u32",
        DataType::F32 => "f32",
    }
}

/// Standard base64 (RFC 4648, `+/`, padding optional, whitespace ignored).
fn base64_decode(text: &str) -> Option<Vec<u8>> {
    let mut out = Vec::with_capacity(text.len() * 3 / 4);
    let mut acc = 0u32;
    let mut bits = 0;
    let mut padding = false;
    for c in text.bytes() {
        let v = match c {
            b'A'..=b'Z' => c - b'A',
            b'a'..=b'z' => c - b'a' + 26,
            b'0'..=b'9' => c - b'0' + 52,
            b'+' | b'-' => 62,
            b'/' | b'_' => 63,
            b'=' => {
                padding = true;
                continue;
            }
            b' ' | b'\n' | b'\r' | b'\t' => continue,
            _ => return None,
        };
        if padding {
            return None;
        }
        acc = (acc << 6) | u32::from(v);
        bits += 6;
        if bits >= 8 {
            bits -= 8;
            out.push((acc >> bits) as u8);
            acc &= (1 << bits) - 1;
        }
    }
    Some(out)
}

/// `%XX` escapes decoded (a URI's path, as a file name).
fn percent_decode(s: &str) -> Option<String> {
    let bytes = s.as_bytes();
    let mut out = Vec::with_capacity(bytes.len());
    let mut i = 0;
    while i < bytes.len() {
        if bytes[i] == b'%' {
            let hex = std::str::from_utf8(bytes.get(i + 1..i + 3)?).ok()?;
            out.push(u8::from_str_radix(hex, 16).ok()?);
            i += 3;
        } else {
            out.push(bytes[i]);
            i += 1;
        }
    }
    String::from_utf8(out).ok()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn base64_round_trip() {
        assert_eq!(base64_decode("aGVsbG8=").unwrap(), b"hello");
        assert_eq!(base64_decode("aGVsbG8").unwrap(), b"hello");
        assert_eq!(base64_decode("AAEC/w==").unwrap(), [0, 1, 2, 255]);
        assert!(base64_decode("a*b").is_none());
        assert!(base64_decode("aG==VsbG8").is_none());
        assert_eq!(base64_decode("").unwrap(), b"");
    }

    #[test]
    fn percent_decoding() {
        assert_eq!(percent_decode("a%20b.bin").unwrap(), "a b.bin");
        assert!(percent_decode("a%2").is_none());
        assert!(percent_decode("a%zz").is_none());
    }

    #[test]
    fn texture_transform_matches_the_extension_example() {
        // offset [0, 1], rotation π/2, scale ½: the unit square onto the lower-left quadrant
        // (v down).
        let f = |uv: Vec2| {
            texture_transform(
                uv,
                Vec2::new(0.0, 1.0),
                std::f32::consts::FRAC_PI_2,
                Vec2::splat(0.5),
            )
        };
        assert!((f(Vec2::ZERO) - Vec2::new(0.0, 1.0)).length() < 1e-6);
        assert!((f(Vec2::X) - Vec2::new(0.0, 0.5)).length() < 1e-6);
        assert!((f(Vec2::Y) - Vec2::new(0.5, 1.0)).length() < 1e-6);
        assert!((f(Vec2::ONE) - Vec2::new(0.5, 0.5)).length() < 1e-6);
    }

    #[test]
    fn wrap_modes_resample_exactly() {
        let img = ImageTexture::from_pixels(
            2,
            1,
            vec![Vec3::new(1.0, 0.0, 0.0), Vec3::new(0.0, 0.0, 1.0)],
        )
        .unwrap();
        let mirrored = wrapped_image(
            &img,
            WrappingMode::MirroredRepeat,
            WrappingMode::Repeat,
            Vec3::ONE,
        );
        assert_eq!(mirrored.width, 4);
        assert_eq!(mirrored.pixels[2], Vec3::Z);
        assert_eq!(mirrored.pixels[3], Vec3::X);
        // Mirrored: u = 1.25 reads what u = 0.75 reads.
        let m = AxisMap::Mirror;
        let a = mirrored.eval(Vec2::new(m.apply(1.25), 0.5));
        let b = mirrored.eval(Vec2::new(m.apply(0.75), 0.5));
        assert!((a - b).length() < 1e-6);
        // Clamped: u = 0 reads the first texel alone, not a blend with the last.
        let clamped = wrapped_image(
            &img,
            WrappingMode::ClampToEdge,
            WrappingMode::Repeat,
            Vec3::splat(0.5),
        );
        let c = AxisMap::Clamp { texels: 2 };
        let e = clamped.eval(Vec2::new(c.apply(0.0), 0.5));
        assert!((e - Vec3::new(0.5, 0.0, 0.0)).length() < 1e-6, "{e}");
        let e = clamped.eval(Vec2::new(c.apply(1.0), 0.5));
        assert!((e - Vec3::new(0.0, 0.0, 0.5)).length() < 1e-6, "{e}");
    }

    #[test]
    fn glb_container_errors() {
        let p = Path::new("x.glb");
        let mut glb = b"glTF".to_vec();
        assert!(split_glb(p, &glb).is_err());
        glb.extend(2u32.to_le_bytes());
        glb.extend(4u32.to_le_bytes()); // length below the header's 12
        assert!(split_glb(p, &glb).is_err());
        let mut glb = b"glTF".to_vec();
        glb.extend(2u32.to_le_bytes());
        glb.extend(28u32.to_le_bytes());
        glb.extend(1000u32.to_le_bytes()); // a chunk longer than the file
        glb.extend(CHUNK_JSON.to_le_bytes());
        glb.extend([0u8; 8]);
        let e = split_glb(p, &glb).unwrap_err().to_string();
        assert!(e.contains("GLB chunk 0"), "{e}");
    }
}
