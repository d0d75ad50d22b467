//! `oslf bake --shard I/N` and `oslf store merge`: the merged store is byte-identical to a
//! single bake, shards resume like a bake, and bad shard sets are refused with named reasons.

use crate::common;

use std::path::{Path, PathBuf};

use common::{oslf, run_ok};

/// The small scene of tests/common (its environment cube is the cube past the sample points):
/// 24 sample points, 25 cubes.
const SCENE: &str = common::LID_SCENE;

const CUBES: u32 = 25;

/// Runs `cmd`, which must fail; returns its stderr.
fn run_err(cmd: &mut std::process::Command) -> String {
    let out = cmd.output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr).to_string();
    assert!(
        !out.status.success(),
        "{cmd:?} succeeded:\n{}",
        String::from_utf8_lossy(&out.stdout)
    );
    assert!(!stderr.contains("panicked"), "{stderr}");
    stderr
}

fn bake(scene: &Path, output: &Path, extra: &[&str]) -> String {
    run_ok(
        oslf("bake")
            .arg(scene)
            .arg("-o")
            .arg(output)
            .args(["-q", "--preview", "none"])
            .args(extra),
    )
}

fn shard(scene: &Path, dir: &Path, i: u32, n: u32, extra: &[&str]) -> PathBuf {
    let out = dir.join(format!("s{i}of{n}"));
    let spec = format!("{i}/{n}");
    let mut args = vec!["--shard", spec.as_str()];
    args.extend_from_slice(extra);
    bake(scene, &out, &args);
    out
}

fn merge(shards: &[PathBuf], output: &Path) -> std::process::Command {
    let mut cmd = oslf("store merge");
    cmd.args(shards).arg("-o").arg(output);
    cmd
}

/// A temporary directory with the scene and its single-bake store: (the directory, the scene
/// file, the store's bytes).
fn setup() -> (tempfile::TempDir, PathBuf, Vec<u8>) {
    let dir = tempfile::tempdir().unwrap();
    let scene = dir.path().join("lid.toml");
    std::fs::write(&scene, SCENE).unwrap();
    let single = dir.path().join("single.oslf");
    bake(&scene, &single, &[]);
    let bytes = std::fs::read(&single).unwrap();
    (dir, scene, bytes)
}

#[test]
fn merged_shards_are_byte_identical_to_a_single_bake() {
    let (tmp, scene, single) = setup();
    let dir = tmp.path();
    // N = 1; N dividing nothing; N larger than the cube count (empty shards).
    for n in [1, 2, 3, 7, CUBES + 3] {
        let mut shards: Vec<PathBuf> = (0..n)
            .map(|i| {
                // Thread counts differ per shard: the bytes must not.
                let threads = (1 + i % 2).to_string();
                shard(&scene, dir, i, n, &["-j", &threads])
            })
            .collect();
        shards.reverse(); // merge takes them in any order
        let merged = dir.join(format!("merged{n}.oslf"));
        let stdout = run_ok(&mut merge(&shards, &merged));
        assert!(stdout.contains(&format!("{CUBES} cubes")), "{stdout}");
        let bytes = std::fs::read(&merged).unwrap();
        assert!(
            bytes == single,
            "N = {n}: the merged store ({} bytes) differs from the single bake ({} bytes)",
            bytes.len(),
            single.len()
        );
        assert!(!dir.join(format!("merged{n}.oslf.partial")).exists());
        run_ok(oslf("store verify").arg(&merged));
        for s in &shards {
            std::fs::remove_file(s).unwrap();
        }
    }
}

#[test]
fn an_interrupted_shard_resumes_and_merges_to_the_same_bytes() {
    let (tmp, scene, single) = setup();
    let dir = tmp.path();
    let n = 3;
    let mut shards = Vec::new();
    for i in 0..n {
        if i != 1 {
            shards.push(shard(&scene, dir, i, n, &[]));
            continue;
        }
        // Shard 1 (8 cubes) stops after 3 cubes, again after 2 more, then finishes.
        let out = dir.join(format!("s{i}of{n}"));
        let partial = dir.join(format!("s{i}of{n}.partial"));
        let stdout = bake(&scene, &out, &["--shard", "1/3", "--max-cubes", "3"]);
        assert!(stdout.contains("--resume"), "{stdout}");
        assert!(partial.exists() && !out.exists());
        bake(
            &scene,
            &out,
            &["--shard", "1/3", "--resume", "--max-cubes", "2", "-j", "1"],
        );
        assert!(partial.exists() && !out.exists());
        // A kill in the middle of a write leaves a torn record: resume drops it.
        let mut torn = std::fs::read(&partial).unwrap();
        torn.extend_from_slice(b"OSCR\x05\0\0\0 torn record");
        std::fs::write(&partial, torn).unwrap();
        let json = dir.join("report.json");
        let report_arg = json.to_str().unwrap();
        bake(
            &scene,
            &out,
            &["--shard", "1/3", "--resume", "--report-json", report_arg],
        );
        let report: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
        assert_eq!(report["finished"], true);
        assert_eq!(report["cubes_resumed"], 5);
        assert_eq!(report["cubes"], 8);
        assert_eq!(report["shard"], "1/3");
        assert!(out.exists() && !partial.exists());
        shards.push(out);
    }
    let merged = dir.join("merged.oslf");
    run_ok(&mut merge(&shards, &merged));
    assert!(std::fs::read(&merged).unwrap() == single);
}

