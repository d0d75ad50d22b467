//! The damaged-store cases (damaged/cases.rs) against a store held in memory
//! (`Store::from_bytes`).

// The same cases against each reader: the file is meant to be a module three times.
#[allow(clippy::duplicate_mod)]
#[path = "damaged/cases.rs"]
mod cases;
use crate::common;

use oslf_format::{Error, Store};

fn open(b: &[u8]) -> Result<Store, Error> {
    Store::from_bytes(b)
}
