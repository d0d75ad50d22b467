//! Writes `examples/room.glb`, the glTF room that `examples/room.toml` includes: a 6 × 3 × 6 m
//! room (glTF: Y up, metres) with a window in its west wall, a table, a textured ball, a
//! camera, and three `KHR_lights_punctual` lights: the sun through the window (directional),
//! a lamp over the table (spot) and a ceiling light (point).
//!
//! ```sh
//! cargo run -p oslf-bake --example make_room_gltf [-- OUTPUT.glb]
//! ```
//!
//! The file is deterministic (no randomness, no time stamps), 36 kB.

#[path = "../tests/data/gltf_builder.rs"]
mod gltf_builder;

use std::path::PathBuf;

use glam::{Mat3, Quat, Vec3};
use gltf_builder::Builder;
use serde_json::{json, Value};

/// One primitive's vertex data.
#[derive(Default)]
struct Part {
    positions: Vec<[f32; 3]>,
    normals: Vec<[f32; 3]>,
    uvs: Vec<[f32; 2]>,
    indices: Vec<u16>,
}

impl Part {
    /// A quad `a b c d` (counter-clockwise seen from the side `normal` points to), uv (0, 0) at
    /// `a` and (`uv.0`, `uv.1`) at `c`.
    fn quad(&mut self, a: Vec3, b: Vec3, c: Vec3, d: Vec3, uv: (f32, f32)) {
        let n = (b - a).cross(d - a).normalize();
        let base = self.positions.len() as u16;
        for (p, t) in
            [a, b, c, d]
                .into_iter()
                .zip([[0.0, 0.0], [uv.0, 0.0], [uv.0, uv.1], [0.0, uv.1]])
        {
            self.positions.push(p.to_array());
            self.normals.push(n.to_array());
            self.uvs.push(t);
        }
        self.indices
            .extend([base, base + 1, base + 2, base, base + 2, base + 3]);
    }

    /// An axis-aligned box, faces outward.
    fn cuboid(&mut self, centre: Vec3, size: Vec3) {
        let h = size * 0.5;
        let c = |x: f32, y: f32, z: f32| centre + Vec3::new(x * h.x, y * h.y, z * h.z);
        let faces = [
            [
                c(-1., -1., 1.),
                c(1., -1., 1.),
                c(1., 1., 1.),
                c(-1., 1., 1.),
            ],
            [
                c(1., -1., -1.),
                c(-1., -1., -1.),
                c(-1., 1., -1.),
                c(1., 1., -1.),
            ],
            [
                c(1., -1., 1.),
                c(1., -1., -1.),
                c(1., 1., -1.),
                c(1., 1., 1.),
            ],
            [
                c(-1., -1., -1.),
                c(-1., -1., 1.),
                c(-1., 1., 1.),
                c(-1., 1., -1.),
            ],
            [
                c(-1., 1., 1.),
                c(1., 1., 1.),
                c(1., 1., -1.),
                c(-1., 1., -1.),
            ],
            [
                c(-1., -1., -1.),
                c(1., -1., -1.),
                c(1., -1., 1.),
                c(-1., -1., 1.),
            ],
        ];
        for [a, b, cc, d] in faces {
            self.quad(a, b, cc, d, (1.0, 1.0));
        }
    }

    /// A UV sphere: u around (from +x towards −z), v from the south pole up.
    fn sphere(&mut self, radius: f32, segments: u16, rings: u16) {
        let base = self.positions.len() as u16;
        for r in 0..=rings {
            let theta = std::f32::consts::PI * r as f32 / rings as f32; // from the south pole
            for s in 0..=segments {
                let phi = std::f32::consts::TAU * s as f32 / segments as f32;
                let n = Vec3::new(
                    theta.sin() * phi.cos(),
                    -theta.cos(),
                    -theta.sin() * phi.sin(),
                );
                self.positions.push((n * radius).to_array());
                self.normals.push(n.to_array());
                // glTF's v runs down the image: the north pole at v = 0.
                self.uvs
                    .push([s as f32 / segments as f32, 1.0 - r as f32 / rings as f32]);
            }
        }
        let row = segments + 1;
        for r in 0..rings {
            for s in 0..segments {
                let a = base + r * row + s;
                let (b, c, d) = (a + 1, a + row + 1, a + row);
                self.indices.extend([a, b, c, a, c, d]);
            }
        }
    }