#[test]
fn resume_refuses_another_shard_or_other_settings() {
    let (tmp, scene, _) = setup();
    let dir = tmp.path();
    let out = dir.join("s");
    bake(&scene, &out, &["--shard", "0/4", "--max-cubes", "1"]);
    let err = run_err(
        oslf("bake")
            .arg(&scene)
            .arg("-o")
            .arg(&out)
            .args(["-q", "--shard", "1/4", "--resume"]),
    );
    assert!(
        err.contains("it is shard 0/4, and this bake is shard 1/4"),
        "{err}"
    );
    let other = dir.join("other.toml");
    std::fs::write(
        &other,
        SCENE.replace("samples_per_texel = 1", "samples_per_texel = 1\nseed = 9"),
    )
    .unwrap();
    let err = run_err(
        oslf("bake")
            .arg(&other)
            .arg("-o")
            .arg(&out)
            .args(["-q", "--shard", "0/4", "--resume"]),
    );
    assert!(err.contains("seed 0 (this bake: 9)"), "{err}");
    // Killed while creating the partial file: nothing to keep, so the shard starts over.
    let partial = dir.join("s.partial");
    let bytes = std::fs::read(&partial).unwrap();
    std::fs::write(&partial, &bytes[..100]).unwrap();
    let out_cmd = oslf("bake")
        .arg(&scene)
        .arg("-o")
        .arg(&out)
        .args(["-q", "--shard", "0/4", "--resume", "--preview", "none"])
        .output()
        .unwrap();
    assert!(out_cmd.status.success());
    let stderr = String::from_utf8_lossy(&out_cmd.stderr);
    assert!(stderr.contains("never completely created"), "{stderr}");
    assert!(out.exists() && !partial.exists());
    let err = run_err(oslf("bake").arg(&scene).args(["--shard", "4/4"]));
    assert!(err.contains("invalid shard \"4/4\""), "{err}");
}

#[test]
fn merge_names_missing_repeated_and_mismatched_shards() {
    let (tmp, scene, _) = setup();
    let dir = tmp.path();
    let s: Vec<PathBuf> = (0..4).map(|i| shard(&scene, dir, i, 4, &[])).collect();
    let out = dir.join("out.oslf");
    let check = |shards: &[PathBuf], needles: &[&str]| {
        let err = run_err(&mut merge(shards, &out));
        for needle in needles {
            assert!(err.contains(needle), "lacks {needle:?}: {err}");
        }
        assert!(!out.exists());
        assert!(!dir.join("out.oslf.partial").exists());
    };
    check(
        &[s[0].clone(), s[3].clone()],
        &["shards 1, 2 of 4 are missing"],
    );
    check(
        &[
            s[0].clone(),
            s[1].clone(),
            s[2].clone(),
            s[3].clone(),
            s[2].clone(),
        ],
        &["shard 2/4 is given 2 times"],
    );
    // Another seed.
    let other = dir.join("other.toml");
    std::fs::write(
        &other,
        SCENE.replace("samples_per_texel = 1", "samples_per_texel = 1\nseed = 5"),
    )
    .unwrap();
    let t = dir.join("t1");
    bake(&other, &t, &["--shard", "1/4"]);
    check(
        &[s[0].clone(), t.clone(), s[2].clone(), s[3].clone()],
        &["shard 1/4", "does not belong", "seed 5"],
    );
    // Another cube resolution.
    let other = dir.join("res.toml");
    std::fs::write(
        &other,
        SCENE.replace("cube_resolution = 2", "cube_resolution = 3"),
    )
    .unwrap();
    bake(&other, &t, &["--shard", "1/4"]);
    check(
        &[s[0].clone(), t.clone(), s[2].clone(), s[3].clone()],
        &["cube_resolution 3"],
    );
    // Another shard count.
    bake(&scene, &t, &["--shard", "1/3"]);
    check(
        &[s[0].clone(), t.clone(), s[2].clone(), s[3].clone()],
        &["different shard counts"],
    );
    // An unfinished shard, a store instead of a shard, a damaged shard.
    bake(&scene, &t, &["--shard", "1/4", "--max-cubes", "1"]);
    let partial = dir.join("t1.partial");
    check(
        &[s[0].clone(), partial, s[2].clone(), s[3].clone()],
        &["never finished", "--resume"],
    );
    check(
        &[
            s[0].clone(),
            dir.join("single.oslf"),
            s[2].clone(),
            s[3].clone(),
        ],
        &["single.oslf", "not an OSLF shard"],
    );
    let mut bytes = std::fs::read(&s[1]).unwrap();
    let last = bytes.len() - 64;
    bytes[last] ^= 1;
    std::fs::write(&t, bytes).unwrap();
    check(
        &[s[0].clone(), t.clone(), s[2].clone(), s[3].clone()],
        &["t1", "frame checksum mismatch", "cube 21"],
    );
    check(&[], &["required"]);
}

/// A shard given where a store is read is named as a shard, with the command that joins it.
#[test]
fn a_shard_read_as_a_store_says_what_it_is() {
    let (dir, scene, _) = setup();
    let s = shard(&scene, dir.path(), 0, 2, &[]);
    for sub in ["store verify", "store info", "render"] {
        let e = run_err(oslf(sub).arg(&s));
        assert!(
            e.contains(&s.display().to_string())
                && e.contains("this is a shard of a sharded bake")
                && e.contains("oslf store merge"),
            "{sub}: {e}"
        );
    }
}
