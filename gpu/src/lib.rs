//! # oslf-gpu: the wgpu device the renderer and the GPU bake share
//!
//! [`Gpu`] is a wgpu device and queue with the limits and features oslf asks for: a headless
//! device on the best adapter there is ([`Gpu::headless`]), or an application's own
//! ([`Gpu::from_device`], [`Gpu::from_host_device`]). It collects wgpu's uncaptured errors (or
//! catches them in error scopes on a host's device), so a validation error is a
//! [`GpuError`], never a silent black image or an empty cube map.
//!
//! [`gpu_struct!`] declares the structs that Rust fills and WGSL reads once, generating the
//! WGSL declaration from the Rust fields ([`layout`]).
//!
//! The runtime (`oslf-runtime`) renders on it and re-exports it; the GPU bake
//! (`oslf-bake-gpu`) captures cube maps on it. It is a layer below both and must never depend
//! on another oslf crate: the GPU bake reaches the device without the renderer.

mod device;
mod error;
pub mod layout;

pub use device::Gpu;
pub use error::GpuError;
pub use layout::WgslType;
