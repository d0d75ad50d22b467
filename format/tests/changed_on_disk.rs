//! A store overwritten in place while it is open (`cp` over it, a truncation) gives errors
//! that name the offset: the reader never trusts a mapping to stay valid, so no SIGBUS.

use crate::common;

use common::*;
use oslf_format::*;

/// Every face of every cube, read once: the results.
fn read_all(store: &Store) -> Vec<Result<(), Error>> {
    let mut buf = vec![0u8; store.face_raw_size()];
    let mut out = Vec::new();
    for cube in 0..store.cube_count() {
        for face in 0..6 {
            out.push(store.read_face_raw(cube, face, &mut buf));
        }
    }
    out
}

#[test]
fn a_store_truncated_while_open_fails_cleanly() {
    let f = fixture(Spec {
        cube_res: 16,
        points: 8,
        ..Spec::default()
    });
    let (_dir, path) = temp_store("open.oslf");
    write(&path, &f);
    let store = Store::open(&path).unwrap();
    assert!(read_all(&store).iter().all(Result::is_ok));
    let points = store.sample_points().len();

    // Truncate in place (same inode, as `cp` does before it writes): with a memory map every
    // later frame read would be a SIGBUS.
    std::fs::write(&path, b"not a store any more").unwrap();
    let results = read_all(&store);
    assert!(results.iter().all(Result::is_err));
    let e = results[0].as_ref().unwrap_err().to_string();
    assert!(
        e.contains("open.oslf") && e.contains("changed on disk") && e.contains("byte offset"),
        "{e}"
    );
    assert!(store.verify().is_err());
    // What was read at open stays valid.
    assert_eq!(store.sample_points().len(), points);
    assert!(store.sample_map(0).is_ok());
}

#[test]
fn a_store_overwritten_with_another_while_open_fails_its_checksums() {
    let (_dir, path) = temp_store("swap.oslf");
    let spec = Spec {
        cube_res: 16,
        points: 8,
        ..Spec::default()
    };
    write(&path, &fixture(spec));
    let store = Store::open(&path).unwrap();
    // Another store of the same layout, other texels: copied over the open one.
    let other = store_bytes(Spec { seed: 2, ..spec });
    std::fs::write(&path, &other).unwrap();
    let results = read_all(&store);
    assert!(results.iter().any(Result::is_err));
    for e in results.iter().filter_map(|r| r.as_ref().err()) {
        let text = e.to_string();
        assert!(
            text.contains("checksum") || text.contains("changed on disk"),
            "{text}"
        );
    }
}
