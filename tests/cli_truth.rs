//! `oslf truth --background scene` and `oslf compare --side-by-side`: the scene behind the
//! object changes no object pixel and no metric, and the pair is written as one PNG.

use std::path::{Path, PathBuf};

use crate::common;

use common::{oslf, read_exr, run_ok};

/// The lid scene of tests/common on a box, so the background behind it holds geometry too.
fn scene_text() -> String {
    format!(
        "{}\n[[box]]\nsize = [8.0, 6.0, 0.2]\ntransform = {{ translate = [0.0, 0.0, -0.1] }}\n\
         material = {{ color = [0.5, 0.4, 0.3] }}\n",
        common::LID_SCENE
    )
}

/// [`scene_text`] written into `dir`; its path.
fn lid_scene(dir: &Path) -> PathBuf {
    let scene = dir.join("lid.toml");
    std::fs::write(&scene, scene_text()).unwrap();
    scene
}

/// `oslf truth SCENE -m mirror ARGS -q -o PREFIX`, which must succeed; the mirror image's path.
fn mirror_truth(scene: &Path, args: &[&str], prefix: &Path) -> PathBuf {
    run_ok(
        oslf("truth")
            .arg(scene)
            .args(["-m", "mirror"])
            .args(args)
            .args(["-q", "-o"])
            .arg(prefix),
    );
    let mut name = prefix.file_name().unwrap().to_os_string();
    name.push("-mirror.exr");
    prefix.with_file_name(name)
}

#[test]
fn the_scene_behind_the_object_changes_no_object_pixel_and_pairs_side_by_side() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    let scene = lid_scene(dir);
    let truth = |background: &str, prefix: &str| {
        let args = ["--spp", "2", "--width", "40", "--height", "30"];
        let args = [&args[..], &["--background", background]].concat();
        read_exr(&mirror_truth(&scene, &args, &dir.join(prefix))).1
    };
    let plain = truth("none", "plain");
    let behind = truth("scene", "behind");
    let object = plain.iter().filter(|p| p[3] == 1.0).count();
    assert!(
        object > 20 && object < plain.len() - 20,
        "{object} object pixels"
    );
    for (a, b) in plain.iter().zip(&behind) {
        assert!(b.iter().all(|c| c.is_finite()));
        assert_eq!(a[3], b[3], "the object mask is kept");
        if a[3] == 1.0 {
            assert_eq!(a, b, "object pixels are the term's");
        } else {
            assert_eq!(a, &[0.0; 4]);
        }
    }
    let lit = behind
        .iter()
        .filter(|p| p[3] == 0.0 && p[0] + p[1] + p[2] > 0.0)
        .count();
    assert_eq!(
        lit,
        plain.len() - object,
        "every background pixel sees the sky or the box"
    );

    // The metrics ignore the background; the side-by-side PNG holds both whole images.
    let png = dir.join("pair.png");
    let out = oslf("compare")
        .arg(dir.join("plain-mirror.exr"))
        .arg(dir.join("behind-mirror.exr"))
        .arg("--side-by-side")
        .arg(&png)
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(
        stdout.contains("RMSE L*a*b* 0.0000 0.0000 0.0000"),
        "{stdout}"
    );
    let pair = image::open(&png).unwrap();
    assert_eq!((pair.width(), pair.height()), (2 * 40 + 8, 30));
    let rgb = pair.to_rgb8();
    // Left: the test image (scene behind) is lit in its corner; right: the reference is black.
    assert_ne!(rgb.get_pixel(0, 0).0, [0, 0, 0]);
    assert_eq!(rgb.get_pixel(40 + 8, 0).0, [0, 0, 0]);

    let bad = oslf("truth")
        .arg(&scene)
        .args(["--background", "env"])
        .output()
        .unwrap();
    assert!(!bad.status.success());
    assert!(String::from_utf8_lossy(&bad.stderr).contains("possible values: none, scene"));
}

