//! A textured glTF object through the command line: examples/orb.toml (its roughness from a
//! metallicRoughnessTexture) baked small, its texture listed by `oslf store info`, rendered in
//! the pbr mode under `--strict`, and `oslf truth -m pbr` against it: the
//! light field reads the same roughness bands as the truth, beating one roughness everywhere.

use crate::common;

use common::{oslf, read_exr, run_ok};

#[test]
fn a_textured_object_bakes_lists_renders_and_matches_the_truth() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let examples = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("examples");
    for f in ["orb.glb", "room.glb"] {
        std::fs::copy(examples.join(f), d.join(f)).unwrap();
    }
    let mut scene = std::fs::read_to_string(examples.join("orb.toml")).unwrap();
    scene.push_str(
        "\n[presets.tiny]\nsample_count = 80\ncube_resolution = 16\nsample_map_resolution = 32\nsamples_per_texel = 4\n",
    );
    std::fs::write(d.join("orb.toml"), scene).unwrap();
    let store = d.join("orb.oslf");
    run_ok(
        oslf("bake")
            .arg(d.join("orb.toml"))
            .args([
                "--preset",
                "tiny",
                "--device",
                "cpu",
                "--preview",
                "none",
                "-q",
                "-o",
            ])
            .arg(&store),
    );
    let info = run_ok(oslf("store info").arg(&store));
    assert!(info.contains("textures: metallic-roughness 4x16"), "{info}");
    let (w, h) = ("96", "72");
    let render = |extra: &[&str], name: &str| {
        let out = d.join(name);
        run_ok(
            oslf("render")
                .arg(&store)
                .args(["--strict", "--width", w, "--height", h, "-M", "16"])
                .args(extra)
                .arg("-o")
                .arg(&out),
        );
        read_exr(&out).1
    };
    let textured = render(&[], "textured.exr");
    // Without the store's material: one roughness, the flag's, everywhere.
    let flat = render(&["--roughness", "0.6", "--metallic", "1"], "flat.exr");
    run_ok(
        oslf("truth")
            .arg(d.join("orb.toml"))
            .args(["--preset", "tiny", "-m", "pbr", "--spp", "256", "-q"])
            .args(["--width", w, "--height", h, "-o"])
            .arg(d.join("truth")),
    );
    let (_, truth) = read_exr(&d.join("truth-pbr.exr"));
    let rmse = |img: &[[f32; 4]]| {
        let (mut sum, mut n) = (0f64, 0usize);
        for (p, t) in img.iter().zip(&truth) {
            if t[3] > 0.5 && p[3] > 0.5 {
                sum += (0..3).map(|c| f64::from(p[c] - t[c]).powi(2)).sum::<f64>();
                n += 1;
            }
        }
        assert!(n > 500, "{n} object pixels");
        (sum / n as f64).sqrt()
    };
    let (with, without) = (rmse(&textured), rmse(&flat));
    println!("RMSE against the truth: textured {with:.4}, one roughness {without:.4}");
    assert!(
        with < 0.7 * without,
        "textured {with}, one roughness {without}"
    );
}
