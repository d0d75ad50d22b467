//! Writes `examples/part.glb`, the hard-surface test asset of `examples/part.toml`: a machined
//! steel part at real scale, a hexagonal block 95 mm across the flats and 35 mm tall with a
//! 44 mm bore through it and a 6 mm chamfer around its top, standing on the table of
//! `examples/room.glb`. Flat faces meet at hard edges (each face has vertices and normals of its
//! own); the bore is smooth. One material: polished steel (metallic 1, roughness 0.18), no
//! textures and no texture coordinates, so the bake lays out an atlas of its own.
//!
//! ```sh
//! cargo run -p oslf-bake --example make_part_gltf [-- OUTPUT.glb]
//! ```
//!
//! glTF coordinates (Y up, metres), as room.glb's. The file is deterministic.

#[path = "../tests/data/gltf_builder.rs"]
mod gltf_builder;

use std::f32::consts::{FRAC_PI_3, TAU};
use std::path::PathBuf;

use glam::Vec3;
use gltf_builder::Builder;
use serde_json::json;

/// Height of the table top in room.glb.
const TABLE_TOP: f32 = 0.78;
/// Where the part stands on the table (glTF x, z): where examples/can.toml puts the can.
const PLACE: [f32; 2] = [-0.05, -0.02];
/// The hexagon's apothem (half the width across the flats), metres.
const APOTHEM: f32 = 0.0475;
/// Height, metres.
const HEIGHT: f32 = 0.035;
/// The chamfer around the top, metres (in from the flats and down from the top).
const CHAMFER: f32 = 0.006;
/// The bore's radius, metres.
const BORE: f32 = 0.022;
/// Segments around the bore (8 per side of the hexagon, so its corners are vertices).
const SEGMENTS: u32 = 48;

/// The point at angle `phi` around the axis on the hexagon of apothem `a`, at height `y`.
fn hexagon(a: f32, phi: f32, y: f32) -> Vec3 {
    let side = (phi / FRAC_PI_3).floor().min(5.0);
    let mid = (side + 0.5) * FRAC_PI_3;
    let t = a / (phi - mid).cos();
    at(t, phi, y)
}

/// The point at radius `r` and angle `phi` around the axis, at height `y`, placed on the table.
fn at(r: f32, phi: f32, y: f32) -> Vec3 {
    Vec3::new(
        PLACE[0] + r * phi.cos(),
        TABLE_TOP + y,
        PLACE[1] - r * phi.sin(),
    )
}

/// Triangles with their vertices and normals.
#[derive(Default)]
struct Mesh {
    positions: Vec<[f32; 3]>,
    normals: Vec<[f32; 3]>,
    indices: Vec<u32>,
}

impl Mesh {
    fn vertex(&mut self, p: Vec3, n: Vec3) -> u32 {
        self.positions.push(p.to_array());
        self.normals.push(n.normalize().to_array());
        self.positions.len() as u32 - 1
    }

    /// The quad a, b, c, d (in order around it) facing `facing`: wound counter-clockwise seen
    /// from that side, whatever order the corners came in.
    fn quad(&mut self, v: [u32; 4], facing: Vec3) {
        let p = |i: u32| Vec3::from_array(self.positions[i as usize]);
        let n = (p(v[1]) - p(v[0])).cross(p(v[2]) - p(v[0]));
        let [a, b, c, d] = if n.dot(facing) >= 0.0 {
            v
        } else {
            [v[0], v[3], v[2], v[1]]
        };
        self.indices.extend([a, b, c, a, c, d]);
    }

    /// A flat face: the quad's own four vertices with one normal.
    fn flat(&mut self, p: [Vec3; 4]) {
        let n = (p[1] - p[0]).cross(p[2] - p[0]);
        let centre = (p[0] + p[1] + p[2] + p[3]) / 4.0;
        let axis = Vec3::new(PLACE[0], centre.y, PLACE[1]);
        // Outward: away from the axis for the sides and chamfer, up or down for the ends.
        let out = if n.y.abs() > 0.99 * n.length() {
            Vec3::Y * n.y.signum()
        } else {
            centre - axis
        };
        let n = if n.dot(out) >= 0.0 { n } else { -n };
        let v = p.map(|q| self.vertex(q, n));
        self.quad(v, n);
    }
}

fn main() {
    let out = std::env::args().nth(1).map_or_else(
        || PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../examples/part.glb"),
        PathBuf::from,
    );
    let mut m = Mesh::default();
    let (top, shoulder) = (HEIGHT, HEIGHT - CHAMFER);
    let inner = APOTHEM - CHAMFER;
    let angle = |k: u32| TAU * k as f32 / SEGMENTS as f32;
    for k in 0..SEGMENTS {
        let (p0, p1) = (angle(k), angle(k + 1));
        // The top: between the chamfer's inner hexagon and the bore.
        m.flat([
            hexagon(inner, p0, top),
            hexagon(inner, p1, top),
            at(BORE, p1, top),
            at(BORE, p0, top),
        ]);
        // The bottom, on the table: between the hexagon and the bore.
        m.flat([
            hexagon(APOTHEM, p0, 0.0),
            at(BORE, p0, 0.0),
            at(BORE, p1, 0.0),
            hexagon(APOTHEM, p1, 0.0),
        ]);
        // The bore: smooth, its normals towards the axis.
        let inward = |phi: f32| -Vec3::new(phi.cos(), 0.0, -phi.sin());
        let v = [
            m.vertex(at(BORE, p0, 0.0), inward(p0)),
            m.vertex(at(BORE, p1, 0.0), inward(p1)),
            m.vertex(at(BORE, p1, top), inward(p1)),
            m.vertex(at(BORE, p0, top), inward(p0)),
        ];
        m.quad(v, inward(0.5 * (p0 + p1)));
    }
    for side in 0..6 {
        let (p0, p1) = (side as f32 * FRAC_PI_3, (side + 1) as f32 * FRAC_PI_3);
        // The flat, from the table to the chamfer.
        m.flat([
            hexagon(APOTHEM, p0, 0.0),
            hexagon(APOTHEM, p1, 0.0),
            hexagon(APOTHEM, p1, shoulder),
            hexagon(APOTHEM, p0, shoulder),
        ]);
        // The chamfer, at 45° between the flat and the top.
        m.flat([
            hexagon(APOTHEM, p0, shoulder),
            hexagon(APOTHEM, p1, shoulder),
            hexagon(inner, p1, top),
            hexagon(inner, p0, top),
        ]);
    }
    let mut b = Builder::new();
    let pos = b.positions(&m.positions);
    let nor = b.vec3(&m.normals);
    let idx = b.indices_u32(&m.indices);
    let doc = json!({
        "scene": 0,
        "scenes": [{"name": "Part", "nodes": [0]}],
        "nodes": [{"name": "Part", "mesh": 0}],
        "materials": [{"name": "Polished steel", "pbrMetallicRoughness": {
            "baseColorFactor": [0.56, 0.57, 0.58, 1.0],
            "metallicFactor": 1.0, "roughnessFactor": 0.18}}],
        "meshes": [{"name": "Part", "primitives": [{
            "attributes": {"POSITION": pos, "NORMAL": nor},
            "indices": idx,
            "material": 0,
        }]}],
    });
    b.write_glb(doc, &out, m.indices.len() / 3);
}
