//! The mapped reader (`Store::open_mapped`) against the positioned one (`Store::open`): the same
//! bytes for every section and frame of every kind of store, the old store kept when a new one
//! is renamed over it, and this project's writers refused while it is mapped.

use crate::common;

use std::path::Path;

use common::*;
use oslf_format::{Encoding, Error, Store, StoreAccess, StoreWriter};

/// Every section and frame `a` and `b` serve are the same bytes.
fn assert_same(a: &Store, b: &Store, what: &str) {
    assert_eq!(a.header(), b.header(), "{what}: header");
    assert_eq!(a.meta(), b.meta(), "{what}: metadata");
    assert_eq!(
        bytemuck::cast_slice::<_, u8>(a.sample_points()),
        bytemuck::cast_slice::<_, u8>(b.sample_points()),
        "{what}: sample points"
    );
    assert!(!a.sample_points().is_empty(), "{what}: no sample points");
    for patch in 0..a.header().patch_count as u32 {
        let (ma, mb) = (a.sample_map(patch).unwrap(), b.sample_map(patch).unwrap());
        assert_eq!(ma.as_u16(), mb.as_u16(), "{what}: sample map {patch}");
        assert_eq!(ma.as_u32(), mb.as_u32(), "{what}: sample map {patch}");
        assert!(ma.as_u16().is_some() || ma.as_u32().is_some());
    }
    assert_eq!(a.cube_count(), b.cube_count());
    assert_eq!(a.cube_bytes(), b.cube_bytes());
    let mut fa = vec![0u8; a.face_raw_size()];
    let mut fb = vec![1u8; b.face_raw_size()];
    for cube in 0..a.cube_count() {
        for face in 0..6 {
            assert_eq!(
                a.face_entry(cube, face).unwrap(),
                b.face_entry(cube, face).unwrap()
            );
            a.read_face_raw(cube, face, &mut fa).unwrap();
            b.read_face_raw(cube, face, &mut fb).unwrap();
            assert_eq!(fa, fb, "{what}: cube {cube} face {face}");
        }
    }
    assert_eq!(a.verify().unwrap(), b.verify().unwrap(), "{what}: verify");
}

fn both(path: &Path) -> (Store, Store) {
    let positioned = Store::open(path).unwrap();
    let mapped = Store::open_mapped(path).unwrap();
    assert_eq!(positioned.access(), Some(StoreAccess::Positioned));
    assert_eq!(mapped.access(), Some(StoreAccess::Mapped));
    (positioned, mapped)
}

#[test]
fn both_readers_serve_the_same_bytes_for_every_store_kind() {
    // The development stores from before format 1.0: both readers refuse them alike.
    for (name, version) in [("v1-rgb9e5", 1), ("v2-rgb9e5-5bits", 2), ("v3-rgba16f", 3)] {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("tests/data/{name}.oslf"));
        for e in [
            Store::open(&path).err().unwrap(),
            Store::open_mapped(&path).err().unwrap(),
        ] {
            assert!(
                matches!(e, Error::UnsupportedVersion { found } if found == version),
                "{name}: {e}"
            );
        }
    }
    for encoding in [
        Encoding::Rgb9e5,
        Encoding::Rgba16f,
        Encoding::Rgba32f,
        Encoding::Bc6h,
    ] {
        for distance in [false, true] {
            for mesh in [false, true] {
                let spec = Spec {
                    encoding,
                    cube_res: 8,
                    distance,
                    ..Spec::default()
                };
                let f = if mesh {
                    with_mesh(fixture(spec), spec)
                } else {
                    fixture(spec)
                };
                let (_dir, path) = temp_store("s.oslf");
                write(&path, &f);
                let (p, m) = both(&path);
                assert_same(
                    &p,
                    &m,
                    &format!("{encoding} distance {distance} mesh {mesh}"),
                );
            }
        }
    }
}

#[test]
fn a_store_renamed_over_while_mapped_keeps_serving_the_old_one() {
    let (dir, path) = temp_store("s.oslf");
    let old = fixture(Spec {
        seed: 1,
        ..Spec::default()
    });
    write(&path, &old);
    let copy = dir.path().join("copy.oslf");
    std::fs::copy(&path, &copy).unwrap();
    let mapped = Store::open_mapped(&path).unwrap();
    // A new store written through the writer (partial file, rename over `path`).
    let new = fixture(Spec {
        seed: 2,
        ..Spec::default()
    });
    write(&path, &new);
    assert_ne!(std::fs::read(&path).unwrap(), std::fs::read(&copy).unwrap());
    assert_same(&Store::open(&copy).unwrap(), &mapped, "old store, mapped");
}

