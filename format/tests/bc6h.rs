//! BC6H faces and stores: error bounds, padding, HDR range, clamping, reserved modes, damaged
//! stores.

use crate::common;

use common::*;
use oslf_format::bc6h::{self, face_error, Quality, BLOCK_BYTES, MAX_BC6H};
use oslf_format::header::{HEADER_BYTES, HEADER_CHECKSUM_OFFSET};
use oslf_format::toc::TOC_ENTRY_BYTES;
use oslf_format::*;
use xxhash_rust::xxh3::xxh3_64;

fn encode(src: &[[f32; 3]], n: u32) -> Vec<u8> {
    let mut blocks = vec![0u8; bc6h::face_bytes(n).unwrap()];
    bc6h::encode_face(src, n, &mut blocks).unwrap();
    blocks
}

fn decode(blocks: &[u8], n: u32) -> Vec<[f32; 3]> {
    let mut out = vec![[0f32; 3]; (n * n) as usize];
    bc6h::decode_face(blocks, n, &mut out, 0, 0).unwrap();
    out
}

/// A smooth HDR face: a colour gradient whose brightness varies over `decades` decades across
/// the face (from 0.05), with a slow hue change.
fn smooth_face(n: u32, decades: f32) -> Vec<[f32; 3]> {
    smooth_crop(n, n, decades)
}

/// The top left `n`² texels of `smooth_face(span, decades)`.
fn smooth_crop(n: u32, span: u32, decades: f32) -> Vec<[f32; 3]> {
    (0..n * n)
        .map(|i| {
            let (x, y) = ((i % n) as f32 / span as f32, (i / n) as f32 / span as f32);
            let l = 10f32.powf(-1.3 + decades * (0.6 * x + 0.4 * y));
            [l, l * (0.5 + 0.3 * y), l * (0.8 - 0.5 * x)]
        })
        .collect()
}

/// The stated bound for smooth data: where neighbouring texels differ by at most about 3 %
/// in each channel, every texel's error, in any channel, is below 2.5 % of the texel's largest
/// channel, and the RMSLE is below 1.5e-3. Measured with the default quality: 2.01 % / 6.6e-4
/// (64², 1 decade across the face), 1.25 % / 1.4e-3 (256², 3 decades). BC6H's 16 (one region)
/// or 8 (two regions) interpolation steps across a block set the error: a block spanning a
/// factor `r` in brightness errs by up to about half a step, `r^(1/30)`.
#[test]
fn smooth_faces_round_trip_within_the_stated_bound() {
    for (n, span, decades) in [(64u32, 64, 1.0f32), (256, 256, 3.0), (16, 64, 1.0)] {
        let src = smooth_crop(n, span, decades);
        let back = decode(&encode(&src, n), n);
        let e = face_error(&src, &back, 1e-6);
        assert!(e.max_relative < 0.025, "{n}²: {e:?}");
        assert!(e.rmsle < 1.5e-3, "{n}²: {e:?}");
        assert!(back.iter().flatten().all(|v| v.is_finite() && *v >= 0.0));
    }
}

/// Every preset is usable and the default is among the better ones on smooth data.
#[test]
fn every_quality_round_trips() {
    let n = 64;
    let src = smooth_face(n, 1.0);
    for q in Quality::ALL {
        let mut blocks = vec![0u8; bc6h::face_bytes(n).unwrap()];
        bc6h::encode_face_with(&src, n, &mut blocks, q).unwrap();
        let e = face_error(&src, &decode(&blocks, n), 1e-6);
        // Measured 2.07 % (very fast) to 1.81 % (very slow).
        assert!(e.max_relative < 0.03, "{}: {e:?}", q.name());
    }
}

