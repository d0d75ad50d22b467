//! Offset surface light fields: the bake, format and runtime crates in one place.
pub use oslf_bake as bake;
pub use oslf_format as format;
