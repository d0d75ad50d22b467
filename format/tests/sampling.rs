//! Format 1.2's sampling record: how a bake sampled and filtered its cubes' texels, written
//! by every store and read as `None` from stores of format 1.1.

use crate::common::*;
use oslf_format::*;
use std::path::Path;

/// A store of the format 1.1 writer (`tests/data/v1.1-rgb9e5.oslf`, commit 925caca) opens,
/// verifies and reads as before: its irradiance is there, its sampling record is not.
#[test]
fn a_format_1_1_store_reads_without_a_sampling_record() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/v1.1-rgb9e5.oslf");
    let bytes = std::fs::read(&path).unwrap();
    assert_eq!(bytes[8..12], VERSION_1_1.to_le_bytes());
    for store in each_reader(&path) {
        assert_eq!(store.header().version, VERSION_1_1);
        assert_eq!(store.meta().bake.sampling, None);
        assert_eq!(store.meta().bake.seed, 3);
        assert_eq!(store.cube_count(), 25);
        assert_eq!(store.irradiance().map(|sh| sh.len()), Some(25));
        store.verify().unwrap();
        let c = store.read_cube(24).unwrap();
        assert!(c.faces.iter().flatten().any(|t| t[0] > 0.0));
    }
}

/// What a bake records of its sampling comes back from the store as written, whichever of
/// the three readers opens it.
#[test]
fn the_sampling_record_round_trips() {
    for sampling in [
        Sampling::default(),
        Sampling {
            target_noise: 0.05,
            denoised: true,
        },
        Sampling {
            target_noise: 1.0,
            denoised: false,
        },
    ] {
        let mut f = fixture(Spec::default());
        f.meta.bake.sampling = Some(sampling);
        let (_dir, path) = temp_store("sampling.oslf");
        write(&path, &f);
        let bytes = std::fs::read(&path).unwrap();
        assert_eq!(bytes[8..12], VERSION.to_le_bytes());
        for store in each_reader(&path) {
            assert_eq!(store.meta().bake.sampling, Some(sampling));
            assert_eq!(store.meta(), &f.meta);
        }
    }
}

/// A writer is given the sampling record or writes nothing: format 1.2 stores hold it, and a
/// target outside (0, 1] is refused before a byte is written.
#[test]
fn a_store_without_or_with_a_bad_sampling_record_is_not_written() {
    let f = fixture(Spec::default());
    for (sampling, says) in [
        (None, "no sampling record"),
        (
            Some(Sampling {
                target_noise: 2.0,
                denoised: false,
            }),
            "target_noise 2 must be 0 or in (0, 1]",
        ),
    ] {
        let mut meta = f.meta.clone();
        meta.bake.sampling = sampling;
        let (_dir, path) = temp_store("none.oslf");
        let e = StoreWriter::create(&path, &meta, &f.points, &f.maps)
            .err()
            .unwrap();
        assert!(
            matches!(&e, Error::InvalidMetadata { detail, .. } if detail.contains(says)),
            "{e}"
        );
        assert!(!path.exists());
        assert!(!oslf_format::writer::partial_path(&path).exists());
    }
}