/// Sides that are not a multiple of 4: the encoder pads by edge replication (the same blocks
/// as encoding the explicitly padded face) and the decoder crops.
#[test]
fn non_multiple_of_4_sides_pad_by_replication_and_crop() {
    for n in [1u32, 2, 3, 5, 6, 7, 13, 30] {
        let src = smooth_crop(n, 64, 1.0);
        let blocks = encode(&src, n);
        assert_eq!(blocks.len(), n.div_ceil(4).pow(2) as usize * BLOCK_BYTES);
        let p = n.div_ceil(4) * 4;
        let padded: Vec<[f32; 3]> = (0..p * p)
            .map(|i| {
                let (x, y) = ((i % p).min(n - 1), (i / p).min(n - 1));
                src[(y * n + x) as usize]
            })
            .collect();
        assert_eq!(
            blocks,
            encode(&padded, p),
            "{n}: padding is not edge replication"
        );
        let back = decode(&blocks, n);
        let full = decode(&blocks, p);
        for y in 0..n {
            for x in 0..n {
                assert_eq!(back[(y * n + x) as usize], full[(y * p + x) as usize]);
            }
        }
        let e = face_error(&src, &back, 1e-6);
        assert!(e.max_relative < 0.025, "{n}: {e:?}");
    }
}

/// 1e-4 and 3e4 in one block (8.5 decades): BC6H works on binary16 bit patterns, a nearly
/// logarithmic scale, so the encoder puts the two values at the ends of one region's endpoint
/// pair and both come back within 2.5 % of themselves (measured: 1.5 % for 3e4, 0.7 % for
/// 1e-4, mode 0b00011 with 10-bit endpoints).
#[test]
fn hdr_values_far_apart_in_one_block() {
    let n = 4;
    let src: Vec<[f32; 3]> = (0..16)
        .map(|i| {
            if i % 3 == 0 {
                [3e4, 2e4, 1e4]
            } else {
                [1e-4, 1e-4, 2e-4]
            }
        })
        .collect();
    let back = decode(&encode(&src, n), n);
    for (s, b) in src.iter().zip(&back) {
        assert!(b.iter().all(|v| v.is_finite() && *v >= 0.0), "{b:?}");
        for c in 0..3 {
            assert!((b[c] - s[c]).abs() <= 0.025 * s[c], "{s:?} -> {b:?}");
        }
    }
    // Alone in its block (a constant block: mode 0b01111 with 16-bit endpoints), the dark
    // value is kept to about binary16 precision (measured 0.04 %).
    let dark = vec![[1e-4f32, 1e-4, 2e-4]; 16];
    for b in decode(&encode(&dark, n), n) {
        for c in 0..3 {
            assert!((b[c] - dark[0][c]).abs() <= 0.01 * dark[0][c], "{b:?}");
        }
    }
    // A bright constant block far above 1: within 0.1 % (measured 0.08 %).
    let bright = vec![[3e4f32, 2e4, 1e4]; 16];
    let e = face_error(&bright, &decode(&encode(&bright, n), n), 1e-6);
    assert!(e.max_relative < 1e-3, "{e:?}");
}

/// Radiance above 65504 is clamped to it and counted; NaN, infinite and negative radiance is
/// an error naming the texel.
#[test]
fn clamping_above_65504_and_invalid_texels() {
    let n = 5;
    let mut src = vec![[1.0f32, 2.0, 3.0]; 25];
    src[3] = [1e5, 1.0, 1.0];
    src[7] = [7e4, 7e4, 7e4];
    src[24] = [f32::MAX, 0.0, 65504.0];
    let mut blocks = vec![0u8; bc6h::face_bytes(n).unwrap()];
    assert_eq!(bc6h::encode_face(&src, n, &mut blocks).unwrap(), 3);
    let back = decode(&blocks, n);
    assert!(back
        .iter()
        .flatten()
        .all(|v| v.is_finite() && *v <= MAX_BC6H));
    assert!(
        back[7].iter().all(|v| *v >= 0.99 * MAX_BC6H),
        "{:?}",
        back[7]
    );
    assert!(back[3][0] >= 0.99 * MAX_BC6H, "{:?}", back[3]);
    for bad in [
        [f32::NAN, 0.0, 0.0],
        [0.0, -1.0, 0.0],
        [0.0, 0.0, f32::INFINITY],
    ] {
        let mut s = src.clone();
        s[11] = bad;
        assert!(matches!(
            bc6h::encode_face(&s, n, &mut blocks),
            Err(Error::InvalidTexel { index: 11, .. })
        ));
    }
    // Through encode_cube: counted in the stats, and NaN named by cube, face and texel.
    let f = fixture(Spec {
        encoding: Encoding::Bc6h,
        cube_res: 5,
        ..Spec::default()
    });
    let mut cube = f.cubes[0].clone();
    cube.faces[2] = src.clone();
    let (_, stats) = encode_cube(&cube, &f.meta.bake, 0).unwrap();
    assert!(stats.clamped_texels >= 3);
    cube.faces[4][6] = [0.0, f32::NAN, 0.0];
    assert!(matches!(
        encode_cube(&cube, &f.meta.bake, 9),
        Err(Error::InvalidRadiance {
            cube: 9,
            face: 4,
            x: 1,
            y: 1,
            ..
        })
    ));
}