#[test]
fn a_mapped_store_is_not_written_in_place_by_a_writer() {
    let (dir, path) = temp_store("s.oslf");
    let f = fixture(Spec::default());
    write(&path, &f);
    let before = std::fs::read(&path).unwrap();
    let mapped = Store::open_mapped(&path).unwrap();
    // A writer whose partial file is the mapped store (a hard link) would empty it in place.
    let other = dir.path().join("other.oslf");
    std::fs::hard_link(&path, dir.path().join("other.oslf.partial")).unwrap();
    match StoreWriter::create(&other, &f.meta, &f.points, &f.maps) {
        Err(Error::Busy { holder, .. }) => assert!(
            !system_lists_flocks_of(std::process::id())
                || holder.contains(&format!("process {}", std::process::id())),
            "{holder}"
        ),
        Err(e) => panic!("{e}"),
        Ok(_) => panic!("the writer took a mapped store"),
    }
    assert_eq!(std::fs::read(&path).unwrap(), before);
    assert_same(&Store::open(&path).unwrap(), &mapped, "after the refusal");
    drop(mapped);
    // Unmapped, the same writer may go ahead (and empties the linked file: that is what the
    // lock protected).
    assert!(StoreWriter::create(&other, &f.meta, &f.points, &f.maps).is_ok());
}

#[test]
fn only_regular_files_are_mapped() {
    let dir = tempfile::tempdir().unwrap();
    // Refused before they are opened (nothing blocks on a FIFO), each named and called what
    // it is; the positioned reader alike.
    for (path, kind) in [
        (dir.path(), "(a directory)"),
        (Path::new("/dev/null"), "(a character device)"),
    ] {
        for e in [
            Store::open_mapped(path).err().unwrap(),
            Store::open(path).err().unwrap(),
        ] {
            assert!(
                matches!(&e, Error::Input(u) if matches!(**u, oslf_util::UtilError::NotRegular { .. }))
                    && e.to_string()
                        .contains(&format!("{} {kind}", path.display())),
                "{e}"
            );
        }
    }
    let empty = dir.path().join("empty.oslf");
    std::fs::write(&empty, b"").unwrap();
    assert!(matches!(
        Store::open_mapped(&empty),
        Err(Error::Truncated { .. })
    ));
}

/// A store written in place while mapped (another program's write: the same size, other
/// bytes) is seen by `changed_since_open`; one replaced by rename, or left alone, is not; the
/// positioned reader never reports one.
#[test]
fn a_store_written_in_place_while_mapped_is_seen_after_the_reads() {
    use std::io::{Seek, SeekFrom, Write};
    let (_dir, path) = temp_store("s.oslf");
    write(&path, &fixture(Spec::default()));
    let mapped = Store::open_mapped(&path).unwrap();
    let positioned = Store::open(&path).unwrap();
    assert_eq!(mapped.changed_since_open(), None);
    // Replaced by rename: the mapping keeps the old file, which did not change.
    write(
        &path,
        &fixture(Spec {
            seed: 3,
            ..Spec::default()
        }),
    );
    assert_eq!(mapped.changed_since_open(), None);
    drop(mapped);
    let mapped = Store::open_mapped(&path).unwrap();
    // Written in place, past the lock (other programs are not bound by it), size unchanged;
    // the modification time is set forward so that a coarse clock cannot hide the write.
    let len = std::fs::metadata(&path).unwrap().len();
    let mut f = std::fs::OpenOptions::new().write(true).open(&path).unwrap();
    f.seek(SeekFrom::Start(len - 1)).unwrap();
    f.write_all(&[0xAB]).unwrap();
    f.set_modified(std::time::SystemTime::now() + std::time::Duration::from_secs(5))
        .unwrap();
    drop(f);
    let said = mapped
        .changed_since_open()
        .expect("an in-place write was not seen");
    assert!(
        said.contains(&path.display().to_string()) && said.contains("written in place"),
        "{said}"
    );
    assert_eq!(positioned.changed_since_open(), None);
}
