//! The capture shader as embedded: assembled from the WGSL modules of shader/ (the BVH
//! traversal, the scene, the path tracer, the preview's camera, and the root module
//! capture.wgsl with the bindings and the `capture`, `trace` and `preview` entry points),
//! oslf-shading's modules and the structs generated from Rust ([`modules`]); the tests check
//! that it is what they assemble to.

/// The whole module's source, as embedded.
pub fn source() -> &'static str {
    include_str!("../generated/capture.wgsl")
}

/// The root module's path.
pub const ROOT: &str = "capture";

/// The modules of the shader as (path under `package::`, source).
pub fn modules() -> Vec<(String, String)> {
    let files = [
        ("bvh", include_str!("shader/bvh.wgsl")),
        ("scene", include_str!("shader/scene.wgsl")),
        ("integrator", include_str!("shader/integrator.wgsl")),
        ("capture", include_str!("shader/capture.wgsl")),
        ("preview", include_str!("shader/preview.wgsl")),
    ];
    let mut modules = oslf_shading::wgsl::modules();
    modules.push(("layouts".into(), crate::layouts::wgsl()));
    modules.extend(
        files
            .into_iter()
            .map(|(name, src)| (name.to_string(), src.to_string())),
    );
    modules
}