/// Wrong buffer sizes are typed errors, never panics.
#[test]
fn wrong_buffers() {
    let src = vec![[1.0f32; 3]; 16];
    let mut small = vec![0u8; 15];
    assert!(matches!(
        bc6h::encode_face(&src, 4, &mut small),
        Err(Error::BufferSize { .. })
    ));
    let mut out = vec![[0f32; 3]; 15];
    assert!(matches!(
        bc6h::decode_face(&[0u8; 16], 4, &mut out, 0, 0),
        Err(Error::BufferSize { .. })
    ));
    assert!(matches!(
        bc6h::decode_face(&[0u8; 17], 4, &mut [[0f32; 3]; 16], 0, 0),
        Err(Error::BufferSize { .. })
    ));
}

/// Every block of random bytes decodes to finite, non-negative texels, except those with a
/// reserved mode, which are an error naming the block.
#[test]
fn random_blocks_decode_or_name_the_reserved_block() {
    let mut rng = Rng(0xbc6);
    for _ in 0..2000 {
        let blocks: Vec<u8> = (0..4 * BLOCK_BYTES).map(|_| rng.next_u64() as u8).collect();
        let mut out = vec![[0f32; 3]; 64];
        match bc6h::decode_face(&blocks, 8, &mut out, 3, 5) {
            Ok(()) => assert!(out
                .iter()
                .flatten()
                .all(|v| v.is_finite() && (0.0..=MAX_BC6H).contains(v))),
            Err(Error::ReservedBc6hMode {
                cube: 3,
                face: 5,
                block,
                mode,
            }) => {
                assert_eq!(bc6h::first_reserved_block(&blocks), Some((block, mode)));
                assert!(matches!(mode, 0b10011 | 0b10111 | 0b11011 | 0b11111));
            }
            Err(e) => panic!("{e}"),
        }
    }
}

fn bc6h_spec() -> Spec {
    Spec {
        encoding: Encoding::Bc6h,
        cube_res: 8,
        distance: true,
        seed: 21,
        ..Spec::default()
    }
}

fn put_u64(b: &mut [u8], off: usize, v: u64) {
    b[off..off + 8].copy_from_slice(&v.to_le_bytes());
}

fn reseal_header(b: &mut [u8]) {
    let sum = xxh3_64(&b[..HEADER_CHECKSUM_OFFSET]);
    put_u64(b, HEADER_CHECKSUM_OFFSET, sum);
}

