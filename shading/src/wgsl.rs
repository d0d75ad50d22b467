//! The WGSL twins of this crate's modules, as WGSL modules with imports (the WESL module
//! system: `import package::shading::ggx::{ggx_d};`) that the shaders of the runtime, the GPU
//! bake and the viewer import ([`modules`]). Its constants are a module generated from the Rust
//! ones (`package::shading::constants`), so they cannot drift.
//!
//! Each shader is assembled from its modules by [`assemble`] (feature `assemble`, the `wesl`
//! crate) into one WGSL file that the crate embeds (its `generated/` folder); each crate's tests
//! assemble it again and fail where the embedded file differs, so that a change to a module
//! reaches every shader that imports it (`OSLF_BLESS=1` rewrites the files).

use std::f32::consts::{FRAC_1_PI, FRAC_PI_2, FRAC_PI_4, PI};

use crate::ggx::{DIELECTRIC_F0, MIN_ALPHA};
use crate::sh;

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
/// `sh.wgsl`: the twin of [`crate::sh`].
const SH: &str = include_str!("sh.wgsl");

/// The constants the WGSL modules use, written from the Rust values (Rust's shortest
/// round-trip formatting, which WGSL parses back to the same `f32`).
pub fn constants() -> String {
    let c = |name: &str, v: f32| format!("const {name}: f32 = {v:?};\n");
    let v3 = |name: &str, v: [f32; 3]| {
        format!(
            "const {name}: vec3<f32> = vec3<f32>({:?}, {:?}, {:?});\n",
            v[0], v[1], v[2]
        )
    };
    [
        "// ---- oslf-shading constants (generated from the Rust values) ----\n".to_string(),
        c("PI", PI),
        c("FRAC_1_PI", FRAC_1_PI),
        c("FRAC_PI_2", FRAC_PI_2),
        c("FRAC_PI_4", FRAC_PI_4),
        c("GGX_MIN_ALPHA", MIN_ALPHA),
        c("GGX_DIELECTRIC_F0", DIELECTRIC_F0),
        c("SH_Y0", sh::Y0),
        c("SH_Y1", sh::Y1),
        c("SH_Y2", sh::Y2),
        c("SH_Y20", sh::Y20),
        c("SH_Y22", sh::Y22),
        v3("SH_COSINE", sh::COSINE),
        v3("SH_AS_DIFFUSE", sh::AS_DIFFUSE),
    ]
    .concat()
}

/// Every WGSL module of this crate as (module path under `package::`, source).
pub fn modules() -> Vec<(String, String)> {
    [
        ("shading::constants", constants()),
        ("shading::ggx", GGX.into()),
        ("shading::fresnel", FRESNEL.into()),
        ("shading::color", COLOR.into()),
        ("shading::random", RANDOM.into()),
        ("shading::warp", WARP.into()),
        ("shading::sh", SH.into()),
    ]
    .into_iter()
    .map(|(path, src)| (path.to_string(), src))
    .collect()
}

/// Assembles the shader whose root module is `root` (a path under `package::`, such as
/// `shade::pixel`) from `modules` ((path, source) pairs; this crate's [`modules`] among them)
/// into one WGSL source, with the WESL module system: each module's `import`s are resolved,
/// checked (a name used and not declared or imported is an error naming it) and every loaded
/// module's declarations are kept under their own names (no mangling; two modules declaring
/// one name is an error). Comments are not kept.
#[cfg(feature = "assemble")]
pub fn assemble(root: &str, modules: &[(String, String)]) -> Result<String, String> {
    use wesl::syntax::{ModulePath, PathOrigin};
    let path = |p: &str| {
        ModulePath::new(
            PathOrigin::Absolute,
            p.split("::").map(str::to_string).collect(),
        )
    };
    let mut resolver = wesl::resolver::VirtualResolver::new();
    for (p, src) in modules {
        resolver.add_module(path(p), src.as_str().into());
    }
    let options = wesl::CompileOptions {
        mangler: wesl::ManglerKind::None,
        strip: false,
        ..Default::default()
    };
    let compiler = wesl::Compiler::new_with_resolver(options, resolver);
    let mut result = compiler
        .compile_module(&path(root))
        .map_err(|e| format!("{root}: {e}"))?;
    // The compiler gathers declarations in no fixed order: put them in the order of `modules`
    // and, within a module, of its source, so that the same modules give the same text.
    let order = |name: &str| -> Option<(usize, usize)> {
        let patterns = [
            format!("fn {name}("),
            format!("struct {name} "),
            format!("const {name}:"),
            format!("const {name} "),
            format!("override {name}:"),
            format!("alias {name} "),
            format!("> {name}:"),
            format!("var {name}:"),
        ];
        modules.iter().enumerate().find_map(|(m, (_, src))| {
            patterns
                .iter()
                .filter_map(|p| src.find(p.as_str()))
                .min()
                .map(|at| (m, at))
        })
    };
    use wesl::syntax::GlobalDeclaration as G;
    let mut keyed = Vec::new();
    for d in std::mem::take(&mut result.syntax.global_declarations) {
        let name = match d.node() {
            G::Declaration(x) => x.ident.name().clone(),
            G::TypeAlias(x) => x.ident.name().clone(),
            G::Struct(x) => x.ident.name().clone(),
            G::Function(x) => x.ident.name().clone(),
            _ => return Err(format!("{root}: a declaration without a name: {d}")),
        };
        let key = order(&name)
            .ok_or_else(|| format!("{root}: {name} is declared in none of the modules"))?;
        keyed.push((key, d));
    }
    keyed.sort_by_key(|(key, _)| *key);
    result.syntax.global_declarations = keyed.into_iter().map(|(_, d)| d).collect();
    Ok(result.syntax.to_string())
}

/// The first lines of an assembled file.
#[cfg(feature = "assemble")]
fn banner(root: &str) -> String {
    format!(
        "// Assembled by oslf_shading::wgsl::assemble from WGSL modules (root `package::{root}`).\n\
         // Do not edit: edit the modules, then run this crate's tests with OSLF_BLESS=1 to write\n\
         // this file again.\n"
    )
}

/// Checks that `file` (a crate's embedded shader) is what [`assemble`] makes of `root` and
/// `modules`, with a banner; with the environment variable `OSLF_BLESS` set, writes it instead.
/// The error says which file is stale and how to write it again.
#[cfg(feature = "assemble")]
pub fn check_assembled(
    file: &std::path::Path,
    root: &str,
    modules: &[(String, String)],
) -> Result<(), String> {
    let text = banner(root) + &assemble(root, modules)?;
    if std::env::var_os("OSLF_BLESS").is_some() {
        return std::fs::write(file, &text).map_err(|e| format!("{}: {e}", file.display()));
    }
    let found = std::fs::read_to_string(file).map_err(|e| format!("{}: {e}", file.display()))?;
    if found != text {
        return Err(format!(
            "{} is not what its modules assemble to (root {root}): run the tests with \
             OSLF_BLESS=1 to write it again",
            file.display()
        ));
    }
    Ok(())
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
            ("sh_", include_str!("sh.rs"), SH),
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
