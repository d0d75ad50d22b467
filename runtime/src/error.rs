//! The runtime crate's one error type.

use std::path::PathBuf;

/// Everything that can go wrong while opening a store or rendering it.
#[derive(Debug, thiserror::Error)]
pub enum RuntimeError {
    /// The store could not be opened or a read from it failed (missing, foreign, other
    /// version, damaged: the format crate's error says what and where).
    #[error("{path}: {source}")]
    Store {
        path: PathBuf,
        #[source]
        source: oslf_format::Error,
    },
    /// A cube map that failed to decode while streaming (checksum, damaged frame). The sample
    /// point falls back; the render goes on and reports this.
    #[error("cube map {cube}: {source}")]
    Cube {
        cube: u32,
        #[source]
        source: oslf_format::Error,
    },
    /// No GPU adapter could be found.
    #[error(
        "no GPU adapter found ({0}). On Linux without a GPU install Mesa's software Vulkan \
         driver (Debian/Ubuntu: `apt-get install mesa-vulkan-drivers`)"
    )]
    NoAdapter(String),
    /// The adapter refused the device we asked for.
    #[error("cannot create a GPU device on {adapter}: {message}")]
    Device { adapter: String, message: String },
    /// The store needs more than this GPU allows (texture size, array layers, buffer size).
    #[error("this GPU cannot hold the store: {0}")]
    Limits(String),
    /// wgpu reported a validation or out-of-memory error.
    #[error("GPU error: {0}")]
    Gpu(String),
    /// A parameter outside its documented range (names the parameter).
    #[error("invalid parameter: {0}")]
    Parameter(String),
}

/// `Result` with [`RuntimeError`].
pub type Result<T, E = RuntimeError> = std::result::Result<T, E>;
