//! Cube-map geometry (the wgpu / Vulkan convention), cube images and their encoding.
//!
//! Faces are stored in layer order +X, -X, +Y, -Y, +Z, -Z (0..5), so the runtime uploads them
//! as they are. A direction maps to a face and face coordinates `(s, t)` by the Vulkan
//! specification's cube-map table ("Cube Map Face Selection"):
//!
//! | face | sc | tc | ma |
//! |------|----|----|----|
//! | +X   | -z | -y | x  |
//! | -X   | +z | -y | x  |
//! | +Y   | +x | +z | y  |
//! | -Y   | +x | -z | y  |
//! | +Z   | +x | -y | z  |
//! | -Z   | -x | -y | z  |
//!
//! `s = (sc / |ma| + 1) / 2`, `t = (tc / |ma| + 1) / 2`. Texel row 0 is `t = 0` and comes first
//! in memory; column 0 is `s = 0`. Texel `(x, y)` of a face of resolution `n` is centred on
//! `s = (x + 0.5) / n`, `t = (y + 0.5) / n`. When two components tie for the largest magnitude
//! the face is chosen in the order x, y, z.

use crate::distance::DistancePlane;
use crate::encoding::{encode_distances, encode_face_texels, quantize_rgb9e5_bytes, Encoding};
use crate::filter::{filter_face_quantized, Filter};
use crate::{BakeParams, Error, MAX_CUBE_RESOLUTION};

/// Number of faces of a cube map.
pub const FACES: usize = 6;

/// Short names of the faces, in layer order.
pub const FACE_NAMES: [&str; FACES] = ["px", "nx", "py", "ny", "pz", "nz"];

/// The face a direction points at and its face coordinates `(s, t)` in `[0, 1]`.
///
/// A zero or non-finite direction gives `(0, 0.5, 0.5)` (never panics).
pub fn direction_to_face_st(dir: [f32; 3]) -> (usize, f32, f32) {
    let [x, y, z] = dir;
    if !(x.is_finite() && y.is_finite() && z.is_finite()) {
        return (0, 0.5, 0.5);
    }
    let (ax, ay, az) = (x.abs(), y.abs(), z.abs());
    let (face, sc, tc, ma) = if ax >= ay && ax >= az {
        if x >= 0.0 {
            (0, -z, -y, ax)
        } else {
            (1, z, -y, ax)
        }
    } else if ay >= az {
        if y >= 0.0 {
            (2, x, z, ay)
        } else {
            (3, x, -z, ay)
        }
    } else if z >= 0.0 {
        (4, x, -y, az)
    } else {
        (5, -x, -y, az)
    };
    if ma <= 0.0 {
        return (0, 0.5, 0.5);
    }
    let s = ((sc / ma + 1.0) * 0.5).clamp(0.0, 1.0);
    let t = ((tc / ma + 1.0) * 0.5).clamp(0.0, 1.0);
    (face, s, t)
}

/// The unit direction through face coordinates `(s, t)` of `face` (inverse of
/// [`direction_to_face_st`]). Face indices of 6 and above are taken modulo 6.
pub fn face_st_to_direction(face: usize, s: f32, t: f32) -> [f32; 3] {
    let sc = 2.0 * s - 1.0;
    let tc = 2.0 * t - 1.0;
    let d = match face % FACES {
        0 => [1.0, -tc, -sc],
        1 => [-1.0, -tc, sc],
        2 => [sc, 1.0, tc],
        3 => [sc, -1.0, -tc],
        4 => [sc, -tc, 1.0],
        _ => [-sc, -tc, -1.0],
    };
    let len = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
    if len > 0.0 && len.is_finite() {
        [d[0] / len, d[1] / len, d[2] / len]
    } else {
        [1.0, 0.0, 0.0]
    }
}

/// The unit direction through the centre of texel `(x, y)` of `face` at `resolution`
/// (a resolution of 0 is treated as 1).
pub fn texel_direction(face: usize, x: u32, y: u32, resolution: u32) -> [f32; 3] {
    let n = resolution.max(1) as f32;
    face_st_to_direction(face, (x as f32 + 0.5) / n, (y as f32 + 0.5) / n)
}

