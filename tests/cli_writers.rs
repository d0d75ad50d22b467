//! Concurrent writers of one store: the first owns the partial file until its rename, a second
//! (bake, resume, convert, merge) is refused with the first's process named, and the first's
//! store is exactly what it would have been alone.

use crate::common;

use std::os::unix::fs::MetadataExt;
use std::path::Path;
use std::process::{Child, Command};
use std::time::{Duration, Instant};

use common::oslf;
use common::store_fixture::system_lists_flocks_of;

/// The lid scene with cube maps large enough that a one-thread bake takes a while after it has
/// created its partial file.
fn scene(seed: u32) -> String {
    format!(
        "{}\n[bake]\nseed = {seed}\nsample_count = 12\ncube_resolution = 24\nsample_map_resolution = 4\nsamples_per_texel = 16\n",
        include_str!("fixtures/teapot-lid.toml")
    )
}

/// Whether some process holds a `flock` on the file at `path` (Linux's /proc/locks).
fn locked(path: &Path) -> bool {
    let Ok(m) = std::fs::metadata(path) else {
        return false;
    };
    let dev = m.dev();
    let major = ((dev >> 8) & 0xfff) | ((dev >> 32) & !0xfff);
    let minor = (dev & 0xff) | ((dev >> 12) & !0xff);
    let id = format!("{major:02x}:{minor:02x}:{}", m.ino());
    std::fs::read_to_string("/proc/locks")
        .unwrap()
        .lines()
        .any(|l| l.contains(" FLOCK ") && l.split_whitespace().any(|w| w == id))
}

/// Sends `signal` (STOP, CONT) to `child`.
fn signal(child: &Child, signal: &str) {
    let ok = Command::new("kill")
        .args([&format!("-{signal}"), &child.id().to_string()])
        .status()
        .unwrap()
        .success();
    assert!(ok, "kill -{signal}");
}

#[test]
fn a_second_writer_of_a_store_is_refused_and_the_first_finishes_alone() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    let (first, second) = (dir.join("first.toml"), dir.join("second.toml"));
    std::fs::write(&first, scene(1)).unwrap();
    std::fs::write(&second, scene(2)).unwrap();
    let bake = |scene: &Path, out: &Path| {
        let mut c = oslf("bake");
        c.arg(scene)
            .args(["-q", "-j", "1", "--preview", "none", "-o"])
            .arg(out);
        c
    };
    let lone = dir.join("lone.oslf");
    let t = Instant::now();
    assert!(bake(&first, &lone).status().unwrap().success());
    let lone_secs = t.elapsed().as_secs_f64();

    let out = dir.join("s.oslf");
    let partial = dir.join("s.oslf.partial");
    let mut a = bake(&first, &out).spawn().unwrap();
    let deadline = Instant::now() + Duration::from_secs(120);
    while !locked(&partial) {
        assert!(
            a.try_wait().unwrap().is_none(),
            "the first bake ended early"
        );
        assert!(
            Instant::now() < deadline,
            "no lock on {}",
            partial.display()
        );
        std::thread::sleep(Duration::from_millis(2));
    }
    // Hold the first writer still while the others try.
    signal(&a, "STOP");
    assert!(
        !out.exists(),
        "the first bake finished before it could be stopped (a lone bake takes {lone_secs:.2} s)"
    );
    let refused = |mut c: Command| {
        let o = c.output().unwrap();
        assert!(!o.status.success());
        let err = String::from_utf8_lossy(&o.stderr).into_owned();
        assert_eq!(
            err.matches("is being written by").count(),
            1,
            "said once: {err}"
        );
        // Named where the system lists the lock (not in every sandbox).
        if system_lists_flocks_of(a.id()) {
            let holder = format!("is being written by process {} (", a.id());
            assert!(err.contains(&holder) && err.contains("oslf bake"), "{err}");
        }
        err
    };
    refused(bake(&second, &out));
    let mut resume = bake(&first, &out);
    resume.arg("--resume");
    refused(resume);
    let mut convert = oslf("store convert");
    convert.arg(&lone).arg(&out).args(["--encoding", "bc6h"]);
    refused(convert);
    signal(&a, "CONT");
    assert!(a.wait().unwrap().success());
    assert!(!partial.exists());
    assert_eq!(
        std::fs::read(&out).unwrap(),
        std::fs::read(&lone).unwrap(),
        "the first bake's store is the lone bake's"
    );
    let verify = oslf("store verify").arg(&out).output().unwrap();
    assert!(verify.status.success(), "{verify:?}");
}

#[test]
fn an_output_that_is_an_input_is_refused_however_it_is_spelled() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    let scene_path = dir.join("lid.toml");
    std::fs::write(&scene_path, common::LID_SCENE).unwrap();
    let store = dir.join("t.oslf");
    let ok = oslf("bake")
        .arg(&scene_path)
        .args(["-q", "--preview", "none", "-o"])
        .arg(&store)
        .status()
        .unwrap();
    assert!(ok.success());
    let original = std::fs::read(&store).unwrap();
    let dotted = dir.join(".").join("t.oslf");
    let o = oslf("store convert")
        .arg(&store)
        .arg(&dotted)
        .args(["--encoding", "bc6h"])
        .output()
        .unwrap();
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("(the same file)"), "{err}");
    assert_eq!(std::fs::read(&store).unwrap(), original);

    // Two shards merged over one of them.
    let mut shards = Vec::new();
    for i in 0..2 {
        let s = dir.join(format!("s{i}"));
        let ok = oslf("bake")
            .arg(&scene_path)
            .args(["-q", "--shard", &format!("{i}/2"), "-o"])
            .arg(&s)
            .status()
            .unwrap();
        assert!(ok.success());
        shards.push(s);
    }
    let shard0 = std::fs::read(&shards[0]).unwrap();
    let o = oslf("store merge")
        .args(&shards)
        .arg("-o")
        .arg(dir.join(".").join("s0"))
        .output()
        .unwrap();
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("(the same file)"), "{err}");
    assert_eq!(std::fs::read(&shards[0]).unwrap(), shard0);
}

/// The store `bake` writes by default (the scene's name with .oslf, in the current directory)
/// is refused when it is the scene itself, and the scene is kept.
#[test]
fn a_default_output_that_is_the_input_is_refused() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    std::fs::write(dir.join("lid.oslf"), common::LID_SCENE).unwrap();
    let o = oslf("bake")
        .arg("lid.oslf")
        .args(["-q", "--preview", "none"])
        .current_dir(dir)
        .output()
        .unwrap();
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("--output lid.oslf is SCENE lid.oslf (the same file)"),
        "{err}"
    );
    assert_eq!(
        std::fs::read_to_string(dir.join("lid.oslf")).unwrap(),
        common::LID_SCENE
    );
    assert_eq!(std::fs::read_dir(dir).unwrap().count(), 1);
}
