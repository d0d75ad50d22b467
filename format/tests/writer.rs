//! Writer behaviour: validation, resume after a kill, byte-identical output.

use crate::common;

use common::*;
use oslf_format::writer::partial_path;
use oslf_format::*;

fn spec() -> Spec {
    Spec {
        encoding: Encoding::Rgb9e5,
        cube_res: 8,
        map_res: 4,
        points: 9,
        patches: 3,
        distance: true,
        env: true,
        seed: 5,
        mantissa_bits: 9,
    }
}

fn reference(f: &Fixture) -> Vec<u8> {
    let (_dir, path) = temp_store("ref.oslf");
    write(&path, f);
    std::fs::read(&path).unwrap()
}

/// The first 8 bytes of a scene hash in hex, as resume's messages show it.
fn hex8(h: &[u8; 32]) -> String {
    let s: String = h[..8].iter().map(|v| format!("{v:02x}")).collect();
    format!("{s}…")
}

fn encoded(f: &Fixture, i: usize) -> EncodedCube {
    encode_cube(&f.cubes[i], &f.meta.bake, i as u32).unwrap().0
}

/// Appends `n` cubes, then drops the writer without finishing (a kill after a flush).
fn start(path: &std::path::Path, f: &Fixture, n: usize) {
    let mut w = StoreWriter::create(path, &f.meta, &f.points, &f.maps).unwrap();
    for i in 0..n {
        w.append(encoded(f, i)).unwrap();
    }
    w.sync().unwrap();
}

fn complete(path: &std::path::Path, f: &Fixture) -> StoreSummary {
    let mut w = StoreWriter::resume(path, &f.meta, &f.points, &f.maps).unwrap();
    for i in w.next_cube() as usize..f.cubes.len() {
        w.append(encoded(f, i)).unwrap();
    }
    w.finish().unwrap()
}

#[test]
fn resume_recovers_complete_cubes_and_is_byte_identical() {
    let f = fixture(spec());
    let want = reference(&f);
    for n in [0usize, 1, 4, 10] {
        let (_dir, path) = temp_store("r.oslf");
        start(&path, &f, n);
        assert!(!path.exists(), "nothing under the final name before finish");
        let w = StoreWriter::resume(&path, &f.meta, &f.points, &f.maps).unwrap();
        assert_eq!(w.next_cube() as usize, n);
        assert_eq!(w.total_cubes() as usize, f.cubes.len());
        drop(w);
        complete(&path, &f);
        assert_eq!(
            std::fs::read(&path).unwrap(),
            want,
            "resumed after {n} cubes"
        );
        assert!(!partial_path(&path).exists());
    }
}

#[test]
fn a_quantized_store_resumes_byte_identical_with_filter_3() {
    let f = fixture(Spec {
        mantissa_bits: 3,
        ..spec()
    });
    let want = reference(&f);
    let (_dir, path) = temp_store("q.oslf");
    start(&path, &f, 4);
    complete(&path, &f);
    assert_eq!(std::fs::read(&path).unwrap(), want);
    let store = Store::open(&path).unwrap();
    assert_eq!(store.header().filter, Filter::PredictPacked);
    store.verify().unwrap();
}

