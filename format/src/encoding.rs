//! Texel encodings: RGB9E5, RGBA16F, RGBA32F and BC6H, and their slice and face encoders and
//! decoders.
//!
//! All encodings store linear RGB radiance, little-endian:
//!
//! * [`Encoding::Rgb9e5`]: one `u32` per texel, the GL_EXT_texture_shared_exponent /
//!   Vulkan `E5B9G9R9_UFLOAT_PACK32` / wgpu `Rgb9e5Ufloat` layout: red mantissa in bits 0..=8,
//!   green in 9..=17, blue in 18..=26, the shared exponent (bias 15) in 27..=31; value =
//!   `mantissa * 2^(exponent - 15 - 9)`. Largest finite value [`MAX_RGB9E5`] = 65408.
//! * [`Encoding::Rgba16f`]: four IEEE binary16 values R, G, B, A with A = 1. Largest finite
//!   value [`MAX_F16`] = 65504.
//! * [`Encoding::Rgba32f`]: four IEEE binary32 values R, G, B, A with A = 1. Exact.
//! * [`Encoding::Bc6h`]: unsigned BC6H blocks (`BC6H_UF16`), 16 bytes per 4×4 texels; a face
//!   is encoded whole (padded by edge replication to a multiple of 4), see [`crate::bc6h`].
//!   Largest value [`MAX_F16`] = 65504.
//!
//! Radiance must be finite and non-negative. Values above an encoding's largest finite value
//! are clamped to it (never encoded as infinity) and counted.

pub use crate::encoding_kind::{Encoding, MAX_F16, MAX_RGB9E5};
use crate::Error;
use half::f16;

const RGB9E5_MANTISSA_BITS: i32 = 9;
const RGB9E5_EXP_BIAS: i32 = 15;
const RGB9E5_MAX_EXP: i32 = 31;

impl std::str::FromStr for Encoding {
    type Err = Error;

    fn from_str(s: &str) -> Result<Self, Error> {
        match s.trim().to_ascii_lowercase().as_str() {
            "rgb9e5" => Ok(Encoding::Rgb9e5),
            "rgba16f" => Ok(Encoding::Rgba16f),
            "rgba32f" => Ok(Encoding::Rgba32f),
            "bc6h" => Ok(Encoding::Bc6h),
            _ => Err(Error::UnknownEncoding(s.to_string())),
        }
    }
}

/// `floor(log2(v))` for a positive finite `v`, exact (read from the float's exponent bits).
fn floor_log2(v: f32) -> i32 {
    let bits = v.to_bits();
    let exp = ((bits >> 23) & 0xff) as i32;
    if exp == 0 {
        // Subnormal: far below anything RGB9E5 can represent.
        -127
    } else {
        exp - 127
    }
}

/// Encodes linear RGB as RGB9E5 per GL_EXT_texture_shared_exponent (round to nearest).
///
/// Channels are clamped to `[0, MAX_RGB9E5]`; NaN becomes 0. Callers that must reject bad
/// values (the store does) check them first.
pub fn encode_rgb9e5(rgb: [f32; 3]) -> u32 {
    let clamp = |v: f32| {
        if v > 0.0 {
            v.min(MAX_RGB9E5)
        } else {
            0.0 // also NaN
        }
    };
    let [r, g, b] = rgb.map(clamp);
    let max = r.max(g).max(b);
    if max <= 0.0 {
        return 0;
    }
    let mut exp = floor_log2(max).max(-RGB9E5_EXP_BIAS - 1) + 1 + RGB9E5_EXP_BIAS;
    let scale = |e: i32| 2f64.powi(e - RGB9E5_EXP_BIAS - RGB9E5_MANTISSA_BITS);
    let max_m = (f64::from(max) / scale(exp) + 0.5).floor();
    if max_m >= f64::from(1u32 << RGB9E5_MANTISSA_BITS) {
        exp += 1;
    }
    let exp = exp.clamp(0, RGB9E5_MAX_EXP);
    let s = scale(exp);
    let m = |v: f32| ((f64::from(v) / s + 0.5).floor() as u32).min(511);
    m(r) | (m(g) << 9) | (m(b) << 18) | ((exp as u32) << 27)
}

