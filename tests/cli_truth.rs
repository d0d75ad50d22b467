//! `oslf truth --background scene` and `oslf compare --side-by-side`: the scene behind the
//! object changes no object pixel and no metric, and the pair is written as one PNG.

use crate::common;

use common::{oslf, read_exr};

/// The lid scene of tests/common on a box, so the background behind it holds geometry too.
fn scene_text() -> String {
    format!(
        "{}\n[[box]]\nsize = [8.0, 6.0, 0.2]\ntransform = {{ translate = [0.0, 0.0, -0.1] }}\n\
         material = {{ color = [0.5, 0.4, 0.3] }}\n",
        common::LID_SCENE
    )
}

#[test]
fn the_scene_behind_the_object_changes_no_object_pixel_and_pairs_side_by_side() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    let scene = dir.join("lid.toml");
    std::fs::write(&scene, scene_text()).unwrap();
    let truth = |background: &str, prefix: &str| {
        let out = oslf("truth")
            .arg(&scene)
            .args([
                "-m", "mirror", "--spp", "2", "--width", "40", "--height", "30", "-q",
            ])
            .args(["--background", background, "-o"])
            .arg(dir.join(prefix))
            .output()
            .unwrap();
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        read_exr(&dir.join(format!("{prefix}-mirror.exr"))).1
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
    let scene = dir.join("lid.toml");
    std::fs::write(&scene, scene_text()).unwrap();
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
