//! The shaders' interface checked against the Rust that fills it: shade.wgsl and gbuffer.wgsl
//! are parsed with naga (wgpu's own WGSL front end, so the offsets are the ones the GPU uses),
//! and every struct shared with Rust is compared field by field (name, order, offset, type) and
//! every constant by value. A change to either side alone fails here.

use std::mem::{offset_of, size_of};

use wgpu::naga;

use crate::geometry::GVertex;
use crate::params::ShadeUniform;
use crate::pipelines::{SHADE_WGSL, WORKGROUP};

/// One field of a Rust struct: name, offset, size, type as `std::any::type_name` spells it.
struct Field {
    name: &'static str,
    offset: usize,
    size: usize,
    ty: &'static str,
}

/// The size and type name of the field that `get` reads.
fn field<T, F>(name: &'static str, offset: usize, _get: fn(&T) -> &F) -> Field {
    Field {
        name,
        offset,
        size: size_of::<F>(),
        ty: std::any::type_name::<F>(),
    }
}

/// The fields of a `#[repr(C)]` struct, listed by name.
macro_rules! fields {
    ($t:ty { $($f:ident),* $(,)? }) => {
        vec![$(field::<$t, _>(stringify!($f), offset_of!($t, $f), |s: &$t| &s.$f)),*]
    };
}

/// The module of WGSL source `src` (named `label` in a parse error).
fn parse(label: &str, src: &str) -> naga::Module {
    naga::front::wgsl::parse_str(src)
        .unwrap_or_else(|e| panic!("{label}: {}", e.emit_to_string(src)))
}

/// A WGSL type spelled as the Rust type that mirrors it (`vec4<f32>` as `[f32; 4]`).
fn rust_name(module: &naga::Module, ty: naga::Handle<naga::Type>) -> String {
    let scalar = |s: naga::Scalar| match (s.kind, s.width) {
        (naga::ScalarKind::Float, 4) => "f32".to_string(),
        (naga::ScalarKind::Uint, 4) => "u32".to_string(),
        (naga::ScalarKind::Sint, 4) => "i32".to_string(),
        other => panic!("no Rust twin for {other:?}"),
    };
    match &module.types[ty].inner {
        naga::TypeInner::Scalar(s) => scalar(*s),
        naga::TypeInner::Vector { size, scalar: s } => format!("[{}; {}]", scalar(*s), *size as u8),
        naga::TypeInner::Matrix {
            columns,
            rows,
            scalar: s,
        } => format!("[[{}; {}]; {}]", scalar(*s), *rows as u8, *columns as u8),
        naga::TypeInner::Array {
            base,
            size: naga::ArraySize::Constant(n),
            ..
        } => format!("[{}; {n}]", rust_name(module, *base)),
        other => panic!("no Rust twin for {other:?}"),
    }
}

/// The members of WGSL struct `name`: (name, offset, size, type as Rust spells it), and the
/// struct's size.
fn wgsl_struct(module: &naga::Module, name: &str) -> (Vec<(String, u32, u32, String)>, u32) {
    let (_, ty) = module
        .types
        .iter()
        .find(|(_, t)| t.name.as_deref() == Some(name))
        .unwrap_or_else(|| panic!("no struct {name}"));
    let naga::TypeInner::Struct { members, span } = &ty.inner else {
        panic!("{name} is not a struct");
    };
    let members = members
        .iter()
        .map(|m| {
            let size = module.types[m.ty].inner.size(module.to_ctx());
            let name = m.name.clone().unwrap_or_default();
            (name, m.offset, size, rust_name(module, m.ty))
        })
        .collect();
    (members, *span)
}

/// Checks WGSL struct `name` against the Rust fields `fields` (in declaration order) of a
/// struct of `size` bytes; with `prefix`, the WGSL struct is only the first of them.
fn check_struct(module: &naga::Module, name: &str, fields: &[Field], size: usize, prefix: bool) {
    // The Rust fields tile their struct: a field added to it but not to the list shows here.
    let mut end = 0;
    for f in fields {
        assert_eq!(
            f.offset, end,
            "Rust {name}: padding or a field missing before {}",
            f.name
        );
        end += f.size;
    }
    assert_eq!(
        end, size,
        "Rust {name}: fields missing after the last listed"
    );
    let (members, span) = wgsl_struct(module, name);
    let rust = if prefix {
        &fields[..members.len()]
    } else {
        fields
    };
    assert_eq!(
        members.len(),
        rust.len(),
        "{name}: WGSL has {} members",
        members.len()
    );
    for ((w_name, w_offset, w_size, w_ty), r) in members.iter().zip(rust) {
        assert_eq!(w_name, r.name, "{name}: member order");
        assert_eq!(*w_offset as usize, r.offset, "{name}.{w_name}: offset");
        assert_eq!(*w_size as usize, r.size, "{name}.{w_name}: size");
        assert_eq!(w_ty, r.ty, "{name}.{w_name}: type");
    }
    if !prefix {
        assert_eq!(span as usize, size, "{name}: struct size");
    }
}

