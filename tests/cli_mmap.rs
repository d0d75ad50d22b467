//! `--mmap`: the commands that read a store give the same output through a memory map as
//! through positioned reads.

use crate::common;

use common::{oslf, LID_SCENE};

/// The lid scene of tests/common baked into `dir`: the store's path.
fn bake_lid(dir: &std::path::Path) -> std::path::PathBuf {
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
    store
}

#[test]
fn mapped_and_positioned_stores_give_the_same_outputs() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    let store = bake_lid(dir);
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

/// A store written in place while `render --mmap` has it mapped (by a program the lock does not
/// bind: the same size, its last byte written again, its modification time moved; the bytes
/// stay valid so that the open's own checks, which may still be running, pass): a warning naming
/// the store, and under `--strict` a failure with no image written. The write is made once
/// the process has mapped the store (seen in /proc/PID/maps), while it is still starting its
/// GPU device, so before the frame reads the mapping and before the check after it.
#[cfg(target_os = "linux")]
#[test]
fn a_store_written_in_place_during_a_mapped_render_is_said_and_refused_under_strict() {
    use std::io::{Seek, SeekFrom, Write};
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    let store = bake_lid(dir);
    for strict in [false, true] {
        let image = dir.join(format!("strict-{strict}.exr"));
        let mut c = oslf("render");
        c.arg(&store)
            .args(["--mmap", "--width", "48", "--height", "32", "-o"])
            .arg(&image)
            .stdout(std::process::Stdio::piped())
            .stderr(std::process::Stdio::piped());
        if strict {
            c.arg("--strict");
        }
        let child = c.spawn().unwrap();
        let maps = format!("/proc/{}/maps", child.id());
        let name = store.display().to_string();
        let start = std::time::Instant::now();
        while !std::fs::read_to_string(&maps).is_ok_and(|m| m.contains(&name)) {
            assert!(
                start.elapsed() < std::time::Duration::from_secs(60),
                "the store was never mapped"
            );
            std::thread::sleep(std::time::Duration::from_micros(200));
        }
        let last = *std::fs::read(&store).unwrap().last().unwrap();
        let len = std::fs::metadata(&store).unwrap().len();
        let mut f = std::fs::OpenOptions::new()
            .write(true)
            .open(&store)
            .unwrap();
        f.seek(SeekFrom::Start(len - 1)).unwrap();
        f.write_all(&[last]).unwrap();
        f.set_modified(std::time::SystemTime::now() + std::time::Duration::from_secs(5))
            .unwrap();
        drop(f);
        let out = child.wait_with_output().unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(
            err.contains(&format!(
                "{name} was written in place while it was memory-mapped"
            )),
            "strict {strict}: {err}"
        );
        assert_eq!(out.status.success(), !strict, "strict {strict}: {err}");
        assert_eq!(image.exists(), !strict, "strict {strict}");
    }
}
