//! The one error type of `oslf-util`.

use std::path::PathBuf;

/// What went wrong, and with which file.
#[derive(Debug, thiserror::Error)]
pub enum UtilError {
    /// An image could not be written (or its pixels do not make the image asked for).
    #[error("{}: {message}", .path.display())]
    Image { path: PathBuf, message: String },
}

pub type Result<T> = std::result::Result<T, UtilError>;
