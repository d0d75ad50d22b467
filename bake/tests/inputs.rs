//! Inputs without bounds: every file a scene names is read only if it is a regular
//! file, and never beyond the limit of its kind; glTF references stay relative to their file.
//! Each read that could block (a FIFO) runs on a thread with a deadline, so that a regression
//! fails the test instead of hanging it.

use crate::gltf_builder;

use std::path::{Path, PathBuf};
use std::time::Duration;

use gltf_builder::Builder;
use oslf_scene::gltf::{load, Options};
use oslf_scene::input::{MAX_IMAGE_BYTES, MAX_TEXT_BYTES};
use oslf_scene::scene::Scene;
use serde_json::json;

const TRIANGLE: [[f32; 3]; 3] = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];

/// `f()`'s result, or a failure if it takes longer than 20 s (a read blocked on a FIFO).
fn within_deadline<T: Send + 'static>(f: impl FnOnce() -> T + Send + 'static) -> T {
    let (tx, rx) = std::sync::mpsc::channel();
    std::thread::spawn(move || {
        let _ = tx.send(f());
    });
    rx.recv_timeout(Duration::from_secs(20))
        .expect("the read blocked (a FIFO opened or read without O_NONBLOCK?)")
}

fn mkfifo(path: &Path) {
    let status = std::process::Command::new("mkfifo")
        .arg(path)
        .status()
        .expect("mkfifo");
    assert!(status.success());
}

/// The error of loading the glTF file at `path`, within the deadline.
fn gltf_err(path: &Path) -> String {
    let path = path.to_path_buf();
    within_deadline(move || {
        let mut materials = Vec::new();
        match load(&path, &Options::default(), &mut materials) {
            Ok(_) => panic!("{} loaded", path.display()),
            Err(e) => e.to_string(),
        }
    })
}

/// A one-triangle `.gltf` in `dir` whose buffer is the file `uri`; returns its path and the
/// buffer's bytes.
fn triangle_gltf(dir: &Path, name: &str, uri: &str) -> (PathBuf, Vec<u8>) {
    let mut b = Builder::new();
    let pos = b.positions(&TRIANGLE);
    let doc = json!({
        "nodes": [{"mesh": 0}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": pos}}]}],
    });
    let (text, bin) = b.gltf_external(doc, uri);
    let path = dir.join(name);
    std::fs::write(&path, text).unwrap();
    (path, bin)
}

fn assert_has(e: &str, wants: &[&str]) {
    for w in wants {
        assert!(e.contains(w), "{e:?} lacks {w:?}");
    }
}

#[test]
fn gltf_buffers_are_regular_files_within_their_declared_length() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    // A FIFO: refused at once, not read forever.
    mkfifo(&d.join("pipe.bin"));
    let (path, _) = triangle_gltf(d, "fifo.gltf", "pipe.bin");
    let e = gltf_err(&path);
    assert_has(
        &e,
        &[
            "fifo.gltf",
            "buffers[0].uri",
            "not a regular file",
            "pipe.bin",
            "(a FIFO)",
        ],
    );
    // A link to /dev/zero (a relative reference, so only the file type stops it).
    std::os::unix::fs::symlink("/dev/zero", d.join("zero.bin")).unwrap();
    let (path, _) = triangle_gltf(d, "zero.gltf", "zero.bin");
    assert_has(
        &gltf_err(&path),
        &[
            "zero.gltf",
            "buffers[0].uri",
            "zero.bin (a character device)",
        ],
    );
    // A directory.
    std::fs::create_dir(d.join("dir.bin")).unwrap();
    let (path, _) = triangle_gltf(d, "dir.gltf", "dir.bin");
    assert_has(&gltf_err(&path), &["dir.bin (a directory)"]);
    // A file longer than its byteLength and the allowance beyond it.
    let (path, mut bin) = triangle_gltf(d, "long.gltf", "long.bin");
    let declared = bin.len();
    bin.resize(declared + 4096, 0);
    std::fs::write(d.join("long.bin"), &bin).unwrap();
    gltf_loads(&path);
    bin.push(0);
    std::fs::write(d.join("long.bin"), &bin).unwrap();
    assert_has(
        &gltf_err(&path),
        &[
            "long.gltf",
            "buffers[0].uri",
            "long.bin is larger than declared",
            &format!("byteLength {declared}"),
            &format!("it has {} bytes", declared + 4097),
        ],
    );
    // A byteLength beyond any buffer's limit.
    let (path, bin) = triangle_gltf(d, "huge.gltf", "huge.bin");
    std::fs::write(d.join("huge.bin"), bin).unwrap();
    let mut doc: serde_json::Value =
        serde_json::from_slice(&std::fs::read(&path).unwrap()).unwrap();
    doc["buffers"][0]["byteLength"] = json!(3u64 << 30);
    std::fs::write(&path, serde_json::to_vec(&doc).unwrap()).unwrap();
    assert_has(
        &gltf_err(&path),
        &[
            "huge.gltf",
            "buffers[0].byteLength",
            "3221225472 is more than the 1 GiB",
        ],
    );
}

