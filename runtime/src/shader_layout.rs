//! The shaders' interface checked against the Rust that fills it: shade.wgsl and gbuffer.wgsl
//! are parsed with naga (wgpu's own WGSL front end, so the offsets are the ones the GPU uses),
//! and every struct shared with Rust is compared field by field (name, order, offset, type) and
//! every constant by value. A change to either side alone fails here.

use std::mem::size_of;

use crate::geometry::GVertex;
use crate::pipelines::{gbuffer_wgsl, shade_wgsl, WORKGROUP};
use crate::uniform::ShadeUniform;
use crate::wgsl_fields as fields;
use crate::wgsl_layout::{check_struct, constant_value, parse, wgsl_struct, Field};

fn shade_fields() -> Vec<Field> {
    fields!(ShadeUniform {
        view_proj,
        camera_pos,
        size,
        terms,
        blend,
        blend_n,
        source,
        m,
        order,
        rs,
        rd,
        nu,
        nv,
        cos_phi_shader,
        seed,
        sample_count,
        env_cube,
        map_res,
        index16,
        cube_res,
        slots_per_texture,
        cam_right,
        cam_up,
        cam_forward,
        bg_color,
        background,
        mip_levels,
        depth_steps,
        depth_thickness,
        probe_pos,
        box_min,
        box_max,
        metallic,
        alpha,
        object_material,
        min_metallic,
        split_sum,
        irradiance,
        surface_error,
        pad2,
    })
}

/// shade.wgsl's and gbuffer.wgsl's `Params`, generated from [`ShadeUniform`], lay it out as
/// Rust does.
#[test]
fn the_uniform_block_is_shade_uniform() {
    let size = size_of::<ShadeUniform>();
    let shade = parse("shade.wgsl", shade_wgsl());
    check_struct(&shade, "Params", &shade_fields(), size, false);
    let gbuffer = parse("gbuffer.wgsl", gbuffer_wgsl());
    check_struct(&gbuffer, "Params", &shade_fields(), size, false);
}

/// gbuffer.wgsl's `GVertex` is [`GVertex`]; shade.wgsl's `PatchGpu` is what
/// [`crate::buffers::PATCH_VEC4S`] vec4s per patch hold (16 control points, the colour, the
/// material).
#[test]
fn the_vertex_and_patch_records_match() {
    let gbuffer = parse("gbuffer.wgsl", gbuffer_wgsl());
    let vertex = fields!(GVertex {
        position_patch,
        normal_u,
        v,
        tangent
    });
    check_struct(&gbuffer, "GVertex", &vertex, size_of::<GVertex>(), false);
    use crate::textures::TextureParams;
    let params = fields!(TextureParams {
        flags,
        normal_scale,
        occlusion_strength,
        pad
    });
    check_struct(
        &gbuffer,
        "TextureParams",
        &params,
        size_of::<TextureParams>(),
        false,
    );
    let shade = parse("shade.wgsl", shade_wgsl());
    let (members, span) = wgsl_struct(&shade, "PatchGpu");
    assert_eq!(span as usize, crate::buffers::PATCH_VEC4S * 16);
    let names: Vec<_> = members
        .iter()
        .map(|m| (m.0.as_str(), m.1, m.3.as_str()))
        .collect();
    assert_eq!(
        names,
        [
            ("cp", 0, "[[f32; 4]; 16]"),
            ("color", 256, "[f32; 4]"),
            ("material", 272, "[f32; 4]"),
            ("emission", 288, "[f32; 4]")
        ]
    );
}

/// Every constant of shade.wgsl has the value of its Rust twin, and every one has a twin.
#[test]
fn shader_constants_are_the_rust_constants() {
    let twins: [(&str, f64); 13] = [
        ("PBR_LOD_BIAS", f64::from(crate::reference::PBR_LOD_BIAS)),
        ("INVALID", f64::from(oslf_format::INVALID_INDEX)),
        ("FAR", f64::from(crate::face::FAR_DISTANCE)),
        ("DEPTH_REFINE", f64::from(crate::reference::DEPTH_REFINE)),
        (
            "DEPTH_ITERATIONS",
            f64::from(crate::reference::DEPTH_ITERATIONS),
        ),
        ("LOOKUP_AGREE", f64::from(crate::reference::LOOKUP_AGREE)),
        ("HIT_AGREE", f64::from(crate::reference::HIT_AGREE)),
        ("LOW_HIT", f64::from(crate::reference::LOW_HIT)),
        ("WORKGROUP", f64::from(WORKGROUP)),
        ("REFINE_STEPS", f64::from(crate::reference::REFINE_STEPS)),
        (
            "REFINE_REACH",
            f64::from(oslf_geometry::bezier::REFINE_REACH),
        ),
        ("REFINE_SLACK", f64::from(crate::reference::REFINE_SLACK)),
        ("REFINE_MISS", f64::from(crate::reference::REFINE_MISS)),
    ];
    // The seam table is checked against the projection it encodes (reference::tests);
    // oslf-shading's constants are its own (generated from their Rust values there).
    let shading = parse("oslf-shading", &oslf_shading::wgsl::constants());
    let mut elsewhere = vec!["SEAM_LO", "SEAM_HI"];
    elsewhere.extend(
        shading
            .constants
            .iter()
            .filter_map(|(_, c)| c.name.as_deref()),
    );
    let shade = parse("shade.wgsl", shade_wgsl());
    let mut seen = Vec::new();
    for (_, c) in shade.constants.iter() {
        let name = c.name.as_deref().unwrap_or_default();
        if elsewhere.contains(&name) {
            continue;
        }
        let (_, rust) = twins
            .iter()
            .find(|(n, _)| *n == name)
            .unwrap_or_else(|| panic!("shade.wgsl constant {name} has no Rust twin here"));
        assert_eq!(constant_value(&shade, c), Some(*rust), "{name}");
        seen.push(name.to_string());
    }
    // The workgroup size is the entry point's attribute, not a constant.
    let entry = &shade.entry_points[0];
    assert_eq!(entry.workgroup_size, [WORKGROUP, WORKGROUP, 1]);
    seen.push("WORKGROUP".into());
    for (name, _) in twins {
        assert!(
            seen.iter().any(|s| s == name),
            "{name} is not in shade.wgsl"
        );
    }
}

/// The pipelines set exactly shade.wgsl's override constants.
#[test]
fn pipeline_overrides_are_the_shaders() {
    let shade = parse("shade.wgsl", shade_wgsl());
    let mut wgsl: Vec<_> = shade
        .overrides
        .iter()
        .map(|(_, o)| o.name.clone().unwrap_or_default())
        .collect();
    let mut rust: Vec<_> = crate::pipelines::ShadeKey::default()
        .constants(1, 0, false)
        .into_iter()
        .map(|(n, _)| n.to_string())
        .collect();
    wgsl.sort();
    rust.sort();
    assert_eq!(wgsl, rust);
}

/// The embedded shaders are what their modules assemble to (`OSLF_BLESS=1` writes them).
#[test]
fn embedded_shaders_are_their_modules_assembled() {
    use crate::pipelines::{composite_modules, gbuffer_modules, shade_modules};
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("generated");
    for (file, root, modules) in [
        ("shade.wgsl", "shade::pixel", shade_modules()),
        ("gbuffer.wgsl", "gbuffer", gbuffer_modules()),
        ("composite.wgsl", "composite", composite_modules()),
    ] {
        oslf_shading::wgsl::check_assembled(&dir.join(file), root, &modules)
            .unwrap_or_else(|e| panic!("{e}"));
    }
}
