//! Writes `examples/can.glb`, the real-scale test asset of `examples/can.toml`: an aluminium
//! drinks can, 66 mm across and 122 mm tall (a 355 ml can), standing on the table of
//! `examples/room.glb`. It is a surface of revolution of a can's profile (domed base, chime,
//! body, necked shoulder, rim, recessed lid), 96 segments around, with a painted label over
//! bare metal through two textures:
//! - `baseColorTexture` (sRGB): a red label with white bands and a row of dark blue lozenges
//!   on the body; brushed aluminium grey elsewhere;
//! - `metallicRoughnessTexture`: the label is paint (metallic 0, roughness 0.35), the rest
//!   metal (metallic 1, roughness 0.12).
//!
//! Its `TEXCOORD_0` (u around, v along the profile from the lid's centre down) is a
//! non-overlapping layout inside [0, 1]², so the bake uses it as the atlas too.
//!
//! ```sh
//! cargo run -p oslf-bake --example make_can_gltf [-- OUTPUT.glb]
//! ```
//!
//! glTF coordinates (Y up, metres), as room.glb's. The file is deterministic.

#[path = "../tests/data/gltf_builder.rs"]
mod gltf_builder;

use std::path::PathBuf;

use gltf_builder::Builder;
use serde_json::json;

/// Height of the table top in room.glb.
const TABLE_TOP: f32 = 0.78;
/// Where the can stands on the table (glTF x, z): beside the teapot of room.toml.
const PLACE: [f32; 2] = [-0.05, 0.02];
/// The profile from the lid's centre to the base's centre: (radius, height), metres.
const PROFILE: [[f32; 2]; 12] = [
    [0.0, 0.1175],
    [0.0245, 0.1175],
    [0.0262, 0.1220],
    [0.0276, 0.1210],
    [0.0290, 0.1160],
    [0.0330, 0.1050],
    [0.0330, 0.0120],
    [0.0318, 0.0050],
    [0.0270, 0.0000],
    [0.0240, 0.0010],
    [0.0200, 0.0050],
    [0.0, 0.0070],
];
/// The label covers the body between these heights (metres).
const LABEL: [f32; 2] = [0.014, 0.102];
/// Segments around.
const SEGMENTS: u32 = 96;
/// Subdivisions of each profile segment (the body's long segment gets proportionally more).
const STEP: f32 = 0.004;

fn main() {
    let out = std::env::args().nth(1).map_or_else(
        || PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../examples/can.glb"),
        PathBuf::from,
    );
    // The profile resampled: points, their outward normals in (r, y), arc length.
    let mut ring: Vec<([f32; 2], [f32; 2], f32)> = Vec::new();
    let mut arc = 0.0f32;
    for w in PROFILE.windows(2) {
        let ([r0, y0], [r1, y1]) = (w[0], w[1]);
        let len = (r1 - r0).hypot(y1 - y0);
        // The profile runs around the outside: the outward normal is its direction turned
        // 90° counter-clockwise in (r, y).
        let n = [-(y1 - y0) / len, (r1 - r0) / len];
        let steps = ((len / STEP).ceil() as u32).max(1);
        // Each segment has rings of its own at both ends: hard edges where the profile turns.
        for k in 0..=steps {
            let t = k as f32 / steps as f32;
            ring.push(([r0 + t * (r1 - r0), y0 + t * (y1 - y0)], n, arc + t * len));
        }
        arc += len;
    }
    let (mut positions, mut normals, mut uvs, mut indices) = (vec![], vec![], vec![], vec![]);
    for &([r, y], [nr, ny], s) in &ring {
        for k in 0..=SEGMENTS {
            let phi = std::f32::consts::TAU * k as f32 / SEGMENTS as f32;
            let (c, sn) = (phi.cos(), phi.sin());
            positions.push([PLACE[0] + r * c, TABLE_TOP + y, PLACE[1] - r * sn]);
            let n = [nr * c, ny, -nr * sn];
            let l = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
            normals.push([n[0] / l, n[1] / l, n[2] / l]);
            uvs.push([k as f32 / SEGMENTS as f32, s / arc]);
        }
    }
    let row = SEGMENTS + 1;
    for i in 0..ring.len() as u32 - 1 {
        if ring[i as usize].0 == ring[i as usize + 1].0 {
            continue; // the joint between two segments' rings
        }
        for k in 0..SEGMENTS {
            let a = i * row + k;
            // Counter-clockwise seen from outside (the profile runs downwards).
            indices.extend([a, a + row, a + row + 1, a, a + row + 1, a + 1]);
        }
    }
    // Textures: u around (256 texels), v along the profile (128 texels).
    let (w, h) = (256u32, 128u32);
    let height_at = |v: f32| -> f32 {
        let s = v * arc;
        let i = ring.partition_point(|p| p.2 < s).min(ring.len() - 1);
        ring[i].0[1]
    };
    let mut colour = Vec::with_capacity((w * h * 3) as usize);
    let mut mr = Vec::with_capacity((w * h * 3) as usize);
    for y in 0..h {
        let height = height_at((y as f32 + 0.5) / h as f32);
        let on_label = (LABEL[0]..=LABEL[1]).contains(&height);
        for x in 0..w {
            let u = (x as f32 + 0.5) / w as f32;
            let rgb: [u8; 3] = if !on_label {
                [200, 203, 207]
            } else {
                let t = (height - LABEL[0]) / (LABEL[1] - LABEL[0]);
                let band = (0.18..0.24).contains(&t) || (0.76..0.82).contains(&t);
                // A row of lozenges around the middle of the label.
                let (cu, ct) = ((u * 12.0).fract() - 0.5, (t - 0.5) / 0.12);
                let lozenge = cu.abs() * 2.0 + ct.abs() < 1.0;
                if band {
                    [236, 236, 230]
                } else if lozenge {
                    [24, 40, 110]
                } else {
                    [178, 22, 30]
                }
            };
            colour.extend(rgb);
            mr.extend(if on_label { [0, 89, 0] } else { [0, 31, 255] });
        }
    }
    let mut b = Builder::new();
    let colour_image = b.png(w, h, &colour);
    let mr_image = b.png(w, h, &mr);
    let pos = b.positions(&positions);
    let nor = b.vec3(&normals);
    let uv = b.vec2(&uvs);
    let idx = b.indices_u32(&indices);
    let doc = json!({
        "scene": 0,
        "scenes": [{"name": "Can", "nodes": [0]}],
        "nodes": [{"name": "Can", "mesh": 0}],
        "images": [
            {"name": "label colour", "bufferView": colour_image, "mimeType": "image/png"},
            {"name": "label metallic-roughness", "bufferView": mr_image, "mimeType": "image/png"},
        ],
        "samplers": [{"magFilter": 9729, "minFilter": 9729, "wrapS": 10497, "wrapT": 33071}],
        "textures": [{"source": 0, "sampler": 0}, {"source": 1, "sampler": 0}],
        "materials": [{"name": "Painted aluminium", "pbrMetallicRoughness": {
            "baseColorTexture": {"index": 0},
            "metallicFactor": 1.0, "roughnessFactor": 1.0,
            "metallicRoughnessTexture": {"index": 1}}}],
        "meshes": [{"name": "Can", "primitives": [{
            "attributes": {"POSITION": pos, "NORMAL": nor, "TEXCOORD_0": uv},
            "indices": idx,
            "material": 0,
        }]}],
    });
    b.write_glb(doc, &out, indices.len() / 3);
}