/// Decodes an RGB9E5 texel.
pub fn decode_rgb9e5(v: u32) -> [f32; 3] {
    let exp = (v >> 27) as i32;
    let s = 2f32.powi(exp - RGB9E5_EXP_BIAS - RGB9E5_MANTISSA_BITS);
    [
        (v & 0x1ff) as f32 * s,
        ((v >> 9) & 0x1ff) as f32 * s,
        ((v >> 18) & 0x1ff) as f32 * s,
    ]
}

/// Lossless RGB9E5: all 9 mantissa bits kept ([`quantize_rgb9e5`] is then the identity).
pub const RGB9E5_FULL_MANTISSA_BITS: u32 = 9;

/// Keeps `bits` (1..=9) of an RGB9E5 texel's 9 mantissa bits: each channel's mantissa `m` is
/// rounded to the nearest multiple of `step = 2^(9 − bits)` (ties up), and a result above 511
/// is lowered to the largest multiple `512 − step`; the shared exponent is unchanged. So the
/// value never leaves the original exponent's range, 0 stays 0, `bits = 9` is the identity,
/// and quantizing twice equals quantizing once.
///
/// Error bound per channel: `|m' − m| ≤ step / 2` (`≤ step − 1` for the clamped top values),
/// so below `2^−bits · 2^(e − 15)`, i.e. `2^−bits` of the exponent's scale. The largest
/// channel of a texel above the smallest exponent has `m ≥ 256`, so its relative error is
/// below `2^(1 − bits)`.
///
/// `bits` outside 1..=9 is taken as the nearest of them.
pub fn quantize_rgb9e5(word: u32, bits: u32) -> u32 {
    let bits = bits.clamp(1, RGB9E5_FULL_MANTISSA_BITS);
    if bits == RGB9E5_FULL_MANTISSA_BITS {
        return word;
    }
    let shift = RGB9E5_FULL_MANTISSA_BITS - bits;
    let step = 1u32 << shift;
    let top = 512 - step;
    let q = |m: u32| (((m + step / 2) >> shift) << shift).min(top);
    let r = q(word & 0x1ff);
    let g = q((word >> 9) & 0x1ff);
    let b = q((word >> 18) & 0x1ff);
    r | (g << 9) | (b << 18) | (word & (0x1f << 27))
}

/// [`quantize_rgb9e5`] applied in place to every texel of an encoded RGB9E5 byte slice
/// (little-endian `u32` per texel; a trailing partial texel is left alone).
pub fn quantize_rgb9e5_bytes(bytes: &mut [u8], bits: u32) {
    if bits >= RGB9E5_FULL_MANTISSA_BITS {
        return;
    }
    for t in bytes.chunks_exact_mut(4) {
        let w = u32::from_le_bytes([t[0], t[1], t[2], t[3]]);
        t.copy_from_slice(&quantize_rgb9e5(w, bits).to_le_bytes());
    }
}

/// Encodes linear RGB as RGBA16F bit patterns (A = 1); channels clamped to `[0, MAX_F16]`.
pub fn encode_rgba16f(rgb: [f32; 3]) -> [u16; 4] {
    let c = |v: f32| {
        let v = if v > 0.0 { v.min(MAX_F16) } else { 0.0 };
        f16::from_f32(v).to_bits()
    };
    [c(rgb[0]), c(rgb[1]), c(rgb[2]), f16::ONE.to_bits()]
}

/// Decodes an RGBA16F texel's RGB.
pub fn decode_rgba16f(v: [u16; 4]) -> [f32; 3] {
    [
        f16::from_bits(v[0]).to_f32(),
        f16::from_bits(v[1]).to_f32(),
        f16::from_bits(v[2]).to_f32(),
    ]
}

fn is_valid(rgb: [f32; 3]) -> bool {
    rgb.iter().all(|c| c.is_finite() && *c >= 0.0)
}

