//! Write with `StoreWriter`, read back with `Store::open` and `Store::from_bytes`, compare.

use crate::common;

use common::*;
use oslf_format::distance::quantize_distance;
use oslf_format::*;
use proptest::prelude::*;

fn check_store(store: &Store, f: &Fixture, spec: Spec) {
    assert_eq!(store.meta(), &f.meta);
    assert_eq!(store.sample_points(), f.points.as_slice());
    assert_eq!(store.cube_count() as usize, f.cubes.len());
    assert_eq!(
        store.env_cube_index(),
        spec.env.then_some(spec.points as u32)
    );
    let res = spec.map_res;
    let per_patch = (res * res) as usize;
    for patch in 0..spec.patches as u32 {
        let view = store.sample_map(patch).unwrap();
        assert_eq!(view.resolution(), res);
        assert_eq!(
            view.width(),
            if spec.points <= 65535 {
                IndexWidth::U16
            } else {
                IndexWidth::U32
            }
        );
        match view.width() {
            IndexWidth::U16 => assert_eq!(view.as_u16().unwrap().len(), per_patch * 4),
            IndexWidth::U32 => assert_eq!(view.as_u32().unwrap().len(), per_patch * 4),
        }
        for y in 0..res {
            for x in 0..res {
                let want = f.maps.indices[patch as usize * per_patch + (y * res + x) as usize];
                assert_eq!(view.get(x, y), Some(want));
            }
        }
        assert_eq!(view.get(res, 0), None);
    }
    assert!(store.sample_map(spec.patches as u32).is_err());
    for (i, want) in f.cubes.iter().enumerate() {
        let got = store.read_cube(i as u32).unwrap();
        assert_eq!(got.resolution, want.resolution);
        for face in 0..6 {
            if spec.encoding == Encoding::Bc6h {
                // Exactly what the BC6H encoder and decoder make of the face.
                let n = spec.cube_res;
                let mut blocks = vec![0u8; Encoding::Bc6h.face_bytes(n).unwrap()];
                oslf_format::bc6h::encode_face(&want.faces[face], n, &mut blocks).unwrap();
                let mut back = vec![[0f32; 3]; (n * n) as usize];
                oslf_format::bc6h::decode_face(&blocks, n, &mut back, i as u32, face).unwrap();
                assert_eq!(back, got.faces[face], "BC6H cube {i} face {face}");
            }
            for (w, g) in want.faces[face].iter().zip(&got.faces[face]) {
                assert!(
                    close_bits(spec.encoding, spec.mantissa_bits, *w, *g),
                    "{:?} cube {i} face {face}: {w:?} -> {g:?}",
                    spec.encoding
                );
            }
        }
        let plane = store.header().distance_plane();
        assert_eq!(got.distance, stored_distances(plane, &want.distance));
        let mut raw = vec![0u8; store.face_raw_size() * 6];
        store.read_cube_raw(i as u32, &mut raw).unwrap();
    }
    let report = store.verify().unwrap();
    assert_eq!(report.cubes as usize, f.cubes.len());
    assert_eq!(report.faces as usize, f.cubes.len() * 6);
}

fn round_trip(spec: Spec) {
    let f = fixture(spec);
    let (_dir, path) = temp_store("rt.oslf");
    let summary = write(&path, &f);
    assert!(!oslf_format::writer::partial_path(&path).exists());
    let bytes = std::fs::read(&path).unwrap();
    assert_eq!(summary.file_size, bytes.len() as u64);
    let opened = Store::open(&path).unwrap();
    check_store(&opened, &f, spec);
    assert_eq!(opened.file_size(), summary.file_size);
    assert_eq!(opened.cube_bytes(), summary.cube_bytes);
    let copied = Store::from_bytes(&bytes).unwrap();
    check_store(&copied, &f, spec);
}

