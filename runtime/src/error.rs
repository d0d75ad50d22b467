//! The runtime crate's one error type.

use std::path::PathBuf;

/// Everything that can go wrong while opening a store or rendering it.
#[derive(Debug, thiserror::Error)]
pub enum RuntimeError {
    /// The store could not be opened or a read from it failed (missing, foreign, other
    /// version, damaged: the format crate's error says what and where).
    ///
    /// The format error is part of the message and not a source, so that a chain of causes
    /// (`{:#}`) prints it once.
    #[error("{}: {error}", .path.display())]
    Store {
        path: PathBuf,
        error: oslf_format::Error,
    },
    /// A cube map that failed to decode while streaming (checksum, damaged frame). The sample
    /// point falls back; the render goes on and reports this.
    #[error("cube map {cube}: {error}")]
    Cube {
        cube: u32,
        error: oslf_format::Error,
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
    /// A parameter of a library call outside its range, named by [`Param`] so that a caller
    /// can name it its own way (the CLI names its flag): `problem` says what is wrong with it.
    #[error("invalid parameter: {} {problem}", param.name())]
    InvalidParam { param: Param, problem: String },
}

impl From<oslf_gpu::GpuError> for RuntimeError {
    /// The device's errors as the runtime's variants of the same name.
    fn from(e: oslf_gpu::GpuError) -> Self {
        match e {
            oslf_gpu::GpuError::NoAdapter(tried) => RuntimeError::NoAdapter(tried),
            oslf_gpu::GpuError::Device { adapter, message } => {
                RuntimeError::Device { adapter, message }
            }
            oslf_gpu::GpuError::Gpu(message) => RuntimeError::Gpu(message),
        }
    }
}

/// Parameters that [`RuntimeError::InvalidParam`] names.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Param {
    /// The GPU cache's budget in megabytes ([`crate::cache::slots_for_megabytes`]).
    CacheMegabytes,
    /// The RAM level's budget in megabytes ([`crate::cache::ram_bytes`]).
    RamMegabytes,
    /// The parallax proxy box ([`crate::ShadingParams::proxy_box`]).
    ProxyBox,
}

impl Param {
    /// The parameter's name in the library's words.
    pub fn name(self) -> &'static str {
        match self {
            Param::CacheMegabytes => "GPU cache budget (MB)",
            Param::RamMegabytes => "RAM budget (MB)",
            Param::ProxyBox => "proxy box",
        }
    }
}

/// `Result` with [`RuntimeError`].
pub type Result<T, E = RuntimeError> = std::result::Result<T, E>;
