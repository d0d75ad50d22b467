//! The bake crate's one error type.

use std::path::PathBuf;

/// Everything that can go wrong while reading a scene or baking it.
///
/// Every variant says *what* is wrong and *where*: a file with line and column, a pixel, a
/// sample index.
#[derive(Debug, thiserror::Error)]
pub enum BakeError {
    /// An input file that is missing, unreadable, not a regular file or larger than its limit
    /// ([`crate::input`]); the message names the file.
    #[error(transparent)]
    Input(#[from] oslf_util::UtilError),
    /// A located problem in a text input (scene file, patch file, OBJ file).
    #[error("{path}:{line}:{column}: {message}")]
    Parse {
        path: PathBuf,
        line: usize,
        column: usize,
        message: String,
    },
    /// An image (texture or environment map) that cannot be used.
    #[error("{path}: {message}")]
    Image { path: PathBuf, message: String },
    /// A glTF file that cannot be read: `at` is the JSON path (`meshes[2].primitives[0].indices`),
    /// the GLB chunk or `JSON`, and the message names the accessor where one is involved.
    #[error("{path}: {at}: {message}")]
    Gltf {
        path: PathBuf,
        at: String,
        message: String,
    },
    /// A pixel of an input image that is NaN, infinite or negative.
    #[error("{path}: pixel ({x}, {y}) is {value} (must be finite and non-negative)")]
    BadPixel {
        path: PathBuf,
        x: u32,
        y: u32,
        value: f32,
    },
    /// A scene that parsed but cannot be baked (no OSLF object, no sample points, ...).
    #[error("{0}")]
    Invalid(String),
    /// Sample-map texels without any visible sample point, refused before the capture
    /// (`oslf_bake::bake::BakeOptions::refuse_empty_texels`).
    #[error("{empty} of {texels} sample-map texels have no visible sample point ({points} sample points in all), so the store could not reconstruct them; nothing was captured{where_}")]
    EmptyTexels {
        empty: u64,
        texels: u64,
        points: u64,
        /// Where they lie and why, per object (`oslf_bake::coverage`): `; where: object "box":
        /// 3496 texels facing down (−z) at …`, or empty.
        where_: String,
    },
    /// An output file that cannot be created (checked before the bake starts).
    #[error("cannot write {what} {path}: {detail}")]
    Unwritable {
        what: &'static str,
        path: PathBuf,
        detail: String,
    },
    /// The capture device (`oslf_bake::device::CaptureDevice`, the GPU) failed: `device` names
    /// it.
    #[error("capture on {device}: {message}")]
    Device { device: String, message: String },
    /// The store could not be written or resumed.
    #[error(transparent)]
    Format(#[from] oslf_format::Error),
}

/// Shorthand used across the crate.
pub type Result<T> = std::result::Result<T, BakeError>;

/// Patch-file and geometry errors keep their kind: a located parse error stays
/// [`BakeError::Parse`], an unusable mesh or camera [`BakeError::Invalid`].
impl From<oslf_geometry::GeometryError> for BakeError {
    fn from(e: oslf_geometry::GeometryError) -> Self {
        match e {
            oslf_geometry::GeometryError::Parse {
                path,
                line,
                column,
                message,
            } => BakeError::Parse {
                path,
                line,
                column,
                message,
            },
            oslf_geometry::GeometryError::Invalid(message) => BakeError::Invalid(message),
            e @ oslf_geometry::GeometryError::AtlasTooLarge { .. } => {
                BakeError::Invalid(e.to_string())
            }
        }
    }
}
