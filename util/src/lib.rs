//! # oslf-util: generic I/O that every part of oslf shares
//!
//! What the bake, the runtime, the measurements and the `oslf` command all need and none of
//! them owns (after pbrt-v4's `util/`):
//!
//! | module | what |
//! | --- | --- |
//! | [`image_file`] | writing images: linear 32-bit float OpenEXR (RGB, or RGBA with an object mask) for measurement, tone-mapped 8-bit sRGB PNG for eyes |
//! | [`ktx2`] | writing HDR cube maps as KTX2 (RGBA16F), the container engines load environment maps from |
//! | [`door`] | a command's inputs and outputs declared once, up front, and checked before any work: no output over an input, onto a device or FIFO |
//! | [`output_file`] | writing any output file: regular files only, through a synced temporary file renamed into place, every write checked |
//! | [`input_file`] | reading inputs with bounds: regular files only (never a FIFO, device or directory), at most a given number of bytes |
//! | [`machine`] | what the machine offers: memory available for new allocations, free space on a volume |
//!
//! It depends on no other oslf crate but `oslf-shading` (for the PNG's tone curve and sRGB
//! encoding, with the `images` feature), so any of them can use it. Without its default
//! feature `images` (what the store library takes) it is the doors alone: no image or EXR
//! crates.

pub mod door;
pub mod error;
#[cfg(feature = "images")]
pub mod image_file;
pub mod input_file;
#[cfg(feature = "images")]
pub mod ktx2;
pub mod machine;
pub mod output_file;

pub use error::{Conflict, Result, UtilError};
