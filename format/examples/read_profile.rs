//! Splits `Store::read_face_raw` into its stages (checksum, zstd, unfilter) on one thread and
//! times each over every face of a store: `cargo run --release -p oslf-format --example
//! read_profile -- STORE.oslf [ROUNDS]`. Throughputs are raw (decoded) bytes per second.
//!
//! Environment variables:
//! - `BITS=k`: first re-encode every cube keeping k RGB9E5 mantissa bits, with the filter
//!   writers use (`Filter::for_store`) or `FILTER=id`, at the store's zstd level or `LEVEL=l`;
//! - `UNFILTER_ONLY=n`: also time n more passes of the unfilter alone (for a profiler);
//! - `SWEEP=1`: instead, compare a few zstd parameter sets (size, decompression speed);
//! - `DUMP=path`: write the decompressed (filtered) faces to `path`.

use std::time::Instant;

use oslf_format::filter::unfilter_face_quantized;
use oslf_format::Store;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let store = Store::open(args.get(1).expect("STORE").as_ref()).expect("open store");
    let rounds: usize = args.get(2).map_or(5, |r| r.parse().expect("ROUNDS"));
    let h = store.header().clone();
    let raw = store.face_raw_size();
    let bytes = std::fs::read(args.get(1).unwrap()).unwrap();
    let mut filter = h.filter;
    let mut bits = store.meta().bake.mantissa_bits;
    let mut frames: Vec<&[u8]> = Vec::new();
    let mut owned: Vec<Vec<u8>> = Vec::new();
    if let Some(b) = std::env::var("BITS")
        .ok()
        .map(|b| b.parse::<u32>().unwrap())
    {
        let mut params = store.meta().bake.clone();
        params.mantissa_bits = b;
        bits = b;
        filter = oslf_format::Filter::for_store(params.encoding, b);
        if let Ok(id) = std::env::var("FILTER") {
            filter = oslf_format::Filter::from_id(id.parse().unwrap()).unwrap();
        }
        let level = std::env::var("LEVEL").map_or(params.zstd_level, |l| l.parse().unwrap());
        params.zstd_level = level;
        for c in 0..store.cube_count() {
            let cube = store.read_cube(c).unwrap();
            let (enc, _) = oslf_format::encode_cube_with_filter(&cube, &params, c, filter).unwrap();
            owned.extend(enc.frames().iter().cloned());
        }
        frames = owned.iter().map(|f| f.as_slice()).collect();
    } else {
        for c in 0..store.cube_count() {
            for f in 0..6 {
                let e = store.face_entry(c, f).unwrap();
                frames.push(&bytes[e.offset as usize..(e.offset + e.compressed_size) as usize]);
            }
        }
    }
    let total_raw = (raw * frames.len()) as f64;
    let fsize = oslf_format::filter::filtered_face_size(
        filter,
        h.encoding,
        h.cube_resolution,
        h.distance_plane(),
        bits,
    )
    .unwrap();
    let compressed: usize = frames.iter().map(|f| f.len()).sum();
    let unfilter = |filtered: &[u8], out: &mut [u8]| {
        unfilter_face_quantized(
            filter,
            h.encoding,
            h.cube_resolution,
            h.distance_plane(),
            bits,
            filtered,
            out,
        )
        .unwrap()
    };
    if std::env::var_os("SWEEP").is_some() {
        sweep(&frames, fsize);
        return;
    }
    println!(
        "{} faces of {} bytes raw, {:.3} bytes per raw byte compressed, filter {}, bits {}",
        frames.len(),
        raw,
        compressed as f64 / total_raw,
        filter,
        bits
    );
    let mut dctx = zstd::bulk::Decompressor::new().unwrap();
    let mut scratch = vec![0u8; fsize * frames.len()];
    let mut out = vec![0u8; raw];
    let (mut t_hash, mut t_zstd, mut t_unf, mut t_all) = (0.0, 0.0, 0.0, 0.0);
    let mut sink = 0u64;
    for _ in 0..rounds {
        let t = Instant::now();
        for f in &frames {
            sink ^= xxhash_rust::xxh3::xxh3_64(f);
        }
        t_hash += t.elapsed().as_secs_f64();
        let t = Instant::now();
        for (f, s) in frames.iter().zip(scratch.chunks_mut(fsize)) {
            dctx.decompress_to_buffer(f, s).unwrap();
        }
        t_zstd += t.elapsed().as_secs_f64();
        if let Some(path) = std::env::var_os("DUMP") {
            std::fs::write(path, &scratch).unwrap();
        }
        let t = Instant::now();
        for s in scratch.chunks(fsize) {
            unfilter(s, &mut out);
            sink ^= u64::from(out[7]);
        }
        t_unf += t.elapsed().as_secs_f64();
        let t = Instant::now();
        for f in &frames {
            sink ^= xxhash_rust::xxh3::xxh3_64(f);
            dctx.decompress_to_buffer(f, &mut scratch[..fsize]).unwrap();
            unfilter(&scratch[..fsize], &mut out);
        }
        t_all += t.elapsed().as_secs_f64();
    }
    if let Some(reps) = std::env::var("UNFILTER_ONLY")
        .ok()
        .map(|r| r.parse::<usize>().unwrap())
    {
        let t = Instant::now();
        for _ in 0..reps {
            for s in scratch.chunks(fsize) {
                unfilter(s, &mut out);
            }
        }
        println!(
            "unfilter only: {:.3} GB/s",
            total_raw * reps as f64 / t.elapsed().as_secs_f64() / 1e9
        );
    }
    let gb = |t: f64| total_raw * rounds as f64 / t / 1e9;
    println!(
        "GB/s of raw bytes: checksum {:.2}, zstd {:.3}, unfilter {:.3}, all three per face {:.3} (sum of stages {:.3}) [{sink}]",
        gb(t_hash),
        gb(t_zstd),
        gb(t_unf),
        gb(t_all),
        gb(t_hash + t_zstd + t_unf)
    );
}