#[test]
fn resume_truncates_a_torn_record() {
    let f = fixture(spec());
    let want = reference(&f);
    let (_dir, path) = temp_store("torn.oslf");
    start(&path, &f, 6);
    let partial = partial_path(&path);
    let full = std::fs::metadata(&partial).unwrap().len();
    // Tear the last record at several points (inside its header, inside its frames).
    let store = Store::from_bytes(&want).unwrap();
    let rec5 = store.face_entry(5, 0).unwrap().offset - 160;
    let end5 = store.face_entry(6, 0).unwrap().offset - 160;
    assert_eq!(end5, full);
    for cut in [rec5 + 1, rec5 + 159, rec5 + 160, rec5 + 200, end5 - 1] {
        let bytes = std::fs::read(&partial).unwrap();
        std::fs::write(&partial, &bytes[..cut as usize]).unwrap();
        let w = StoreWriter::resume(&path, &f.meta, &f.points, &f.maps).unwrap();
        assert_eq!(w.next_cube(), 5, "cut at {cut}");
        drop(w);
        assert_eq!(std::fs::metadata(&partial).unwrap().len(), rec5);
        // Put cube 5 back for the next cut.
        let mut w = StoreWriter::resume(&path, &f.meta, &f.points, &f.maps).unwrap();
        w.append(encoded(&f, 5)).unwrap();
        w.sync().unwrap();
    }
    // A damaged frame in cube 3: cubes 3.. are dropped.
    let mut bytes = std::fs::read(&partial).unwrap();
    let e = store.face_entry(3, 2).unwrap();
    bytes[e.offset as usize + 3] ^= 0xff;
    std::fs::write(&partial, &bytes).unwrap();
    let w = StoreWriter::resume(&path, &f.meta, &f.points, &f.maps).unwrap();
    assert_eq!(w.next_cube(), 3);
    drop(w);
    complete(&path, &f);
    assert_eq!(std::fs::read(&path).unwrap(), want);
}

#[test]
fn resume_after_a_kill_inside_finish() {
    // finish() got as far as writing the TOC and patching the header, but not the rename.
    let f = fixture(spec());
    let want = reference(&f);
    let (_dir, path) = temp_store("fin.oslf");
    let partial = partial_path(&path);
    std::fs::write(&partial, &want).unwrap();
    let w = StoreWriter::resume(&path, &f.meta, &f.points, &f.maps).unwrap();
    assert_eq!(w.next_cube() as usize, f.cubes.len());
    w.finish().unwrap();
    assert_eq!(std::fs::read(&path).unwrap(), want);
}

#[test]
fn resume_with_different_inputs_is_a_mismatch() {
    let f = fixture(spec());
    let (_dir, path) = temp_store("mm.oslf");
    start(&path, &f, 2);
    let mut meta = f.meta.clone();
    meta.bake.seed += 1;
    let e = StoreWriter::resume(&path, &meta, &f.points, &f.maps)
        .err()
        .unwrap();
    // Each refusal names the setting, its value in the partial file and in this bake.
    assert!(
        matches!(&e, Error::ResumeSettings { differences, .. }
            if differences == &["seed 5 (this bake: 6)"]),
        "{e}"
    );
    assert!(
        e.to_string()
            .ends_with("it was started with different settings: seed 5 (this bake: 6)"),
        "{e}"
    );
    let mut meta = f.meta.clone();
    meta.bake.encoding = Encoding::Rgba16f;
    let e = StoreWriter::resume(&path, &meta, &f.points, &f.maps)
        .err()
        .unwrap();
    assert!(
        matches!(&e, Error::ResumeSettings { differences, .. }
            if differences[0] == "encoding rgb9e5 (this bake: rgba16f)"),
        "{e}"
    );
    // How the cubes were sampled and filtered (format 1.2's sampling record): a bake that
    // would denoise, or sample to a target, does not continue one that did not.
    let mut meta = f.meta.clone();
    meta.bake.sampling = Some(Sampling {
        target_noise: 0.1,
        denoised: true,
    });
    let e = StoreWriter::resume(&path, &meta, &f.points, &f.maps)
        .err()
        .unwrap();
    assert!(
        matches!(&e, Error::ResumeSettings { differences, .. }
            if differences == &["target_noise 0 (this bake: 0.1)", "denoise false (this bake: true)"]),
        "{e}"
    );
    // Several settings at once, each named.
    let mut meta = f.meta.clone();
    meta.bake.cube_resolution = 16;
    meta.bake.epsilon = 0.25;
    meta.bake.scene_hash[0] ^= 0xff;
    let e = StoreWriter::resume(&path, &meta, &f.points, &f.maps)
        .err()
        .unwrap();
    let want = format!(
        "scene hash (the scene file's text) {} (this bake: {}), cube_resolution 8 (this bake: 16), epsilon 0.05 (this bake: 0.25)",
        hex8(&f.meta.bake.scene_hash),
        hex8(&meta.bake.scene_hash)
    );
    assert!(
        matches!(&e, Error::ResumeSettings { differences, .. } if differences.join(", ") == want),
        "{e}\nwant {want}"
    );
    // A different number of sample points (e.g. another sample_count), a camera, an object.
    let mut points = f.points.clone();
    points.push(points[0]);
    let e = StoreWriter::resume(&path, &f.meta, &points, &f.maps)
        .err()
        .unwrap();
    assert!(
        matches!(&e, Error::ResumeSettings { differences, .. } if differences == &["sample count 9 (this bake: 10)"]),
        "{e}"
    );
    let mut meta = f.meta.clone();
    assert!(meta.camera.is_none());
    meta.camera = Some(CameraInfo {
        position: [0.0, 1.0, 5.0],
        target: [0.0, 0.0, 0.0],
        up: [0.0, 1.0, 0.0],
        vfov_deg: 30.0,
    });
    meta.objects[1].base_color = [1.0, 0.0, 0.0];
    let e = StoreWriter::resume(&path, &meta, &f.points, &f.maps)
        .err()
        .unwrap();
    assert!(
        matches!(&e, Error::ResumeSettings { differences, .. }
            if differences == &["camera none (this bake: position [0.0, 1.0, 5.0], target [0.0, 0.0, 0.0], up [0.0, 1.0, 0.0], vfov 30°)",
                "object 1 (\"lid\") colour [0.1, 0.2, 0.3] (this bake: [1.0, 0.0, 0.0])"]),
        "{e}"
    );
    let mut points = f.points.clone();
    points[4].position[1] += 1.0;
    let e = StoreWriter::resume(&path, &f.meta, &points, &f.maps)
        .err()
        .unwrap();
    assert!(
        matches!(&e, Error::ResumeMismatch { what, .. } if what.contains("point 4")),
        "{e}"
    );
    let mut maps = f.maps.clone();
    maps.indices[7] = [0, 1, 2, 3];
    let e = StoreWriter::resume(&path, &f.meta, &f.points, &maps)
        .err()
        .unwrap();
    assert!(
        matches!(&e, Error::ResumeMismatch { what, .. } if what.contains("sample maps")),
        "{e}"
    );
    // The unchanged inputs still resume.
    assert_eq!(
        StoreWriter::resume(&path, &f.meta, &f.points, &f.maps)
            .unwrap()
            .next_cube(),
        2
    );
}

