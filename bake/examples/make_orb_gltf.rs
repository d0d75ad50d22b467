//! Writes `examples/orb.glb`, the textured OSLF object of `examples/orb.toml`: a metal sphere
//! (a UV sphere of radius 0.16 m, 48 × 24 segments, standing on the table of
//! `examples/room.glb`) whose roughness varies over its surface through a
//! `metallicRoughnessTexture`: four bands from the south pole up, roughness 0.6, 0.3, 0.15 and
//! 0.05, metallic 1 throughout, with a gold `baseColorFactor`. Its `TEXCOORD_0` (u around,
//! v from the north pole down) is a non-overlapping layout inside [0, 1]², so the bake uses it
//! as the atlas too.
//!
//! ```sh
//! cargo run -p oslf-bake --example make_orb_gltf [-- OUTPUT.glb]
//! ```
//!
//! glTF coordinates (Y up, metres), as room.glb's. The file is deterministic.

#[path = "../tests/data/gltf_builder.rs"]
mod gltf_builder;

use std::path::PathBuf;

use gltf_builder::Builder;
use serde_json::json;

/// Radius, metres.
const RADIUS: f32 = 0.16;
/// Height of the table top in room.glb.
const TABLE_TOP: f32 = 0.78;
/// Roughness of each band, from the south pole up (the texture's bottom rows up).
const BANDS: [f32; 4] = [0.6, 0.3, 0.15, 0.05];

fn main() {
    let out = std::env::args().nth(1).map_or_else(
        || PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../examples/orb.glb"),
        PathBuf::from,
    );
    let (segments, rings) = (48u16, 24u16);
    let (mut positions, mut normals, mut uvs, mut indices) = (vec![], vec![], vec![], vec![]);
    for r in 0..=rings {
        let theta = std::f32::consts::PI * f32::from(r) / f32::from(rings); // from the south pole
        for s in 0..=segments {
            let phi = std::f32::consts::TAU * f32::from(s) / f32::from(segments);
            let n = [
                theta.sin() * phi.cos(),
                -theta.cos(),
                -theta.sin() * phi.sin(),
            ];
            positions.push([
                n[0] * RADIUS,
                n[1] * RADIUS + TABLE_TOP + RADIUS,
                n[2] * RADIUS,
            ]);
            normals.push(n);
            // glTF's v runs down the image: the north pole at v = 0.
            uvs.push([
                f32::from(s) / f32::from(segments),
                1.0 - f32::from(r) / f32::from(rings),
            ]);
        }
    }
    let row = segments + 1;
    for r in 0..rings {
        for s in 0..segments {
            let a = r * row + s;
            indices.extend([a, a + 1, a + row + 1, a, a + row + 1, a + row]);
        }
    }
    // 4 × 16 texels, one band per four rows; row 0 (the image's top) is the north pole's.
    let (w, h) = (4u32, 16u32);
    let texels: Vec<u8> = (0..h)
        .flat_map(|y| {
            let band = BANDS[BANDS.len() - 1 - (y / 4) as usize];
            let g = (band * 255.0).round() as u8;
            (0..w).flat_map(move |_| [0, g, 255])
        })
        .collect();
    let mut b = Builder::new();
    let image = b.png(w, h, &texels);
    let pos = b.positions(&positions);
    let nor = b.vec3(&normals);
    let uv = b.vec2(&uvs);
    let idx = b.indices_u16(&indices);
    let doc = json!({
        "scene": 0,
        "scenes": [{"name": "Orb", "nodes": [0]}],
        "nodes": [{"name": "Orb", "mesh": 0, "translation": [0.0, 0.0, 0.0]}],
        "images": [{"name": "roughness bands", "bufferView": image, "mimeType": "image/png"}],
        "samplers": [{"magFilter": 9729, "minFilter": 9729, "wrapS": 10497, "wrapT": 10497}],
        "textures": [{"source": 0, "sampler": 0}],
        "materials": [{"name": "Banded gold", "pbrMetallicRoughness": {
            "baseColorFactor": [1.0, 0.78, 0.34, 1.0],
            "metallicFactor": 1.0, "roughnessFactor": 1.0,
            "metallicRoughnessTexture": {"index": 0}}}],
        "meshes": [{"name": "Orb", "primitives": [{
            "attributes": {"POSITION": pos, "NORMAL": nor, "TEXCOORD_0": uv},
            "indices": idx,
            "material": 0,
        }]}],
    });
    b.write_glb(doc, &out, indices.len() / 3);
}
