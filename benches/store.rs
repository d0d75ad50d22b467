//! Store benchmark on cube maps baked from the example scene (quick preset):
//! bytes per texel of each encoding at the default zstd level, and decompression throughput
//! of one core (`read_face_raw`, checksum included).
//!
//! Cubes are stored with the default face filter ([`Filter::Predict`]); the unfiltered size is
//! printed beside it.
//!
//! `cargo bench --bench store`. The lossless RGBA32F bake is cached in
//! `target/bench-data/`; each encoding is re-encoded from it, so all see the same radiance.

use std::path::{Path, PathBuf};

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use oslf::bake::bake::{bake, BakeOptions};
use oslf::bake::scene::Scene;
use oslf::format::{
    encode_cube, encode_cube_with_filter, Encoding, Filter, SampleMaps, Store, StoreWriter,
};

fn data_dir() -> PathBuf {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("target/bench-data");
    std::fs::create_dir_all(&dir).expect("create target/bench-data");
    dir
}

/// The example scene baked losslessly (RGBA32F), baked once and cached.
fn reference_store() -> PathBuf {
    let path = data_dir().join("gazebo-quick-rgba32f.oslf");
    if !path.exists() {
        let scene_path = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/gazebo.toml");
        let mut scene = Scene::load(&scene_path, None).expect("load examples/gazebo.toml");
        scene.bake.encoding = Encoding::Rgba32f;
        eprintln!("baking {} (once) ...", path.display());
        let options = BakeOptions {
            output: path.clone(),
            resume: false,
            progress: false,
            cube_limit: None,
        };
        bake(&scene, &options).expect("bake the example scene");
    }
    path
}

/// Re-encodes every cube of `source` with `encoding` into a new store.
/// Returns the store's path, its compressed cube bytes, the texel count and the compressed
/// cube bytes without a face filter (`Filter::None`, for comparison).
fn reencode(source: &Store, encoding: Encoding) -> (PathBuf, u64, u64, u64) {
    // A name of its own: the RGBA32F copy must not replace the reference it is read from.
    let path = data_dir().join(format!("gazebo-quick-{}-reencoded.oslf", encoding.name()));
    let mut meta = source.meta().clone();
    meta.bake.encoding = encoding;
    let points = source.sample_points().to_vec();
    let res = meta.bake.sample_map_resolution;
    let mut indices = Vec::new();
    for p in 0..meta.patches.len() as u32 {
        let map = source.sample_map(p).expect("sample map");
        for y in 0..res {
            for x in 0..res {
                indices.push(map.get(x, y).expect("texel"));
            }
        }
    }
    let maps = SampleMaps {
        resolution: res,
        indices,
    };
    let mut writer = StoreWriter::create(&path, &meta, &points, &maps).expect("create store");
    let (mut compressed, mut texels, mut unfiltered) = (0u64, 0u64, 0u64);
    for c in 0..source.cube_count() {
        let cube = source.read_cube(c).expect("read cube");
        let (enc, stats) = encode_cube(&cube, &meta.bake, c).expect("encode");
        compressed += stats.compressed_bytes;
        let (_, plain) =
            encode_cube_with_filter(&cube, &meta.bake, c, Filter::None).expect("encode");
        unfiltered += plain.compressed_bytes;
        texels += 6 * (cube.resolution as u64).pow(2);
        writer.append(enc).expect("append");
    }
    writer.finish().expect("finish");
    (path, compressed, texels, unfiltered)
}

fn store_benchmarks(c: &mut Criterion) {
    let reference = Store::open(&reference_store()).expect("open reference store");
    let mut group = c.benchmark_group("read_face_raw");
    for encoding in [Encoding::Rgb9e5, Encoding::Rgba16f, Encoding::Rgba32f] {
        let (path, compressed, texels, unfiltered) = reencode(&reference, encoding);
        println!(
            "{:8} zstd level {}: {:.3} bytes per texel with filter {} ({:.3} unfiltered; {} cubes of {}², {:.2} MB of cube data; raw {} bytes per texel)",
            encoding.name(),
            reference.meta().bake.zstd_level,
            compressed as f64 / texels as f64,
            Filter::default(),
            unfiltered as f64 / texels as f64,
            reference.cube_count(),
            reference.cube_resolution(),
            compressed as f64 / 1e6,
            encoding.bytes_per_texel()
        );
        let store = Store::open(&path).expect("open re-encoded store");
        let face = store.face_raw_size();
        let faces = store.cube_count() as usize * 6;
        let mut buffer = vec![0u8; face];
        group.throughput(Throughput::Bytes((face * faces) as u64));
        group.bench_function(encoding.name(), |b| {
            b.iter(|| {
                for cube in 0..store.cube_count() {
                    for f in 0..6 {
                        store
                            .read_face_raw(cube, f, &mut buffer)
                            .expect("read face");
                    }
                }
            })
        });
    }
    group.finish();
}

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(20);
    targets = store_benchmarks
}
criterion_main!(benches);
