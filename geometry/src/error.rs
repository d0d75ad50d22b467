//! The geometry crate's one error type.

use std::path::PathBuf;

/// A patch file that does not parse, or geometry that cannot be used.
#[derive(Debug, thiserror::Error)]
pub enum GeometryError {
    /// A located problem in a patch file.
    #[error("{path}:{line}:{column}: {message}")]
    Parse {
        path: PathBuf,
        line: usize,
        column: usize,
        message: String,
    },
    /// A mesh or camera that cannot be used (non-finite values, indices out of range,
    /// a degenerate view).
    #[error("{0}")]
    Invalid(String),
    /// A mesh whose per-triangle atlas charts do not fit in the largest allowed atlas grid
    /// (`crate::atlas`).
    #[error(
        "mesh of {triangles} triangles and area {area:.6e} needs an atlas grid of at least \
         {needed}×{needed} pages of {page_resolution}² texels at texel size {texel_size}, more \
         than the largest allowed {limit}×{limit} (max_grid {max_grid}, at most \
         {max_resolution} texels per atlas side); raise texel_size or max_grid"
    )]
    AtlasTooLarge {
        /// Triangles in the mesh.
        triangles: usize,
        /// Surface area of the mesh.
        area: f64,
        /// Requested world size of one texel.
        texel_size: f32,
        /// Texels per page side, `m`.
        page_resolution: u32,
        /// Smallest grid `k` the charts could need (a lower bound when packing failed).
        needed: u64,
        /// The largest grid allowed: `max_grid`, lowered so that `k·m` stays within
        /// `max_resolution`.
        limit: u32,
        /// The requested `max_grid`.
        max_grid: u32,
        /// Largest atlas side in texels ([`crate::atlas::MAX_ATLAS_RESOLUTION`]).
        max_resolution: u32,
    },
}

/// Shorthand used across the crate.
pub type Result<T> = std::result::Result<T, GeometryError>;
