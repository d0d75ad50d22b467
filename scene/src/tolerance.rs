//! Tolerances shared by the bake's stages: how closely the ray-traced geometry must follow
//! the OSLF objects' surfaces.

/// Relative self-intersection tolerance of the ray tracer: 4 ulps (2⁻²¹) of the origin's
/// largest coordinate (≈1.4e-6 for a teapot at the origin, so ε down to 1e-6 of its size still
/// works). The smallest ε a scene may ask for is twice this.
pub const SELF_TOLERANCE: f32 = 1.0 / (1u32 << 21) as f32;

/// Tessellation error allowed for ray tracing the OSLF object, as a fraction of ε (the
/// runtime's G-buffer tessellates to it too).
pub use oslf_geometry::bezier::TESSELLATION_ERROR;