/// A BC6H store round-trips through the writer and the reader: filter 2 (what
/// `Filter::for_store` picks: the blocks as they are, the distance plane predicted), the raw faces are the blocks followed by the distance plane,
/// it verifies, and every texel is what the BC6H decoder makes of the encoder's blocks.
#[test]
fn bc6h_stores_round_trip() {
    let spec = bc6h_spec();
    let f = fixture(spec);
    let (_dir, path) = temp_store("bc6h.oslf");
    let summary = write(&path, &f);
    let store = Store::open(&path).unwrap();
    assert_eq!(store.header().encoding, Encoding::Bc6h);
    assert_eq!(store.header().filter, Filter::PredictRows);
    assert_eq!(store.face_raw_size(), 4 * BLOCK_BYTES + 64 * 4);
    assert!(store.verify().is_ok());
    assert_eq!(summary.raw_cube_bytes, f.cubes.len() as u64 * 6 * 320);
    let mut raw = vec![0u8; store.face_raw_size()];
    for (i, c) in f.cubes.iter().enumerate() {
        let got = store.read_cube(i as u32).unwrap();
        for face in 0..6 {
            let blocks = encode(&c.faces[face], 8);
            store.read_face_raw(i as u32, face, &mut raw).unwrap();
            assert_eq!(&raw[..blocks.len()], blocks.as_slice());
            assert_eq!(got.faces[face], decode(&blocks, 8));
        }
        let plane = store.header().distance_plane();
        assert_eq!(plane, DistancePlane::Lattice { bits: 3 });
        assert_eq!(got.distance, stored_distances(plane, &c.distance));
    }
    // Every filter round-trips a BC6H store too.
    for filter in Filter::ALL {
        let (_d, p) = temp_store("bc6h-filter.oslf");
        let mut w =
            StoreWriter::create_with_filter(&p, &f.meta, &f.points, &f.maps, filter).unwrap();
        for (i, c) in f.cubes.iter().enumerate() {
            w.append(
                encode_cube_with_filter(c, &f.meta.bake, i as u32, filter)
                    .unwrap()
                    .0,
            )
            .unwrap();
        }
        w.finish().unwrap();
        let s = Store::open(&p).unwrap();
        assert!(s.verify().is_ok());
        for i in 0..s.cube_count() {
            assert_eq!(
                s.read_cube(i).unwrap().faces,
                store.read_cube(i).unwrap().faces
            );
        }
    }
}

/// Replaces the first BC6H block `block` of face `face` of cube `cube` with one whose mode is
/// reserved, keeping the frame's compressed size (tries the reserved first bytes in turn until
/// zstd gives the same size), and reseals the frame checksum in the table of contents, its
/// trailer and the header. Returns the new bytes.
fn with_reserved_block(bytes: &[u8], cube: u32, face: usize, block: usize) -> Vec<u8> {
    let store = Store::from_bytes(bytes).unwrap();
    let h = store.header();
    let e = store.face_entry(cube, face).unwrap();
    let level = store.meta().bake.zstd_level;
    let mut raw = vec![0u8; store.face_raw_size()];
    store.read_face_raw(cube, face, &mut raw).unwrap();
    let toc = store.header().toc;
    for hi in 0..8u8 {
        for mode in [0b10011u8, 0b10111, 0b11011, 0b11111] {
            let mut r = raw.clone();
            r[block * BLOCK_BYTES] = mode | (hi << 5);
            let plane = h.distance_plane();
            let size =
                filter::filtered_face_size(h.filter, h.encoding, h.cube_resolution, plane, 9);
            let mut filtered = vec![0u8; size.unwrap()];
            filter::filter_face(
                h.filter,
                h.encoding,
                h.cube_resolution,
                plane,
                &r,
                &mut filtered,
            )
            .unwrap();
            let frame = zstd::bulk::compress(&filtered, level).unwrap();
            if frame.len() as u64 != e.compressed_size {
                continue;
            }
            let mut b = bytes.to_vec();
            let off = e.offset as usize;
            b[off..off + frame.len()].copy_from_slice(&frame);
            let entry = toc.offset as usize + (cube as usize * 6 + face) * TOC_ENTRY_BYTES;
            put_u64(&mut b, entry + 24, xxh3_64(&frame));
            let end = (toc.offset + toc.size - 8) as usize;
            let t = xxh3_64(&b[toc.offset as usize..end]);
            put_u64(&mut b, end, t);
            reseal_header(&mut b);
            return b;
        }
    }
    panic!("no reserved mode recompresses to the same size");
}

/// A block with a reserved mode is a typed error naming cube, face and block: from the decoded
/// read, from the raw read (what a GPU upload would take), and from verify.
#[test]
fn a_reserved_mode_block_is_a_typed_error() {
    let b = store_bytes(bc6h_spec());
    let c = with_reserved_block(&b, 2, 3, 1);
    let store = Store::from_bytes(&c).unwrap();
    let is_it = |e: &Error| {
        matches!(
            e,
            Error::ReservedBc6hMode {
                cube: 2,
                face: 3,
                block: 1,
                ..
            }
        )
    };
    let e = store.read_cube(2).unwrap_err();
    assert!(is_it(&e), "{e}");
    assert!(
        e.to_string().contains("cube 2, face 3, BC6H block 1"),
        "{e}"
    );
    let mut raw = vec![0u8; store.face_raw_size()];
    let e = store.read_face_raw(2, 3, &mut raw).unwrap_err();
    assert!(is_it(&e), "{e}");
    assert!(store.verify().is_err());
    // The other faces still read.
    store.read_face_raw(2, 2, &mut raw).unwrap();
    store.read_cube(1).unwrap();
}

