//! BC6H encoder presets on real cube maps: encode time per cube, error against the store's
//! texels (use an RGBA32F bake: exact) and against RGB9E5, and bytes per texel after zstd
//! (the blocks as stored, and regrouped into byte planes).
//!
//! `cargo run --release -p oslf-format --example bc6h_quality -- store.oslf [max_cubes]`
use oslf_format::bc6h::{self, face_error, FaceError, Quality};
use oslf_format::encoding::{decode_rgb9e5, encode_rgb9e5};
use oslf_format::Store;
use std::time::Instant;

fn main() {
    let mut args = std::env::args().skip(1);
    let path = args.next().expect("store path");
    let max: u32 = args
        .next()
        .map_or(u32::MAX, |s| s.parse().expect("max_cubes"));
    let store = Store::open(std::path::Path::new(&path)).expect("open");
    let n = store.cube_resolution();
    let level = store.meta().bake.zstd_level;
    let cubes: Vec<_> = (0..store.cube_count().min(max))
        .map(|c| store.read_cube(c).expect("cube"))
        .collect();
    let texels = cubes.len() as f64 * 6.0 * f64::from(n).powi(2);
    println!(
        "{path}: {} cubes of {n}², source encoding {}, zstd level {level}",
        cubes.len(),
        store.header().encoding
    );
    // RGB9E5 of the same texels, for reference.
    let mut e9 = FaceError::default();
    for c in &cubes {
        for f in &c.faces {
            let back: Vec<[f32; 3]> = f.iter().map(|t| decode_rgb9e5(encode_rgb9e5(*t))).collect();
            e9 = e9.merge(face_error(f, &back, 1e-3));
        }
    }
    println!(
        "  rgb9e5 vs source: RMSLE {:.3e}, relative error max {:.3e} mean {:.3e}",
        e9.rmsle, e9.max_relative, e9.mean_relative
    );
    let bytes = bc6h::face_bytes(n).expect("size");
    for q in Quality::ALL {
        let mut blocks = vec![vec![0u8; bytes]; cubes.len() * 6];
        let start = Instant::now();
        for (i, c) in cubes.iter().enumerate() {
            for (f, face) in c.faces.iter().enumerate() {
                bc6h::encode_face_with(face, n, &mut blocks[i * 6 + f], q).expect("encode");
            }
        }
        let secs = start.elapsed().as_secs_f64();
        let (mut es, mut e9b) = (FaceError::default(), FaceError::default());
        let mut per_face = Vec::new();
        let mut back = vec![[0f32; 3]; (n * n) as usize];
        for (i, c) in cubes.iter().enumerate() {
            for (f, face) in c.faces.iter().enumerate() {
                bc6h::decode_face(&blocks[i * 6 + f], n, &mut back, i as u32, f).expect("decode");
                let e = face_error(face, &back, 1e-3);
                per_face.push(e.rmsle);
                es = es.merge(e);
                let r9: Vec<[f32; 3]> = face
                    .iter()
                    .map(|t| decode_rgb9e5(encode_rgb9e5(*t)))
                    .collect();
                e9b = e9b.merge(face_error(&r9, &back, 1e-3));
            }
        }
        // Bytes per texel after zstd: the blocks as stored, and as 16 byte planes (byte j of
        // every block together), the transform the face filters do not use.
        let mut sizes = [0usize; 2];
        for b in &blocks {
            sizes[0] += zstd::bulk::compress(b, level).expect("zstd").len();
            let planes: Vec<u8> = (0..16)
                .flat_map(|j| b.chunks_exact(16).map(move |blk| blk[j]))
                .collect();
            sizes[1] += zstd::bulk::compress(&planes, level).expect("zstd").len();
        }
        let sizes = [
            format!("blocks {:.3}", sizes[0] as f64 / texels),
            format!("planes {:.3}", sizes[1] as f64 / texels),
        ];
        println!(
            "  bc6h {:9}: {:.2} ms/cube; vs source RMSLE {:.3e} (per face: median {:.3e}, max {:.3e}) rel max {:.3e} mean {:.3e}; vs rgb9e5 RMSLE {:.3e} rel max {:.3e}; bytes/texel {}",
            q.name(),
            1e3 * secs / cubes.len() as f64,
            es.rmsle,
            median(&mut per_face),
            per_face.iter().fold(0f64, |a, b| a.max(*b)),
            es.max_relative,
            es.mean_relative,
            e9b.rmsle,
            e9b.max_relative,
            sizes.join(", ")
        );
    }
}

fn median(v: &mut [f64]) -> f64 {
    v.sort_by(f64::total_cmp);
    v.get(v.len() / 2).copied().unwrap_or(0.0)
}