    fn primitive(&self, b: &mut Builder, material: usize) -> Value {
        let pos = b.positions(&self.positions);
        let nor = b.vec3(&self.normals);
        let uv = b.vec2(&self.uvs);
        let idx = b.indices_u16(&self.indices);
        json!({
            "attributes": {"POSITION": pos, "NORMAL": nor, "TEXCOORD_0": uv},
            "indices": idx,
            "material": material,
        })
    }
}

/// The room's shell, normals inward: floor, ceiling and four walls, the west wall (x = −3)
/// with a window 1.6 wide (z ∈ [−0.8, 0.8]) and 1.2 high (y ∈ [1.0, 2.2]).
fn room() -> (Part, Part, Part) {
    let v = Vec3::new;
    let (w, h) = (3.0, 3.0);
    let mut floor = Part::default();
    floor.quad(
        v(-w, 0., w),
        v(w, 0., w),
        v(w, 0., -w),
        v(-w, 0., -w),
        (1.0, 1.0),
    );
    let mut walls = Part::default();
    walls.quad(
        v(-w, h, -w),
        v(w, h, -w),
        v(w, h, w),
        v(-w, h, w),
        (1.0, 1.0),
    ); // ceiling
    walls.quad(
        v(-w, 0., -w),
        v(w, 0., -w),
        v(w, h, -w),
        v(-w, h, -w),
        (1.0, 1.0),
    ); // north
    walls.quad(
        v(w, 0., w),
        v(-w, 0., w),
        v(-w, h, w),
        v(w, h, w),
        (1.0, 1.0),
    ); // south
    let mut east = Part::default();
    east.quad(
        v(w, 0., -w),
        v(w, 0., w),
        v(w, h, w),
        v(w, h, -w),
        (1.0, 1.0),
    );
    // West wall around the window, seen from inside (+x): z from −3 to 3 left to right.
    let (z0, z1, y0, y1) = (-0.8, 0.8, 1.0, 2.2);
    let west = |p: &mut Part, za: f32, zb: f32, ya: f32, yb: f32| {
        p.quad(
            v(-w, ya, zb),
            v(-w, ya, za),
            v(-w, yb, za),
            v(-w, yb, zb),
            (1.0, 1.0),
        );
    };
    west(&mut walls, -w, z0, 0., h);
    west(&mut walls, z1, w, 0., h);
    west(&mut walls, z0, z1, 0., y0);
    west(&mut walls, z0, z1, y1, h);
    (floor, walls, east)
}

/// The rotation whose −z looks along `forward` with +y as near `up` as it can be.
fn look(forward: Vec3, up: Vec3) -> Quat {
    let f = forward.normalize();
    let r = f.cross(up).normalize();
    let u = r.cross(f);
    Quat::from_mat3(&Mat3::from_cols(r, u, -f))
}

fn texture_pixels(w: u32, h: u32, f: impl Fn(u32, u32) -> [u8; 3]) -> Vec<u8> {
    (0..h)
        .flat_map(|y| (0..w).map(move |x| (x, y)))
        .flat_map(|(x, y)| f(x, y))
        .collect()
}

