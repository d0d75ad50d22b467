//! glTF 2.0 scenes: `.gltf` (JSON with external or data-URI buffers and images) and `.glb`
//! (binary) files read into what a scene file's shapes become: triangle meshes with
//! metallic-roughness materials, point, spot and directional lights, and perspective cameras.
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
//!   lists), indexed or not: `POSITION`, `NORMAL` (flat normals where absent, or computed by
//!   [`Options::normals`] where the scene asks), the
//!   `TEXCOORD_n` set the material's textures use;
//! - materials (`materials.rs`): glTF's metallic-roughness model with its factors, emission
//!   (`KHR_materials_emissive_strength`) and its base-colour, metallic-roughness, normal,
//!   occlusion and emissive textures, with `KHR_texture_transform` and the sampler's wrap
//!   modes, where they map texture coordinates alike;
//! - `KHR_lights_punctual` point, spot and directional lights, photometric units converted
//!   with [`Options::watts_per_lumen`];
//! - perspective cameras.
//!
//! Everything else the file uses (skins, morph targets, animations, textures that map texture
//! coordinates unlike the material's others, alpha, vertex colours, other extensions,
//! orthographic cameras, points and lines, light ranges) is reported in [`Import::warnings`],
//! naming the node, mesh or material, and otherwise ignored.
//!
//! Conventions: glTF is Y-up, right-handed, in metres; nothing here converts axes or units:
//! the include's transform does (`rotate = [90, 0, 0]` turns glTF's +Y into the scene's +Z).
//! glTF's texture coordinate origin is the image's top-left corner; the crate's textures put
//! `v = 0` at the bottom ([`crate::texture`]), so `v` is flipped on import.
//!
//! Submodules by concern: [`import`] (what a file contributes: options, objects, cameras),
//! `loader` (one document being read), `container` (GLB, JSON checks, buffers and views),
//! `accessors`, `nodes` (the hierarchy and transforms), `meshes`, `materials`, `textures`
//! (images, wrap modes, texture transforms), `cameras` and `lights`.

mod accessors;
mod cameras;
mod container;
pub mod import;
mod lights;
mod loader;
mod materials;
mod meshes;
mod nodes;
mod textures;

use std::path::Path;

use crate::input::{read_input, InputKind};
use crate::material::Material;
use crate::Result;
pub use import::{
    GltfCamera, Import, ImportedObject, Options, SUPPORTED_EXTENSIONS, WATTS_PER_LUMEN,
};
use loader::{error, Loader};
pub use textures::texture_transform;

/// Reads a `.gltf` or `.glb` file (recognised by content: GLB starts with `glTF`). New
/// materials are appended to `materials`; the shapes index into it.
pub fn load(path: &Path, options: &Options, materials: &mut Vec<Material>) -> Result<Import> {
    let bytes = read_input(path, InputKind::Mesh)?;
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

fn load_bytes(
    path: &Path,
    bytes: &[u8],
    options: &Options,
    materials: &mut Vec<Material>,
) -> Result<Import> {
    let (doc, bin) = container::parse_document(path, bytes)?;
    let mut loader = Loader::new(path, &doc);
    loader.normal_rule = options.normals;
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
    warn_environment_normal_textures(&mut import, materials);
    import.files = loader.files.take();
    Ok(import)
}

/// Warns, once per material, where environment geometry uses a material with a normal,
/// emissive or occlusion texture: those are drawn on the OSLF objects (the store carries
/// them), not on the environment, which the path tracer draws with its interpolated normals
/// and its emission factor, its occlusion traced.
fn warn_environment_normal_textures(import: &mut Import, materials: &[Material]) {
    let mut seen = std::collections::BTreeSet::new();
    for shape in &import.shapes {
        let Some(m) = materials.get(shape.material as usize) else {
            continue;
        };
        let textured = m.normal_texture.is_some()
            || m.emissive_texture.is_some()
            || m.occlusion_texture.is_some();
        if textured && seen.insert(shape.material) {
            let mut what = Vec::new();
            if m.normal_texture.is_some() {
                what.push("normalTexture (this geometry is drawn with its interpolated normals)");
            }
            if m.emissive_texture.is_some() {
                what.push("emissiveTexture (this geometry emits its emissiveFactor alone)");
            }
            if m.occlusion_texture.is_some() {
                what.push("occlusionTexture (the path tracer traces this geometry's occlusion)");
            }
            import.warnings.push(format!(
                "{}: drawn on OSLF objects only: {}",
                shape.name,
                what.join("; ")
            ));
        }
    }
}