#[test]
fn resume_with_other_mantissa_bits_or_version_is_a_mismatch() {
    let f = fixture(spec());
    let (_dir, path) = temp_store("bits.oslf");
    start(&path, &f, 3);
    let mut meta = f.meta.clone();
    meta.bake.mantissa_bits = 5;
    let e = StoreWriter::resume(&path, &meta, &f.points, &f.maps)
        .err()
        .unwrap();
    assert!(
        matches!(&e, Error::ResumeSettings { differences, .. } if differences == &["mantissa_bits 9 (this bake: 5)", "face filter predict-rows (this bake: predict-packed)"]),
        "{e}"
    );
    // A cube quantized differently is refused by append.
    let mut w = StoreWriter::resume(&path, &f.meta, &f.points, &f.maps).unwrap();
    let (cube, _) = encode_cube(&f.cubes[3], &meta.bake, 3).unwrap();
    let e = w.append(cube).err().unwrap();
    assert!(
        matches!(&e, Error::CubeParamsMismatch { detail, .. } if detail.contains("mantissa_bits=5")),
        "{e}"
    );
    // A partial file of format version 1 (here: a complete version-1 store, whose finish()
    // was interrupted as far as resume can tell) is not continued with version-2 records.
    let spec1 = Spec {
        distance: true,
        seed: 2,
        ..Spec::default()
    };
    let f1 = fixture(spec1);
    let (_dir1, path1) = temp_store("v1.oslf");
    std::fs::copy(
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/v1-rgb9e5.oslf"),
        partial_path(&path1),
    )
    .unwrap();
    let e = StoreWriter::resume(&path1, &f1.meta, &f1.points, &f1.maps)
        .err()
        .unwrap();
    assert!(
        matches!(&e, Error::ResumeMismatch { what, .. } if what.contains("format version 1")),
        "{e}"
    );
}

