//! Writes `examples/blob.glb`, the mesh OSLF object of `examples/meshes.toml`: a smooth,
//! lumpy blob (an icosahedron subdivided three times, 1 280 triangles, pushed out along its
//! normals by a sum of three low-frequency waves) standing on the table of `examples/room.glb`.
//! It has positions, smooth normals and indices but **no texture coordinates**, so the bake
//! lays out its sample maps in an atlas of per-triangle charts.
//!
//! ```sh
//! cargo run -p oslf-bake --example make_blob_gltf [-- OUTPUT.glb]
//! ```
//!
//! glTF coordinates (Y up, metres), as room.glb's. The file is deterministic.

#[path = "../tests/data/gltf_builder.rs"]
mod gltf_builder;

use std::collections::HashMap;
use std::path::PathBuf;

use glam::Vec3;
use gltf_builder::Builder;
use serde_json::json;

/// Radius of the blob before its waves, metres.
const RADIUS: f32 = 0.17;
/// Height of the table top in room.glb.
const TABLE_TOP: f32 = 0.78;

/// The icosahedron's 12 vertices and 20 counter-clockwise faces.
fn icosahedron() -> (Vec<Vec3>, Vec<[u32; 3]>) {
    let t = (1.0 + 5f32.sqrt()) / 2.0;
    let v = [
        [-1.0, t, 0.0],
        [1.0, t, 0.0],
        [-1.0, -t, 0.0],
        [1.0, -t, 0.0],
        [0.0, -1.0, t],
        [0.0, 1.0, t],
        [0.0, -1.0, -t],
        [0.0, 1.0, -t],
        [t, 0.0, -1.0],
        [t, 0.0, 1.0],
        [-t, 0.0, -1.0],
        [-t, 0.0, 1.0],
    ]
    .map(|p| Vec3::from_array(p).normalize());
    let f = vec![
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    (v.to_vec(), f)
}

/// Splits every triangle into four, projecting new vertices onto the unit sphere.
fn subdivide(points: &mut Vec<Vec3>, faces: &[[u32; 3]]) -> Vec<[u32; 3]> {
    let mut midpoint: HashMap<(u32, u32), u32> = HashMap::new();
    let mut mid = |a: u32, b: u32, points: &mut Vec<Vec3>| {
        *midpoint.entry((a.min(b), a.max(b))).or_insert_with(|| {
            points.push((points[a as usize] + points[b as usize]).normalize());
            (points.len() - 1) as u32
        })
    };
    let mut out = Vec::with_capacity(faces.len() * 4);
    for &[a, b, c] in faces {
        let ab = mid(a, b, points);
        let bc = mid(b, c, points);
        let ca = mid(c, a, points);
        out.extend([[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]);
    }
    out
}

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
    let (mut dirs, mut faces) = icosahedron();
    for _ in 0..3 {
        faces = subdivide(&mut dirs, &faces);
    }
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
    let glb = b.glb(doc);
    std::fs::write(&out, &glb).unwrap_or_else(|e| panic!("{}: {e}", out.display()));
    println!(
        "{} ({} bytes, {} triangles)",
        out.display(),
        glb.len(),
        faces.len()
    );
}
