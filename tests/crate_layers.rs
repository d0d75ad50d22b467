//! The workspace's crates form layers: each crate's normal dependencies on other oslf crates
//! lie below it, and the rules each crate's `lib.rs` states ("never depends on …") hold in its
//! Cargo.toml. Read from the manifests, so a new edge that breaks a layer fails here.

use std::path::Path;

/// Bottom to top. A crate may depend (normally, not only for its tests) on crates before it.
const LAYERS: [&str; 13] = [
    "oslf-shading",
    "oslf-util",
    "oslf-geometry",
    "oslf-format",
    "oslf-gpu",
    "oslf-scene",
    "oslf-trace",
    "oslf-bake",
    "oslf-runtime",
    "oslf-bake-gpu",
    "oslf-measure",
    "oslf-bevy",
    "oslf",
];

/// Dependencies a crate must never have, whatever the layers allow.
const NEVER: [(&str, &[&str]); 7] = [
    ("oslf-scene", &["oslf-trace", "oslf-bake", "wgpu"]),
    ("oslf-trace", &["oslf-bake", "wgpu"]),
    ("oslf-bake", &["wgpu", "oslf-runtime"]),
    (
        "oslf-runtime",
        &["oslf-scene", "oslf-trace", "oslf-bake", "oslf-bake-gpu"],
    ),
    ("oslf-format", &["clap", "anyhow", "indicatif"]),
    (
        "oslf-gpu",
        &[
            "oslf-shading",
            "oslf-util",
            "oslf-geometry",
            "oslf-format",
            "oslf-scene",
            "oslf-trace",
            "oslf-bake",
        ],
    ),
    ("oslf-bake-gpu", &["oslf-runtime"]),
];

/// The `[package] name` and the names under `[dependencies]` (and target-specific
/// `dependencies` tables) of a manifest.
fn manifest(text: &str) -> (String, Vec<String>) {
    let mut name = String::new();
    let mut section = String::new();
    let mut deps = Vec::new();
    for line in text.lines() {
        let line = line.trim();
        if line.starts_with('[') {
            section = line.trim_matches(['[', ']']).to_string();
            continue;
        }
        if line.starts_with('#') || line.is_empty() {
            continue;
        }
        let key = line.split(['=', '.', ' ']).next().unwrap_or_default();
        if section == "package" && key == "name" {
            name = line.split('"').nth(1).unwrap_or_default().to_string();
        }
        if section == "dependencies" || section.ends_with(".dependencies") {
            deps.push(key.to_string());
        }
    }
    (name, deps)
}

#[test]
fn crates_depend_only_downwards() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut manifests = vec![root.join("Cargo.toml")];
    for entry in std::fs::read_dir(root).unwrap() {
        let dir = entry.unwrap().path();
        if dir.join("Cargo.toml").is_file() && dir.join("src").is_dir() {
            manifests.push(dir.join("Cargo.toml"));
        }
    }
    let mut report = Vec::new();
    let mut seen = Vec::new();
    for path in &manifests {
        let (name, deps) = manifest(&std::fs::read_to_string(path).unwrap());
        let Some(rank) = LAYERS.iter().position(|l| *l == name) else {
            report.push(format!("{name} ({}) has no layer here", path.display()));
            continue;
        };
        seen.push(name.clone());
        for dep in deps.iter().filter(|d| d.starts_with("oslf")) {
            match LAYERS.iter().position(|l| l == dep) {
                Some(r) if r < rank => {}
                _ => report.push(format!("{name} depends on {dep}, not below it")),
            }
        }
        for (crate_name, never) in NEVER {
            if crate_name == name {
                for dep in deps.iter().filter(|d| never.contains(&d.as_str())) {
                    report.push(format!("{name} must never depend on {dep}"));
                }
            }
        }
    }
    assert_eq!(seen.len(), LAYERS.len(), "crates found: {seen:?}");
    assert!(report.is_empty(), "{}", report.join("\n"));
}

#[test]
fn manifests_are_read_as_cargo_reads_them() {
    let (name, deps) = manifest(
        "[package]\nname = \"oslf-trace\"\n\n[dependencies]\n# a comment\noslf-bake.workspace = \
         true\nglam = { workspace = true }\n\n[dev-dependencies]\noslf-runtime.workspace = true\n\
         [target.'cfg(unix)'.dependencies]\nrustix = \"1\"\n",
    );
    assert_eq!(name, "oslf-trace");
    assert_eq!(deps, ["oslf-bake", "glam", "rustix"]);
}
