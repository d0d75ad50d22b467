//! Reversible, lossless filters applied to a face's raw bytes before zstd and undone after
//! decompression (the byte layout and the exact predictors are in `docs/format.md`, "Face
//! filters").
//!
//! The filters never fail on content: [`unfilter_face`] maps any input of the right size to
//! some output (wrapping arithmetic throughout), and [`filter_face`] followed by
//! [`unfilter_face`] is the identity on every input, canonical or not.

mod distance;
mod ints;
mod predict;
mod residual;
mod rows;

use crate::distance::DistancePlane;
use crate::encoding::Encoding;
use crate::Error;
use distance::{lattice_forward, lattice_inverse};
use ints::{ints_forward, ints_inverse};
use predict::{rgb9e5_forward, rgb9e5_inverse};
pub use rows::packed_planes;
use rows::{packed_forward, packed_inverse, rows_forward, rows_inverse, Lattice, Packed, Planes9};

/// How a face's raw bytes are transformed before compression (header bytes 176..180).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Default)]
pub enum Filter {
    /// Id 0: the raw bytes are compressed as they are.
    None,
    /// Id 1: planes of predicted, zig-zag encoded residuals; RGB9E5 texels predicted from
    /// their left and upper neighbours.
    Predict,
    /// Id 2: as [`Filter::Predict`], but RGB9E5 texels are predicted from the row above only
    /// (binary32 arithmetic), so a row decodes without a texel-to-texel dependency. What
    /// writers use for lossless stores ([`Filter::for_store`]).
    #[default]
    PredictRows,
    /// Id 3: filter 2's predictions, but each RGB9E5 texel's exponent and three residuals
    /// (in units of the store's mantissa lattice) packed into `⌈(5 + 3k) / 8⌉` byte planes
    /// for `k` mantissa bits: fewer bytes for zstd to decode. What writers use for RGB9E5
    /// stores that keep at most 6 mantissa bits ([`Filter::for_store`]).
    PredictPacked,
}

impl Filter {
    /// All filters, in id order.
    pub const ALL: [Filter; 4] = [
        Filter::None,
        Filter::Predict,
        Filter::PredictRows,
        Filter::PredictPacked,
    ];

    /// The on-disk id: 0, 1 or 2.
    pub fn id(self) -> u32 {
        match self {
            Filter::None => 0,
            Filter::Predict => 1,
            Filter::PredictRows => 2,
            Filter::PredictPacked => 3,
        }
    }

    /// The filter with on-disk id `id`.
    pub fn from_id(id: u32) -> Option<Self> {
        match id {
            0 => Some(Filter::None),
            1 => Some(Filter::Predict),
            2 => Some(Filter::PredictRows),
            3 => Some(Filter::PredictPacked),
            _ => None,
        }
    }

    /// The filter writers use for a store of `encoding` keeping `mantissa_bits` RGB9E5 mantissa
    /// bits: [`Filter::PredictPacked`] for RGB9E5 with at most 6 bits, where it is smaller
    /// and faster to read than filter 2, [`Filter::PredictRows`] otherwise (with 7 to 9 bits
    /// filter 3's code splits residuals across bytes and compresses worse: docs/measurements.md,
    /// "Quantized RGB9E5"). BC6H stores get [`Filter::PredictRows`] too: filters 1 to 3 leave
    /// BC6H blocks as they are (regrouping their bytes into planes compressed worse: 1.004
    /// against 0.973 bytes per texel on the example scene; `docs/format.md`, "BC6H") and predict the
    /// distance plane.
    pub fn for_store(encoding: Encoding, mantissa_bits: u32) -> Self {
        if encoding == Encoding::Rgb9e5 && mantissa_bits <= 6 {
            Filter::PredictPacked
        } else {
            Filter::PredictRows
        }
    }

    /// `"none"`, `"predict"`, `"predict-rows"` or `"predict-packed"`.
    pub fn name(self) -> &'static str {
        match self {
            Filter::None => "none",
            Filter::Predict => "predict",
            Filter::PredictRows => "predict-rows",
            Filter::PredictPacked => "predict-packed",
        }
    }
}