/// Re-compresses every face with other zstd parameters and reports size and decompression
/// speed (zstd alone) for each.
#[allow(dead_code)]
pub fn sweep(frames: &[&[u8]], raw: usize) {
    use zstd::zstd_safe::CParameter;
    let mut dctx = zstd::bulk::Decompressor::new().unwrap();
    let mut filtered = vec![0u8; raw * frames.len()];
    for (f, s) in frames.iter().zip(filtered.chunks_mut(raw)) {
        dctx.decompress_to_buffer(f, s).unwrap();
    }
    let configs: Vec<(String, Vec<CParameter>)> = vec![
        ("level 3".into(), vec![CParameter::CompressionLevel(3)]),
        (
            "l3 minmatch 6".into(),
            vec![CParameter::CompressionLevel(3), CParameter::MinMatch(6)],
        ),
        (
            "l3 minmatch 7".into(),
            vec![CParameter::CompressionLevel(3), CParameter::MinMatch(7)],
        ),
        ("level 6".into(), vec![CParameter::CompressionLevel(6)]),
        (
            "l6 minmatch 7".into(),
            vec![CParameter::CompressionLevel(6), CParameter::MinMatch(7)],
        ),
    ];

    let mut compressed = Vec::new();
    for (name, params) in &configs {
        let mut c = zstd::bulk::Compressor::new(3).unwrap();
        for p in params {
            c.set_parameter(*p).unwrap();
        }
        let comp: Vec<Vec<u8>> = filtered
            .chunks(raw)
            .map(|s| c.compress(s).unwrap())
            .collect();
        let size: usize = comp.iter().map(|c| c.len()).sum();
        println!(
            "{name:>16}: {:.4} bytes per filtered byte",
            size as f64 / filtered.len() as f64
        );
        compressed.push(comp);
    }
    let mut out = vec![0u8; raw];
    let mut secs = vec![0f64; configs.len()];
    for _round in 0..5 {
        for (k, comp) in compressed.iter().enumerate() {
            let t = std::time::Instant::now();
            for c in comp {
                dctx.decompress_to_buffer(c, &mut out).unwrap();
            }
            secs[k] += t.elapsed().as_secs_f64();
        }
    }
    for ((name, _), s) in configs.iter().zip(secs) {
        println!(
            "{name:>16}: zstd {:.3} GB/s of filtered bytes",
            (filtered.len() * 5) as f64 / s / 1e9
        );
    }
}