/// Encodes `src` into `out` (exactly `src.len() * encoding.bytes_per_texel()` bytes).
///
/// Returns how many texels had a channel above [`Encoding::max_value`] and were clamped.
/// Fails with [`Error::InvalidTexel`] (naming the first bad texel) on NaN, infinite or
/// negative radiance, with [`Error::BufferSize`] on a wrong-sized `out`, and with
/// [`Error::WholeFaceEncoding`] for BC6H, which encodes whole faces ([`encode_face_texels`]).
pub fn encode_texels(encoding: Encoding, src: &[[f32; 3]], out: &mut [u8]) -> Result<u64, Error> {
    if encoding.is_block_compressed() {
        return Err(Error::WholeFaceEncoding { encoding });
    }
    let bpt = encoding.bytes_per_texel();
    let expected = src.len().checked_mul(bpt);
    if expected != Some(out.len()) {
        return Err(Error::BufferSize {
            what: "encoded texel output",
            expected: expected.unwrap_or(usize::MAX) as u64,
            actual: out.len() as u64,
        });
    }
    let max = encoding.max_value();
    let mut clamped = 0u64;
    for (index, (rgb, dst)) in src.iter().zip(out.chunks_exact_mut(bpt)).enumerate() {
        let rgb = *rgb;
        if !is_valid(rgb) {
            return Err(Error::InvalidTexel { index, value: rgb });
        }
        if rgb.iter().any(|c| *c > max) {
            clamped += 1;
        }
        match encoding {
            Encoding::Rgb9e5 => dst.copy_from_slice(&encode_rgb9e5(rgb).to_le_bytes()),
            Encoding::Rgba16f => {
                for (d, h) in dst.chunks_exact_mut(2).zip(encode_rgba16f(rgb)) {
                    d.copy_from_slice(&h.to_le_bytes());
                }
            }
            Encoding::Rgba32f => {
                for (d, f) in dst.chunks_exact_mut(4).zip([rgb[0], rgb[1], rgb[2], 1.0]) {
                    d.copy_from_slice(&f.to_le_bytes());
                }
            }
            Encoding::Bc6h => return Err(Error::WholeFaceEncoding { encoding }),
        }
    }
    Ok(clamped)
}

/// Encodes one face (`src`: `resolution²` texels, row-major) into `out` (exactly
/// [`Encoding::face_bytes`] bytes), in any encoding: BC6H through [`crate::bc6h::encode_face`],
/// the others texel by texel as [`encode_texels`]. Returns the clamped texel count; the errors
/// are [`encode_texels`]'s.
pub fn encode_face_texels(
    encoding: Encoding,
    resolution: u32,
    src: &[[f32; 3]],
    out: &mut [u8],
) -> Result<u64, Error> {
    let texels = (resolution as usize).checked_mul(resolution as usize);
    if texels != Some(src.len()) {
        return Err(Error::BufferSize {
            what: "face texels",
            expected: texels.unwrap_or(usize::MAX) as u64,
            actual: src.len() as u64,
        });
    }
    match encoding {
        Encoding::Bc6h => crate::bc6h::encode_face(src, resolution, out),
        _ => encode_texels(encoding, src, out),
    }
}

/// Decodes one face (`src`: exactly [`Encoding::face_bytes`] bytes) into `out`
/// (`resolution²` texels, row-major), in any encoding. `cube` and `face` only name the face in
/// errors: a BC6H block with a reserved mode is an [`Error::ReservedBc6hMode`]; the other
/// encodings never fail on content.
pub fn decode_face_texels(
    encoding: Encoding,
    resolution: u32,
    src: &[u8],
    out: &mut [[f32; 3]],
    cube: u32,
    face: usize,
) -> Result<(), Error> {
    let texels = (resolution as usize).checked_mul(resolution as usize);
    if texels != Some(out.len()) {
        return Err(Error::BufferSize {
            what: "decoded face texels",
            expected: texels.unwrap_or(usize::MAX) as u64,
            actual: out.len() as u64,
        });
    }
    match encoding {
        Encoding::Bc6h => crate::bc6h::decode_face(src, resolution, out, cube, face),
        _ => decode_texels(encoding, src, out),
    }
}

