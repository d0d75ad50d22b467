//! The crate's error type.

use std::path::PathBuf;

/// Everything that can go wrong while measuring.
#[derive(Debug, thiserror::Error)]
pub enum MeasureError {
    #[error(transparent)]
    Bake(#[from] oslf_scene::BakeError),
    #[error(transparent)]
    Runtime(#[from] oslf_runtime::RuntimeError),
    #[error(transparent)]
    Store(#[from] oslf_format::Error),
    /// The GPU capture a bake asked for cannot be had.
    #[error(transparent)]
    Gpu(#[from] oslf_bake_gpu::GpuBakeError),
    /// An input or output refused or failed at the door ([`oslf_util::door`]).
    #[error(transparent)]
    File(#[from] oslf_util::UtilError),
    /// Writing an output file failed.
    #[error("{path}: {message}")]
    Output { path: PathBuf, message: String },
    /// A sweep variation (`KEY=V1,V2,…`, [`crate::sweep::parse_vary`]) or a change of one
    /// setting ([`crate::sweep::Change`]) that cannot be applied. `setting` names it: the key,
    /// or the whole variation (quoted) where it has no key; `None` where the key is not one the
    /// sweep knows (`problem` names it).
    #[error("variation{}: {problem}", setting.as_ref().map(|s| format!(" {s}")).unwrap_or_default())]
    Vary {
        setting: Option<String>,
        problem: String,
    },
    /// An argument or input that cannot be measured.
    #[error("{0}")]
    Invalid(String),
    /// A parameter of a replay outside its range, named by [`ReplayParam`] so that a caller
    /// can name it its own way (the CLI names its flag).
    #[error("invalid parameter: {} {problem}", param.name())]
    InvalidParam { param: ReplayParam, problem: String },
}

/// Parameters of a replay that [`MeasureError::InvalidParam`] names, so that a caller can name
/// them its own way (the CLI names its flags).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ReplayParam {
    /// The frames of a still path (`replay::CameraPath::still`).
    StillFrames,
    /// The frames of an orbit (`replay::CameraPath::orbit`).
    OrbitFrames,
    /// The angle an orbit turns through (`replay::CameraPath::orbit`).
    OrbitDegrees,
}

impl ReplayParam {
    /// The parameter's name in the library's words.
    pub fn name(self) -> &'static str {
        match self {
            ReplayParam::StillFrames => "still path frames",
            ReplayParam::OrbitFrames => "orbit frames",
            ReplayParam::OrbitDegrees => "orbit degrees",
        }
    }
}

/// Results of this crate.
pub type Result<T, E = MeasureError> = std::result::Result<T, E>;