#[test]
fn resume_without_partial() {
    let f = fixture(spec());
    let (_dir, path) = temp_store("nothing.oslf");
    assert!(matches!(
        StoreWriter::resume(&path, &f.meta, &f.points, &f.maps),
        Err(Error::NoPartial(_))
    ));
}

#[test]
fn append_checks_order_and_params() {
    let f = fixture(spec());
    let (_dir, path) = temp_store("order.oslf");
    let mut w = StoreWriter::create(&path, &f.meta, &f.points, &f.maps).unwrap();
    assert!(matches!(
        w.append(encoded(&f, 1)),
        Err(Error::CubeOutOfOrder {
            expected: 0,
            got: 1
        })
    ));
    let mut other = f.meta.bake.clone();
    other.encoding = Encoding::Rgba32f;
    let (e, _) = encode_cube(&f.cubes[0], &other, 0).unwrap();
    assert!(matches!(
        w.append(e),
        Err(Error::CubeParamsMismatch { cube: 0, .. })
    ));
    let (e, _) = encode_cube(&f.cubes[0], &f.meta.bake, 99).unwrap();
    assert!(matches!(
        w.append(e),
        Err(Error::CubeOutOfRange { cube: 99, .. })
    ));
    w.append(encoded(&f, 0)).unwrap();
    assert!(matches!(
        w.finish(),
        Err(Error::Incomplete {
            present: 1,
            total: 10
        })
    ));
    assert!(!path.exists());
}

#[test]
fn create_validates_inputs() {
    let f = fixture(spec());
    let (_dir, path) = temp_store("bad.oslf");
    let mut maps = f.maps.clone();
    maps.indices[5] = [0, 9, INVALID_INDEX, INVALID_INDEX];
    assert!(matches!(
        StoreWriter::create(&path, &f.meta, &f.points, &maps),
        Err(Error::InvalidSampleMap { channel: 1, .. })
    ));
    let mut maps = f.maps.clone();
    maps.indices[5] = [INVALID_INDEX, 1, INVALID_INDEX, INVALID_INDEX];
    assert!(matches!(
        StoreWriter::create(&path, &f.meta, &f.points, &maps),
        Err(Error::InvalidSampleMap { channel: 1, .. })
    ));
    let mut maps = f.maps.clone();
    maps.indices.pop();
    assert!(matches!(
        StoreWriter::create(&path, &f.meta, &f.points, &maps),
        Err(Error::SampleMapShape(_))
    ));
    let mut points = f.points.clone();
    points[2].normal[0] = f32::NAN;
    assert!(matches!(
        StoreWriter::create(&path, &f.meta, &points, &f.maps),
        Err(Error::InvalidSamplePoint { index: 2, .. })
    ));
    let mut meta = f.meta.clone();
    meta.objects[1].patch_count += 1;
    assert!(matches!(
        StoreWriter::create(&path, &meta, &f.points, &f.maps),
        Err(Error::InvalidMetadata { .. })
    ));
    let mut meta = f.meta.clone();
    meta.objects[0].name = "x".repeat(5000);
    assert!(matches!(
        StoreWriter::create(&path, &meta, &f.points, &f.maps),
        Err(Error::InvalidMetadata { .. })
    ));
    let mut meta = f.meta.clone();
    meta.camera = Some(CameraInfo {
        position: [0.0; 3],
        target: [0.0; 3],
        up: [0.0; 3],
        vfov_deg: f32::INFINITY,
    });
    assert!(matches!(
        StoreWriter::create(&path, &meta, &f.points, &f.maps),
        Err(Error::InvalidMetadata { .. })
    ));
}