/// Decodes `src` (exactly `out.len() * encoding.bytes_per_texel()` bytes) into `out`.
///
/// Decoding never fails on content: every bit pattern decodes to some value (RGBA16F and
/// RGBA32F patterns that are NaN or infinite decode as such; the store's writer never
/// produces them). BC6H is an [`Error::WholeFaceEncoding`]: use [`decode_face_texels`].
pub fn decode_texels(encoding: Encoding, src: &[u8], out: &mut [[f32; 3]]) -> Result<(), Error> {
    if encoding.is_block_compressed() {
        return Err(Error::WholeFaceEncoding { encoding });
    }
    let bpt = encoding.bytes_per_texel();
    let expected = out.len().checked_mul(bpt);
    if expected != Some(src.len()) {
        return Err(Error::BufferSize {
            what: "encoded texel input",
            expected: expected.unwrap_or(usize::MAX) as u64,
            actual: src.len() as u64,
        });
    }
    for (s, dst) in src.chunks_exact(bpt).zip(out.iter_mut()) {
        *dst = match encoding {
            Encoding::Rgb9e5 => decode_rgb9e5(u32::from_le_bytes([s[0], s[1], s[2], s[3]])),
            Encoding::Rgba16f => {
                let h = |i: usize| u16::from_le_bytes([s[2 * i], s[2 * i + 1]]);
                decode_rgba16f([h(0), h(1), h(2), h(3)])
            }
            Encoding::Rgba32f => {
                let f = |i: usize| {
                    f32::from_le_bytes([s[4 * i], s[4 * i + 1], s[4 * i + 2], s[4 * i + 3]])
                };
                [f(0), f(1), f(2)]
            }
            Encoding::Bc6h => return Err(Error::WholeFaceEncoding { encoding }),
        };
    }
    Ok(())
}

/// Encodes a distance plane (`f32` little-endian per texel) into `out` (`4 * src.len()` bytes).
///
/// Values are copied as they are; [`crate::encode_cube`] rejects NaN, infinite and negative
/// distances (escaped rays are `f32::MAX`) before calling this.
pub fn encode_distances(src: &[f32], out: &mut [u8]) -> Result<(), Error> {
    let expected = src.len().checked_mul(4);
    if expected != Some(out.len()) {
        return Err(Error::BufferSize {
            what: "encoded distance output",
            expected: expected.unwrap_or(usize::MAX) as u64,
            actual: out.len() as u64,
        });
    }
    for (d, dst) in src.iter().zip(out.chunks_exact_mut(4)) {
        dst.copy_from_slice(&d.to_le_bytes());
    }
    Ok(())
}

/// Decodes a distance plane (`4 * out.len()` bytes of little-endian `f32`).
pub fn decode_distances(src: &[u8], out: &mut [f32]) -> Result<(), Error> {
    let expected = out.len().checked_mul(4);
    if expected != Some(src.len()) {
        return Err(Error::BufferSize {
            what: "encoded distance input",
            expected: expected.unwrap_or(usize::MAX) as u64,
            actual: src.len() as u64,
        });
    }
    for (s, dst) in src.chunks_exact(4).zip(out.iter_mut()) {
        *dst = f32::from_le_bytes([s[0], s[1], s[2], s[3]]);
    }
    Ok(())
}

/// Typical compressed bytes per cube-map texel (colour only), by encoding and `mantissa_bits`,
/// for estimates (the bake's preflight, the store budget of the settings a scene chooses):
/// the mean of the 32² and 128² gazebo bakes of docs/measurements.md, "Store sizes"
/// (lossless table: RGB9E5 3.443 and 3.121 of 4 raw bytes; RGBA16F 4.658 and 3.985 of
/// 8; RGBA32F 9.207 of 16 — the 32² column, the only one baked from unquantised radiance;
/// quantized RGB9E5 table for `mantissa_bits` < 9; BC6H 0.973 and 0.920 of 1 raw byte, the
/// quick preset's 32² cubes and a 128² bake of the same scene converted from RGBA32F, filter
/// none: `oslf_format::bc6h`). A cube map of a simpler scene compresses
/// better; one of noisier radiance (fewer samples per texel) a little worse.
pub fn compressed_texel_bytes(encoding: Encoding, mantissa_bits: u32) -> f64 {
    match encoding {
        Encoding::Rgb9e5 => {
            // k = 1..=9 kept mantissa bits.
            const TABLE: [f64; 9] = [0.53, 0.93, 1.23, 1.56, 1.99, 2.32, 2.72, 3.19, 3.28];
            TABLE[(mantissa_bits.clamp(1, 9) - 1) as usize]
        }
        Encoding::Rgba16f => 4.32,
        Encoding::Rgba32f => 9.21,
        Encoding::Bc6h => 0.95,
    }
}

