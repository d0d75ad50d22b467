//! `mantissa_bits`: a quantized bake stores exactly the lossless bake's RGB9E5 texels with
//! fewer mantissa bits (same seed, so the same radiance before quantization).

use std::path::Path;

use oslf_bake::bake::{bake, BakeOptions};
use oslf_format::encoding::{decode_rgb9e5, quantize_rgb9e5};
use oslf_format::Store;
use oslf_scene::scene::Scene;

/// The teapot's lid under a sky (tests/fixtures/teapot-lid.toml).
const SCENE: &str = concat!(
    include_str!("../../tests/fixtures/teapot-lid.toml"),
    r#"
[bake]
sample_count = 12
cube_resolution = 8
sample_map_resolution = 4
samples_per_texel = 4
seed = 3
"#
);

/// Bakes the scene with `bits` (set on the parsed scene, so that the scene hash is the same).
fn bake_with(bits: u32, dir: &Path) -> Store {
    let text = SCENE.replace("seed = 3", &format!("seed = 3\nmantissa_bits = {bits}"));
    let parsed = Scene::from_str(&text, &dir.join("lid.toml"), None).unwrap();
    assert_eq!(parsed.bake.mantissa_bits, bits);
    let mut scene = Scene::from_str(SCENE, &dir.join("lid.toml"), None).unwrap();
    assert_eq!(scene.bake.mantissa_bits, 9);
    scene.bake.mantissa_bits = bits;
    let output = dir.join(format!("lid-{bits}.oslf"));
    let options = BakeOptions {
        output: output.clone(),
        resume: false,
        progress: None,
        cube_limit: None,
        refuse_empty_texels: false,
        device: None,
    };
    let report = bake(&scene, &options).unwrap();
    assert!(report.finished);
    let store = Store::open(&output).unwrap();
    store.verify().unwrap();
    store
}

#[test]
fn five_bits_is_the_nine_bit_bake_quantized() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    let full = bake_with(9, dir);
    let q = bake_with(5, dir);
    assert_eq!(full.meta().bake.mantissa_bits, 9);
    assert_eq!(q.meta().bake.mantissa_bits, 5);
    // Quantized stores are written with filter 3, lossless ones with filter 2.
    assert_eq!(q.header().filter, oslf_format::Filter::PredictPacked);
    assert_eq!(full.header().filter, oslf_format::Filter::PredictRows);
    let mut meta = q.meta().clone();
    meta.bake.mantissa_bits = 9;
    assert_eq!(&meta, full.meta(), "only mantissa_bits differs");
    assert_eq!(q.sample_points(), full.sample_points());
    assert_eq!(q.cube_count(), full.cube_count());

    let (mut a, mut b) = (
        vec![0u8; full.face_raw_size()],
        vec![0u8; q.face_raw_size()],
    );
    let (mut changed, mut texels, mut worst) = (0u64, 0u64, 0f64);
    for cube in 0..full.cube_count() {
        for face in 0..6 {
            full.read_face_raw(cube, face, &mut a).unwrap();
            q.read_face_raw(cube, face, &mut b).unwrap();
            // The RGB9E5 texels; the distance plane after them is not quantized.
            let texel_bytes = (full.cube_resolution() as usize).pow(2) * 4;
            assert_eq!(
                a[texel_bytes..],
                b[texel_bytes..],
                "cube {cube} face {face}"
            );
            for (ta, tb) in a[..texel_bytes]
                .chunks_exact(4)
                .zip(b[..texel_bytes].chunks_exact(4))
            {
                let wa = u32::from_le_bytes(ta.try_into().unwrap());
                let wb = u32::from_le_bytes(tb.try_into().unwrap());
                assert_eq!(wb, quantize_rgb9e5(wa, 5), "cube {cube} face {face}");
                // Within 2^-5 of the exponent's scale, per channel.
                let scale = 2f64.powi((wa >> 27) as i32 - 15);
                for (x, y) in decode_rgb9e5(wa).iter().zip(decode_rgb9e5(wb)) {
                    let err = (f64::from(*x) - f64::from(y)).abs() / scale;
                    assert!(err < 1.0 / 32.0, "error {err}");
                    worst = worst.max(err);
                }
                changed += u64::from(wa != wb);
                texels += 1;
            }
        }
    }
    // Lit cube maps: most texels lose bits, and the store shrinks.
    assert!(changed * 2 > texels, "{changed} of {texels} texels changed");
    assert!(worst > 1.0 / 128.0, "worst error {worst}");
    assert!(
        q.cube_bytes() < full.cube_bytes(),
        "{} vs {} bytes",
        q.cube_bytes(),
        full.cube_bytes()
    );
    println!(
        "9 bits: {} B, 5 bits: {} B of cube data; {changed} of {texels} texels changed; worst error {worst:.4} of the exponent's scale",
        full.cube_bytes(),
        q.cube_bytes()
    );
}
