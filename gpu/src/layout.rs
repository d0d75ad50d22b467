//! Struct layouts written once for Rust and WGSL: [`gpu_struct!`](crate::gpu_struct) declares
//! a `#[repr(C)]` Rust struct and generates its WGSL declaration from the same field list, so
//! the two cannot drift apart. The shaders that use such a struct include the generated text
//! instead of a hand-kept copy; the layout tests (naga, wgpu's own WGSL front end) still check
//! that WGSL places every field at the Rust offset, which now tests the generator.

/// A Rust type whose WGSL twin has the same size and layout in a host-shareable buffer.
pub trait WgslType {
    /// The WGSL type.
    const WGSL: &'static str;
}

macro_rules! wgsl_types {
    ($($rust:ty => $wgsl:literal),* $(,)?) => {
        $(impl WgslType for $rust {
            const WGSL: &'static str = $wgsl;
        })*
    };
}

// `[f32; 3]` is 12 bytes and `vec3<f32>` 12 bytes aligned to 16: the same layout where a
// 4-byte field follows (the layout tests say where not); `[u32; 3]` becomes an array, which
// keeps a 4-byte stride in storage buffers (not in uniform ones).
wgsl_types! {
    f32 => "f32",
    u32 => "u32",
    i32 => "i32",
    [f32; 2] => "vec2<f32>",
    [u32; 2] => "vec2<u32>",
    [f32; 3] => "vec3<f32>",
    [u32; 3] => "array<u32, 3>",
    [f32; 4] => "vec4<f32>",
    [u32; 4] => "vec4<u32>",
    [i32; 4] => "vec4<i32>",
    [[f32; 4]; 4] => "mat4x4<f32>",
}

/// Declares a `#[repr(C)]` struct (with the attributes and derives given) and a `wgsl()`
/// associated function returning its WGSL declaration under the WGSL name after `as`, each
/// field with the WGSL twin of its type ([`WgslType`](crate::WgslType)), in the same order.
/// The struct is a [`WgslType`](crate::WgslType) itself, so structs nest.
///
/// ```
/// oslf_gpu::gpu_struct! {
///     /// A light.
///     #[derive(Clone, Copy)]
///     pub struct Light as "LightGpu" {
///         pub position: [f32; 4],
///         pub power: f32,
///     }
/// }
/// assert_eq!(
///     Light::wgsl(),
///     "struct LightGpu {\n    position: vec4<f32>,\n    power: f32,\n};\n"
/// );
/// ```
#[macro_export]
macro_rules! gpu_struct {
    (
        $(#[$meta:meta])*
        $vis:vis struct $name:ident as $wgsl:literal {
            $( $(#[$field_meta:meta])* pub $field:ident : $ty:ty ),* $(,)?
        }
    ) => {
        $(#[$meta])*
        #[repr(C)]
        $vis struct $name {
            $( $(#[$field_meta])* pub $field: $ty, )*
        }

        impl $crate::WgslType for $name {
            const WGSL: &'static str = $wgsl;
        }

        impl $name {
            /// The WGSL declaration of this struct, generated from its Rust fields.
            pub fn wgsl() -> String {
                let mut s = String::from(concat!("struct ", $wgsl, " {\n"));
                $(
                    s.push_str(concat!("    ", stringify!($field), ": "));
                    s.push_str(<$ty as $crate::WgslType>::WGSL);
                    s.push_str(",\n");
                )*
                s.push_str("};\n");
                s
            }
        }
    };
}

#[cfg(test)]
mod tests {
    crate::gpu_struct! {
        #[derive(Clone, Copy, Debug)]
        struct Probe as "ProbeGpu" {
            pub view: [[f32; 4]; 4],
            pub size: [u32; 2],
            pub scale: f32,
            pub flags: u32,
        }
    }

    #[test]
    fn the_declaration_follows_the_fields() {
        assert_eq!(
            Probe::wgsl(),
            "struct ProbeGpu {\n    view: mat4x4<f32>,\n    size: vec2<u32>,\n    scale: f32,\n    flags: u32,\n};\n"
        );
        assert_eq!(std::mem::size_of::<Probe>(), 64 + 8 + 4 + 4);
    }
}
