//! WGSL structs checked against the Rust that fills them, for tests: the WGSL is parsed with
//! naga (wgpu's own front end, so the offsets are the ones the GPU uses) and each struct is
//! compared field by field (name, order, offset, size, type) with a `#[repr(C)]` Rust struct
//! listed by [`wgsl_fields!`](crate::wgsl_fields). The checks panic with the mismatch. The
//! renderer's shaders are checked this way (`shader_layout`), and so are other crates' (the
//! GPU bake's).

use std::mem::size_of;

use wgpu::naga;

/// One field of a Rust struct: name, offset, size, type as `std::any::type_name` spells it.
pub struct Field {
    pub name: &'static str,
    pub offset: usize,
    pub size: usize,
    pub ty: &'static str,
}

/// The size and type name of the field that `get` reads.
pub fn field<T, F>(name: &'static str, offset: usize, _get: fn(&T) -> &F) -> Field {
    Field {
        name,
        offset,
        size: size_of::<F>(),
        ty: std::any::type_name::<F>(),
    }
}

/// The fields of a `#[repr(C)]` struct, listed by name: `wgsl_fields!(Params { a, b })`.
#[macro_export]
macro_rules! wgsl_fields {
    ($t:ty { $($f:ident),* $(,)? }) => {
        vec![$($crate::wgsl_layout::field::<$t, _>(
            stringify!($f),
            std::mem::offset_of!($t, $f),
            |s: &$t| &s.$f,
        )),*]
    };
}

/// The module of WGSL source `src` (named `label` in a parse error).
pub fn parse(label: &str, src: &str) -> naga::Module {
    naga::front::wgsl::parse_str(src)
        .unwrap_or_else(|e| panic!("{label}: {}", e.emit_to_string(src)))
}

/// A WGSL type spelled as the Rust type that mirrors it (`vec4<f32>` as `[f32; 4]`).
pub fn rust_name(module: &naga::Module, ty: naga::Handle<naga::Type>) -> String {
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
        // A nested struct: its name (checked on its own).
        naga::TypeInner::Struct { .. } => module.types[ty]
            .name
            .clone()
            .unwrap_or_else(|| panic!("an unnamed struct has no Rust twin")),
        other => panic!("no Rust twin for {other:?}"),
    }
}

/// The members of WGSL struct `name`: (name, offset, size, type as Rust spells it), and the
/// struct's size.
pub fn wgsl_struct(module: &naga::Module, name: &str) -> (Vec<(String, u32, u32, String)>, u32) {
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
pub fn check_struct(
    module: &naga::Module,
    name: &str,
    fields: &[Field],
    size: usize,
    prefix: bool,
) {
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
        // A nested struct's Rust type is its path (`crate::module::Name`).
        let same_type = w_ty == r.ty || r.ty.ends_with(&format!("::{w_ty}"));
        assert!(
            same_type,
            "{name}.{w_name}: WGSL type {w_ty}, Rust {}",
            r.ty
        );
    }
    if !prefix {
        assert_eq!(span as usize, size, "{name}: struct size");
    }
}

/// The value of WGSL constant `c`, as f64.
pub fn constant_value(module: &naga::Module, c: &naga::Constant) -> Option<f64> {
    match module.global_expressions[c.init] {
        naga::Expression::Literal(naga::Literal::U32(v)) => Some(f64::from(v)),
        naga::Expression::Literal(naga::Literal::I32(v)) => Some(f64::from(v)),
        naga::Expression::Literal(naga::Literal::F32(v)) => Some(f64::from(v)),
        _ => None,
    }
}
