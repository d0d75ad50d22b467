//! Stores and partial files of the development builds before format 1.0 (kept in
//! `tests/data`, written by those builds) are refused with one clear error that says to bake
//! the scene again: the reader, `verify` and `StoreWriter::resume` never misread them.

use crate::common;

use common::*;
use oslf_format::writer::partial_path;
use oslf_format::*;
use std::path::{Path, PathBuf};

/// A store of `tests/data`.
fn data(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data")
        .join(name)
}

/// Asserts that the development store `name` of format version `version` is refused by
/// `Store::open` and `Store::from_bytes` with [`Error::UnsupportedVersion`], whose message
/// names the version and says to bake again; and that, copied as the partial file of a
/// bake, `StoreWriter::resume` refuses it too, saying what it is.
fn refused(name: &str, version: u32, spec: Spec) {
    let path = data(name);
    let bytes = std::fs::read(&path).unwrap();
    assert_eq!(bytes[8..12], version.to_le_bytes(), "{name}");
    for e in [
        Store::open(&path).err().unwrap(),
        Store::from_bytes(&bytes).err().unwrap(),
    ] {
        assert!(
            matches!(e, Error::UnsupportedVersion { found } if found == version),
            "{name}: {e}"
        );
        let message = e.to_string();
        assert!(
            message.contains(&format!("development format version {version}"))
                && message.contains("bake the scene again"),
            "{name}: {message}"
        );
    }
    let f = fixture(spec);
    let (_dir, out) = temp_store("resumed.oslf");
    std::fs::copy(&path, partial_path(&out)).unwrap();
    let e = StoreWriter::resume(&out, &f.meta, &f.points, &f.maps)
        .err()
        .unwrap();
    assert!(
        matches!(&e, Error::ResumeMismatch { what, .. } if what.contains(&format!("development format version {version}, from before format 1.0"))),
        "{name}: {e}"
    );
    // The partial file is left as it was.
    assert_eq!(std::fs::read(partial_path(&out)).unwrap(), bytes);
}

/// Version 1 (commit 791094d): before `mantissa_bits`.
#[test]
fn a_version_1_store_is_refused_saying_bake_again() {
    let spec = Spec {
        distance: true,
        seed: 2,
        ..Spec::default()
    };
    refused("v1-rgb9e5.oslf", 1, spec);
}

/// Version 2: before the checksum of the decoded faces.
#[test]
fn a_version_2_store_is_refused_saying_bake_again() {
    let spec = Spec {
        distance: true,
        seed: 3,
        mantissa_bits: 5,
        ..Spec::default()
    };
    refused("v2-rgb9e5-5bits.oslf", 2, spec);
}

/// Version 3 (commit e976e68): before BC6H and mesh objects.
#[test]
fn a_version_3_store_is_refused_saying_bake_again() {
    let spec = Spec {
        encoding: Encoding::Rgba16f,
        distance: true,
        seed: 4,
        ..Spec::default()
    };
    refused("v3-rgba16f.oslf", 3, spec);
}

/// Version 5 (commit b59f778): `f32` distance planes, before the distance lattice.
#[test]
fn a_version_5_store_is_refused_saying_bake_again() {
    refused("v5-bc6h.oslf", 5, Spec::default());
}

/// A store of today's writer with its version field set to each development version is
/// refused the same way, whatever follows the header: the version is checked before
/// anything else is read.
#[test]
fn each_development_version_number_is_refused_before_the_rest_is_read() {
    let good = store_bytes(Spec::default());
    assert_eq!(good[8..12], VERSION.to_le_bytes());
    assert_eq!(version_name(VERSION), "1.2");
    for v in 1..=LAST_DEVELOPMENT_VERSION {
        let mut b = good.clone();
        b[8..12].copy_from_slice(&v.to_le_bytes());
        // Damage everything after the header as well: the version error comes first.
        for x in &mut b[256..] {
            *x ^= 0x5a;
        }
        let e = Store::from_bytes(&b).err().unwrap();
        assert!(
            matches!(e, Error::UnsupportedVersion { found } if found == v),
            "{v}: {e}"
        );
    }
}
