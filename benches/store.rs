//! Store benchmark on cube maps baked from the example scene: bytes per texel of each encoding
//! at the default zstd level, and decompression throughput of one core (`read_face_raw`:
//! checksum, zstd and unfilter).
//!
//! Cubes are stored with the face filter writers use ([`Filter::for_store`]: `predict-rows`,
//! or `predict-packed` for RGB9E5 with fewer mantissa bits); the sizes with filter 1
//! (`predict`) and unfiltered are printed beside it.
//!
//! `cargo bench --bench store`: the quick preset (32² cube maps), baked losslessly (RGBA32F)
//! once and cached in `target/bench-data/`; each encoding is re-encoded from it, so all see
//! the same radiance.
//!
//! RGB9E5 is also measured with fewer mantissa bits (`mantissa_bits` 8..1, sizes with filters
//! 3 and 2), and a second RGB9E5 store keeping 3 bits is timed beside the lossless one
//! (`rgb9e5-3bits`); `OSLF_BENCH_BITS=k` times k bits instead of 3.
//!
//! `OSLF_BENCH_STORE=path.oslf [OSLF_BENCH_CUBES=N] cargo bench --bench store`: the cube maps
//! of an existing store instead (its first N cubes), e.g. the thesis preset's 128² cube maps
//! from `oslf bake examples/gazebo.toml --preset thesis`. Re-encoding an RGB9E5 store to RGB9E5
//! is exact; its RGBA16F/RGBA32F figures are then of RGB9E5-quantised radiance.

use std::path::{Path, PathBuf};

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use oslf_bake::bake::{bake, BakeOptions};
use oslf_format::{
    encode_cube, encode_cube_with_filter, Encoding, Filter, SampleMaps, Store, StoreWriter,
};
use oslf_scene::scene::Scene;

fn data_dir() -> PathBuf {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("target/bench-data");
    std::fs::create_dir_all(&dir).expect("create target/bench-data");
    dir
}

/// The example scene baked losslessly (RGBA32F), baked once and cached, or the store named
/// by `OSLF_BENCH_STORE`.
fn reference_store() -> PathBuf {
    if let Some(path) = std::env::var_os("OSLF_BENCH_STORE") {
        return PathBuf::from(path);
    }
    let path = data_dir().join("gazebo-quick-rgba32f.oslf");
    if !path.exists() {
        let scene_path = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/gazebo.toml");
        let mut scene = Scene::load(&scene_path, None).expect("load examples/gazebo.toml");
        scene.bake.encoding = Encoding::Rgba32f;
        eprintln!("baking {} (once) ...", path.display());
        let options = BakeOptions {
            output: path.clone(),
            resume: false,
            progress: None,
            cube_limit: None,
            refuse_empty_texels: false,
            device: None,
        };
        bake(&scene, &options).expect("bake the example scene");
    }
    path
}

