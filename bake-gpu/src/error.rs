//! The crate's one error type.

use thiserror::Error;

/// What can go wrong on the GPU path.
#[derive(Debug, Error)]
pub enum GpuBakeError {
    /// No adapter, or a device that cannot be created or failed (from `oslf_gpu::Gpu`).
    #[error(transparent)]
    Device(#[from] oslf_gpu::GpuError),
    /// The scene cannot be uploaded (too large for the device's limits, too deep a BVH, ...).
    #[error("{0}")]
    Scene(String),
    /// wgpu reported an error while capturing, or a readback failed.
    #[error("{adapter}: {message}")]
    Gpu { adapter: String, message: String },
    /// The bake's own error (building the scene's triangles).
    #[error(transparent)]
    Bake(#[from] oslf_scene::BakeError),
}

/// Shorthand used across the crate.
pub type Result<T> = std::result::Result<T, GpuBakeError>;
