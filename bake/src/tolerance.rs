//! Tolerances shared by the bake's stages: how closely the ray-traced geometry must follow
//! the OSLF objects' surfaces.

/// Tessellation error allowed for ray tracing the OSLF object, as a fraction of ε.
pub const TESSELLATION_ERROR: f32 = 1.0 / 50.0;
