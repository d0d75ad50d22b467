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
    /// The store needs more than this GPU allows (texture size, array layers, buffer size).
    #[error("this GPU cannot hold the store: {0}")]
    Limits(String),
    /// The device (`oslf_gpu::GpuError` says what): no adapter, a device that cannot be
    /// created, or a wgpu validation or out-of-memory error, ours or the device's.
    #[error(transparent)]
    Gpu(#[from] oslf_gpu::GpuError),
    /// A parameter outside its documented range (names the parameter).
    #[error("invalid parameter: {0}")]
    Parameter(String),
    /// A parameter of a library call outside its range, named by [`Param`] so that a caller
    /// can name it its own way (the CLI names its flag): `problem` says what is wrong with it.
    #[error("invalid parameter: {} {problem}", param.name())]
    InvalidParam { param: Param, problem: String },
}

impl RuntimeError {
    /// [`RuntimeError::Gpu`] with `message` ([`oslf_gpu::GpuError::Gpu`]).
    pub(crate) fn gpu(message: impl Into<String>) -> Self {
        RuntimeError::Gpu(oslf_gpu::GpuError::Gpu(message.into()))
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