/// Re-encodes every cube of `source` with `encoding` (keeping `bits` RGB9E5 mantissa bits)
/// into a new store. Returns the store's path, its compressed cube bytes, the texel count and
/// the compressed cube bytes without a face filter (`Filter::None`) and with filter 1, for
/// comparison.
fn reencode(
    source: &Store,
    encoding: Encoding,
    bits: u32,
    cubes: u32,
) -> (PathBuf, u64, u64, u64, u64) {
    // A name of its own: the RGBA32F copy must not replace the reference it is read from.
    let path = data_dir().join(format!(
        "gazebo-bench-{}-{bits}-reencoded.oslf",
        encoding.name()
    ));
    let mut meta = source.meta().clone();
    meta.bake.encoding = encoding;
    meta.bake.mantissa_bits = bits;
    let points = source.sample_points().to_vec();
    let res = meta.bake.sample_map_resolution;
    let mut indices = Vec::new();
    for p in 0..meta.map_count() as u32 {
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
    // With fewer cubes than the source: a store of the first `cubes` sample points, sample
    // maps cut to them, no environment cube.
    let cubes = if cubes >= source.cube_count() {
        source.cube_count()
    } else {
        let cubes = cubes.min(points.len() as u32);
        meta.has_env_cube = false;
        cubes
    };
    let (points, maps) = if cubes == source.cube_count() {
        (points, maps)
    } else {
        let indices = maps
            .indices
            .iter()
            .map(|texel| {
                // The texel's points that remain, nearest first, then invalid entries.
                let mut kept = [oslf_format::INVALID_INDEX; 4];
                for (slot, &i) in kept.iter_mut().zip(texel.iter().filter(|&&i| i < cubes)) {
                    *slot = i;
                }
                kept
            })
            .collect();
        (
            points[..cubes as usize].to_vec(),
            SampleMaps {
                resolution: maps.resolution,
                indices,
            },
        )
    };
    let mut writer = StoreWriter::create(&path, &meta, &points, &maps).expect("create store");
    let (mut compressed, mut texels, mut unfiltered, mut predict) = (0u64, 0u64, 0u64, 0u64);
    for c in 0..cubes {
        let cube = source.read_cube(c).expect("read cube");
        let (enc, stats) = encode_cube(&cube, &meta.bake, c).expect("encode");
        compressed += stats.compressed_bytes;
        let (_, plain) =
            encode_cube_with_filter(&cube, &meta.bake, c, Filter::None).expect("encode");
        unfiltered += plain.compressed_bytes;
        let (_, p) =
            encode_cube_with_filter(&cube, &meta.bake, c, Filter::Predict).expect("encode");
        predict += p.compressed_bytes;
        texels += 6 * (cube.resolution as u64).pow(2);
        writer.append(enc).expect("append");
    }
    writer.finish().expect("finish");
    (path, compressed, texels, unfiltered, predict)
}

/// Nanoseconds this thread has run on a CPU (Linux: /proc/thread-self/schedstat), if known.
fn thread_cpu_ns() -> Option<u64> {
    let s = std::fs::read_to_string("/proc/thread-self/schedstat").ok()?;
    s.split_whitespace().next()?.parse().ok()
}

fn store_benchmarks(c: &mut Criterion) {
    let source = reference_store();
    let reference = Store::open(&source).expect("open reference store");
    let cubes = std::env::var("OSLF_BENCH_CUBES")
        .ok()
        .and_then(|v| v.parse::<u32>().ok())
        .map_or(reference.cube_count(), |n| {
            n.clamp(1, reference.cube_count())
        });
    let bake = &reference.meta().bake;
    println!(
        "cube maps: {} of {} cubes of {}² from {} ({} samples per texel, {} bounces, stored as {})",
        cubes,
        reference.cube_count(),
        reference.cube_resolution(),
        source.display(),
        bake.samples_per_texel,
        bake.bounces,
        bake.encoding.name()
    );
    let bits = std::env::var("OSLF_BENCH_BITS")
        .ok()
        .and_then(|v| v.parse::<u32>().ok())
        .map_or(3, |b| b.clamp(1, 9));
    // Quantized RGB9E5, sizes only (encoded, not written).
    let mut sizes = Vec::new();
    for k in (1..=8).rev() {
        let mut params = reference.meta().bake.clone();
        params.encoding = Encoding::Rgb9e5;
        params.mantissa_bits = k;
        let (mut packed, mut rows, mut texels) = (0u64, 0u64, 0u64);
        for c in 0..cubes {
            let cube = reference.read_cube(c).expect("read cube");
            let (_, stats) =
                encode_cube_with_filter(&cube, &params, c, Filter::PredictPacked).expect("encode");
            packed += stats.compressed_bytes;
            let (_, stats) =
                encode_cube_with_filter(&cube, &params, c, Filter::PredictRows).expect("encode");
            rows += stats.compressed_bytes;
            texels += 6 * (cube.resolution as u64).pow(2);
        }
        sizes.push(format!(
            "{k} bits {:.3} ({:.3})",
            packed as f64 / texels as f64,
            rows as f64 / texels as f64
        ));
    }
    println!(
        "rgb9e5   zstd level {}, bytes per texel with fewer mantissa bits, filter {} ({}): {}",
        reference.meta().bake.zstd_level,
        Filter::PredictPacked,
        Filter::PredictRows,
        sizes.join(", ")
    );
    let mut group = c.benchmark_group("read_face_raw");
    for (encoding, k) in [
        (Encoding::Rgb9e5, 9),
        (Encoding::Rgb9e5, bits),
        (Encoding::Rgba16f, 9),
        (Encoding::Rgba32f, 9),
    ] {
        let name = if k < 9 {
            format!("{}-{k}bits", encoding.name())
        } else {
            encoding.name().to_string()
        };
        let (path, compressed, texels, unfiltered, predict) =
            reencode(&reference, encoding, k, cubes);
        println!(
            "{name:8} mantissa_bits {k} zstd level {}: {:.3} bytes per texel with filter {} ({:.3} with predict, {:.3} unfiltered; {:.2} MB of cube data; raw {} bytes per texel)",
            reference.meta().bake.zstd_level,
            compressed as f64 / texels as f64,
            Filter::for_store(encoding, k),
            predict as f64 / texels as f64,
            unfiltered as f64 / texels as f64,
            compressed as f64 / 1e6,
            encoding.bytes_per_texel()
        );
        let store = Store::open(&path).expect("open re-encoded store");
        let face = store.face_raw_size();
        let faces = store.cube_count() as usize * 6;
        let mut buffer = vec![0u8; face];
        // The same work timed by this thread's CPU time as well as wall time: on a shared
        // machine the wall time also counts time the thread waited for a core.
        let (wall, cpu) = {
            let start = (std::time::Instant::now(), thread_cpu_ns());
            let mut bytes = 0u64;
            while bytes < 2_000_000_000 {
                for cube in 0..store.cube_count() {
                    for f in 0..6 {
                        store
                            .read_face_raw(cube, f, &mut buffer)
                            .expect("read face");
                    }
                }
                bytes += (face * faces) as u64;
            }
            let wall = bytes as f64 / start.0.elapsed().as_secs_f64() / 1e9;
            let cpu = thread_cpu_ns()
                .zip(start.1)
                .map(|(b, a)| bytes as f64 / (b - a) as f64);
            (wall, cpu)
        };
        println!(
            "{name:8} read_face_raw: {:.3} GB/s of wall time, {} GB/s of this thread's CPU time",
            wall,
            cpu.map_or("(unknown)".to_string(), |c| format!("{c:.3}"))
        );
        group.throughput(Throughput::Bytes((face * faces) as u64));
        group.bench_function(name.as_str(), |b| {
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
