//! `oslf store`: info, verify, exports, and clear errors.

mod common;

use common::oslf;
use common::store_fixture::*;

fn bin() -> std::process::Command {
    oslf("store")
}

#[test]
fn info_verify_and_exports() {
    let f = fixture(Spec::default());
    let (dir, path) = temp_store("cli.oslf");
    write(&path, &f);
    let out = bin().arg("info").arg(&path).output().unwrap();
    assert!(out.status.success());
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        text.contains("rgb9e5")
            && text.contains("bytes/texel")
            && text.contains("mantissa bits    9"),
        "{text}"
    );
    let out = bin().args(["info", "--json"]).arg(&path).output().unwrap();
    assert!(out.status.success());
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["cubes"], 6);
    assert_eq!(v["mantissa_bits"], 9);
    assert_eq!(v["version"], 2);
    assert_eq!(v["env_cube_index"], 5);
    let out = bin().arg("verify").arg(&path).output().unwrap();
    assert!(out.status.success());

    let exr = dir.path().join("cube.exr");
    let out = bin()
        .arg("export-cube")
        .arg(&path)
        .arg("2")
        .arg("-o")
        .arg(&exr)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(exr.exists());
    let out = bin()
        .arg("export-cube")
        .arg(&path)
        .args(["5", "--layout", "faces", "-o"])
        .arg(&exr)
        .output()
        .unwrap();
    assert!(out.status.success());
    assert!(dir.path().join("cube_nz.exr").exists());
    let png = dir.path().join("map.png");
    let out = bin()
        .arg("export-sample-map")
        .arg(&path)
        .args(["1", "--channel", "2", "-o"])
        .arg(&png)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(png.exists());

    // Errors: non-zero exit, a message, no panic.
    let out = bin()
        .arg("export-cube")
        .arg(&path)
        .args(["99", "-o"])
        .arg(&exr)
        .output()
        .unwrap();
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("out of range"));

    let mut bytes = std::fs::read(&path).unwrap();
    let store = oslf_format::Store::open(&path).unwrap();
    let e = store.face_entry(3, 4).unwrap();
    drop(store);
    bytes[e.offset as usize + 2] ^= 0x55;
    let bad = dir.path().join("bad.oslf");
    std::fs::write(&bad, &bytes).unwrap();
    let out = bin().arg("verify").arg(&bad).output().unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("cube 3, face 4") && err.contains("offset"),
        "{err}"
    );
    assert!(!err.contains("panicked"));

    let out = bin()
        .arg("info")
        .arg(dir.path().join("missing.oslf"))
        .output()
        .unwrap();
    assert!(!out.status.success());
    assert!(!String::from_utf8_lossy(&out.stderr).contains("panicked"));
}