#[test]
fn encode_cube_rejects_bad_radiance_and_counts_clamps() {
    let f = fixture(spec());
    let mut c = f.cubes[0].clone();
    c.faces[4][8 * 3 + 5] = [1.0, f32::NAN, 0.0];
    assert!(matches!(
        encode_cube(&c, &f.meta.bake, 7),
        Err(Error::InvalidRadiance {
            cube: 7,
            face: 4,
            x: 5,
            y: 3,
            ..
        })
    ));
    let mut c = f.cubes[0].clone();
    c.faces[1][2] = [-1.0, 0.0, 0.0];
    assert!(matches!(
        encode_cube(&c, &f.meta.bake, 0),
        Err(Error::InvalidRadiance {
            face: 1,
            x: 2,
            y: 0,
            ..
        })
    ));
    let mut c = f.cubes[0].clone();
    c.distance.as_mut().unwrap()[5][9] = f32::INFINITY;
    assert!(matches!(
        encode_cube(&c, &f.meta.bake, 0),
        Err(Error::InvalidDistance {
            face: 5,
            x: 1,
            y: 1,
            ..
        })
    ));
    let mut c = f.cubes[0].clone();
    c.faces[0][0] = [1e6, 0.0, 0.0];
    c.faces[2][0] = [0.0, 70000.0, 0.0];
    let (_, stats) = encode_cube(&c, &f.meta.bake, 0).unwrap();
    assert_eq!(stats.clamped_texels, 2);
    assert_eq!(stats.raw_bytes, 6 * 64 * 8);
    let mut c = f.cubes[0].clone();
    c.faces[3].pop();
    assert!(matches!(
        encode_cube(&c, &f.meta.bake, 0),
        Err(Error::CubeShape { .. })
    ));
    let mut c = f.cubes[0].clone();
    c.distance = None;
    assert!(matches!(
        encode_cube(&c, &f.meta.bake, 0),
        Err(Error::CubeShape { .. })
    ));
}

/// A partial file whose `create()` was killed before the header, metadata, sample points and
/// sample maps were all written holds no cube maps: resume says so with its own error (the
/// bake then starts over), whatever settings it was started with.
#[test]
fn a_partial_killed_during_create_is_never_created_not_a_mismatch() {
    let f = fixture(spec());
    let (_dir, path) = temp_store("torn.oslf");
    start(&path, &f, 0);
    let partial = partial_path(&path);
    let full = std::fs::read(&partial).unwrap();
    let fixed = full.len();
    let mut other = f.meta.clone();
    other.bake.seed += 1;
    for cut in [0, 1, 100, 255, 256, 300, fixed - 1] {
        std::fs::write(&partial, &full[..cut]).unwrap();
        for meta in [&f.meta, &other] {
            match StoreWriter::resume(&path, meta, &f.points, &f.maps) {
                Err(Error::PartialNeverCreated { path: p, detail }) => {
                    assert_eq!(p, partial);
                    let want = if cut < 256 {
                        format!("it has {cut} bytes, less than its 256-byte header")
                    } else {
                        format!("it has {cut} bytes, less than the {fixed} bytes of its header, metadata, sample points and sample maps")
                    };
                    assert_eq!(detail, want);
                }
                other => panic!("cut {cut}: {:?}", other.err()),
            }
        }
    }
    let e = Error::PartialNeverCreated {
        path: partial.clone(),
        detail: "it has 0 bytes, less than its 256-byte header".into(),
    };
    assert_eq!(
        e.to_string(),
        format!(
            "{} was never completely created (it has 0 bytes, less than its 256-byte header), so it holds no finished cube maps",
            partial.display()
        )
    );
    // Full length but the header never reached the disk (zeros).
    let mut zeroed = full.clone();
    zeroed[..256].fill(0);
    std::fs::write(&partial, &zeroed).unwrap();
    assert!(matches!(
        StoreWriter::resume(&path, &f.meta, &f.points, &f.maps),
        Err(Error::PartialNeverCreated { detail, .. }) if detail == "its header is all zero bytes"
    ));
    // Complete fixed sections and no cube: resumes from cube 0.
    std::fs::write(&partial, &full).unwrap();
    let w = StoreWriter::resume(&path, &f.meta, &f.points, &f.maps).unwrap();
    assert_eq!(w.next_cube(), 0);
}

