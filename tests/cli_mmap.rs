//! `--mmap`: the commands that read a store give the same output through a memory map as
//! through positioned reads.

mod common;

use common::{oslf, LID_SCENE};

#[test]
fn mapped_and_positioned_stores_give_the_same_outputs() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    let scene = dir.join("lid.toml");
    std::fs::write(&scene, LID_SCENE).unwrap();
    let store = dir.join("lid.oslf");
    let ok = oslf("bake")
        .arg(&scene)
        .args(["-q", "--preview", "none", "-o"])
        .arg(&store)
        .status()
        .unwrap();
    assert!(ok.success());
    let stdout = |args: &[&str]| {
        let o = oslf(args[0]).args(&args[1..]).output().unwrap();
        assert!(
            o.status.success(),
            "{args:?}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
        String::from_utf8(o.stdout).unwrap()
    };
    let s = store.to_str().unwrap();
    for sub in ["store info", "store verify"] {
        let plain = stdout(&[sub, s]);
        assert_eq!(stdout(&[sub, "--mmap", s]), plain, "{sub}");
        assert_eq!(stdout(&[sub, s, "--mmap"]), plain, "{sub}");
    }
    // The same image, bit for bit, from both readers, on the GPU (sample maps uploaded from
    // the mapping) and with the CPU reference.
    let mut images = Vec::new();
    for (name, mmap, cpu) in [
        ("positioned.exr", false, false),
        ("mapped.exr", true, false),
        ("positioned-cpu.exr", false, true),
        ("mapped-cpu.exr", true, true),
    ] {
        let out = dir.join(name);
        let mut c = oslf("render");
        c.arg(&store)
            .args(["--width", "48", "--height", "32", "-o"])
            .arg(&out);
        if mmap {
            c.arg("--mmap");
        }
        if cpu {
            c.arg("--cpu");
        }
        let o = c.output().unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        images.push(std::fs::read(&out).unwrap());
    }
    assert_eq!(images[0], images[1], "GPU");
    assert_eq!(images[2], images[3], "CPU reference");
}