impl std::fmt::Display for Filter {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// Size in bytes of one face after `filter`, i.e. what its zstd frame decompresses to: the
/// raw face size ([`crate::Store::face_raw_size`]), except filter 3 on RGB9E5, whose texel
/// part is `n² × ⌈(5 + 3k) / 8⌉` bytes for `k = mantissa_bits`, and filters 1 to 3 on a
/// distance plane on the distance lattice ([`DistancePlane::Lattice`]), which takes `n² × 2`
/// bytes instead of `n² × 4`. `distance` is the face's distance plane. `None` if the size
/// overflows `usize`.
pub fn filtered_face_size(
    filter: Filter,
    encoding: Encoding,
    resolution: u32,
    distance: DistancePlane,
    mantissa_bits: u32,
) -> Option<usize> {
    let texels = (resolution as usize).checked_mul(resolution as usize)?;
    let color = match (filter, encoding) {
        (Filter::PredictPacked, Encoding::Rgb9e5) => {
            texels.checked_mul(packed_planes(mantissa_bits))?
        }
        _ => encoding.face_bytes(resolution)?,
    };
    let per_texel = match filter {
        Filter::None if distance.is_present() => 4,
        _ => distance.filtered_bytes_per_texel(),
    };
    color.checked_add(texels.checked_mul(per_texel)?)
}

/// Checks the lengths of a filter's input `raw` (the raw face) and output `filtered`;
/// returns the texel count and the lengths of their texel parts.
#[allow(clippy::too_many_arguments)]
fn check_sizes(
    filter: Filter,
    encoding: Encoding,
    resolution: u32,
    distance: DistancePlane,
    mantissa_bits: u32,
    raw: usize,
    filtered: usize,
) -> Result<(usize, usize, usize), Error> {
    let overflow = || Error::Limit {
        what: "face texels",
        value: u64::from(resolution),
        max: u64::from(crate::MAX_CUBE_RESOLUTION),
    };
    let texels = (resolution as usize)
        .checked_mul(resolution as usize)
        .ok_or_else(overflow)?;
    let raw_size =
        filtered_face_size(Filter::None, encoding, resolution, distance, 9).ok_or_else(overflow)?;
    let filtered_size = filtered_face_size(filter, encoding, resolution, distance, mantissa_bits)
        .ok_or_else(overflow)?;
    for (what, len, expected) in [
        ("raw face", raw, raw_size),
        ("filtered face", filtered, filtered_size),
    ] {
        if len != expected {
            return Err(Error::BufferSize {
                what,
                expected: expected as u64,
                actual: len as u64,
            });
        }
    }
    let raw_dist = if distance.is_present() { texels * 4 } else { 0 };
    let filtered_dist = match filter {
        Filter::None => raw_dist,
        _ => texels * distance.filtered_bytes_per_texel(),
    };
    Ok((texels, raw_size - raw_dist, filtered_size - filtered_dist))
}

/// Filters one face's raw bytes (`raw`, exactly the face raw size) into `out` (same size).
/// For a store of lossless RGB9E5 (`mantissa_bits` 9); see [`filter_face_quantized`].
pub fn filter_face(
    filter: Filter,
    encoding: Encoding,
    resolution: u32,
    distance: DistancePlane,
    raw: &[u8],
    out: &mut [u8],
) -> Result<(), Error> {
    filter_face_quantized(filter, encoding, resolution, distance, 9, raw, out)
}

/// [`filter_face`] for a store keeping `mantissa_bits` (1..=9) RGB9E5 mantissa bits. `out`
/// is [`filtered_face_size`] bytes (the raw size except for filter 3).
///
/// Filter 2 rounds its RGB9E5 predictions to the store's mantissa lattice (`docs/format.md`, "Face
/// filters"): lossless for every input whatever `mantissa_bits` is, compact when the texels
/// were quantized to those bits. Filter 3 stores residuals in lattice steps, so its RGB9E5
/// input must be quantized ([`crate::encoding::quantize_rgb9e5`]): a mantissa off the
/// lattice is an [`Error::Unquantized`]. Other filters and encodings ignore `mantissa_bits`.
pub fn filter_face_quantized(
    filter: Filter,
    encoding: Encoding,
    resolution: u32,
    distance: DistancePlane,
    mantissa_bits: u32,
    raw: &[u8],
    out: &mut [u8],
) -> Result<(), Error> {
    let (t, rc_len, oc_len) = check_sizes(
        filter,
        encoding,
        resolution,
        distance,
        mantissa_bits,
        raw.len(),
        out.len(),
    )?;
    let n = resolution as usize;
    if filter == Filter::None {
        out.copy_from_slice(raw);
        return Ok(());
    }
    let (rc, rd) = raw.split_at(rc_len);
    let (oc, od) = out.split_at_mut(oc_len);
    match (filter, encoding) {
        (Filter::PredictPacked, Encoding::Rgb9e5) => {
            check_quantized(rc, mantissa_bits)?;
            packed_forward(n, t, rc, oc, Packed::new(mantissa_bits))
        }
        (Filter::PredictRows, Encoding::Rgb9e5) => {
            rows_forward::<_, 4>(n, t, rc, oc, Planes9(Lattice::new(mantissa_bits)))
        }
        (_, Encoding::Rgb9e5) => rgb9e5_forward(n, t, rc, oc),
        (_, Encoding::Rgba16f) => ints_forward::<2>(n, t, rc, oc),
        (_, Encoding::Rgba32f) => ints_forward::<4>(n, t, rc, oc),
        // BC6H blocks are left as they are (byte planes of them compress worse).
        (_, Encoding::Bc6h) => oc.copy_from_slice(rc),
    }
    match distance {
        DistancePlane::Absent => {}
        DistancePlane::Lattice { bits } => lattice_forward(n, t, bits, rd, od)?,
    }
    Ok(())
}

/// [`Error::Unquantized`] for the first RGB9E5 texel in `raw` whose mantissas are not all
/// multiples of `2^(9 − mantissa_bits)`.
fn check_quantized(raw: &[u8], mantissa_bits: u32) -> Result<(), Error> {
    let step = 1u32 << (9 - mantissa_bits.clamp(1, 9));
    let low = (step - 1) * (1 | 1 << 9 | 1 << 18);
    match raw
        .chunks_exact(4)
        .position(|c| u32::from_le_bytes([c[0], c[1], c[2], c[3]]) & low != 0)
    {
        None => Ok(()),
        Some(texel) => Err(Error::Unquantized {
            texel,
            mantissa_bits,
        }),
    }
}

/// Undoes [`filter_face`]: `filtered` (exactly the face raw size) into `out` (same size).
/// Never fails on content.
pub fn unfilter_face(
    filter: Filter,
    encoding: Encoding,
    resolution: u32,
    distance: DistancePlane,
    filtered: &[u8],
    out: &mut [u8],
) -> Result<(), Error> {
    unfilter_face_quantized(filter, encoding, resolution, distance, 9, filtered, out)
}

/// Undoes [`filter_face_quantized`] with the same `mantissa_bits`: `filtered`
/// ([`filtered_face_size`] bytes) into `out` (the raw face size). Never fails on content.
pub fn unfilter_face_quantized(
    filter: Filter,
    encoding: Encoding,
    resolution: u32,
    distance: DistancePlane,
    mantissa_bits: u32,
    filtered: &[u8],
    out: &mut [u8],
) -> Result<(), Error> {
    let (t, oc_len, fc_len) = check_sizes(
        filter,
        encoding,
        resolution,
        distance,
        mantissa_bits,
        out.len(),
        filtered.len(),
    )?;
    let n = resolution as usize;
    if filter == Filter::None {
        out.copy_from_slice(filtered);
        return Ok(());
    }
    let (fc, fd) = filtered.split_at(fc_len);
    let (oc, od) = out.split_at_mut(oc_len);
    match (filter, encoding) {
        (Filter::PredictPacked, Encoding::Rgb9e5) => {
            packed_inverse(n, t, fc, oc, Packed::new(mantissa_bits))
        }
        (Filter::PredictRows, Encoding::Rgb9e5) => {
            rows_inverse::<_, 4>(n, t, fc, oc, Planes9(Lattice::new(mantissa_bits)))
        }
        (_, Encoding::Rgb9e5) => rgb9e5_inverse(n, t, fc, oc),
        (_, Encoding::Rgba16f) => ints_inverse::<2>(n, t, fc, oc),
        (_, Encoding::Rgba32f) => ints_inverse::<4>(n, t, fc, oc),
        (_, Encoding::Bc6h) => oc.copy_from_slice(fc),
    }
    match distance {
        DistancePlane::Absent => {}
        DistancePlane::Lattice { bits } => lattice_inverse(n, t, bits, fd, od),
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::residual::{unzigzag, unzigzag9, zigzag, zigzag9};
    use super::*;

    struct Rng(u64);
    impl Rng {
        fn next(&mut self) -> u64 {
            self.0 ^= self.0 << 13;
            self.0 ^= self.0 >> 7;
            self.0 ^= self.0 << 17;
            self.0
        }
    }

    #[test]
    fn zigzags_are_inverse() {
        for r in 0..512 {
            assert_eq!(unzigzag9(zigzag9(r)), r);
        }
        assert_eq!(zigzag9(0), 0);
        assert_eq!(zigzag9(511), 1);
        assert_eq!(zigzag9(1), 2);
        for r in 0..=0xffffu64 {
            assert_eq!(unzigzag::<2>(zigzag::<2>(r)), r);
        }
        for r in [0u64, 1, 0x7fff_ffff, 0x8000_0000, 0xffff_ffff, 12345678] {
            assert_eq!(unzigzag::<4>(zigzag::<4>(r)), r);
        }
        assert_eq!(zigzag::<4>(0xffff_ffff), 1);
    }

    #[test]
    fn round_trips_any_bytes() {
        let mut rng = Rng(0x1234_5678_9abc_def1);
        for enc in Encoding::ALL {
            for res in [1u32, 2, 3, 5, 16] {
                for distance in [DistancePlane::Absent, DistancePlane::Lattice { bits: 5 }] {
                    let len = filtered_face_size(Filter::None, enc, res, distance, 9).unwrap();
                    for kind in 0..3 {
                        let mut raw: Vec<u8> = (0..len)
                            .map(|i| match kind {
                                0 => rng.next() as u8,
                                1 => (i / 7) as u8,
                                _ => [0u8, 0xff][(rng.next() & 1) as usize],
                            })
                            .collect();
                        on_distance_lattice(&mut raw, enc, res, distance);
                        for f in Filter::ALL {
                            let size = filtered_face_size(f, enc, res, distance, 9).unwrap();
                            let mut filtered = vec![0u8; size];
                            filter_face(f, enc, res, distance, &raw, &mut filtered).unwrap();
                            let mut back = vec![0u8; len];
                            unfilter_face(f, enc, res, distance, &filtered, &mut back).unwrap();
                            assert_eq!(back, raw, "{enc} {f} res {res} distance {distance}");
                            // Lossless with any mantissa lattice, on texels that are not
                            // on it as well.
                            for bits in [1, 4, 5, 8] {
                                let packed = f == Filter::PredictPacked && enc == Encoding::Rgb9e5;
                                // Filter 3 takes texels on the lattice only: others are an
                                // error, and the rest of the round trip runs on the texels
                                // quantized to `bits`.
                                let raw = if packed {
                                    let q = lattice_floor(&raw, (res * res) as usize, bits);
                                    let size = filtered_face_size(f, enc, res, distance, bits);
                                    let mut out = vec![0u8; size.unwrap()];
                                    let r = filter_face_quantized(
                                        f, enc, res, distance, bits, &raw, &mut out,
                                    );
                                    if q != raw {
                                        assert!(
                                            matches!(r, Err(Error::Unquantized { .. })),
                                            "{r:?}"
                                        );
                                    }
                                    q
                                } else {
                                    raw.clone()
                                };
                                let mut filtered =
                                    vec![
                                        0u8;
                                        filtered_face_size(f, enc, res, distance, bits).unwrap()
                                    ];
                                let q = |a: &[u8], o: &mut [u8], inv: bool| {
                                    let g = if inv {
                                        unfilter_face_quantized
                                    } else {
                                        filter_face_quantized
                                    };
                                    g(f, enc, res, distance, bits, a, o).unwrap()
                                };
                                q(&raw, &mut filtered, false);
                                q(&filtered, &mut back, true);
                                assert_eq!(back, raw, "{enc} {f} res {res} bits {bits}");
                            }
                        }
                    }
                }
            }
        }
    }

    /// Puts the distance part of the raw face `raw` (any bytes) on `plane`'s lattice: each
    /// pattern made finite and non-negative, then rounded.
    fn on_distance_lattice(raw: &mut [u8], enc: Encoding, res: u32, plane: DistancePlane) {
        if !plane.is_present() {
            return;
        }
        let texel_bytes = enc.face_bytes(res).unwrap();
        for d in raw[texel_bytes..].chunks_exact_mut(4) {
            let v = u32::from_le_bytes([d[0], d[1], d[2], d[3]]) & 0x7f7f_ffff;
            d.copy_from_slice(&plane.quantize(f32::from_bits(v)).to_le_bytes());
        }
    }

    /// Filter 2's RGB9E5 residuals computed texel by texel from the spec in `docs/format.md` ("Face
    /// filters"), independently of the row code.
    fn predict_rows_reference(n: usize, tex: &[u32], bits: u32) -> Vec<u8> {
        let t = n * n;
        let mut out = vec![0u8; 4 * t];
        for (i, (&v, [pr, pg, pb])) in tex
            .iter()
            .zip(rows_predictions_reference(n, tex, bits))
            .enumerate()
        {
            let e = v >> 27;
            let (r, g, b) = (v & 511, (v >> 9) & 511, (v >> 18) & 511);
            let z = |c: u32, p: u32| zigzag9(c.wrapping_sub(p));
            let (zr, zg, zb) = (z(r, pr), z(g, pg), z(b, pb));
            out[i] = (e | (zr >> 8) << 5 | (zg >> 8) << 6 | (zb >> 8) << 7) as u8;
            out[t + i] = zg as u8;
            out[2 * t + i] = zr as u8;
            out[3 * t + i] = zb as u8;
        }
        out
    }

    /// Texel `i` of a face of `kind` for the spec tests: 0 any bit pattern, 1 a smooth HDR
    /// gradient with a few exponents, 2 that gradient quantized to `bits`, 3 zeros and
    /// extremes.
    fn spec_texel(kind: usize, i: usize, bits: u32, rng: &mut Rng) -> u32 {
        let gradient = || {
            crate::encoding::encode_rgb9e5([
                0.01 + i as f32 * 0.37,
                0.02 + i as f32 * 0.5,
                0.005 + (i % 5) as f32,
            ])
        };
        match kind {
            0 => rng.next() as u32,
            1 => gradient(),
            2 => crate::encoding::quantize_rgb9e5(gradient(), bits),
            _ => [0u32, u32::MAX, 1 << 27, 511][(rng.next() % 4) as usize],
        }
    }

    /// `raw` with the mantissas of its first `t` RGB9E5 texels rounded down to multiples of
    /// `2^(9 − bits)`.
    fn lattice_floor(raw: &[u8], t: usize, bits: u32) -> Vec<u8> {
        let s = (1u32 << (9 - bits)) - 1;
        let mut q = raw.to_vec();
        for c in q[..4 * t].chunks_exact_mut(4) {
            let v = u32::from_le_bytes([c[0], c[1], c[2], c[3]]);
            c.copy_from_slice(&(v & !(s | s << 9 | s << 18)).to_le_bytes());
        }
        q
    }

    /// Filter 3's planes from the spec, on the predictions of [`rows_predictions_reference`].
    fn predict_packed_reference(n: usize, tex: &[u32], bits: u32) -> Vec<u8> {
        let t = n * n;
        let planes = (5 + 3 * bits as usize).div_ceil(8);
        let s = 1u32 << (9 - bits);
        let zk = |c: u32, p: u32| {
            let q = (c + 512 - p) % 512 / s;
            if q < 1 << (bits - 1) {
                2 * q
            } else {
                2 * ((1 << bits) - q) - 1
            }
        };
        let mut out = vec![0u8; planes * t];
        for (i, (&v, [pr, pg, pb])) in tex
            .iter()
            .zip(rows_predictions_reference(n, tex, bits))
            .enumerate()
        {
            let e = v >> 27;
            let (r, g, b) = (v & 511, (v >> 9) & 511, (v >> 18) & 511);
            let code = u64::from(e)
                | u64::from(zk(g, pg)) << 5
                | u64::from(zk(r, pr)) << (5 + bits)
                | u64::from(zk(b, pb)) << (5 + 2 * bits);
            for j in 0..planes {
                out[j * t + i] = (code >> (8 * j)) as u8;
            }
        }
        out
    }

    /// Filter 2's (and 3's) predictions `[pR, pG, pB]` of every texel, texel by texel from
    /// the spec in lib.rs ("Face filters").
    fn rows_predictions_reference(n: usize, tex: &[u32], bits: u32) -> Vec<[u32; 3]> {
        let value = |v: u32, shift: u32| ((v >> shift) & 511) as f32 * 2f32.powi((v >> 27) as i32);
        // Round to nearest, then to the lattice of multiples of s = 2^(9 - bits), at most
        // 512 - s.
        let s = 1u32 << (9 - bits);
        let lattice = |p: u32| ((p + s / 2) / s * s).min(512 - s);
        let round = |x: f32| lattice((x + 0.5).clamp(0.0, 511.0).trunc() as u32);
        let mut out = vec![[0u32; 3]; n * n];
        for y in 0..n {
            for x in 0..n {
                let i = y * n + x;
                let v = tex[i];
                let e = v >> 27;
                let g = (v >> 9) & 511;
                let taps = match (x, y) {
                    (0, 0) => None,
                    (_, 0) => Some([i - 1; 3]),
                    _ => Some([
                        (y - 1) * n + x.saturating_sub(1),
                        (y - 1) * n + x,
                        (y - 1) * n + (x + 1).min(n - 1),
                    ]),
                };
                let sum = |shift: u32| {
                    taps.map_or(0.0, |[a, b, c]| {
                        (value(tex[a], shift) + 2.0 * value(tex[b], shift)) + value(tex[c], shift)
                    })
                };
                let (sr, sg, sb) = (sum(0), sum(9), sum(18));
                let q = 2f32.powi(-(e as i32) - 2);
                let pg = round(sg * q);
                let pc = |sc: f32| {
                    if sg == 0.0 {
                        round(sc * q)
                    } else {
                        round(g as f32 * (sc / sg))
                    }
                };
                out[i] = [pc(sr), pg, pc(sb)];
            }
        }
        out
    }

    #[test]
    fn predict_packed_matches_the_spec() {
        let mut rng = Rng(0x5eed_0f9a_cced);
        for res in [1usize, 2, 3, 7, 16, 33] {
            for bits in 1..=9u32 {
                for kind in 0..3 {
                    let t = res * res;
                    // Any bit pattern, the quantized gradient, zeros and extremes (all put on
                    // the lattice below).
                    let tex: Vec<u32> = (0..t)
                        .map(|i| spec_texel([0, 2, 3][kind], i, bits, &mut rng))
                        .collect();
                    let raw: Vec<u8> = tex.iter().flat_map(|v| v.to_le_bytes()).collect();
                    let raw = lattice_floor(&raw, t, bits);
                    let tex: Vec<u32> = raw
                        .chunks_exact(4)
                        .map(|c| u32::from_le_bytes([c[0], c[1], c[2], c[3]]))
                        .collect();
                    let n = res as u32;
                    let size = filtered_face_size(
                        Filter::PredictPacked,
                        Encoding::Rgb9e5,
                        n,
                        DistancePlane::Absent,
                        bits,
                    );
                    assert_eq!(size, Some(t * packed_planes(bits)));
                    let mut filtered = vec![0u8; t * packed_planes(bits)];
                    let f = Filter::PredictPacked;
                    filter_face_quantized(
                        f,
                        Encoding::Rgb9e5,
                        n,
                        DistancePlane::Absent,
                        bits,
                        &raw,
                        &mut filtered,
                    )
                    .unwrap();
                    let want = predict_packed_reference(res, &tex, bits);
                    assert_eq!(filtered, want, "res {res} kind {kind} bits {bits}");
                    let mut back = vec![0u8; raw.len()];
                    unfilter_face_quantized(
                        f,
                        Encoding::Rgb9e5,
                        n,
                        DistancePlane::Absent,
                        bits,
                        &filtered,
                        &mut back,
                    )
                    .unwrap();
                    assert_eq!(back, raw, "res {res} kind {kind} bits {bits}");
                    // Any bytes decode to texels on the lattice.
                    let junk: Vec<u8> = (0..filtered.len()).map(|_| rng.next() as u8).collect();
                    unfilter_face_quantized(
                        f,
                        Encoding::Rgb9e5,
                        n,
                        DistancePlane::Absent,
                        bits,
                        &junk,
                        &mut back,
                    )
                    .unwrap();
                    assert_eq!(lattice_floor(&back, t, bits), back, "res {res} bits {bits}");
                }
            }
        }
    }

    #[test]
    fn predict_rows_matches_the_spec() {
        let mut rng = Rng(0x0dd_ba11_cafe_f00d);
        for (res, kind, bits) in [1usize, 2, 3, 7, 16, 33]
            .into_iter()
            .flat_map(|r| (0..4).map(move |k| (r, k)))
            .flat_map(|(r, k)| [9u32, 7, 5, 2, 1].map(|b| (r, k, b)))
        {
            {
                let tex: Vec<u32> = (0..res * res)
                    .map(|i| spec_texel(kind, i, bits, &mut rng))
                    .collect();
                let raw: Vec<u8> = tex.iter().flat_map(|v| v.to_le_bytes()).collect();
                let mut filtered = vec![0u8; raw.len()];
                let n = res as u32;
                filter_face_quantized(
                    Filter::PredictRows,
                    Encoding::Rgb9e5,
                    n,
                    DistancePlane::Absent,
                    bits,
                    &raw,
                    &mut filtered,
                )
                .unwrap();
                assert_eq!(
                    filtered,
                    predict_rows_reference(res, &tex, bits),
                    "res {res} kind {kind} bits {bits}"
                );
                if kind == 2 && res > 1 {
                    // Quantized texels leave residuals on the lattice: zigzag9 of a
                    // multiple of s is 2js or 2js - 1 (low bits all zero or all one).
                    let s = 1u32 << (9 - bits);
                    let t = res * res;
                    for i in 0..t {
                        let h = u32::from(filtered[i]);
                        for (plane, hi) in [(1, 6), (2, 5), (3, 7)] {
                            let z = u32::from(filtered[plane * t + i]) | (h >> hi & 1) << 8;
                            let r = unzigzag9(z);
                            assert_eq!(r % s, 0, "res {res} bits {bits} texel {i}");
                        }
                    }
                }
                // The decoder (vectorised where the processor allows) inverts it.
                let mut back = vec![0u8; raw.len()];
                unfilter_face_quantized(
                    Filter::PredictRows,
                    Encoding::Rgb9e5,
                    n,
                    DistancePlane::Absent,
                    bits,
                    &filtered,
                    &mut back,
                )
                .unwrap();
                assert_eq!(back, raw, "res {res} kind {kind} bits {bits}");
            }
        }
    }

    #[test]
    fn predict_rows_of_a_constant_face_is_zero_after_the_first_texel() {
        let n = 8u32;
        let v = crate::encoding::encode_rgb9e5([1.5, 0.75, 0.2]);
        let raw: Vec<u8> = (0..n * n).flat_map(|_| v.to_le_bytes()).collect();
        let mut filtered = vec![0u8; raw.len()];
        filter_face(
            Filter::PredictRows,
            Encoding::Rgb9e5,
            n,
            DistancePlane::Absent,
            &raw,
            &mut filtered,
        )
        .unwrap();
        let t = (n * n) as usize;
        for i in 1..t {
            assert_eq!(filtered[i], (v >> 27) as u8, "exponent plane, texel {i}");
            for p in 1..4 {
                assert_eq!(filtered[p * t + i], 0, "plane {p}, texel {i}");
            }
        }
    }

    #[test]
    fn wrong_sizes_are_errors() {
        let mut out = vec![0u8; 16];
        assert!(matches!(
            filter_face(
                Filter::Predict,
                Encoding::Rgb9e5,
                2,
                DistancePlane::Absent,
                &[0; 15],
                &mut out
            ),
            Err(Error::BufferSize { .. })
        ));
        assert!(matches!(
            unfilter_face(
                Filter::Predict,
                Encoding::Rgb9e5,
                2,
                DistancePlane::Lattice { bits: 2 },
                &[0; 16],
                &mut out
            ),
            Err(Error::BufferSize { .. })
        ));
        assert!(Filter::from_id(4).is_none());
        for f in Filter::ALL {
            assert_eq!(Filter::from_id(f.id()), Some(f));
        }
    }
}
