//! The crate's error type.

use std::path::PathBuf;

/// Everything that can go wrong while measuring.
#[derive(Debug, thiserror::Error)]
pub enum MeasureError {
    #[error(transparent)]
    Bake(#[from] oslf_bake::BakeError),
    #[error(transparent)]
    Runtime(#[from] oslf_runtime::RuntimeError),
    #[error(transparent)]
    Store(#[from] oslf_format::Error),
    /// Writing an output file failed.
    #[error("{path}: {message}")]
    Output { path: PathBuf, message: String },
    /// An argument or input that cannot be measured.
    #[error("{0}")]
    Invalid(String),
}

/// Results of this crate.
pub type Result<T, E = MeasureError> = std::result::Result<T, E>;