fn gltf_loads(path: &Path) {
    let mut materials = Vec::new();
    if let Err(e) = load(path, &Options::default(), &mut materials) {
        panic!("{}: {e}", path.display());
    }
}

#[test]
fn gltf_references_are_relative_and_stay_in_the_directory() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    std::fs::create_dir(d.join("sub")).unwrap();
    let (path, bin) = triangle_gltf(&d.join("sub"), "ok.gltf", "x.bin");
    std::fs::write(d.join("sub/x.bin"), &bin).unwrap();
    std::fs::write(d.join("outside.bin"), &bin).unwrap();
    gltf_loads(&path);
    let absolute = d.join("outside.bin").display().to_string();
    for (uri, problem) in [
        (absolute.as_str(), "is an absolute path"),
        ("/dev/zero", "is an absolute path"),
        ("../outside.bin", "leaves the glTF file's directory"),
        ("file:///dev/zero", "has a scheme"),
    ] {
        let (path, _) = triangle_gltf(&d.join("sub"), "ref.gltf", uri);
        let e = gltf_err(&path);
        assert_has(
            &e,
            &["ref.gltf", "buffers[0].uri", &format!("{uri:?} {problem}")],
        );
    }
}

/// A textured one-triangle `.gltf` in `dir` whose image is the file `uri`.
fn textured_gltf(dir: &Path, name: &str, uri: &str) -> PathBuf {
    let mut b = Builder::new();
    let pos = b.positions(&TRIANGLE);
    let uv = b.vec2(&[[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]]);
    let doc = json!({
        "nodes": [{"mesh": 0}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": pos, "TEXCOORD_0": uv}, "material": 0}]}],
        "materials": [{"pbrMetallicRoughness": {"baseColorTexture": {"index": 0}}}],
        "textures": [{"source": 0}],
        "images": [{"uri": uri}],
    });
    let (text, bin) = b.gltf_external(doc, &format!("{name}.bin"));
    std::fs::write(dir.join(format!("{name}.bin")), bin).unwrap();
    let path = dir.join(name);
    std::fs::write(&path, text).unwrap();
    path
}

#[test]
fn gltf_images_are_regular_files_of_bounded_size() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    mkfifo(&d.join("pipe.png"));
    let path = textured_gltf(d, "tex.gltf", "pipe.png");
    assert_has(
        &gltf_err(&path),
        &["tex.gltf", "images[0].uri", "pipe.png (a FIFO)"],
    );
    std::fs::write(d.join("huge.png"), png_header(20000, 20000)).unwrap();
    let path = textured_gltf(d, "huge.gltf", "huge.png");
    assert_has(
        &gltf_err(&path),
        &[
            "huge.gltf",
            "images[0]",
            "20000 × 20000 pixels are more than the 268435456",
        ],
    );
}

/// `text` as a scene file in `dir`, loaded within the deadline; its error.
fn scene_err(dir: &Path, text: &str) -> String {
    let path = dir.join("scene.toml");
    std::fs::write(&path, text).unwrap();
    within_deadline(move || match Scene::load(&path, None) {
        Ok(_) => panic!("the scene loaded"),
        Err(e) => e.to_string(),
    })
}

const SCENE: &str = r#"
[environment]
uniform = [1, 1, 1]

[[object]]
patches = "newell-teapot"
material = { color = [0.1, 0.4, 0.1] }
"#;

#[test]
fn scene_inputs_that_are_not_regular_files_are_named_as_such() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    mkfifo(&d.join("pipe.obj"));
    std::fs::create_dir(d.join("dir.obj")).unwrap();
    for (name, kind) in [
        ("pipe.obj", "(a FIFO)"),
        ("dir.obj", "(a directory)"),
        ("/dev/zero", "(a character device)"),
    ] {
        let e = scene_err(
            d,
            &format!(
                "{SCENE}\n[[mesh]]\npath = {name:?}\nmaterial = {{ color = [0.5, 0.5, 0.5] }}\n"
            ),
        );
        assert_has(&e, &["scene.toml:10:", "not a regular file", name, kind]);
        assert!(!e.contains("file not found"), "{e}");
    }
    let e = scene_err(
        d,
        &SCENE.replace("uniform = [1, 1, 1]", "map = { path = \"/dev/zero\" }"),
    );
    assert_has(&e, &["scene.toml:3:", "/dev/zero (a character device)"]);
    // The scene itself, TOML or glTF.
    std::os::unix::fs::symlink("/dev/zero", d.join("zero.glb")).unwrap();
    for path in [PathBuf::from("/dev/zero"), d.join("zero.glb")] {
        let e = within_deadline(move || Scene::load(&path, None).unwrap_err().to_string());
        assert!(e.contains("(a character device)"), "{e}");
    }
    let fifo = d.join("scene-pipe.toml");
    mkfifo(&fifo);
    let e = within_deadline(move || Scene::load(&fifo, None).unwrap_err().to_string());
    assert_has(&e, &["scene-pipe.toml (a FIFO)"]);
}

