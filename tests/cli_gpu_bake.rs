//! `oslf bake --device gpu` end to end on the CI's adapter (lavapipe): a Bézier object and a
//! mesh object baked on both devices give the same cubes up to rounding; GPU bakes are
//! deterministic, their shards merge into the single GPU bake byte for byte, and an
//! interrupted GPU bake resumes into it; the summary names the device, and `[bake] device`
//! is read and checked.

use crate::common;

use std::path::{Path, PathBuf};

use common::oslf;

fn run(cmd: &mut std::process::Command) -> (String, String) {
    let out = cmd.output().unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout).to_string();
    let stderr = String::from_utf8_lossy(&out.stderr).to_string();
    assert!(out.status.success(), "{cmd:?} failed:\n{stdout}\n{stderr}");
    (stdout, stderr)
}

fn bake(scene: &Path, output: &Path, extra: &[&str]) -> String {
    run(oslf("bake")
        .arg(scene)
        .arg("-o")
        .arg(output)
        .args(["-q", "--preview", "none"])
        .args(extra))
    .0
}

/// The lid scene with 8² cubes stored as f32, so that texels compare unrounded.
fn lid_scene(dir: &Path) -> PathBuf {
    let scene = dir.join("lid.toml");
    let text = common::LID_SCENE
        .replace("cube_resolution = 2", "cube_resolution = 8")
        .replace(
            "samples_per_texel = 1",
            "samples_per_texel = 4\nencoding = \"rgba32f\"\nbounces = 2",
        );
    std::fs::write(&scene, text).unwrap();
    scene
}

/// Every texel of every cube of the two stores: how many differ by more than 10⁻³
/// (relative), and how many there are.
fn differing_texels(a: &Path, b: &Path) -> (usize, usize) {
    let a = oslf_format::Store::open(a).unwrap();
    let b = oslf_format::Store::open(b).unwrap();
    assert_eq!(a.cube_count(), b.cube_count());
    let (mut differ, mut all) = (0, 0);
    for cube in 0..a.cube_count() {
        let (ca, cb) = (a.read_cube(cube).unwrap(), b.read_cube(cube).unwrap());
        for (x, y) in ca.faces.iter().flatten().zip(cb.faces.iter().flatten()) {
            all += 1;
            if (0..3).any(|c| (x[c] - y[c]).abs() > 1e-3 * x[c].abs().max(1e-2)) {
                differ += 1;
            }
        }
    }
    (differ, all)
}

#[test]
fn a_bezier_object_bakes_on_the_gpu_as_on_the_cpu() {
    let tmp = tempfile::tempdir().unwrap();
    let scene = lid_scene(tmp.path());
    let cpu = tmp.path().join("cpu.oslf");
    let gpu = tmp.path().join("gpu.oslf");
    let summary_cpu = bake(&scene, &cpu, &["--device", "cpu"]);
    let summary_gpu = bake(&scene, &gpu, &["--device", "gpu"]);
    assert!(
        summary_cpu.contains("capture        CPU, as --device asks"),
        "{summary_cpu}"
    );
    assert!(summary_gpu.contains("capture        GPU "), "{summary_gpu}");
    let (differ, all) = differing_texels(&cpu, &gpu);
    assert!(
        all > 1000 && differ * 100 <= 3 * all,
        "{differ} of {all} texels differ"
    );
}

#[test]
fn a_mesh_object_bakes_on_the_gpu_as_on_the_cpu() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    // An octahedron object over a checkered floor, lit by a point light, the sky and its sun.
    std::fs::write(
        dir.join("gem.obj"),
        "v 0 0 1\nv 1 0 0\nv 0 1 0\nv -1 0 0\nv 0 -1 0\nv 0 0 -1\n\
         f 1 2 3\nf 1 3 4\nf 1 4 5\nf 1 5 2\nf 6 3 2\nf 6 4 3\nf 6 5 4\nf 6 2 5\n",
    )
    .unwrap();
    let scene = dir.join("gem.toml");
    std::fs::write(
        &scene,
        r#"
[environment]
sky = { sun_direction = [0.4, 0.3, 0.7], sun_irradiance = [2.0, 2.0, 1.8], turbidity = 3.0, intensity = 1.0 }

[[point_light]]
position = [1.5, -1.0, 3.0]
intensity = [15.0, 12.0, 10.0]

[[object]]
name = "gem"
mesh = "gem.obj"
transform = { translate = [0.0, 0.0, 1.2], scale = 0.6 }
material = { color = [0.6, 0.6, 0.6] }

[[plane]]
size = [6.0, 6.0]
material = { checker = { a = [0.8, 0.8, 0.8], b = [0.2, 0.3, 0.1], scale = 3.0 } }

[bake]
epsilon = 0.03
sample_count = 40
cube_resolution = 8
sample_map_resolution = 16
samples_per_texel = 4
encoding = "rgba32f"
"#,
    )
    .unwrap();
    let cpu = dir.join("cpu.oslf");
    let gpu = dir.join("gpu.oslf");
    bake(&scene, &cpu, &["--device", "cpu"]);
    bake(&scene, &gpu, &["--device", "gpu"]);
    let (differ, all) = differing_texels(&cpu, &gpu);
    assert!(
        all > 1000 && differ * 100 <= 3 * all,
        "{differ} of {all} texels differ"
    );
}

