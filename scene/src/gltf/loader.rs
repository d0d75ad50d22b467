//! The reader of one glTF document: its buffers, decoded images, the materials made so far
//! and the warnings met; located errors and labels for what it reads.

use std::borrow::Cow;
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use crate::normals::NormalRule;
use crate::texture::ImageTexture;
use crate::BakeError;

pub(super) fn error(path: &Path, at: impl Into<String>, message: impl Into<String>) -> BakeError {
    BakeError::Gltf {
        path: path.to_path_buf(),
        at: at.into(),
        message: message.into(),
    }
}

pub(super) struct Loader<'d> {
    pub(super) path: &'d Path,
    pub(super) dir: PathBuf,
    pub(super) doc: &'d gltf::Document,
    pub(super) buffers: Vec<Cow<'d, [u8]>>,
    /// Decoded images (linear RGB), by image index.
    /// Decoded images by index and whether decoded from sRGB.
    pub(super) images: HashMap<(usize, bool), Arc<ImageTexture>>,
    /// Scene material index, by (glTF material index, texture coordinate set).
    pub(super) materials: HashMap<(Option<usize>, u32), u32>,
    pub(super) warnings: Vec<String>,
    /// The file's name, for warnings.
    pub(super) file: String,
    /// External files read (buffers, images), in reading order.
    pub(super) files: std::cell::RefCell<Vec<PathBuf>>,
    /// [`super::Options::normals`]: how every primitive's normals are computed.
    pub(super) normal_rule: Option<NormalRule>,
}

/// `nodes[3] "Arm"` or `nodes[3]`.
pub(super) fn label(kind: &str, index: usize, name: Option<&str>) -> String {
    match name {
        Some(n) => format!("{kind}[{index}] {n:?}"),
        None => format!("{kind}[{index}]"),
    }
}

pub(super) fn material_label(m: &gltf::Material) -> String {
    match m.index() {
        Some(i) => label("materials", i, m.name()),
        None => "the default material".into(),
    }
}

impl<'d> Loader<'d> {
    /// A reader of `doc`, the document of the file at `path`.
    pub(super) fn new(path: &'d Path, doc: &'d gltf::Document) -> Self {
        Loader {
            path,
            dir: path
                .parent()
                .unwrap_or_else(|| Path::new("."))
                .to_path_buf(),
            doc,
            buffers: Vec::new(),
            images: HashMap::new(),
            materials: HashMap::new(),
            warnings: Vec::new(),
            file: path.file_name().map_or_else(
                || path.display().to_string(),
                |n| n.to_string_lossy().into_owned(),
            ),
            files: Default::default(),
            normal_rule: None,
        }
    }

    pub(super) fn err(&self, at: impl Into<String>, message: impl Into<String>) -> BakeError {
        error(self.path, at, message)
    }

    pub(super) fn warn(&mut self, what: impl AsRef<str>) {
        self.warnings
            .push(format!("{}: {}", self.file, what.as_ref()));
    }
}
