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
}

/// Shorthand used across the crate.
pub type Result<T> = std::result::Result<T, GeometryError>;