/// The value of WGSL constant `c`, as f64.
fn constant_value(module: &naga::Module, c: &naga::Constant) -> Option<f64> {
    match module.global_expressions[c.init] {
        naga::Expression::Literal(naga::Literal::U32(v)) => Some(f64::from(v)),
        naga::Expression::Literal(naga::Literal::I32(v)) => Some(f64::from(v)),
        naga::Expression::Literal(naga::Literal::F32(v)) => Some(f64::from(v)),
        _ => None,
    }
}

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
        pad,
    })
}

/// shade.wgsl's `Params` is [`ShadeUniform`]; gbuffer.wgsl's is its first members.
#[test]
fn the_uniform_block_is_shade_uniform() {
    let size = size_of::<ShadeUniform>();
    let shade = parse("shade.wgsl", SHADE_WGSL);
    check_struct(&shade, "Params", &shade_fields(), size, false);
    let gbuffer = parse("gbuffer.wgsl", include_str!("gbuffer.wgsl"));
    check_struct(&gbuffer, "Params", &shade_fields(), size, true);
}

/// gbuffer.wgsl's `GVertex` is [`GVertex`]; shade.wgsl's `PatchGpu` is what
/// [`crate::buffers::PATCH_VEC4S`] vec4s per patch hold (16 control points, the colour).
#[test]
fn the_vertex_and_patch_records_match() {
    let gbuffer = parse("gbuffer.wgsl", include_str!("gbuffer.wgsl"));
    let vertex = fields!(GVertex {
        position_patch,
        normal_u,
        v
    });
    check_struct(&gbuffer, "GVertex", &vertex, size_of::<GVertex>(), false);
    let shade = parse("shade.wgsl", SHADE_WGSL);
    let (members, span) = wgsl_struct(&shade, "PatchGpu");
    assert_eq!(span as usize, crate::buffers::PATCH_VEC4S * 16);
    let names: Vec<_> = members
        .iter()
        .map(|m| (m.0.as_str(), m.1, m.3.as_str()))
        .collect();
    assert_eq!(
        names,
        [("cp", 0, "[[f32; 4]; 16]"), ("color", 256, "[f32; 4]")]
    );
}

/// Every constant of shade.wgsl has the value of its Rust twin, and every one has a twin.
#[test]
fn shader_constants_are_the_rust_constants() {
    let twins: [(&str, f64); 8] = [
        ("INVALID", f64::from(oslf_format::INVALID_INDEX)),
        ("PI", f64::from(std::f32::consts::PI)),
        ("FAR", f64::from(crate::face::FAR_DISTANCE)),
        ("DEPTH_REFINE", f64::from(crate::reference::DEPTH_REFINE)),
        (
            "DEPTH_ITERATIONS",
            f64::from(crate::reference::DEPTH_ITERATIONS),
        ),
        ("LOOKUP_AGREE", f64::from(crate::reference::LOOKUP_AGREE)),
        ("HIT_AGREE", f64::from(crate::reference::HIT_AGREE)),
        ("WORKGROUP", f64::from(WORKGROUP)),
    ];
    // The seam table is checked against the projection it encodes (reference::tests).
    let elsewhere = ["SEAM_LO", "SEAM_HI"];
    let shade = parse("shade.wgsl", SHADE_WGSL);
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
    let shade = parse("shade.wgsl", SHADE_WGSL);
    let mut wgsl: Vec<_> = shade
        .overrides
        .iter()
        .map(|(_, o)| o.name.clone().unwrap_or_default())
        .collect();
    let mut rust: Vec<_> = crate::pipelines::ShadeKey::default()
        .constants(1, 0)
        .into_iter()
        .map(|(n, _)| n.to_string())
        .collect();
    wgsl.sort();
    rust.sort();
    assert_eq!(wgsl, rust);
}