/// The solid angle of texel `(x, y)` of a face of `resolution` texels a side (a resolution of
/// 0 is treated as 1): exact, from the area element of the unit-distance face, so that the
/// texels of a cube sum to 4π.
pub fn texel_solid_angle(x: u32, y: u32, resolution: u32) -> f32 {
    let n = f64::from(resolution.max(1));
    // ∫∫ (1 + a² + b²)^(−3/2) da db from the origin to (a, b).
    let area = |a: f64, b: f64| (a * b).atan2((a * a + b * b + 1.0).sqrt());
    let edge = |i: u32| 2.0 * f64::from(i) / n - 1.0;
    let (a0, a1, b0, b1) = (edge(x), edge(x + 1), edge(y), edge(y + 1));
    (area(a1, b1) - area(a0, b1) - area(a1, b0) + area(a0, b0)) as f32
}

/// Where face coordinates `(s, t)` land on a face of side `n`: the four texels around them,
/// clamped at the face's edges, and the bilinear weights (as `Tap` in the runtime's
/// shade.wgsl).
pub struct Tap {
    pub x0: u32,
    pub y0: u32,
    pub x1: u32,
    pub y1: u32,
    pub wx: f32,
    pub wy: f32,
}

impl Tap {
    pub fn new(n: u32, s: f32, t: f32) -> Self {
        let nf = n as f32;
        let fx = (s * nf - 0.5).clamp(0.0, nf - 1.0);
        let fy = (t * nf - 0.5).clamp(0.0, nf - 1.0);
        let (x0, y0) = (fx.floor() as u32, fy.floor() as u32);
        Tap {
            x0,
            y0,
            x1: (x0 + 1).min(n - 1),
            y1: (y0 + 1).min(n - 1),
            wx: fx - fx.floor(),
            wy: fy - fy.floor(),
        }
    }
}

/// A decoded cube map: linear RGB radiance, row-major per face, faces in layer order.
#[derive(Clone, Debug)]
pub struct CubeImage {
    /// Texels per face edge.
    pub resolution: u32,
    /// `resolution * resolution` texels per face, row 0 first.
    pub faces: [Vec<[f32; 3]>; FACES],
    /// Optional distance to the first hit per texel (`f32::MAX` where the ray escaped).
    pub distance: Option<[Vec<f32>; FACES]>,
}

impl CubeImage {
    /// The radiance towards `dir`, bilinear within the face it points at ([`Tap`]).
    pub fn bilinear(&self, dir: [f32; 3]) -> [f32; 3] {
        let (face, s, t) = direction_to_face_st(dir);
        let n = self.resolution.max(1);
        let tap = Tap::new(n, s, t);
        let texels = &self.faces[face];
        let at = |x: u32, y: u32| texels[(y * n + x) as usize];
        let (x0, y0, x1, y1, wx, wy) = (tap.x0, tap.y0, tap.x1, tap.y1, tap.wx, tap.wy);
        let lerp =
            |a: [f32; 3], b: [f32; 3], w: f32| std::array::from_fn(|i| a[i] + (b[i] - a[i]) * w);
        let top = lerp(at(x0, y0), at(x1, y0), wx);
        let bottom = lerp(at(x0, y1), at(x1, y1), wx);
        lerp(top, bottom, wy)
    }

    /// A black cube (with a zero distance plane if `distance`).
    pub fn black(resolution: u32, distance: bool) -> Self {
        let n = (resolution as usize).saturating_mul(resolution as usize);
        CubeImage {
            resolution,
            faces: std::array::from_fn(|_| vec![[0.0; 3]; n]),
            distance: distance.then(|| std::array::from_fn(|_| vec![0.0; n])),
        }
    }
}