/// `oslf truth -m pbr` renders glTF's metallic-roughness reflection of the object: finite,
/// lit where the object is, and not the same for a near-mirror metal as for a rough
/// dielectric; a metallic factor out of range is an error naming it.
#[test]
fn the_pbr_truth_renders_and_checks_its_material() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    let scene = lid_scene(dir);
    let truth = |metallic: &str, roughness: &str, prefix: &str| {
        oslf("truth")
            .arg(&scene)
            .args([
                "-m", "pbr", "--spp", "16", "--width", "40", "--height", "30", "-q",
            ])
            .args(["--metallic", metallic, "--roughness", roughness, "-o"])
            .arg(dir.join(prefix))
            .output()
            .unwrap()
    };
    let mut means = Vec::new();
    for (metallic, roughness, prefix) in [("1", "0.1", "metal"), ("0", "0.9", "rough")] {
        let out = truth(metallic, roughness, prefix);
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        let pixels = read_exr(&dir.join(format!("{prefix}-pbr.exr"))).1;
        let object: Vec<_> = pixels.iter().filter(|p| p[3] == 1.0).collect();
        assert!(object.len() > 20, "{} object pixels", object.len());
        assert!(pixels.iter().all(|p| p.iter().all(|c| c.is_finite())));
        let mean = object.iter().map(|p| p[0] + p[1] + p[2]).sum::<f32>() / object.len() as f32;
        assert!(mean > 0.0, "{prefix}: the object is black");
        means.push(mean);
    }
    assert!(
        means[0] != means[1],
        "the material changes nothing: {means:?}"
    );
    let out = truth("2", "0.5", "bad");
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("metallic 2"), "{err}");
}

/// `oslf compare --second-reference`: three truths of one scene at other seeds; the third
/// judged against the first two's mean. Its error is then only noise, of the same size as
/// each truth's: raw √(σ² + σ²/2), the mean's noise σ/√2, and the corrected error σ, √(2/3)
/// of the raw. The JSON and CSV carry it, and the side-by-side pair names the mean; a CSV of
/// another header and a second reference of another size are refused.
#[test]
fn a_second_reference_takes_the_references_noise_out_of_the_error() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    let scene = lid_scene(dir);
    let truth = |seed: &str, width: &str| {
        let args = [
            "--spp", "4", "--width", width, "--height", "60", "--seed", seed,
        ];
        mirror_truth(&scene, &args, &dir.join(format!("t{seed}-{width}")))
    };
    let (a, b, test) = (truth("1", "80"), truth("2", "80"), truth("3", "80"));
    let (json, csv) = (dir.join("c.json"), dir.join("c.csv"));
    let compare = |second: &std::path::Path, csv: &std::path::Path| {
        let mut command = oslf("compare");
        command
            .arg(&a)
            .arg(&test)
            .arg("--second-reference")
            .arg(second)
            .arg("--json")
            .arg(&json)
            .arg("--csv")
            .arg(csv)
            .arg("--side-by-side")
            .arg(dir.join("pair.png"));
        command
    };
    let stdout = run_ok(&mut compare(&b, &csv));
    assert!(stdout.contains("reference   the mean of "), "{stdout}");
    assert!(stdout.contains("corrected   RMSE L*a*b* "), "{stdout}");
    // The pair's right half is what the test was judged against, and says so.
    assert!(stdout.contains(", right the mean of "), "{stdout}");
    let j: serde_json::Value = serde_json::from_slice(&std::fs::read(&json).unwrap()).unwrap();
    let c = &j["corrected"];
    for ch in 0..3 {
        let raw = j["rmse_rgb"][ch].as_f64().unwrap();
        let corrected = c["rmse_rgb"][ch].as_f64().unwrap();
        let noise = c["reference_noise_rgb"][ch].as_f64().unwrap();
        assert!(raw > 0.0 && noise > 0.0, "{j}");
        let ratio = corrected / raw;
        assert!(
            (0.72..0.93).contains(&ratio),
            "channel {ch}: {ratio} of the raw: {j}"
        );
    }
    let l = c["rmse_lab"][0].as_f64().unwrap() / j["rmse_lab"][0].as_f64().unwrap();
    assert!((0.6..0.95).contains(&l), "L*: {l} of the raw: {j}");
    let text = std::fs::read_to_string(&csv).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    assert_eq!(lines.len(), 2, "{text}");
    assert!(
        lines[0].ends_with(",second_reference,rmse_l_corrected,rmse_a_corrected,rmse_b_corrected")
    );
    assert_eq!(
        lines[0].split(',').count(),
        lines[1].split(',').count(),
        "{text}"
    );
    // Refused: a CSV whose header is another's, and a second reference of another size.
    let old = dir.join("old.csv");
    std::fs::write(&old, "reference,test,pixels\n").unwrap();
    let out = compare(&b, &old).output().unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("old.csv: line 1 is not the header"), "{err}");
    assert_eq!(
        std::fs::read_to_string(&old).unwrap(),
        "reference,test,pixels\n"
    );
    let out = compare(&truth("2", "60"), &csv).output().unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("is 80x60 but") && err.contains("is 60x60"),
        "{err}"
    );
}