fn main() {
    let out = std::env::args().nth(1).map_or_else(
        || PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../examples/room.glb"),
        PathBuf::from,
    );
    let mut b = Builder::new();
    // Textures (sRGB): floor planks, 32 × 32; the ball's stripes, 16 × 8.
    let planks = texture_pixels(32, 32, |x, y| {
        let plank = x / 8;
        let seam = x % 8 == 0 || (y + plank * 11) % 32 == 0;
        let grain = ((y * 7 + plank * 13) % 5) as u8 * 4;
        if seam {
            [70, 45, 25]
        } else {
            [150 + grain, 105 + grain / 2, 62]
        }
    });
    let stripes = texture_pixels(16, 8, |x, y| {
        if (x / 2 + y / 2) % 2 == 0 {
            [230, 200, 40]
        } else {
            [40, 90, 200]
        }
    });
    let planks_view = b.png(32, 32, &planks);
    let stripes_view = b.png(16, 8, &stripes);

    let (floor, walls, east) = room();
    let mut table = Part::default();
    table.cuboid(Vec3::new(0.0, 0.75, 0.0), Vec3::new(1.6, 0.06, 1.0));
    for (x, z) in [(-0.7, -0.4), (0.7, -0.4), (-0.7, 0.4), (0.7, 0.4)] {
        table.cuboid(Vec3::new(x, 0.36, z), Vec3::new(0.06, 0.72, 0.06));
    }
    let mut ball = Part::default();
    ball.sphere(0.35, 32, 16);

    let floor_prim = floor.primitive(&mut b, 0);
    let walls_prim = walls.primitive(&mut b, 1);
    let east_prim = east.primitive(&mut b, 2);
    let table_prim = table.primitive(&mut b, 3);
    let ball_prim = ball.primitive(&mut b, 4);

    let camera_pos = Vec3::new(2.3, 1.55, 2.5);
    let camera_rot = look(Vec3::new(0.0, 0.85, 0.0) - camera_pos, Vec3::Y);
    // The sun enters through the window going east, down, a little south.
    let sun_rot = Quat::from_rotation_arc(Vec3::NEG_Z, Vec3::new(1.0, -0.75, 0.25).normalize());
    let down = look(Vec3::NEG_Y, Vec3::NEG_Z);
    let lm = 683.0; // lumens per watt: the intensities below are W/sr or W/m² × 683.
    let doc = json!({
        "extensionsUsed": ["KHR_lights_punctual", "KHR_texture_transform"],
        "extensions": {"KHR_lights_punctual": {"lights": [
            {"name": "Sun", "type": "directional", "color": [1.0, 0.92, 0.8],
             "intensity": 5.0 * lm},
            {"name": "Table lamp", "type": "spot", "color": [1.0, 0.85, 0.6],
             "intensity": 3.0 * lm,
             "spot": {"innerConeAngle": 0.35, "outerConeAngle": 0.6}},
            {"name": "Ceiling", "type": "point", "intensity": 4.0 * lm},
        ]}},
        "scene": 0,
        "scenes": [{"name": "Room", "nodes": [0, 1, 2, 3, 4, 5, 6]}],
        "nodes": [
            {"name": "Room", "mesh": 0},
            {"name": "Table", "mesh": 1, "translation": [0.0, 0.0, 0.0]},
            {"name": "Ball", "mesh": 2, "translation": [0.6, 0.35, -1.7],
             "rotation": Quat::from_rotation_y(0.6).to_array()},
            {"name": "Camera", "camera": 0, "translation": camera_pos.to_array(),
             "rotation": camera_rot.to_array()},
            {"name": "Sun", "rotation": sun_rot.to_array(),
             "extensions": {"KHR_lights_punctual": {"light": 0}}},
            {"name": "Table lamp", "translation": [0.0, 2.9, 0.0], "rotation": down.to_array(),
             "extensions": {"KHR_lights_punctual": {"light": 1}}},
            {"name": "Ceiling light", "translation": [0.5, 2.8, 1.2],
             "extensions": {"KHR_lights_punctual": {"light": 2}}},
        ],
        "cameras": [{"name": "View", "type": "perspective",
            "perspective": {"yfov": 0.75, "aspectRatio": 1.424, "znear": 0.05}}],
        "images": [
            {"name": "planks", "bufferView": planks_view, "mimeType": "image/png"},
            {"name": "stripes", "bufferView": stripes_view, "mimeType": "image/png"},
        ],
        "samplers": [{"magFilter": 9729, "minFilter": 9729, "wrapS": 10497, "wrapT": 10497}],
        "textures": [{"source": 0, "sampler": 0}, {"source": 1, "sampler": 0}],
        "materials": [
            {"name": "Floor", "pbrMetallicRoughness": {"metallicFactor": 0.0,
                "baseColorTexture": {"index": 0, "extensions": {"KHR_texture_transform":
                    {"scale": [4.0, 4.0]}}}}},
            {"name": "Plaster", "pbrMetallicRoughness": {"metallicFactor": 0.0,
                "baseColorFactor": [0.78, 0.76, 0.72, 1.0]}},
            {"name": "Accent wall", "pbrMetallicRoughness": {"metallicFactor": 0.0,
                "baseColorFactor": [0.55, 0.22, 0.18, 1.0]}},
            {"name": "Table", "pbrMetallicRoughness": {"metallicFactor": 0.0,
                "baseColorFactor": [0.35, 0.22, 0.12, 1.0]}},
            {"name": "Ball", "pbrMetallicRoughness": {"metallicFactor": 0.0,
                "baseColorTexture": {"index": 1}}},
        ],
        "meshes": [
            {"name": "Room", "primitives": [floor_prim, walls_prim, east_prim]},
            {"name": "Table", "primitives": [table_prim]},
            {"name": "Ball", "primitives": [ball_prim]},
        ],
    });
    let glb = b.glb(doc);
    std::fs::write(&out, &glb).unwrap_or_else(|e| panic!("{}: {e}", out.display()));
    println!("{} ({} bytes)", out.display(), glb.len());
}
