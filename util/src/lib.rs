//! # oslf-util: generic I/O that every part of oslf shares
//!
//! What the bake, the runtime, the measurements and the `oslf` command all need and none of
//! them owns (after pbrt-v4's `util/`):
//!
//! | module | what |
//! | --- | --- |
//! | [`image_file`] | writing images: linear 32-bit float OpenEXR (RGB, or RGBA with an object mask) for measurement, tone-mapped 8-bit sRGB PNG for eyes |
//! | [`ktx2`] | writing HDR cube maps as KTX2 (RGBA16F), the container engines load environment maps from |
//! | [`input_file`] | reading inputs with bounds: regular files only (never a FIFO, device or directory), at most a given number of bytes |
//! | [`machine`] | what the machine offers: memory available for new allocations, free space on a volume |
//!
//! It depends on no other oslf crate, so any of them can use it.

pub mod error;
pub mod image_file;
pub mod input_file;
pub mod ktx2;
pub mod machine;

pub use error::{Result, UtilError};