/// Bytes of one face's raw (decompressed) data: encoded texels ([`Encoding::face_bytes`]),
/// then the distance plane.
pub fn face_raw_size(
    encoding: Encoding,
    resolution: u32,
    distance_channel: bool,
) -> Result<u64, Error> {
    let overflow = || Error::Limit {
        what: "face raw size",
        value: u64::MAX,
        max: u64::MAX,
    };
    let texels = u64::from(resolution) * u64::from(resolution);
    let color = encoding.face_bytes(resolution).ok_or_else(overflow)? as u64;
    let dist = if distance_channel { texels * 4 } else { 0 };
    color.checked_add(dist).ok_or_else(overflow)
}

/// Counters from [`encode_cube`].
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct EncodeStats {
    /// Texels with a channel above the encoding's largest finite value (stored clamped).
    pub clamped_texels: u64,
    /// Raw (encoded, uncompressed) bytes of the six faces.
    pub raw_bytes: u64,
    /// zstd-compressed bytes of the six faces.
    pub compressed_bytes: u64,
}

impl std::ops::AddAssign for EncodeStats {
    fn add_assign(&mut self, o: Self) {
        self.clamped_texels += o.clamped_texels;
        self.raw_bytes += o.raw_bytes;
        self.compressed_bytes += o.compressed_bytes;
    }
}

/// A cube encoded and compressed, ready for [`crate::StoreWriter::append`].
#[derive(Clone, Debug)]
pub struct EncodedCube {
    pub(crate) cube_index: u32,
    pub(crate) encoding: Encoding,
    pub(crate) filter: Filter,
    pub(crate) resolution: u32,
    /// How the frames hold the distance plane.
    pub(crate) distance: DistancePlane,
    pub(crate) mantissa_bits: u32,
    pub(crate) raw_size: u64,
    pub(crate) frames: [Vec<u8>; FACES],
    pub(crate) checksums: [u64; FACES],
    /// xxh3-64 of each raw (unfiltered) face: what the store's decoded-faces checksum covers.
    pub(crate) raw_checksums: [u64; FACES],
}

impl EncodedCube {
    /// The cube index it was encoded for.
    pub fn cube_index(&self) -> u32 {
        self.cube_index
    }
    /// Raw (decompressed) bytes of each face.
    pub fn face_raw_size(&self) -> u64 {
        self.raw_size
    }
    /// The face filter the frames were written with.
    pub fn filter(&self) -> Filter {
        self.filter
    }
    /// The six zstd frames.
    pub fn frames(&self) -> &[Vec<u8>; FACES] {
        &self.frames
    }
    /// Compressed bytes of all six faces.
    pub fn compressed_bytes(&self) -> u64 {
        self.frames.iter().map(|f| f.len() as u64).sum()
    }
}

/// Encodes and compresses a cube. Pure: run it in parallel.
///
/// Checks the cube's shape against `params` (resolution, distance channel), rejects NaN,
/// infinite or negative radiance ([`Error::InvalidRadiance`]) and distances
/// ([`Error::InvalidDistance`]), clamps values above the encoding's largest finite value and
/// counts them in [`EncodeStats::clamped_texels`]. RGB9E5 texels keep
/// [`BakeParams::mantissa_bits`] mantissa bits ([`crate::encoding::quantize_rgb9e5`]) before
/// the face filter and zstd.
///
/// Faces are filtered with [`Filter::for_store`] of `params`' encoding and mantissa bits, the filter
/// [`crate::StoreWriter::create`] records; see [`encode_cube_with_filter`].
pub fn encode_cube(
    cube: &CubeImage,
    params: &BakeParams,
    cube_index: u32,
) -> Result<(EncodedCube, EncodeStats), Error> {
    let filter = Filter::for_store(params.encoding, params.mantissa_bits);
    encode_cube_with_filter(cube, params, cube_index, filter)
}