/// Damage a BC6H store: a flipped frame byte is a checksum error naming cube and face; an
/// unknown encoding tag is refused; every random damage is a typed error or
/// leaves readable faces, never a panic.
#[test]
fn a_damaged_bc6h_store_gives_typed_errors() {
    let b = store_bytes(bc6h_spec());
    let store = Store::from_bytes(&b).unwrap();
    let e = store.face_entry(1, 4).unwrap();
    let mut c = b.clone();
    c[e.offset as usize + 3] ^= 0x40;
    let s = Store::from_bytes(&c).unwrap();
    assert!(matches!(
        s.read_cube(1),
        Err(Error::FaceChecksum {
            cube: 1,
            face: 4,
            ..
        })
    ));
    // An unknown encoding tag.
    let mut c = b.clone();
    c[16..20].copy_from_slice(&4u32.to_le_bytes());
    reseal_header(&mut c);
    assert!(matches!(
        Store::from_bytes(&c),
        Err(Error::InvalidHeader {
            field: "encoding",
            ..
        })
    ));
    // Random byte damage after the header: typed errors only.
    let mut rng = Rng(77);
    for _ in 0..300 {
        let mut c = b.clone();
        let at = HEADER_BYTES + (rng.next_u64() as usize) % (c.len() - HEADER_BYTES);
        c[at] ^= 1 << (rng.next_u64() % 8);
        if let Ok(s) = Store::from_bytes(&c) {
            for cube in 0..s.cube_count() {
                let _ = s.read_cube(cube);
            }
            let _ = s.verify();
        }
    }
}

/// `face_error` on known values.
#[test]
fn face_error_measures() {
    let a = [[1.0f32, 0.5, 0.0], [2.0, 2.0, 2.0]];
    let b = [[1.0f32, 0.5, 0.1], [2.0, 2.0, 2.0]];
    let e = face_error(&a, &b, 1e-3);
    assert_eq!(e.texels, 2);
    assert!((e.max_relative - 0.1).abs() < 1e-6);
    assert!((e.mean_relative - 0.05).abs() < 1e-6);
    let want = ((1.1f64.ln()).powi(2) / 6.0).sqrt();
    assert!((e.rmsle - want).abs() < 1e-6);
    assert_eq!(face_error(&a, &a, 1e-3).max_relative, 0.0);
    let m = e.merge(face_error(&a, &a, 1e-3));
    assert_eq!(m.texels, 4);
    assert!((m.max_relative - 0.1).abs() < 1e-6);
}

/// A BC6H bake split into shards merges into the store a single bake writes, byte for byte.
#[test]
fn bc6h_shards_merge_byte_for_byte() {
    let spec = bc6h_spec();
    let f = fixture(spec);
    let (dir, single) = temp_store("single.oslf");
    write(&single, &f);
    let total = f.cubes.len() as u32;
    let mut paths = Vec::new();
    for index in 0..3 {
        let s = ShardSpec::new(index, 3).unwrap();
        let path = dir.path().join(format!("s.shard-{index}"));
        let mut w = ShardWriter::create(&path, s, &f.meta, &f.points, &f.maps).unwrap();
        for k in 0..s.cubes_of(total) {
            let i = s.cube(k);
            let (e, _) = encode_cube(&f.cubes[i as usize], &f.meta.bake, i).unwrap();
            w.append(e).unwrap();
        }
        w.finish().unwrap();
        paths.push(path);
    }
    let merged = dir.path().join("merged.oslf");
    shard::merge(&paths, &merged).unwrap();
    assert_eq!(
        std::fs::read(&merged).unwrap(),
        std::fs::read(&single).unwrap()
    );
    assert_eq!(
        Store::open(&merged).unwrap().header().encoding,
        Encoding::Bc6h
    );
}
