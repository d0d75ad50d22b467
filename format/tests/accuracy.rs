//! Encoding accuracy over the HDR range 1e-4..6e4 (log-spaced), including colour ratios.
//! The figures printed by `cargo test -p oslf-format --test integration accuracy:: -- --nocapture` are the
//! ones recorded in the crate docs.

use oslf_format::encoding::*;

const STEPS: usize = 20_000;

fn values() -> impl Iterator<Item = f32> {
    (0..=STEPS).map(|i| 10f64.powf(-4.0 + (4.0 + 6e4f64.log10()) * i as f64 / STEPS as f64) as f32)
}

const RATIOS: [[f32; 3]; 5] = [
    [1.0, 1.0, 1.0],
    [1.0, 0.5, 0.25],
    [1.0, 1e-3, 0.0],
    [0.2, 1.0, 0.7],
    [0.01, 0.1, 1.0],
];

#[derive(Default, Debug)]
struct Stats {
    /// Largest error of any channel relative to the texel's largest channel.
    max_rel_to_max: f64,
    /// Largest relative error of the texel's largest channel.
    max_rel_max_channel: f64,
    /// Mean relative error of the largest channel.
    sum_rel_max_channel: f64,
    /// Largest per-channel relative error over channels >= floor.
    max_rel_channel: f64,
    sum_rel_channel: f64,
    n_channel: u64,
    n: u64,
}

fn measure(codec: impl Fn([f32; 3]) -> [f32; 3], floor: f32) -> Stats {
    let mut s = Stats::default();
    for v in values() {
        for r in RATIOS {
            let rgb = [v * r[0], v * r[1], v * r[2]];
            let back = codec(rgb);
            let max = rgb.iter().fold(0f32, |a, b| a.max(*b)) as f64;
            let mut max_ch_err = 0.0;
            for c in 0..3 {
                let (w, g) = (rgb[c] as f64, back[c] as f64);
                let err = (w - g).abs();
                s.max_rel_to_max = s.max_rel_to_max.max(err / max);
                if rgb[c] as f64 == max {
                    max_ch_err = err / max;
                }
                if rgb[c] >= floor {
                    let rel = err / w;
                    s.max_rel_channel = s.max_rel_channel.max(rel);
                    s.sum_rel_channel += rel;
                    s.n_channel += 1;
                }
            }
            s.max_rel_max_channel = s.max_rel_max_channel.max(max_ch_err);
            s.sum_rel_max_channel += max_ch_err;
            s.n += 1;
        }
    }
    s
}

#[test]
fn rgb9e5_accuracy() {
    let s = measure(|c| decode_rgb9e5(encode_rgb9e5(c)), 1e-4);
    let mean_max = s.sum_rel_max_channel / s.n as f64;
    let mean_ch = s.sum_rel_channel / s.n_channel as f64;
    println!(
        "rgb9e5: largest channel: max rel {:.3e}, mean rel {:.3e}; any channel vs largest: max {:.3e}; per channel (>= 1e-4): max rel {:.3e}, mean rel {:.3e} ({} samples)",
        s.max_rel_max_channel, mean_max, s.max_rel_to_max, s.max_rel_channel, mean_ch, s.n
    );
    // Documented bounds: half a step of a 9-bit mantissa whose top bit is set.
    assert!(s.max_rel_max_channel <= 1.0 / 512.0);
    assert!(s.max_rel_to_max <= 1.0 / 512.0);
    assert!(mean_max <= 8e-4);
}

#[test]
fn rgba16f_accuracy() {
    let s = measure(|c| decode_rgba16f(encode_rgba16f(c)), 6.104e-5);
    let mean_max = s.sum_rel_max_channel / s.n as f64;
    let mean_ch = s.sum_rel_channel / s.n_channel as f64;
    println!(
        "rgba16f: largest channel: max rel {:.3e}, mean rel {:.3e}; any channel vs largest: max {:.3e}; per channel (>= 6.1e-5, f16 normal): max rel {:.3e}, mean rel {:.3e} ({} samples)",
        s.max_rel_max_channel, mean_max, s.max_rel_to_max, s.max_rel_channel, mean_ch, s.n
    );
    // Documented bound: half an ulp of an 11-bit significand.
    assert!(s.max_rel_channel <= 1.0 / 2048.0);
    assert!(s.max_rel_max_channel <= 1.0 / 2048.0);
    assert!(mean_ch <= 2e-4);
}

#[test]
fn clamping_is_counted_and_finite() {
    for enc in [Encoding::Rgb9e5, Encoding::Rgba16f] {
        let src = [[1e5, 0.0, 0.0], [6e4, 6e4, 6e4], [f32::MAX, 1.0, 2.0]];
        let mut out = vec![0u8; src.len() * enc.bytes_per_texel()];
        let clamped = encode_texels(enc, &src, &mut out).unwrap();
        let mut back = [[0.0; 3]; 3];
        decode_texels(enc, &out, &mut back).unwrap();
        assert_eq!(clamped, 2, "{enc}");
        assert_eq!(back[0][0], enc.max_value());
        assert!(back.iter().flatten().all(|v| v.is_finite()));
    }
}