#[test]
fn gpu_bakes_are_deterministic_and_their_shards_and_slices_make_the_single_bake() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    let scene = lid_scene(dir);
    let single = dir.join("single.oslf");
    bake(&scene, &single, &["--device", "gpu"]);
    let bytes = std::fs::read(&single).unwrap();
    let again = dir.join("again.oslf");
    bake(&scene, &again, &["--device", "gpu", "-j", "1"]);
    assert!(
        std::fs::read(&again).unwrap() == bytes,
        "a second GPU bake differs"
    );
    let shards: Vec<PathBuf> = (0..3)
        .map(|i| {
            let out = dir.join(format!("s{i}"));
            bake(
                &scene,
                &out,
                &["--device", "gpu", "--shard", &format!("{i}/3")],
            );
            out
        })
        .collect();
    let merged = dir.join("merged.oslf");
    run(oslf("store merge").args(&shards).arg("-o").arg(&merged));
    assert!(
        std::fs::read(&merged).unwrap() == bytes,
        "the merged GPU shards differ from the single GPU bake"
    );
    let sliced = dir.join("sliced.oslf");
    bake(&scene, &sliced, &["--device", "gpu", "--max-cubes", "7"]);
    bake(&scene, &sliced, &["--device", "gpu", "--resume"]);
    assert!(
        std::fs::read(&sliced).unwrap() == bytes,
        "the resumed GPU bake differs"
    );
}

#[test]
fn the_scene_chooses_the_device_and_a_bad_one_is_refused_where_it_stands() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    let scene = dir.join("lid.toml");
    std::fs::write(
        &scene,
        common::LID_SCENE.replace("[bake]\n", "[bake]\ndevice = \"gpu\"\n"),
    )
    .unwrap();
    let summary = bake(&scene, &dir.join("a.oslf"), &[]);
    assert!(
        summary.contains("capture        GPU ") && summary.contains("as [bake] device asks"),
        "{summary}"
    );
    // Not quiet: the estimate's capture time is the GPU's, measured on this scene.
    let (_, stderr) = run(oslf("bake")
        .arg(&scene)
        .arg("-o")
        .arg(dir.join("c.oslf"))
        .args(["--preview", "none"]));
    assert!(
        stderr.contains("capture on GPU ") && stderr.contains("with the cube maps on GPU "),
        "{stderr}"
    );
    // …and the device memory the capture holds: the scene and one batch.
    assert!(stderr.contains(" (GPU memory ~"), "{stderr}");
    // The flag wins over the scene.
    let summary = bake(&scene, &dir.join("b.oslf"), &["--device", "cpu"]);
    assert!(
        summary.contains("capture        CPU, as --device asks"),
        "{summary}"
    );
    std::fs::write(
        &scene,
        common::LID_SCENE.replace("[bake]\n", "[bake]\ndevice = \"tpu\"\n"),
    )
    .unwrap();
    let out = oslf("bake")
        .arg(&scene)
        .args(["-q", "--preview", "none"])
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success());
    assert!(
        stderr.contains("lid.toml:") && stderr.contains("unknown device \"tpu\""),
        "{stderr}"
    );
    assert!(!stderr.contains("panicked"), "{stderr}");
}

#[test]
fn a_gpu_capture_takes_the_scenes_gpu_preset_unless_another_is_asked_for() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    let scene = dir.join("lid.toml");
    std::fs::write(
        &scene,
        format!(
            "{}\n[presets.gpu]\nsamples_per_texel = 9\n\n[presets.four]\nsamples_per_texel = 4\n",
            common::LID_SCENE
        ),
    )
    .unwrap();
    let samples = |store: &str| {
        oslf_format::Store::open(&dir.join(store))
            .unwrap()
            .meta()
            .bake
            .samples_per_texel
    };
    let summary = bake(&scene, &dir.join("gpu.oslf"), &["--device", "gpu"]);
    assert!(
        summary.contains("settings: the scene's preset \"gpu\", applied for a GPU capture"),
        "{summary}"
    );
    assert!(summary.contains("9 samples per texel"), "{summary}");
    assert_eq!(samples("gpu.oslf"), 9);
    // On the CPU, and where another preset is asked for, the scene's own settings.
    let summary = bake(&scene, &dir.join("cpu.oslf"), &["--device", "cpu"]);
    assert!(!summary.contains("preset \"gpu\""), "{summary}");
    assert_eq!(samples("cpu.oslf"), 1);
    let summary = bake(
        &scene,
        &dir.join("four.oslf"),
        &["--device", "gpu", "--preset", "four"],
    );
    assert!(!summary.contains("preset \"gpu\""), "{summary}");
    assert_eq!(samples("four.oslf"), 4);
}
