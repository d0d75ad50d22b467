//! Writes a scan-like test asset: the lumpy blob of `make_blob_gltf` at 81 920 triangles (an
//! icosahedron subdivided six times) with a fine ripple on top, 0.25 m across, resting on
//! z = 0, as a Wavefront OBJ **without normals or texture coordinates**, as scanned meshes
//! often come. docs/measurements.md ("Hard-surface and scanned assets") bakes it on the table
//! of `examples/room.glb`.
//!
//! ```sh
//! cargo run --release -p oslf-bake --example make_scan_obj -- OUTPUT.obj
//! ```
//!
//! Z up, metres. The file is deterministic.

use std::fmt::Write as _;
use std::path::PathBuf;

use glam::Vec3;

/// Radius before the waves, metres.
const RADIUS: f32 = 0.12;

/// The radius along unit direction `d`: three low-frequency waves and a fine ripple.
fn radius(d: Vec3) -> f32 {
    let wave = 0.16 * (3.0 * d.x).sin() * (2.0 * d.z + 0.5).cos()
        + 0.10 * (4.0 * d.y + 1.0).sin()
        + 0.08 * (5.0 * d.z).cos() * d.x;
    let ripple = 0.015 * (23.0 * d.x + 7.0 * d.y).sin() * (19.0 * d.z - 5.0 * d.x).sin();
    RADIUS * (1.0 + wave + ripple)
}

fn main() {
    let Some(out) = std::env::args().nth(1).map(PathBuf::from) else {
        eprintln!("usage: make_scan_obj OUTPUT.obj");
        std::process::exit(2);
    };
    let sphere = oslf_geometry::mesh::Mesh::icosphere(6);
    let positions: Vec<Vec3> = sphere.positions.iter().map(|&d| d * radius(d)).collect();
    let lowest = positions.iter().map(|p| p.z).fold(f32::MAX, f32::min);
    let mut text = String::with_capacity(64 * positions.len());
    for p in &positions {
        writeln!(text, "v {:.6} {:.6} {:.6}", p.x, p.y, p.z - lowest).expect("writing to a String");
    }
    for t in &sphere.triangles {
        writeln!(text, "f {} {} {}", t[0] + 1, t[1] + 1, t[2] + 1).expect("writing to a String");
    }
    if let Err(e) = std::fs::write(&out, text) {
        eprintln!("error: cannot write {}: {e}", out.display());
        std::process::exit(1);
    }
    println!(
        "{}: {} triangles, {} vertices",
        out.display(),
        sphere.triangles.len(),
        positions.len()
    );
}