fn encoding() -> impl Strategy<Value = Encoding> {
    prop_oneof![
        Just(Encoding::Rgb9e5),
        Just(Encoding::Rgba16f),
        Just(Encoding::Rgba32f),
        Just(Encoding::Bc6h)
    ]
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 48, ..ProptestConfig::default() })]

    #[test]
    fn small_stores_round_trip(
        encoding in encoding(),
        cube_res in prop_oneof![1u32..=8, Just(16u32), Just(33u32)],
        map_res in prop_oneof![1u32..=8, Just(17u32)],
        points in 1usize..12,
        patches in 1usize..5,
        distance in any::<bool>(),
        env in any::<bool>(),
        seed in any::<u64>(),
        bits in 1u32..=9,
    ) {
        let mantissa_bits = if encoding == Encoding::Rgb9e5 { bits } else { 9 };
        round_trip(Spec { encoding, cube_res, map_res, points, patches, distance, env, seed, mantissa_bits });
    }
}

#[test]
fn larger_resolution_round_trips() {
    for encoding in Encoding::ALL {
        round_trip(Spec {
            encoding,
            cube_res: 64,
            map_res: 32,
            points: 2,
            patches: 2,
            distance: true,
            env: true,
            seed: 7,
            mantissa_bits: 9,
        });
    }
}

#[test]
fn zero_sample_points_with_env_cube() {
    round_trip(Spec {
        points: 0,
        env: true,
        ..Spec::default()
    });
}

#[test]
fn u32_indices_above_65535_points() {
    for points in [65535usize, 65536] {
        let spec = Spec {
            encoding: Encoding::Rgb9e5,
            cube_res: 1,
            map_res: 4,
            points,
            patches: 3,
            distance: false,
            env: points == 65536,
            seed: 3,
            mantissa_bits: 9,
        };
        let mut f = fixture(spec);
        // Make sure large indices actually occur.
        f.maps.indices[0] = [points as u32 - 1, 0, INVALID_INDEX, INVALID_INDEX];
        let (_dir, path) = temp_store("wide.oslf");
        write(&path, &f);
        let store = Store::open(&path).unwrap();
        let view = store.sample_map(0).unwrap();
        let want = if points <= 65535 {
            IndexWidth::U16
        } else {
            IndexWidth::U32
        };
        assert_eq!(view.width(), want);
        assert_eq!(
            view.get(0, 0),
            Some([points as u32 - 1, 0, INVALID_INDEX, INVALID_INDEX])
        );
        check_store(&store, &f, spec);
    }
}

#[test]
fn summary_counts() {
    let spec = Spec::default();
    let f = fixture(spec);
    let (_dir, path) = temp_store("sum.oslf");
    let s = write(&path, &f);
    assert_eq!(s.cubes as usize, f.cubes.len());
    assert_eq!(s.texels, f.cubes.len() as u64 * 6 * 16);
    assert_eq!(s.raw_cube_bytes, s.texels * 4);
    assert_eq!(s.sample_points, spec.points as u64);
}

#[test]
fn both_filters_round_trip_and_are_recorded() {
    for filter in Filter::ALL {
        for encoding in Encoding::ALL {
            let spec = Spec {
                encoding,
                cube_res: 9,
                distance: true,
                ..Spec::default()
            };
            let f = fixture(spec);
            let (_dir, path) = temp_store("filter.oslf");
            let mut w = StoreWriter::create_with_filter(&path, &f.meta, &f.points, &f.maps, filter)
                .unwrap();
            for (i, c) in f.cubes.iter().enumerate() {
                let (e, _) = encode_cube_with_filter(c, &f.meta.bake, i as u32, filter).unwrap();
                assert_eq!(e.filter(), filter);
                w.append(e).unwrap();
            }
            w.finish().unwrap();
            let store = Store::open(&path).unwrap();
            assert_eq!(store.header().filter, filter);
            let bytes = std::fs::read(&path).unwrap();
            assert_eq!(
                u32::from_le_bytes(bytes[176..180].try_into().unwrap()),
                filter.id()
            );
            check_store(&store, &f, spec);
            // The raw bytes read back are exactly the encoded texels and the distances on
            // the 4-bit lattice of 9² faces, whatever the filter.
            let plane = store.header().distance_plane();
            assert_eq!(plane, DistancePlane::Lattice { bits: 4 });
            for (i, c) in f.cubes.iter().enumerate() {
                let mut raw = vec![0u8; store.face_raw_size()];
                for face in 0..6 {
                    store.read_face_raw(i as u32, face, &mut raw).unwrap();
                    let mut want = vec![0u8; encoding.face_bytes(9).unwrap()];
                    encoding::encode_face_texels(encoding, 9, &c.faces[face], &mut want).unwrap();
                    assert_eq!(&raw[..want.len()], want.as_slice());
                    let d = c.distance.as_ref().unwrap();
                    let dist: Vec<u8> = d[face]
                        .iter()
                        .flat_map(|v| plane.quantize(*v).to_le_bytes())
                        .collect();
                    assert_eq!(&raw[want.len()..], dist.as_slice());
                }
            }
        }
    }
}