/// `oslf truth --cube-floor N` draws the mirror term as an N² cube map at each shaded point
/// reads it: a coarser cube strays further from the truth; a floor at the bake's largest
/// resolution is the truth within its noise; other modes and resolutions out of range are
/// refused, naming the flag.
#[test]
fn the_cube_floor_approaches_the_truth_as_its_cube_grows() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    let scene = lid_scene(dir);
    let args = ["--spp", "16", "--width", "40", "--height", "30"];
    let truth = read_exr(&mirror_truth(&scene, &args, &dir.join("t"))).1;
    let floor = |n: &str, lookup: &str| {
        let args = [
            &args[..],
            &["--cube-floor", n, "--cube-floor-lookup", lookup],
        ]
        .concat();
        read_exr(&mirror_truth(
            &scene,
            &args,
            &dir.join(format!("f{n}{lookup}")),
        ))
        .1
    };
    // Mean squared difference of the object's pixels' luminance from the truth's.
    let error = |image: &[[f32; 4]]| {
        let (mut sum, mut count) = (0.0f64, 0);
        for (a, b) in image.iter().zip(&truth) {
            assert!(a.iter().all(|c| c.is_finite()));
            assert_eq!(a[3], b[3], "the object mask is the truth's");
            if b[3] == 1.0 {
                let y = |p: &[f32; 4]| f64::from(0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2]);
                sum += (y(a) - y(b)).powi(2);
                count += 1;
            }
        }
        sum / f64::from(count)
    };
    let coarse = error(&floor("2", "bilinear"));
    let medium = error(&floor("8", "bilinear"));
    let fine = error(&floor("16384", "bilinear"));
    let nearest = error(&floor("2", "nearest"));
    assert!(coarse > 2.0 * medium, "2²: {coarse}, 8²: {medium}");
    assert!(medium > 2.0 * fine, "8²: {medium}, 16384²: {fine}");
    assert!(nearest > 2.0 * medium, "2² nearest: {nearest}");

    for (extra, says) in [
        (
            &["--cube-floor", "0"][..],
            "--cube-floor: cube floor resolution 0",
        ),
        (&["--cube-floor", "16385"][..], "16385 must be in 1..=16384"),
        (
            &["--cube-floor", "64", "-m", "recon,mirror"][..],
            "mirror term only",
        ),
        (&["--cube-floor-lookup", "nearest"][..], "--cube-floor"),
    ] {
        let out = oslf("truth")
            .arg(&scene)
            .args(["--width", "8", "--height", "6", "-q", "-o"])
            .arg(dir.join("bad"))
            .args(extra)
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(
            !out.status.success() && stderr.contains(says),
            "{extra:?}: {stderr}"
        );
    }
}