#[test]
fn inputs_larger_than_their_limit_are_refused_before_reading() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    // Sparse files: their length is what counts, and nothing of them is read.
    let sparse = |name: &str, len: u64| {
        let path = d.join(name);
        std::fs::File::create(&path).unwrap().set_len(len).unwrap();
        path
    };
    let scene = sparse("big.toml", MAX_TEXT_BYTES + 1);
    let e = Scene::load(&scene, None).unwrap_err().to_string();
    assert_has(
        &e,
        &["big.toml is larger than the 64 MiB allowed for a scene or patch file"],
    );
    sparse("big.png", MAX_IMAGE_BYTES + 1);
    let e = scene_err(
        d,
        &SCENE.replace("uniform = [1, 1, 1]", "map = { path = \"big.png\" }"),
    );
    assert_has(
        &e,
        &["big.png is larger than the 512 MiB allowed for an image"],
    );
}

/// Shapes carry names for messages (the zero-area error names them).
#[test]
fn shapes_are_named_by_table_and_file() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    std::fs::write(d.join("tri.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
    let text = format!(
        "{SCENE}\n[[box]]\nsize = [1, 1, 1]\nmaterial = {{ color = [0.5, 0.5, 0.5] }}\n\
         [[box]]\nsize = [1, 1, 1]\nmaterial = {{ color = [0.5, 0.5, 0.5] }}\n\
         [[mesh]]\npath = \"tri.obj\"\nmaterial = {{ color = [0.5, 0.5, 0.5] }}\n"
    );
    let path = d.join("named.toml");
    std::fs::write(&path, text).unwrap();
    let scene = Scene::load(&path, None).unwrap();
    let names: Vec<&str> = scene.shapes.iter().map(|s| s.name.as_str()).collect();
    assert_eq!(names, ["[[box]] 0", "[[box]] 1", "[[mesh]] \"tri.obj\""]);
    let instances = oslf_trace::bvh::scene_instances(&scene, true, 0.01);
    assert_eq!(instances.last().unwrap().name, "object \"object0\"");
}

/// CRC-32 (ISO 3309, as PNG uses it).
fn crc32(data: &[u8]) -> u32 {
    let mut c = !0u32;
    for &b in data {
        c ^= u32::from(b);
        for _ in 0..8 {
            c = if c & 1 != 0 {
                0xEDB8_8320 ^ (c >> 1)
            } else {
                c >> 1
            };
        }
    }
    !c
}

/// The start of a PNG whose header declares `width` × `height` RGB8 pixels (and no pixels).
fn png_header(width: u32, height: u32) -> Vec<u8> {
    let mut png = vec![137, 80, 78, 71, 13, 10, 26, 10];
    let mut chunk = |kind: &[u8], data: &[u8]| {
        png.extend((data.len() as u32).to_be_bytes());
        let start = png.len();
        png.extend(kind);
        png.extend(data);
        let crc = crc32(&png[start..]);
        png.extend(crc.to_be_bytes());
    };
    let mut ihdr = Vec::new();
    ihdr.extend(width.to_be_bytes());
    ihdr.extend(height.to_be_bytes());
    ihdr.extend([8, 2, 0, 0, 0]);
    chunk(b"IHDR", &ihdr);
    chunk(b"IDAT", &[]);
    chunk(b"IEND", &[]);
    png
}

#[test]
fn images_declaring_too_many_pixels_are_refused_before_decoding() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    std::fs::write(d.join("huge.png"), png_header(20000, 20000)).unwrap();
    let e = scene_err(
        d,
        &SCENE.replace("uniform = [1, 1, 1]", "map = { path = \"huge.png\" }"),
    );
    assert_has(
        &e,
        &[
            "huge.png",
            "20000 × 20000 pixels are more than the 268435456 an image may have",
        ],
    );
}

/// An OpenEXR file whose header declares 300000000 × 1 pixels (an uncompressed 1 × 1 image,
/// its data window widened; still one chunk, so the file is consistent up to the pixels):
/// refused from the header, before 3.6 GB of pixels are allocated.
#[test]
fn exr_headers_declaring_too_many_pixels_are_refused_before_decoding() {
    use exr::prelude::{Encoding, Image, SpecificChannels, WritableImage as _};
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    let path = d.join("huge.exr");
    let channels = SpecificChannels::rgb(|_| (1f32, 1f32, 1f32));
    Image::from_encoded_channels((1, 1), Encoding::UNCOMPRESSED, channels)
        .write()
        .to_file(&path)
        .unwrap();
    let mut bytes = std::fs::read(&path).unwrap();
    let key = b"dataWindow\0box2i\0";
    let at = bytes
        .windows(key.len())
        .position(|w| w == key)
        .expect("a dataWindow attribute")
        + key.len()
        + 4; // the attribute's size
             // xMax (xMin, yMin and yMax stay 0).
    bytes[at + 8..at + 12].copy_from_slice(&299_999_999i32.to_le_bytes());
    std::fs::write(&path, bytes).unwrap();
    let e = scene_err(
        d,
        &SCENE.replace("uniform = [1, 1, 1]", "map = { path = \"huge.exr\" }"),
    );
    assert_has(
        &e,
        &[
            "huge.exr",
            "300000000 × 1 pixels are more than the 268435456",
        ],
    );
}
