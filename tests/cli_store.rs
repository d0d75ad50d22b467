//! `oslf store`: info, verify, exports, and clear errors.

use crate::common;

use common::oslf;
use common::store_fixture::*;

fn bin() -> std::process::Command {
    oslf("store")
}

#[test]
fn info_verify_and_exports() {
    let f = fixture(Spec::default());
    let (dir, path) = temp_store("cli.oslf");
    write(&path, &f);
    let out = bin().arg("info").arg(&path).output().unwrap();
    assert!(out.status.success());
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        text.contains("rgb9e5")
            && text.contains("bytes/texel")
            && text.contains("mantissa bits    9")
            && text
                .contains("sampling         the same samples in every texel, cubes not denoised"),
        "{text}"
    );
    let out = bin().args(["info", "--json"]).arg(&path).output().unwrap();
    assert!(out.status.success());
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["cubes"], 6);
    assert_eq!(v["mantissa_bits"], 9);
    assert_eq!(v["format"], "1.2");
    assert_eq!(v["bake"]["target_noise"], 0.0);
    assert_eq!(v["bake"]["denoised"], false);
    // A format 1.1 store says it does not record how it was sampled.
    let old =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("format/tests/data/v1.1-rgb9e5.oslf");
    let out = bin().arg("info").arg(&old).output().unwrap();
    assert!(out.status.success());
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        text.contains("format           1.1")
            && text
                .contains("sampling         not recorded (format 1.0 and 1.1 stores do not say)"),
        "{text}"
    );
    let out = bin().args(["info", "--json"]).arg(&old).output().unwrap();
    let w: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert!(w["bake"]["denoised"].is_null() && w["bake"]["target_noise"].is_null());
    assert_eq!(v["irradiance_bytes"], v["cubes"].as_u64().unwrap() * 108);
    assert_eq!(v["env_cube_index"], 5);
    let out = bin().arg("verify").arg(&path).output().unwrap();
    assert!(out.status.success());

    let exr = dir.path().join("cube.exr");
    let out = bin()
        .arg("export-cube")
        .arg(&path)
        .arg("2")
        .arg("-o")
        .arg(&exr)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(exr.exists());
    let out = bin()
        .arg("export-cube")
        .arg(&path)
        .args(["5", "--layout", "faces", "-o"])
        .arg(&exr)
        .output()
        .unwrap();
    assert!(out.status.success());
    assert!(dir.path().join("cube_nz.exr").exists());
    let png = dir.path().join("map.png");
    let out = bin()
        .arg("export-sample-map")
        .arg(&path)
        .args(["1", "--channel", "2", "-o"])
        .arg(&png)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(png.exists());

    // Errors: non-zero exit, a message, no panic.
    let out = bin()
        .arg("export-cube")
        .arg(&path)
        .args(["99", "-o"])
        .arg(&exr)
        .output()
        .unwrap();
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("out of range"));

    let mut bytes = std::fs::read(&path).unwrap();
    let store = oslf_format::Store::open(&path).unwrap();
    let e = store.face_entry(3, 4).unwrap();
    drop(store);
    bytes[e.offset as usize + 2] ^= 0x55;
    let bad = dir.path().join("bad.oslf");
    std::fs::write(&bad, &bytes).unwrap();
    let out = bin().arg("verify").arg(&bad).output().unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("cube 3, face 4") && err.contains("offset"),
        "{err}"
    );
    assert!(!err.contains("panicked"));

    let out = bin()
        .arg("info")
        .arg(dir.path().join("missing.oslf"))
        .output()
        .unwrap();
    assert!(!out.status.success());
    assert!(!String::from_utf8_lossy(&out.stderr).contains("panicked"));
}

