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

/// Runs `cmd`, asserts it succeeded (showing its stdout and stderr if not) and returns its
/// stdout.
pub fn run_ok(cmd: &mut Command) -> String {
    let out = cmd.output().unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout).to_string();
    assert!(
        out.status.success(),
        "{cmd:?} failed:\n{stdout}\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    stdout
}

/// A small scene: the teapot's lid (tests/fixtures/teapot-lid.toml), 12 sample points (24
/// after refinement, plus the environment cube: 25 cubes) of 2² texels. Bakes in well under a
/// second.
pub const LID_SCENE: &str = concat!(
    include_str!("../fixtures/teapot-lid.toml"),
    r#"
[bake]
epsilon = 0.1
sample_count = 12
cube_resolution = 2
sample_map_resolution = 4
samples_per_texel = 1
"#
);

/// The width and the pixels (row-major RGBA) of the OpenEXR image at `path`.
pub fn read_exr(path: &std::path::Path) -> (usize, Vec<[f32; 4]>) {
    let image = exr::prelude::read_first_rgba_layer_from_file(
        path,
        |res, _| (res.width(), vec![[0f32; 4]; res.width() * res.height()]),
        |(w, px), pos, (r, g, b, a): (f32, f32, f32, f32)| {
            px[pos.y() * *w + pos.x()] = [r, g, b, a]
        },
    )
    .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    image.layer_data.channel_data.pixels
}
