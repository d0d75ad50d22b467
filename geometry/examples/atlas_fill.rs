//! How well the atlas of our own charts fills its pages: the figures of docs/measurements.md,
//! "Hard-surface and scanned assets".
//!
//! ```sh
//! cargo run --release -p oslf-geometry --example atlas_fill [-- MESH.obj ...]
//! ```
//!
//! For the atlas tests' lumpy blob and icosphere (32² pages, texel 0.05), the blob of
//! `examples/meshes.toml` (the lumpy blob at 0.17 m, 128² pages, texel 0.045 / 8, as its bake)
//! and each OBJ given (`v` and `f` lines only, at the blob's options), one line:
//!
//! - pages and charts;
//! - `fill`: `Atlas::fill`, the share of the atlas's texels in a triangle's footprint;
//! - `strict`: the share whose interior a triangle meets (no footprint margin);
//! - `least density`: the least-dense triangle's texels per unit area, times the surface's
//!   area, over the atlas's texels: 1 would be every texel at the density the least-dense
//!   triangle has, what a bake needs;
//! - the time the atlas took.

use std::time::Instant;

use glam::{DVec2, Vec3};
use oslf_geometry::atlas::{Atlas, AtlasOptions};
use oslf_geometry::Mesh;

/// The lumpy blob of `examples/blob.glb` at radius `r` (as `make_blob_gltf`).
fn lumpy(r: f32) -> Mesh {
    let mut mesh = Mesh::icosphere(3);
    for p in &mut mesh.positions {
        let d = *p;
        let wave = 0.16 * (3.0 * d.x).sin() * (2.0 * d.z + 0.5).cos()
            + 0.10 * (4.0 * d.y + 1.0).sin()
            + 0.08 * (5.0 * d.z).cos() * d.x;
        *p = d * (1.0 + wave) * r;
    }
    mesh.compute_smooth_normals();
    mesh
}

/// Positions and faces of an OBJ file (polygons fanned), smooth normals.
fn obj(path: &str) -> Result<Mesh, String> {
    let text = std::fs::read_to_string(path).map_err(|e| format!("{path}: {e}"))?;
    let mut mesh = Mesh::new();
    for (n, line) in text.lines().enumerate() {
        let at = |what: &str| format!("{path}:{}: {what}", n + 1);
        let words: Vec<&str> = line.split_whitespace().collect();
        match words.first() {
            Some(&"v") if words.len() >= 4 => {
                let c: Vec<f32> = words[1..4]
                    .iter()
                    .map(|w| w.parse().map_err(|_| at("a bad coordinate")))
                    .collect::<Result<_, _>>()?;
                mesh.positions.push(Vec3::new(c[0], c[1], c[2]));
            }
            Some(&"f") => {
                let index = |w: &str| -> Result<u32, String> {
                    let i: u32 = w
                        .split('/')
                        .next()
                        .unwrap_or("")
                        .parse()
                        .map_err(|_| at("a bad index"))?;
                    i.checked_sub(1).ok_or_else(|| at("index 0"))
                };
                let corners: Vec<u32> = words[1..]
                    .iter()
                    .map(|w| index(w))
                    .collect::<Result<_, _>>()?;
                for k in 1..corners.len().saturating_sub(1) {
                    mesh.triangles
                        .push([corners[0], corners[k], corners[k + 1]]);
                }
            }
            _ => {}
        }
    }
    mesh.normals = vec![Vec3::Z; mesh.positions.len()];
    mesh.compute_smooth_normals();
    Ok(mesh)
}

/// Whether the open texel square `(x, x+1) × (y, y+1)` meets triangle `p` (separating axes).
fn meets(p: &[DVec2; 3], x: f64, y: f64) -> bool {
    let (lo, hi) = (p[0].min(p[1]).min(p[2]), p[0].max(p[1]).max(p[2]));
    if hi.x <= x || lo.x >= x + 1.0 || hi.y <= y || lo.y >= y + 1.0 {
        return false;
    }
    let centre = DVec2::new(x + 0.5, y + 0.5);
    (0..3).all(|k| {
        let n = (p[(k + 1) % 3] - p[k]).perp();
        let d = p.map(|q| n.dot(q));
        let (a, b) = (d[0].min(d[1]).min(d[2]), d[0].max(d[1]).max(d[2]));
        let (c, r) = (n.dot(centre), (n.x.abs() + n.y.abs()) * 0.5);
        n == DVec2::ZERO || (b > c - r && a < c + r)
    })
}

fn report(name: &str, mesh: &Mesh, page_resolution: u32, texel_size: f32) -> Result<(), String> {
    let options = AtlasOptions {
        page_resolution,
        texel_size,
        max_grid: 16,
    };
    let start = Instant::now();
    let atlas = Atlas::build(mesh, &[], &options).map_err(|e| format!("{name}: {e}"))?;
    let seconds = start.elapsed().as_secs_f64();
    let a = f64::from(atlas.resolution());
    let side = atlas.resolution() as usize;
    let mut strict = vec![false; side * side];
    let (mut least, mut area) = (f64::MAX, 0.0);
    for (t, tri) in mesh.triangles.iter().enumerate() {
        let p = tri.map(|i| mesh.positions[i as usize].as_dvec3());
        let area3 = 0.5 * (p[1] - p[0]).cross(p[2] - p[0]).length();
        let uv = atlas.mesh.triangles[t].map(|i| atlas.mesh.uvs[i as usize].as_dvec2() * a);
        let area2 = 0.5 * (uv[1] - uv[0]).perp_dot(uv[2] - uv[0]).abs();
        area += area3;
        if area3 > 1e-12 {
            least = least.min(area2 / area3);
        }
        let (lo, hi) = (uv[0].min(uv[1]).min(uv[2]), uv[0].max(uv[1]).max(uv[2]));
        for y in (lo.y.floor().max(0.0) as usize)..=(hi.y.floor() as usize).min(side - 1) {
            for x in (lo.x.floor().max(0.0) as usize)..=(hi.x.floor() as usize).min(side - 1) {
                strict[y * side + x] |= meets(&uv, x as f64, y as f64);
            }
        }
    }
    let strict = strict.iter().filter(|&&s| s).count() as f64 / (a * a);
    println!(
        "{name}: {} pages, {} charts, fill {:.3}, strict {strict:.3}, least density {:.3} ({seconds:.2} s)",
        atlas.page_count(),
        atlas.chart_count(),
        atlas.fill(),
        least * area / (a * a),
    );
    Ok(())
}

fn main() {
    let run = || -> Result<(), String> {
        report("lumpy (tests)", &lumpy(1.0), 32, 0.05)?;
        report("icosphere (tests)", &Mesh::icosphere(3), 32, 0.05)?;
        report("blob (meshes.toml)", &lumpy(0.17), 128, 0.045 / 8.0)?;
        for path in std::env::args().skip(1) {
            report(&path, &obj(&path)?, 128, 0.045 / 8.0)?;
        }
        Ok(())
    };
    if let Err(e) = run() {
        eprintln!("error: {e}");
        std::process::exit(1);
    }
}
