//! A store as a web page receives it (`oslf_runtime::web`): the bytes are those the renderer
//! uploads, the manifest's offsets and sizes are the Rust layouts', and bad requests are named.

use oslf_format::Store;
use oslf_runtime::face::FaceLayout;
use oslf_runtime::web::{WebStore, WEB_FORMAT_VERSION};
use oslf_runtime::{CacheConfig, RuntimeError};

use super::common;

fn web(path: &std::path::Path) -> WebStore {
    let store = Store::open(path).unwrap();
    WebStore::new(store, "fixture.oslf", 1234, &CacheConfig::default()).unwrap()
}

#[test]
fn cubes_are_the_face_payloads_the_renderer_uploads() {
    let path = common::store_path();
    let web = web(&path);
    let m = web.manifest();
    assert_eq!(m.format, WEB_FORMAT_VERSION);
    assert_eq!(m.variants.len(), 1, "an RGB9E5 store has one encoding");
    let v = &m.variants[0];
    assert_eq!(v.encoding, "rgb9e5");
    let store = Store::open(&path).unwrap();
    let face = FaceLayout::new(&store, oslf_format::Encoding::Rgb9e5);
    assert_eq!(v.face_bytes, face.payload_bytes());
    assert_eq!(v.levels.len() as u32, face.levels);
    let cube = m.cube_count - 1;
    let bytes = web.cube(cube, "rgb9e5").unwrap();
    let expected: Vec<u8> = (0..6u8)
        .flat_map(|f| face.build(&store, cube, f).unwrap())
        .collect();
    assert_eq!(bytes, expected);
    // Every mode's uniform has the Rust struct's size, and the fields the page writes lie in it.
    for mode in &v.modes {
        assert_eq!(
            mode.uniform.len() * 4,
            m.uniform_fields.bytes,
            "{}",
            mode.name
        );
        assert!(mode.constants.iter().any(|(k, _)| k == "TERMS"));
    }
    assert!(m.uniform_fields.cam_forward + 16 <= m.uniform_fields.bytes);
    assert_eq!(m.default_mode, "recon-mirror");
    assert_eq!(m.default_background, "env");
}

#[test]
fn resources_have_the_sizes_the_manifest_gives() {
    let web = web(&common::store_path());
    let m = web.manifest().clone();
    let get = |n: &str| web.resource(n).unwrap().unwrap();
    assert_eq!(get("indices.bin").len(), m.index_count as usize * 4);
    assert_eq!(
        get("maps.bin").len(),
        (m.map_res * m.map_res * m.map_texel_bytes * m.map_count) as usize
    );
    // The sample points, then each cube's nine spherical-harmonic coefficients (format 1.1).
    let cubes = web.store().irradiance().map_or(0, <[_]>::len);
    assert_eq!(cubes as u32, web.store().cube_count());
    assert_eq!(
        get("samples.bin").len(),
        16 * (web.store().sample_points().len() + 9 * cubes)
    );
    assert_eq!(get("vertices.bin").len() % 64, 0);
    for name in web.resource_names() {
        assert!(web.resource(&name).unwrap().is_some(), "{name}");
    }
    assert!(web.resource("../etc/passwd").unwrap().is_none());
    assert!(web.resource("texture-0-base_colour.bin").unwrap().is_none());
}

#[test]
fn bad_cube_requests_say_what_is_wrong() {
    let web = web(&common::store_path());
    let n = web.manifest().cube_count;
    match web.cube(n, "rgb9e5") {
        Err(RuntimeError::Parameter(m)) => assert!(m.contains(&format!("{n} cubes")), "{m}"),
        other => panic!("{:?}", other.map(|b| b.len())),
    }
    match web.cube(0, "bc6h") {
        Err(RuntimeError::Parameter(m)) => assert!(m.contains("rgb9e5"), "{m}"),
        other => panic!("{:?}", other.map(|b| b.len())),
    }
}

#[test]
fn a_bc6h_store_comes_in_both_encodings_with_a_probe_block() {
    let web = web(&common::store_path_bc6h());
    let m = web.manifest();
    let names: Vec<&str> = m.variants.iter().map(|v| v.encoding.as_str()).collect();
    assert_eq!(names, ["bc6h", "rgb9e5"]);
    let bc = &m.variants[0];
    assert_eq!(bc.feature.as_deref(), Some("texture-compression-bc"));
    let probe = bc.probe.as_ref().expect("a probe block");
    assert_eq!(probe.block.len(), 16);
    assert_eq!(probe.texels.len(), 16);
    assert!(probe.texels.iter().flatten().any(|&x| x > 0.0));
    assert!(m.variants[1].probe.is_none());
    for v in &m.variants {
        assert_eq!(web.cube(0, &v.encoding).unwrap().len(), 6 * v.face_bytes);
    }
}
