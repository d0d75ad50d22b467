//! Writes `examples/blob.glb`, the mesh OSLF object of `examples/meshes.toml`: a smooth,
//! lumpy blob (an icosahedron subdivided three times, 1 280 triangles, pushed out along its
//! normals by a sum of three low-frequency waves) standing on the table of `examples/room.glb`.
//! It has positions, smooth normals and indices but **no texture coordinates**, so the bake
//! lays out its sample maps in an atlas of charts of its own.
//!
//! ```sh
//! cargo run -p oslf-bake --example make_blob_gltf [-- OUTPUT.glb]
//! ```
//!
//! glTF coordinates (Y up, metres), as room.glb's. The file is deterministic.

#[path = "../tests/data/gltf_builder.rs"]
mod gltf_builder;

use std::path::PathBuf;

use glam::Vec3;
use gltf_builder::Builder;
use serde_json::json;

/// Radius of the blob before its waves, metres.
const RADIUS: f32 = 0.17;
/// Height of the table top in room.glb.
const TABLE_TOP: f32 = 0.78;

/// The blob's radius along unit direction `d`.
fn radius(d: Vec3) -> f32 {
    let wave = 0.16 * (3.0 * d.x).sin() * (2.0 * d.z + 0.5).cos()
        + 0.10 * (4.0 * d.y + 1.0).sin()
        + 0.08 * (5.0 * d.z).cos() * d.x;
    RADIUS * (1.0 + wave)
}

fn main() {
    let out = std::env::args().nth(1).map_or_else(
        || PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../examples/blob.glb"),
        PathBuf::from,
    );
    let sphere = oslf_geometry::mesh::Mesh::icosphere(3);
    let (dirs, faces) = (sphere.positions, sphere.triangles);
    // Lift so the lowest point rests on the table top.
    let lowest = dirs
        .iter()
        .map(|&d| d.y * radius(d))
        .fold(f32::MAX, f32::min);
    let lift = Vec3::new(0.0, TABLE_TOP - lowest, 0.0);
    let positions: Vec<Vec3> = dirs.iter().map(|&d| d * radius(d) + lift).collect();
    // Smooth normals: area-weighted face normals summed at each vertex.
    let mut normals = vec![Vec3::ZERO; positions.len()];
    for &[a, b, c] in &faces {
        let (pa, pb, pc) = (
            positions[a as usize],
            positions[b as usize],
            positions[c as usize],
        );
        let n = (pb - pa).cross(pc - pa);
        for i in [a, b, c] {
            normals[i as usize] += n;
        }
    }
    let normals: Vec<[f32; 3]> = normals.iter().map(|n| n.normalize().to_array()).collect();
    let positions: Vec<[f32; 3]> = positions.iter().map(|p| p.to_array()).collect();
    let indices: Vec<u32> = faces.iter().flatten().copied().collect();

    let mut b = Builder::new();
    let pos = b.positions(&positions);
    let nor = b.vec3(&normals);
    let idx = b.indices_u32(&indices);
    let doc = json!({
        "scene": 0,
        "scenes": [{"name": "Blob", "nodes": [0]}],
        "nodes": [{"name": "Blob", "mesh": 0, "translation": [-0.3, 0.0, 0.05]}],
        "materials": [{"name": "Glaze", "pbrMetallicRoughness": {"metallicFactor": 0.0,
            "baseColorFactor": [0.62, 0.18, 0.12, 1.0]}}],
        "meshes": [{"name": "Blob", "primitives": [{
            "attributes": {"POSITION": pos, "NORMAL": nor},
            "indices": idx,
            "material": 0,
        }]}],
    });
    b.write_glb(doc, &out, faces.len());
}
