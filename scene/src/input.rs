//! The bake's inputs read with bounds: every file a scene names (the scene itself, patch files,
//! OBJ meshes, glTF files, their buffers and images, textures, environment maps) is read with
//! [`oslf_util::input_file::read`], so that only regular files are read (a FIFO, device or
//! directory is refused at once, `/dev/zero` included) and never more than the limit of its
//! kind. The limits are documented in docs/scene-format.md ("Input limits").

use std::path::Path;

use oslf_util::input_file::{byte_size, Limit};

use crate::Result;

/// What an input file is, which decides how large it may be.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum InputKind {
    /// A TOML scene file or a Bézier patch file: [`MAX_TEXT_BYTES`].
    Text,
    /// A Wavefront OBJ file, or a `.gltf` / `.glb` file: [`MAX_MESH_BYTES`].
    Mesh,
    /// An image file (texture, environment map, glTF image): [`MAX_IMAGE_BYTES`].
    Image,
    /// Any file a scene includes, read again for the scene's hash: the largest of the limits
    /// (a glTF buffer's, [`MAX_MESH_BYTES`] + [`GLTF_BUFFER_ALLOWANCE`]); each was read with
    /// the limit of its kind before.
    Included,
}

/// The most bytes of a scene file or patch file: 64 MiB.
pub const MAX_TEXT_BYTES: u64 = 64 << 20;
/// The most bytes of an OBJ, `.gltf` or `.glb` file, and the largest `byteLength` a glTF
/// buffer may declare: 1 GiB.
pub const MAX_MESH_BYTES: u64 = 1 << 30;
/// The most bytes of an image file (PNG, JPEG, OpenEXR, Radiance HDR): 512 MiB.
pub const MAX_IMAGE_BYTES: u64 = 512 << 20;
/// The most pixels a decoded image may have (16384 × 16384): what its header declares is
/// checked before the pixels are decoded, so a small file cannot claim a huge image.
pub const MAX_IMAGE_PIXELS: u64 = 1 << 28;
/// How many bytes an external glTF buffer file may have beyond the `byteLength` its buffer
/// declares (padding, a trailing newline): 4 KiB.
pub const GLTF_BUFFER_ALLOWANCE: u64 = 4 << 10;

impl InputKind {
    /// The bound on files of this kind, worded for the message when one is larger.
    pub fn limit(self) -> Limit {
        let (bytes, what) = match self {
            InputKind::Text => (MAX_TEXT_BYTES, "a scene or patch file"),
            InputKind::Mesh => (MAX_MESH_BYTES, "a mesh or glTF file"),
            InputKind::Image => (MAX_IMAGE_BYTES, "an image"),
            InputKind::Included => (
                MAX_MESH_BYTES + GLTF_BUFFER_ALLOWANCE,
                "a file a scene includes",
            ),
        };
        Limit::new(
            bytes,
            format!("the {} allowed for {what}", byte_size(bytes)),
        )
    }
}

/// The content of the input file at `path`, a regular file within the limit of `kind`.
pub fn read_input(path: &Path, kind: InputKind) -> Result<Vec<u8>> {
    Ok(oslf_util::input_file::read(path, &kind.limit())?)
}

/// The bound on an external glTF buffer that declares `byte_length` bytes.
pub fn gltf_buffer_limit(byte_length: u64) -> Limit {
    Limit::new(
        byte_length.saturating_add(GLTF_BUFFER_ALLOWANCE),
        format!(
            "declared (byteLength {byte_length}, plus the {} allowed beyond it)",
            byte_size(GLTF_BUFFER_ALLOWANCE)
        ),
    )
}
