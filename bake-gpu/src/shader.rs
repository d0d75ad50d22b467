//! The capture shader: its WGSL files joined in dependency order (bindings and entry points
//! then, each file naming the functions of bake/src it mirrors).

/// The BVH traversal and the triangle test.
const BVH: &str = include_str!("shader/bvh.wgsl");
/// Hits, textures, materials, lights, environment.
const SCENE: &str = include_str!("shader/scene.wgsl");
/// Sampling, BRDFs and the path tracer.
const INTEGRATOR: &str = include_str!("shader/integrator.wgsl");
/// Bindings, the layout structs and the `capture` and `trace` entry points.
pub const CAPTURE: &str = include_str!("shader/capture.wgsl");
/// The bake's preview: the scene camera's image.
const PREVIEW: &str = include_str!("shader/preview.wgsl");

/// The whole module's source: oslf-shading's WGSL modules (GGX, Fresnel, colour, random
/// streams, warps), the structs generated from their Rust definitions, then the capture
/// shader's files.
pub fn source() -> String {
    let shading = oslf_shading::wgsl::source();
    [
        shading,
        crate::layouts::wgsl(),
        BVH.into(),
        SCENE.into(),
        INTEGRATOR.into(),
        CAPTURE.into(),
        PREVIEW.into(),
    ]
    .join("\n")
}