/// `oslf store verify` checks every padding byte and what the faces decode to: a non-zero
/// padding byte, or a face filter id changed with the header checksum recomputed, fails with
/// the byte offset.
#[test]
fn verify_checks_padding_and_the_decoded_faces() {
    let f = fixture(Spec::default());
    let (dir, path) = temp_store("pad.oslf");
    write(&path, &f);
    let out = bin().arg("verify").arg(&path).output().unwrap();
    assert!(out.status.success());
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        text.contains("padding bytes checked; the decoded faces match their checksum"),
        "{text}"
    );
    let good = std::fs::read(&path).unwrap();
    let h = oslf_format::header::Header::parse(&good).unwrap();
    let verify = |bytes: &[u8]| {
        let bad = dir.path().join("bad.oslf");
        std::fs::write(&bad, bytes).unwrap();
        let out = bin().arg("verify").arg(&bad).output().unwrap();
        assert!(!out.status.success());
        String::from_utf8_lossy(&out.stderr).into_owned()
    };
    let at = h.meta.end();
    assert!(!at.is_multiple_of(8), "the fixture pads its metadata");
    let mut bytes = good.clone();
    bytes[at as usize] = 1;
    let err = verify(&bytes);
    assert!(
        err.contains(&format!(
            "padding byte at byte offset {at} (after the metadata section) is 0x01; padding must be zero"
        )),
        "{err}"
    );
    let mut bytes = good.clone();
    bytes[176..180].copy_from_slice(&oslf_format::Filter::None.id().to_le_bytes());
    let sum = xxhash_rust::xxh3::xxh3_64(&bytes[..248]);
    bytes[248..256].copy_from_slice(&sum.to_le_bytes());
    let err = verify(&bytes);
    assert!(
        err.contains(
            "the decoded cube faces do not match their checksum at header byte offset 180"
        ),
        "{err}"
    );
    // A development store (version 2, before format 1.0) is refused, saying to bake again.
    let v2 = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("format/tests/data/v2-rgb9e5-5bits.oslf");
    let out = bin().arg("verify").arg(&v2).output().unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("development format version 2") && err.contains("bake the scene again"),
        "{err}"
    );
}

/// `oslf store convert IN OUT --encoding bc6h` re-encodes the cube maps and keeps everything
/// else; converting back to the input's encoding (RGBA16F, from BC6H's binary16 values) and
/// to RGB9E5 works too, and a bad encoding is a clear error.
#[test]
fn convert_re_encodes_and_keeps_the_rest() {
    use oslf_format::{Encoding, Store};
    let spec = Spec {
        encoding: Encoding::Rgba16f,
        cube_res: 6,
        distance: true,
        ..Spec::default()
    };
    let f = fixture(spec);
    let (dir, path) = temp_store("in.oslf");
    write(&path, &f);
    let bc = dir.path().join("bc6h.oslf");
    let out = bin()
        .arg("convert")
        .arg(&path)
        .arg(&bc)
        .args(["--encoding", "bc6h", "-j", "2"])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        text.contains("rgba16f → bc6h") && text.contains("RMSLE"),
        "{text}"
    );
    let (a, b) = (Store::open(&path).unwrap(), Store::open(&bc).unwrap());
    assert_eq!(b.header().encoding, Encoding::Bc6h);
    assert!(b.verify().is_ok());
    let mut meta = a.meta().clone();
    meta.bake.encoding = Encoding::Bc6h;
    assert_eq!(b.meta(), &meta);
    assert_eq!(a.sample_points(), b.sample_points());
    assert_eq!(a.env_cube_index(), b.env_cube_index());
    for p in 0..spec.patches as u32 {
        let (ma, mb) = (a.sample_map(p).unwrap(), b.sample_map(p).unwrap());
        for y in 0..spec.map_res {
            for x in 0..spec.map_res {
                assert_eq!(ma.get(x, y), mb.get(x, y));
            }
        }
    }
    for c in 0..a.cube_count() {
        let (ca, cb) = (a.read_cube(c).unwrap(), b.read_cube(c).unwrap());
        assert_eq!(ca.distance, cb.distance);
        for face in 0..6 {
            // Exactly what the BC6H encoder and decoder make of the input's texels.
            let mut blocks = vec![0u8; Encoding::Bc6h.face_bytes(6).unwrap()];
            oslf_format::bc6h::encode_face(&ca.faces[face], 6, &mut blocks).unwrap();
            let mut want = vec![[0f32; 3]; 36];
            oslf_format::bc6h::decode_face(&blocks, 6, &mut want, c, face).unwrap();
            assert_eq!(cb.faces[face], want);
        }
    }
    // BC6H → RGBA16F keeps BC6H's binary16 values exactly.
    let back = dir.path().join("back.oslf");
    let out = bin()
        .arg("convert")
        .arg(&bc)
        .arg(&back)
        .args(["--encoding", "rgba16f"])
        .output()
        .unwrap();
    assert!(out.status.success());
    let r = Store::open(&back).unwrap();
    assert!(r.verify().is_ok());
    for c in 0..r.cube_count() {
        assert_eq!(r.read_cube(c).unwrap().faces, b.read_cube(c).unwrap().faces);
    }
    // Clear errors.
    let out = bin()
        .arg("convert")
        .arg(&path)
        .arg(dir.path().join("x.oslf"))
        .args(["--encoding", "bc7"])
        .output()
        .unwrap();
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("bc6h"));
    let out = bin()
        .arg("convert")
        .arg(&path)
        .arg(&path)
        .args(["--encoding", "bc6h"])
        .output()
        .unwrap();
    assert!(!out.status.success());
}