#[test]
fn a_cube_with_another_filter_is_refused() {
    let spec = Spec::default();
    let f = fixture(spec);
    let (_dir, path) = temp_store("mix.oslf");
    let mut w = StoreWriter::create(&path, &f.meta, &f.points, &f.maps).unwrap();
    let (e, _) = encode_cube_with_filter(&f.cubes[0], &f.meta.bake, 0, Filter::None).unwrap();
    assert!(matches!(
        w.append(e),
        Err(Error::CubeParamsMismatch { cube: 0, .. })
    ));
    // A partial file written with another filter is not resumed.
    drop(w);
    let mut w =
        StoreWriter::create_with_filter(&path, &f.meta, &f.points, &f.maps, Filter::None).unwrap();
    let (e, _) = encode_cube_with_filter(&f.cubes[0], &f.meta.bake, 0, Filter::None).unwrap();
    w.append(e).unwrap();
    w.sync().unwrap();
    drop(w);
    assert!(matches!(
        StoreWriter::resume(&path, &f.meta, &f.points, &f.maps),
        Err(Error::ResumeSettings { differences, .. })
            if differences == ["face filter none (this bake: predict-rows)"]
    ));
}

#[test]
fn quantized_stores_hold_exactly_the_quantized_texels() {
    for bits in 1..=9 {
        let spec = Spec {
            cube_res: 16,
            distance: true,
            mantissa_bits: bits,
            ..Spec::default()
        };
        round_trip(spec);
        let f = fixture(spec);
        let (_dir, path) = temp_store("q.oslf");
        write(&path, &f);
        let store = Store::open(&path).unwrap();
        assert_eq!(store.meta().bake.mantissa_bits, bits);
        let n = 16 * 16;
        let mut raw = vec![0u8; store.face_raw_size()];
        let step = 1u32 << (9 - bits);
        for (c, cube) in f.cubes.iter().enumerate() {
            for face in 0..6 {
                store.read_face_raw(c as u32, face, &mut raw).unwrap();
                for (t, rgb) in cube.faces[face].iter().enumerate() {
                    let got = u32::from_le_bytes(raw[4 * t..4 * t + 4].try_into().unwrap());
                    let full = encoding::encode_rgb9e5(*rgb);
                    assert_eq!(got, encoding::quantize_rgb9e5(full, bits));
                    assert_eq!(got >> 27, full >> 27);
                    for ch in 0..3 {
                        assert_eq!((got >> (9 * ch)) & 0x1ff & (step - 1), 0);
                    }
                }
                // The distance plane is on the distance lattice of 16² faces, whatever the
                // mantissa bits.
                let d = &raw[4 * n..];
                let want: Vec<u8> = cube.distance.as_ref().unwrap()[face]
                    .iter()
                    .flat_map(|v| quantize_distance(*v, 4).to_le_bytes())
                    .collect();
                assert_eq!(d, want.as_slice());
            }
        }
    }
}

#[test]
fn mantissa_bits_are_checked() {
    let f = fixture(Spec::default());
    for (encoding, bits) in [
        (Encoding::Rgb9e5, 0),
        (Encoding::Rgb9e5, 10),
        (Encoding::Rgba16f, 8),
        (Encoding::Rgba32f, 5),
    ] {
        let mut meta = f.meta.clone();
        meta.bake.encoding = encoding;
        meta.bake.mantissa_bits = bits;
        let (_dir, path) = temp_store("bad-bits.oslf");
        let e = StoreWriter::create(&path, &meta, &f.points, &f.maps)
            .err()
            .unwrap();
        assert!(
            matches!(&e, Error::InvalidMetadata { detail, .. } if detail.contains("mantissa_bits")),
            "{e}"
        );
        let e = encode_cube(&f.cubes[0], &meta.bake, 0).err().unwrap();
        assert!(matches!(e, Error::InvalidBakeParams { .. }), "{e}");
    }
}