/// A partial file that is not a store, or whose header or metadata is damaged, is refused with
/// what is wrong and what to do (it may hold finished cubes, so it is not silently replaced).
#[test]
fn a_damaged_partial_is_refused_with_a_reason() {
    let f = fixture(spec());
    let (_dir, path) = temp_store("dmg.oslf");
    start(&path, &f, 2);
    let partial = partial_path(&path);
    let good = std::fs::read(&partial).unwrap();
    let refused = |bytes: &[u8]| -> String {
        std::fs::write(&partial, bytes).unwrap();
        match StoreWriter::resume(&path, &f.meta, &f.points, &f.maps) {
            Err(Error::ResumeMismatch { what, .. }) => what,
            other => panic!("{:?}", other.err()),
        }
    };
    let mut b = good.clone();
    b[..8].copy_from_slice(b"NOTOSLF!");
    assert!(refused(&b).starts_with("it is not an OSLF store"));
    let mut b = good.clone();
    b[8..12].copy_from_slice(&VERSION_1_1.to_le_bytes());
    assert_eq!(
        refused(&b),
        "it is of format 1.1, written by an earlier oslf, and this writer continues only format 1.2 files"
    );
    let mut b = good.clone();
    b[8..12].copy_from_slice(&(VERSION + 1).to_le_bytes());
    assert_eq!(
        refused(&b),
        "it is of format version 0x00010003, and this writer continues only format 1.2 files"
    );
    b[8..12].copy_from_slice(&8u32.to_le_bytes());
    assert_eq!(
        refused(&b),
        "it is of development format version 8, from before format 1.0, and this writer continues only format 1.2 files"
    );
    let mut b = good.clone();
    b[30] ^= 1;
    assert!(refused(&b).starts_with("its header is damaged: header checksum mismatch"));
    let mut b = good.clone();
    b[300] ^= 1;
    assert!(refused(&b).starts_with("its metadata section (byte offset 256) is damaged"));
}

/// A shard whose bake never finished it is refused by the merge, naming the file and the
/// shard (index and count), with no hint of a command-line flag.
#[test]
fn merging_an_unfinished_shard_names_it() {
    let f = fixture(spec());
    let (dir, _) = temp_store("unused.oslf");
    let total = f.cubes.len() as u32;
    let mut paths = Vec::new();
    for index in 0..2 {
        let s = ShardSpec::new(index, 2).unwrap();
        let path = dir.path().join(format!("s.shard-{index}"));
        let mut w = ShardWriter::create(&path, s, &f.meta, &f.points, &f.maps).unwrap();
        for k in 0..s.cubes_of(total) {
            let i = s.cube(k);
            w.append(encoded(&f, i as usize)).unwrap();
        }
        if index == 0 {
            w.finish().unwrap();
            paths.push(path);
        } else {
            // Killed before finish(): the file keeps its `.partial` name.
            paths.push(w.partial_path().to_path_buf());
            drop(w);
        }
    }
    let e = shard::merge(&paths, &dir.path().join("merged.oslf"))
        .err()
        .unwrap();
    assert!(
        matches!(&e, Error::UnfinishedShard { path, index: 1, count: 2 } if *path == paths[1]),
        "{e}"
    );
    assert!(!e.to_string().contains("--"), "{e}");
}