/// [`encode_cube`] with an explicit face filter (for stores created with
/// [`crate::StoreWriter::create_with_filter`]).
pub fn encode_cube_with_filter(
    cube: &CubeImage,
    params: &BakeParams,
    cube_index: u32,
    filter: Filter,
) -> Result<(EncodedCube, EncodeStats), Error> {
    check_cube_shape(cube, params, cube_index)?;
    let res = params.cube_resolution;
    let enc = params.encoding;
    crate::meta::check_mantissa_bits(enc, params.mantissa_bits).map_err(|detail| {
        Error::InvalidBakeParams {
            cube: cube_index,
            detail,
        }
    })?;
    let raw_size = face_raw_size(enc, res, params.distance_channel)?;
    let mut raw = vec![0u8; raw_size as usize];
    let plane = DistancePlane::for_store(res, params.distance_channel);
    let filtered_size =
        crate::filter::filtered_face_size(filter, enc, res, plane, params.mantissa_bits).ok_or(
            Error::Limit {
                what: "cube resolution",
                value: u64::from(res),
                max: u64::from(crate::MAX_CUBE_RESOLUTION),
            },
        )?;
    let mut filtered = vec![0u8; filtered_size];
    let mut compressor =
        zstd::bulk::Compressor::new(params.zstd_level).map_err(|e| Error::Compress {
            cube: cube_index,
            face: 0,
            detail: e.to_string(),
        })?;
    let mut stats = EncodeStats::default();
    let mut frames: [Vec<u8>; FACES] = Default::default();
    let mut checksums = [0u64; FACES];
    let mut raw_checksums = [0u64; FACES];
    for face in 0..FACES {
        stats.clamped_texels += encode_raw_face(cube, params, plane, cube_index, face, &mut raw)?;
        raw_checksums[face] = xxhash_rust::xxh3::xxh3_64(&raw);
        filter_face_quantized(
            filter,
            enc,
            res,
            plane,
            params.mantissa_bits,
            &raw,
            &mut filtered,
        )?;
        let frame = compressor
            .compress(&filtered)
            .map_err(|e| Error::Compress {
                cube: cube_index,
                face,
                detail: e.to_string(),
            })?;
        checksums[face] = xxhash_rust::xxh3::xxh3_64(&frame);
        stats.raw_bytes += raw_size;
        stats.compressed_bytes += frame.len() as u64;
        frames[face] = frame;
    }
    Ok((
        EncodedCube {
            cube_index,
            encoding: enc,
            filter,
            resolution: res,
            distance: plane,
            mantissa_bits: params.mantissa_bits,
            raw_size,
            frames,
            checksums,
            raw_checksums,
        },
        stats,
    ))
}

/// Checks that `cube` (cube `cube_index`) has the shape of a bake with `params`: its
/// resolution and whether it has a distance plane.
fn check_cube_shape(cube: &CubeImage, params: &BakeParams, cube_index: u32) -> Result<(), Error> {
    let res = params.cube_resolution;
    if res == 0 || res > MAX_CUBE_RESOLUTION {
        return Err(Error::Limit {
            what: "cube resolution",
            value: u64::from(res),
            max: u64::from(MAX_CUBE_RESOLUTION),
        });
    }
    if cube.resolution != res {
        return Err(Error::CubeShape {
            cube: cube_index,
            detail: format!(
                "resolution {} differs from the bake's {res}",
                cube.resolution
            ),
        });
    }
    if cube.distance.is_some() != params.distance_channel {
        return Err(Error::CubeShape {
            cube: cube_index,
            detail: format!(
                "distance plane {} but the bake's distance_channel is {}",
                if cube.distance.is_some() {
                    "present"
                } else {
                    "absent"
                },
                params.distance_channel
            ),
        });
    }
    Ok(())
}

