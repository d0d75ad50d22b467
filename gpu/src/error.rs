//! The device crate's one error type.

/// What can go wrong while creating or using the device.
#[derive(Debug, thiserror::Error)]
pub enum GpuError {
    /// No GPU adapter could be found (what was tried).
    #[error(
        "no GPU adapter found ({0}). On Linux without a GPU install Mesa's software Vulkan \
         driver (Debian/Ubuntu: `apt-get install mesa-vulkan-drivers`)"
    )]
    NoAdapter(String),
    /// The adapter refused the device asked for, or cannot do what oslf needs.
    #[error("cannot create a GPU device on {adapter}: {message}")]
    Device { adapter: String, message: String },
    /// wgpu reported a validation or out-of-memory error, or a mapping or poll failed.
    #[error("GPU error: {0}")]
    Gpu(String),
}