/// Compressed bytes per texel of the distance plane: the store holds each distance on
/// the distance lattice as a 16-bit code in two predicted byte planes; measured 0.450 (gazebo)
/// and 0.427 (meshes) at 32² (docs/measurements.md, "Compact distances"; the f32 planes of
/// version 5 took 2.35).
pub const DISTANCE_COMPRESSED_BYTES: f64 = 0.45;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rgb9e5_known_values() {
        assert_eq!(encode_rgb9e5([0.0; 3]), 0);
        assert_eq!(
            decode_rgb9e5(encode_rgb9e5([1.0, 1.0, 1.0])),
            [1.0, 1.0, 1.0]
        );
        assert_eq!(
            decode_rgb9e5(encode_rgb9e5([MAX_RGB9E5; 3])),
            [MAX_RGB9E5; 3]
        );
        assert_eq!(decode_rgb9e5(encode_rgb9e5([1e9, 0.0, 0.0]))[0], MAX_RGB9E5);
        // 1.0 = 256 * 2^(16 - 15 - 9): exponent 16, red mantissa 256.
        assert_eq!(encode_rgb9e5([1.0, 0.0, 0.0]), 256 | (16 << 27));
        assert_eq!(decode_rgb9e5(u32::MAX), [MAX_RGB9E5; 3]);
    }

    /// Decoded error of one channel against the exponent's scale `2^(e − 15)`.
    fn scaled_errors(word: u32, bits: u32) -> [f64; 3] {
        let q = quantize_rgb9e5(word, bits);
        let scale = 2f64.powi((word >> 27) as i32 - 15);
        let a = decode_rgb9e5(word);
        let b = decode_rgb9e5(q);
        std::array::from_fn(|c| (f64::from(a[c]) - f64::from(b[c])).abs() / scale)
    }

    #[test]
    fn quantize_bounds_identity_and_idempotence() {
        // Log-spaced HDR values 1e-20..6.5e4 in several colour ratios, plus 0 and the maximum.
        let mut words = vec![0u32, encode_rgb9e5([MAX_RGB9E5; 3]), u32::MAX, 0x1ff];
        let ratios = [
            [1.0, 1.0, 1.0],
            [1.0, 0.5, 0.25],
            [1.0, 1e-3, 0.0],
            [0.2, 1.0, 0.7],
        ];
        for i in 0..=4000 {
            let v = 10f64.powf(-20.0 + 24.8129 * f64::from(i) / 4000.0) as f32;
            for r in ratios {
                words.push(encode_rgb9e5([v * r[0], v * r[1], v * r[2]]));
            }
        }
        // Every mantissa value at one exponent.
        for m in 0..512u32 {
            words.push(m | (m << 9) | ((511 - m) << 18) | (20 << 27));
        }
        for bits in 1..=9 {
            let bound = 2f64.powi(-(bits as i32));
            let mut worst = 0f64;
            for &w in &words {
                let q = quantize_rgb9e5(w, bits);
                assert_eq!(q >> 27, w >> 27, "exponent changed: {w:#x} bits {bits}");
                assert_eq!(quantize_rgb9e5(q, bits), q, "not idempotent: {w:#x}");
                let step = 1u32 << (9 - bits);
                for c in 0..3 {
                    let m = (q >> (9 * c)) & 0x1ff;
                    assert_eq!(m % step, 0, "mantissa {m} not a multiple of {step}");
                    if (w >> (9 * c)) & 0x1ff == 0 {
                        assert_eq!(m, 0, "0 must stay 0");
                    }
                }
                let e = scaled_errors(w, bits);
                for err in e {
                    assert!(err < bound, "{w:#x} bits {bits}: error {err} ≥ {bound}");
                    worst = worst.max(err);
                }
                let a = decode_rgb9e5(w);
                let b = decode_rgb9e5(q);
                for c in 0..3 {
                    assert!(b[c] <= MAX_RGB9E5 && b[c].is_finite());
                    // Rounding to nearest: at most half a step, except where clamped at 511.
                    if a[c] <= b[c] || (w >> (9 * c)) & 0x1ff < 512 - step / 2 {
                        assert!(e[c] <= bound / 2.0 + 1e-12, "{w:#x} bits {bits} c {c}");
                    }
                }
            }
            if bits < 9 {
                assert!(
                    worst > bound / 4.0,
                    "bits {bits}: the bound is not approached"
                );
            } else {
                assert_eq!(worst, 0.0);
            }
        }
        for &w in &words {
            assert_eq!(quantize_rgb9e5(w, 9), w);
        }
        assert_eq!(quantize_rgb9e5(0, 1), 0);
        // 511 with 1 bit: rounds to 512, lowered to 256 (the exponent is kept).
        assert_eq!(quantize_rgb9e5(511 | (3 << 27), 1), 256 | (3 << 27));
        assert_eq!(quantize_rgb9e5(383 | (3 << 27), 2), 384 | (3 << 27));
        assert_eq!(quantize_rgb9e5(127 | (3 << 27), 1), 3 << 27);
        let mut bytes: Vec<u8> = words.iter().flat_map(|w| w.to_le_bytes()).collect();
        quantize_rgb9e5_bytes(&mut bytes, 5);
        for (w, t) in words.iter().zip(bytes.chunks_exact(4)) {
            assert_eq!(
                u32::from_le_bytes([t[0], t[1], t[2], t[3]]),
                quantize_rgb9e5(*w, 5)
            );
        }
    }

    #[test]
    fn f16_clamps_never_inf() {
        let d = decode_rgba16f(encode_rgba16f([1e30, 65519.0, 7.0]));
        assert_eq!(d, [MAX_F16, MAX_F16, 7.0]);
    }

    #[test]
    fn encode_texels_counts_and_rejects() {
        let src = [[1.0, 2.0, 3.0], [7e4, 0.0, 0.0]];
        for enc in Encoding::PER_TEXEL {
            let mut out = vec![0u8; src.len() * enc.bytes_per_texel()];
            let clamped = encode_texels(enc, &src, &mut out).unwrap();
            assert_eq!(clamped, if enc == Encoding::Rgba32f { 0 } else { 1 });
            let mut back = [[0.0; 3]; 2];
            decode_texels(enc, &out, &mut back).unwrap();
            assert_eq!(back[0], [1.0, 2.0, 3.0]);
            let bad = [[1.0, f32::NAN, 0.0]];
            let mut out = vec![0u8; enc.bytes_per_texel()];
            assert!(matches!(
                encode_texels(enc, &bad, &mut out),
                Err(Error::InvalidTexel { index: 0, .. })
            ));
            let neg = [[1.0, 0.0, -1.0]];
            assert!(encode_texels(enc, &neg, &mut out).is_err());
        }
    }

    #[test]
    fn names_round_trip() {
        for enc in Encoding::ALL {
            assert_eq!(enc.name().parse::<Encoding>().unwrap(), enc);
            assert_eq!(Encoding::from_tag(enc.tag()), Some(enc));
        }
        assert!("rgb10".parse::<Encoding>().is_err());
        assert_eq!("BC6H".parse::<Encoding>().unwrap(), Encoding::Bc6h);
        assert_eq!(Encoding::Bc6h.tag(), 3);
        assert_eq!(Encoding::Bc6h.face_bytes(32), Some(1024));
        assert_eq!(Encoding::Bc6h.face_bytes(5), Some(4 * 16));
        assert_eq!(Encoding::Rgb9e5.face_bytes(5), Some(100));
        let mut out = [0u8; 16];
        assert!(matches!(
            encode_texels(Encoding::Bc6h, &[[0.0; 3]; 16], &mut out),
            Err(Error::WholeFaceEncoding { .. })
        ));
        assert_eq!(Encoding::default(), Encoding::Rgb9e5);
    }
}