/// Encodes face `face` of `cube` (cube `cube_index` of a bake with `params`) into `raw`, the
/// face's raw bytes: its texels (RGB9E5 ones quantized to the bake's mantissa bits), then its
/// distance plane if any, rounded to `plane`'s lattice. Returns the count of clamped texels.
fn encode_raw_face(
    cube: &CubeImage,
    params: &BakeParams,
    plane: DistancePlane,
    cube_index: u32,
    face: usize,
    raw: &mut [u8],
) -> Result<u64, Error> {
    let (enc, res) = (params.encoding, params.cube_resolution);
    let texels = (res as usize) * (res as usize); // res <= 16384: no overflow
    let color_bytes = enc.face_bytes(res).ok_or(Error::Limit {
        what: "cube resolution",
        value: u64::from(res),
        max: u64::from(MAX_CUBE_RESOLUTION),
    })?;
    let rgb = &cube.faces[face];
    if rgb.len() != texels {
        return Err(Error::CubeShape {
            cube: cube_index,
            detail: format!("face {face} has {} texels, expected {texels}", rgb.len()),
        });
    }
    let (color, dist_out) = raw.split_at_mut(color_bytes);
    let clamped = encode_face_texels(enc, res, rgb, color).map_err(|e| match e {
        Error::InvalidTexel { index, value } => Error::InvalidRadiance {
            cube: cube_index,
            face,
            x: (index % res as usize) as u32,
            y: (index / res as usize) as u32,
            value,
        },
        other => other,
    })?;
    if enc == Encoding::Rgb9e5 {
        quantize_rgb9e5_bytes(color, params.mantissa_bits);
    }
    if let Some(dist) = &cube.distance {
        let d = &dist[face];
        if d.len() != texels {
            return Err(Error::CubeShape {
                cube: cube_index,
                detail: format!(
                    "distance plane of face {face} has {} texels, expected {texels}",
                    d.len()
                ),
            });
        }
        if let Some(i) = d.iter().position(|v| !(v.is_finite() && *v >= 0.0)) {
            return Err(Error::InvalidDistance {
                cube: cube_index,
                face,
                x: (i % res as usize) as u32,
                y: (i / res as usize) as u32,
                value: d.get(i).copied().unwrap_or(f32::NAN),
            });
        }
        let q: Vec<f32> = d.iter().map(|v| plane.quantize(*v)).collect();
        encode_distances(&q, dist_out)?;
    }
    Ok(clamped)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: [f32; 3], b: [f32; 3]) -> bool {
        a.iter().zip(b).all(|(x, y)| (x - y).abs() < 1e-5)
    }

    #[test]
    fn axes_hit_face_centres() {
        let axes = [
            [1.0, 0.0, 0.0],
            [-1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, -1.0, 0.0],
            [0.0, 0.0, 1.0],
            [0.0, 0.0, -1.0],
        ];
        for (face, a) in axes.iter().enumerate() {
            assert_eq!(direction_to_face_st(*a), (face, 0.5, 0.5));
            assert!(close(face_st_to_direction(face, 0.5, 0.5), *a));
        }
    }

    #[test]
    fn vulkan_table_corners() {
        // +X: s grows towards -z, t grows towards -y.
        let (f, s, t) = direction_to_face_st([1.0, -0.5, -0.5]);
        assert_eq!((f, s, t), (0, 0.75, 0.75));
        // +Y: s grows with +x, t grows with +z.
        let (f, s, t) = direction_to_face_st([0.5, 1.0, 0.5]);
        assert_eq!((f, s, t), (2, 0.75, 0.75));
        // -Z: s grows towards -x.
        let (f, s, _) = direction_to_face_st([-0.5, 0.0, -1.0]);
        assert_eq!((f, s), (5, 0.75));
    }

    #[test]
    fn round_trip_texel_directions() {
        let n = 7;
        for face in 0..FACES {
            for y in 0..n {
                for x in 0..n {
                    let d = texel_direction(face, x, y, n);
                    let len = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
                    assert!((len - 1.0).abs() < 1e-6);
                    let (f, s, t) = direction_to_face_st(d);
                    assert_eq!(f, face);
                    assert!((s - (x as f32 + 0.5) / n as f32).abs() < 1e-6);
                    assert!((t - (y as f32 + 0.5) / n as f32).abs() < 1e-6);
                }
            }
        }
    }

    #[test]
    fn degenerate_directions_do_not_panic() {
        assert_eq!(direction_to_face_st([0.0; 3]), (0, 0.5, 0.5));
        assert_eq!(direction_to_face_st([f32::NAN, 1.0, 0.0]), (0, 0.5, 0.5));
        let _ = face_st_to_direction(99, f32::NAN, 2.0);
        let _ = texel_direction(0, 5, 5, 0);
    }
}