/// The distance lattice at the extremes, through a whole store: zero, the
/// smallest subnormal, tiny and huge values, the largest finite `f32` below the no-hit value,
/// and no hit (`f32::MAX`) read back as [`DistancePlane::quantize`] says (no hit and zero
/// exactly); NaN, infinite and negative distances are refused at encode, naming the texel.
#[test]
fn distance_extremes_round_trip_and_bad_distances_are_refused() {
    let f = fixture(spec());
    let extremes = [
        0.0,
        f32::from_bits(1),
        f32::MIN_POSITIVE,
        1e-30,
        0.1,
        1.0,
        3.3,
        1e30,
        3.39e38,
        f32::from_bits(f32::MAX.to_bits() - 1),
        f32::MAX,
    ];
    let mut cubes = f.cubes.clone();
    for (face, plane) in cubes[0].distance.as_mut().unwrap().iter_mut().enumerate() {
        for (i, d) in plane.iter_mut().enumerate() {
            *d = extremes[(i + face) % extremes.len()];
        }
    }
    let (_dir, path) = temp_store("extremes.oslf");
    let mut w = StoreWriter::create(&path, &f.meta, &f.points, &f.maps).unwrap();
    for (i, c) in cubes.iter().enumerate() {
        w.append(encode_cube(c, &f.meta.bake, i as u32).unwrap().0)
            .unwrap();
    }
    w.finish().unwrap();
    let store = Store::open(&path).unwrap();
    let plane = store.header().distance_plane();
    assert_eq!(plane, DistancePlane::Lattice { bits: 3 }); // 8² faces
    assert!(store.verify().is_ok());
    let got = store.read_cube(0).unwrap().distance.unwrap();
    for (face, plane_got) in got.iter().enumerate() {
        for (i, g) in plane_got.iter().enumerate() {
            let want = extremes[(i + face) % extremes.len()];
            assert_eq!(*g, plane.quantize(want), "face {face} texel {i}: {want}");
            assert!(g.is_finite() && *g >= 0.0);
            if want == 0.0 || want == f32::MAX {
                assert_eq!(*g, want);
            } else if want < 3.39e38 {
                // Below the last lattice step: within half a step (2^-4 relative), or at most
                // the subnormal's own size.
                assert!(
                    (g - want).abs() <= want / 16.0 + f32::from_bits(1),
                    "{want} → {g}"
                );
            } else {
                assert!(
                    *g < f32::MAX && (g - want).abs() <= want / 8.0,
                    "{want} → {g}"
                );
            }
        }
    }
    for (bad, name) in [
        (f32::NAN, "NaN"),
        (f32::NEG_INFINITY, "-inf"),
        (-1e-3, "negative"),
    ] {
        let mut c = f.cubes[0].clone();
        c.distance.as_mut().unwrap()[2][8 * 6 + 7] = bad;
        let e = encode_cube(&c, &f.meta.bake, 4).err().unwrap();
        assert!(
            matches!(
                e,
                Error::InvalidDistance {
                    cube: 4,
                    face: 2,
                    x: 7,
                    y: 6,
                    ..
                }
            ),
            "{name}: {e}"
        );
    }
}

/// One writer per output: while a store writer, a shard writer or a merge holds a path's partial
/// file, every other writer of that path is refused with [`Error::Busy`] and the first one's
/// file is left as it was; once the first has finished, the path is free again.
#[test]
fn a_second_writer_of_any_kind_is_busy() {
    let f = fixture(spec());
    let (dir, path) = temp_store("one.oslf");
    let busy = |r: Result<(), Error>| match r {
        Err(Error::Busy { holder, .. }) => {
            assert!(
                !system_lists_flocks_of(std::process::id())
                    || holder.contains(&format!("process {}", std::process::id())),
                "{holder}"
            )
        }
        Err(e) => panic!("{e}"),
        Ok(()) => panic!("a second writer was let in"),
    };
    let first = StoreWriter::create(&path, &f.meta, &f.points, &f.maps).unwrap();
    let held = std::fs::read(partial_path(&path)).unwrap();
    busy(StoreWriter::create(&path, &f.meta, &f.points, &f.maps).map(drop));
    busy(StoreWriter::resume(&path, &f.meta, &f.points, &f.maps).map(drop));
    assert_eq!(std::fs::read(partial_path(&path)).unwrap(), held);

    // Shards: two writers of one shard file; a merge into a path another writer holds.
    let total = f.cubes.len() as u32;
    let mut shards = Vec::new();
    for index in 0..2 {
        let s = ShardSpec::new(index, 2).unwrap();
        let shard = dir.path().join(format!("s.shard-{index}"));
        let mut w = ShardWriter::create(&shard, s, &f.meta, &f.points, &f.maps).unwrap();
        busy(ShardWriter::create(&shard, s, &f.meta, &f.points, &f.maps).map(drop));
        busy(ShardWriter::resume(&shard, s, &f.meta, &f.points, &f.maps).map(drop));
        for k in 0..s.cubes_of(total) {
            w.append(encoded(&f, s.cube(k) as usize)).unwrap();
        }
        w.finish().unwrap();
        shards.push(shard);
    }
    busy(shard::merge(&shards, &path).map(drop));
    drop(first);
    shard::merge(&shards, &path).unwrap();
    Store::open(&path).unwrap().verify().unwrap();
}