#[test]
fn a_cube_exports_as_a_ktx2_cube_map_that_a_ktx2_reader_opens() {
    let f = fixture(Spec::default());
    let (dir, path) = temp_store("ktx2.oslf");
    write(&path, &f);
    let out_path = dir.path().join("env.ktx2");
    let out = bin()
        .arg("export-cube")
        .arg(&path)
        .args(["5", "--format", "ktx2", "-o"])
        .arg(&out_path)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(!oslf_format::writer::partial_path(&out_path).exists());

    // An independent reader (the `ktx2` crate, which Bevy's loader uses) validates it.
    let bytes = std::fs::read(&out_path).unwrap();
    let reader = ktx2::Reader::new(&bytes[..]).unwrap();
    let header = reader.header();
    let cube = oslf_format::Store::open(&path)
        .unwrap()
        .read_cube(5)
        .unwrap();
    let n = cube.resolution;
    assert_eq!(header.format, Some(ktx2::Format::R16G16B16A16_SFLOAT));
    assert_eq!(
        (header.pixel_width, header.pixel_height, header.pixel_depth),
        (n, n, 0)
    );
    assert_eq!(
        (header.layer_count, header.face_count, header.level_count),
        (0, 6, 1)
    );
    assert_eq!(
        reader.transfer_function(),
        Some(ktx2::TransferFunction::Linear)
    );
    assert_eq!(reader.color_primaries(), Some(ktx2::ColorPrimaries::BT709));
    // The data format descriptor is the one the Khronos rules give for the format.
    let (expected, type_size) =
        ktx2::dfd::Basic::from_format(ktx2::Format::R16G16B16A16_SFLOAT).unwrap();
    assert_eq!(type_size, header.type_size);
    assert_eq!(reader.basic_dfd(), Some(&expected));
    let orientation = reader
        .key_value_data()
        .find(|(k, _)| *k == "KTXorientation")
        .map(|(_, v)| v.to_vec());
    assert_eq!(orientation.as_deref(), Some(&b"rd\0"[..]));

    // Faces +X −X +Y −Y +Z −Z, rows from the top: every texel is the store's, as half floats.
    let level = reader.levels().next().unwrap();
    let texels = (n * n) as usize;
    assert_eq!(level.data.len(), 6 * texels * 8);
    for face in 0..6 {
        for (i, rgb) in cube.faces[face].iter().enumerate() {
            let at = (face * texels + i) * 8;
            let h = |k: usize| {
                half::f16::from_le_bytes([level.data[at + 2 * k], level.data[at + 2 * k + 1]])
            };
            for (k, &v) in rgb.iter().enumerate() {
                assert_eq!(h(k), half::f16::from_f32(v), "face {face}, texel {i}");
            }
            assert_eq!(h(3), half::f16::ONE);
        }
    }
    // --layout is for OpenEXR output only.
    let out = bin()
        .arg("export-cube")
        .arg(&path)
        .args(["5", "--format", "ktx2", "--layout", "faces", "-o"])
        .arg(&out_path)
        .output()
        .unwrap();
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("--layout applies to OpenEXR output"));
}

/// A store of a development build from before format 1.0 (the version-3 fixture of the format
/// crate's tests) is refused by `info`, `verify` and `render` with a non-zero exit and a
/// message that names the version and says to bake again; nothing is written.
#[test]
fn a_development_store_is_refused_saying_bake_again() {
    let old =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("format/tests/data/v3-rgba16f.oslf");
    let dir = tempfile::tempdir().unwrap();
    let exr = dir.path().join("out.exr");
    for mut cmd in [
        {
            let mut c = bin();
            c.arg("info").arg(&old);
            c
        },
        {
            let mut c = bin();
            c.arg("verify").arg(&old);
            c
        },
        {
            let mut c = oslf("render");
            c.arg(&old).arg("-o").arg(&exr);
            c
        },
    ] {
        let out = cmd.output().unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success(), "{err}");
        assert!(
            err.contains("development format version 3") && err.contains("bake the scene again"),
            "{err}"
        );
    }
    assert!(!exr.exists() && !exr.with_extension("png").exists());
}
