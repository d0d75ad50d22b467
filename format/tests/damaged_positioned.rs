//! The damaged-store cases (damaged/cases.rs) against a store file opened with
//! `Store::open`: fixed sections in memory, frames by positioned reads.

// The same cases against each reader: the file is meant to be a module three times.
#[allow(clippy::duplicate_mod)]
#[path = "damaged/cases.rs"]
mod cases;
use crate::common;

use oslf_format::{Error, Store, StoreAccess};

/// `b` written to a file and opened from it (the file is unlinked at once: the open store
/// keeps reading it).
fn open(b: &[u8]) -> Result<Store, Error> {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("damaged.oslf");
    std::fs::write(&path, b).unwrap();
    let store = Store::open_with(&path, StoreAccess::Positioned);
    if let Ok(s) = &store {
        assert_eq!(s.access(), Some(StoreAccess::Positioned));
    }
    store
}
