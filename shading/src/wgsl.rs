//! The WGSL twins of this crate's modules, as one source text that the shader assemblers of
//! the runtime, the GPU bake and the viewer put before their own files ([`source`]). Its
//! constants are generated from the Rust ones, so they cannot drift.

use std::f32::consts::{FRAC_1_PI, FRAC_PI_2, FRAC_PI_4, PI};

use crate::ggx::{DIELECTRIC_F0, MIN_ALPHA};

/// `ggx.wgsl`: the twin of [`crate::ggx`].
const GGX: &str = include_str!("ggx.wgsl");
/// `fresnel.wgsl`: the twin of [`crate::fresnel`].
const FRESNEL: &str = include_str!("fresnel.wgsl");
/// `color.wgsl`: the twin of [`crate::color`].
const COLOR: &str = include_str!("color.wgsl");
/// `random.wgsl`: the twin of [`crate::random`].
const RANDOM: &str = include_str!("random.wgsl");
/// `warp.wgsl`: the twin of [`crate::warp`].
const WARP: &str = include_str!("warp.wgsl");

/// The constants the WGSL modules use, written from the Rust values (Rust's shortest
/// round-trip formatting, which WGSL parses back to the same `f32`).
pub fn constants() -> String {
    let c = |name: &str, v: f32| format!("const {name}: f32 = {v:?};\n");
    [
        "// ---- oslf-shading constants (generated from the Rust values) ----\n".to_string(),
        c("PI", PI),
        c("FRAC_1_PI", FRAC_1_PI),
        c("FRAC_PI_2", FRAC_PI_2),
        c("FRAC_PI_4", FRAC_PI_4),
        c("GGX_MIN_ALPHA", MIN_ALPHA),
        c("GGX_DIELECTRIC_F0", DIELECTRIC_F0),
    ]
    .concat()
}

/// Every WGSL module of this crate, constants first, to put before a shader's own files.
pub fn source() -> String {
    [constants().as_str(), GGX, FRESNEL, COLOR, RANDOM, WARP].join("\n")
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The names of the `fn`s declared in `src` (Rust `pub fn` or WGSL `fn` at line start),
    /// tests excluded, in order.
    fn functions(src: &str, keyword: &str) -> Vec<String> {
        let body = src.split("#[cfg(test)]").next().unwrap();
        body.lines()
            .filter_map(|l| l.strip_prefix(keyword))
            .map(|l| l.split('(').next().unwrap().to_string())
            .collect()
    }

    /// Each Rust module and its WGSL twin declare the same functions (the WGSL's with the
    /// module's prefix) in the same order.
    #[test]
    fn twins_declare_the_same_functions_in_order() {
        for (prefix, rust, wgsl) in [
            ("ggx_", include_str!("ggx.rs"), GGX),
            ("fresnel_", include_str!("fresnel.rs"), FRESNEL),
            ("", include_str!("color.rs"), COLOR),
        ] {
            let rust: Vec<String> = functions(rust, "pub fn ")
                .into_iter()
                .map(|f| format!("{prefix}{f}"))
                .collect();
            assert!(!rust.is_empty());
            assert_eq!(rust, functions(wgsl, "fn "), "{prefix}");
        }
    }

    #[test]
    fn constants_parse_back_to_the_rust_values() {
        for (name, v) in [("PI", PI), ("GGX_MIN_ALPHA", MIN_ALPHA)] {
            let line = constants()
                .lines()
                .find(|l| l.starts_with(&format!("const {name}:")))
                .unwrap()
                .to_string();
            let text = line.rsplit(' ').next().unwrap().trim_end_matches(';');
            assert_eq!(text.parse::<f32>().unwrap(), v, "{line}");
        }
    }

    /// The warps the GPU draws are Rust's, in Rust's order (`frame_from_normal` is
    /// `Frame::from_normal`; the inverses and most densities are Rust only).
    #[test]
    fn warps_follow_the_rust_order() {
        let rust: Vec<String> = include_str!("warp.rs")
            .split("#[cfg(test)]")
            .next()
            .unwrap()
            .lines()
            .filter_map(|l| l.trim_start().strip_prefix("pub fn "))
            .map(|l| l.split('(').next().unwrap().to_string())
            .collect();
        let wgsl: Vec<String> = functions(WARP, "fn ")
            .into_iter()
            .map(|f| f.trim_start_matches("frame_").to_string())
            .collect();
        assert_eq!(wgsl.len(), 7, "{wgsl:?}");
        let mut at = 0;
        for f in &wgsl {
            let found = rust[at..].iter().position(|r| r == f);
            let found =
                found.unwrap_or_else(|| panic!("{f} is not in warp.rs after {at}: {rust:?}"));
            at += found + 1;
        }
    }
}
