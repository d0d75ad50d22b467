//! What the top-level tests share: the `oslf` binary, and the fixtures of the library crates'
//! own tests (a synthetic store from `oslf-format`'s tests, a small baked teapot store from
//! `oslf-runtime`'s), included by path so both suites build the very same inputs.

#![allow(dead_code)]

use std::process::Command;

#[path = "../../format/tests/common/mod.rs"]
pub mod store_fixture;

#[path = "../../runtime/tests/common/mod.rs"]
pub mod runtime_fixture;

/// `oslf SUBCOMMAND`, ready for more arguments. `sub` may hold several words (`"store info"`).
pub fn oslf(sub: &str) -> Command {
    let mut command = Command::new(env!("CARGO_BIN_EXE_oslf"));
    command.args(sub.split_whitespace());
    command
}
