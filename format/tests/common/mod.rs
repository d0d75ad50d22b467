//! Shared test fixtures: small synthetic stores.
#![allow(dead_code)]

use std::path::{Path, PathBuf};

use oslf_format::*;

/// A deterministic xorshift generator.
pub struct Rng(pub u64);

impl Rng {
    pub fn next_u64(&mut self) -> u64 {
        let mut x = self.0.max(1);
        x ^= x << 13;
        x ^= x >> 7;
        x ^= x << 17;
        self.0 = x;
        x
    }
    pub fn unit(&mut self) -> f32 {
        (self.next_u64() >> 40) as f32 / (1u64 << 24) as f32
    }
    /// Log-uniform HDR value in 1e-4..6e4, sometimes exactly 0.
    pub fn hdr(&mut self) -> f32 {
        if self.next_u64().is_multiple_of(17) {
            0.0
        } else {
            10f32.powf(-4.0 + self.unit() * 8.77)
        }
    }
}

pub struct Fixture {
    pub meta: StoreMeta,
    pub points: Vec<SamplePoint>,
    pub maps: SampleMaps,
    pub cubes: Vec<CubeImage>,
}

#[derive(Clone, Copy, Debug)]
pub struct Spec {
    pub encoding: Encoding,
    pub cube_res: u32,
    pub map_res: u32,
    pub points: usize,
    pub patches: usize,
    pub distance: bool,
    pub env: bool,
    pub seed: u64,
    /// RGB9E5 mantissa bits (9 = lossless; must be 9 for other encodings).
    pub mantissa_bits: u32,
}

impl Default for Spec {
    fn default() -> Self {
        Spec {
            encoding: Encoding::Rgb9e5,
            cube_res: 4,
            map_res: 3,
            points: 5,
            patches: 3,
            distance: false,
            env: true,
            seed: 1,
            mantissa_bits: 9,
        }
    }
}

pub fn fixture(spec: Spec) -> Fixture {
    let mut rng = Rng(spec.seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1);
    let patches: Vec<Patch> = (0..spec.patches)
        .map(|p| Patch {
            control_points: std::array::from_fn(|k| {
                [(k / 4) as f32, (k % 4) as f32, p as f32 * 0.5]
            }),
        })
        .collect();
    // Two objects when there are at least two patches.
    let split = (spec.patches / 2) as u32;
    let mut objects = vec![ObjectInfo {
        name: "teapot body ✓".into(),
        transform: [
            [1.0, 0.0, 0.0, 0.0],
            [0.0, 1.0, 0.0, 0.0],
            [0.0, 0.0, 1.0, 0.0],
            [0.5, -1.0, 2.0, 1.0],
        ],
        base_color: [0.8, 0.6, 0.2],
        first_patch: 0,
        patch_count: split,
        mesh: None,
        material: Default::default(),
        textures: None,
    }];
    objects.push(ObjectInfo {
        name: "lid".into(),
        transform: objects[0].transform,
        base_color: [0.1, 0.2, 0.3],
        first_patch: split,
        patch_count: spec.patches as u32 - split,
        mesh: None,
        material: Default::default(),
        textures: None,
    });
    let meta = StoreMeta {
        objects,
        patches,
        bake: BakeParams {
            epsilon: 0.05,
            phi_samplemap_deg: 12.5,
            cube_resolution: spec.cube_res,
            sample_map_resolution: spec.map_res,
            samples_per_texel: 64,
            bounces: 4,
            seed: spec.seed,
            encoding: spec.encoding,
            distance_channel: spec.distance,
            zstd_level: 3,
            scene_hash: std::array::from_fn(|i| i as u8 ^ spec.seed as u8),
            mantissa_bits: spec.mantissa_bits,
            sampling: Some(Sampling {
                target_noise: if spec.seed.is_multiple_of(3) {
                    0.05
                } else {
                    0.0
                },
                denoised: spec.seed.is_multiple_of(2),
            }),
        },
        camera: spec.seed.is_multiple_of(2).then_some(CameraInfo {
            position: [0.0, 1.0, 5.0],
            target: [0.0, 0.0, 0.0],
            up: [0.0, 1.0, 0.0],
            vfov_deg: 40.0,
        }),
        has_env_cube: spec.env,
    };
    let points: Vec<SamplePoint> = (0..spec.points)
        .map(|i| {
            let patch = (i % spec.patches.max(1)) as u32;
            SamplePoint {
                position: [rng.unit(), rng.unit(), rng.unit()],
                normal: [0.0, 0.0, 1.0],
                uv: [rng.unit(), rng.unit()],
                patch,
                object: u32::from(patch >= split),
            }
        })
        .collect();
    let texels = spec.patches * (spec.map_res as usize).pow(2);
    let indices = (0..texels)
        .map(|_| {
            let valid = (rng.next_u64() % 5) as usize;
            let valid = valid.min(spec.points);
            std::array::from_fn(|k| {
                if k < valid {
                    (rng.next_u64() % spec.points as u64) as u32
                } else {
                    INVALID_INDEX
                }
            })
        })
        .collect();
    let maps = SampleMaps {
        resolution: spec.map_res,
        indices,
    };
    let n = (spec.cube_res as usize).pow(2);
    let total = spec.points + usize::from(spec.env);
    let cubes = (0..total)
        .map(|_| CubeImage {
            resolution: spec.cube_res,
            faces: std::array::from_fn(|_| {
                (0..n)
                    .map(|_| {
                        let a = rng.hdr();
                        [a, a * rng.unit(), rng.hdr()]
                    })
                    .collect()
            }),
            distance: spec.distance.then(|| {
                std::array::from_fn(|_| {
                    (0..n)
                        .map(|_| {
                            if rng.next_u64().is_multiple_of(5) {
                                f32::MAX
                            } else {
                                rng.unit() * 10.0
                            }
                        })
                        .collect()
                })
            }),
        })
        .collect();
    Fixture {
        meta,
        points,
        maps,
        cubes,
    }
}

/// A fresh, unique path in a temp dir (the dir lives as long as the returned guard).
pub fn temp_store(name: &str) -> (tempfile::TempDir, PathBuf) {
    let dir = tempfile::tempdir().expect("tempdir");
    let path = dir.path().join(name);
    (dir, path)
}

/// Writes the fixture as a complete store at `path`.
pub fn write(path: &Path, f: &Fixture) -> StoreSummary {
    let mut w = StoreWriter::create(path, &f.meta, &f.points, &f.maps).expect("create");
    for (i, c) in f.cubes.iter().enumerate() {
        let (e, _) = encode_cube(c, &f.meta.bake, i as u32).expect("encode");
        w.append(e).expect("append");
    }
    w.finish().expect("finish")
}

/// The store at `path` as each of the three readers opens it: positioned reads, in memory and
/// memory-mapped.
pub fn each_reader(path: &Path) -> [Store; 3] {
    let bytes = std::fs::read(path).expect("read");
    [
        Store::open(path).expect("open"),
        Store::from_bytes(&bytes).expect("from_bytes"),
        Store::open_mapped(path).expect("open_mapped"),
    ]
}

/// Writes the fixture and returns the store's bytes.
pub fn store_bytes(spec: Spec) -> Vec<u8> {
    let f = fixture(spec);
    let (_dir, path) = temp_store("s.oslf");
    write(&path, &f);
    std::fs::read(&path).expect("read")
}

/// Relative error tolerance per encoding for a channel, relative to the texel's largest
/// channel (shared-exponent formats lose small channels) — see the crate docs.
pub fn close(enc: Encoding, want: [f32; 3], got: [f32; 3]) -> bool {
    close_bits(enc, 9, want, got)
}

/// [`close`] for a store keeping `bits` RGB9E5 mantissa bits: rounding to RGB9E5 (half a
/// mantissa step) plus quantization (`2^(9 − bits) − 1` steps at most, with clamping at the
/// top), where one step is at most `max / 256` (the largest channel's mantissa is ≥ 256 above
/// the smallest exponent) plus `2^−24` (the step of the smallest exponent).
pub fn close_bits(enc: Encoding, bits: u32, want: [f32; 3], got: [f32; 3]) -> bool {
    let max = want.iter().fold(0f32, |a, b| a.max(*b));
    let steps = f64::from(1u32 << (9 - bits.clamp(1, 9))) - 0.5;
    want.iter().zip(got).all(|(w, g)| {
        let err = (w - g).abs();
        match enc {
            Encoding::Rgba32f => err == 0.0,
            Encoding::Rgba16f => err <= w.abs() * 4.9e-4 + 6.0e-8,
            Encoding::Rgb9e5 => f64::from(err) <= steps * (f64::from(max) / 256.0 * 1.004 + 6.0e-8),
            // BC6H is lossy per 4×4 block, without a per-texel bound on arbitrary data: this only
            // checks the range; the round-trip tests compare BC6H faces with the reference
            // encoder and decoder instead (format/tests/bc6h.rs states the error bounds).
            Encoding::Bc6h => g.is_finite() && (0.0..=65504.0).contains(&g),
        }
    })
}

/// The distance planes a store with distance plane `plane` holds for a bake's `distance`:
/// each value on the plane's lattice.
pub fn stored_distances(
    plane: DistancePlane,
    distance: &Option<[Vec<f32>; 6]>,
) -> Option<[Vec<f32>; 6]> {
    distance
        .as_ref()
        .map(|d| std::array::from_fn(|f| d[f].iter().map(|v| plane.quantize(*v)).collect()))
}

/// The mesh object [`with_mesh`] adds: a bent quad of 5 vertices and 4 triangles over a 2×2
/// atlas (4 sample maps).
pub fn test_mesh() -> MeshInfo {
    let s = std::f32::consts::FRAC_1_SQRT_2;
    MeshInfo {
        atlas_grid: 2,
        positions: vec![
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [1.0, 1.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.5, 0.5, 0.3],
        ],
        normals: vec![
            [0.0, 0.0, 1.0],
            [0.0, 0.0, 1.0],
            [0.0, s, s],
            [0.0, 0.0, 1.0],
            [0.0, 0.0, 1.0],
        ],
        uvs: vec![[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0], [0.5, 0.5]],
        triangles: vec![[0, 1, 4], [1, 2, 4], [2, 3, 4], [3, 0, 4]],
    }
}

/// `f` (the fixture of `spec`) with a third object, a triangle mesh ([`test_mesh`]) owning 4
/// atlas pages after the Bézier patches, 3 sample points on its pages (with their cubes,
/// inserted before the environment cube) and sample maps for its pages.
pub fn with_mesh(mut f: Fixture, spec: Spec) -> Fixture {
    let mut rng = Rng(spec.seed.wrapping_mul(31) | 1);
    let first = spec.patches as u32;
    f.meta.objects.push(ObjectInfo {
        name: "mesh".into(),
        transform: [
            [2.0, 0.0, 0.0, 0.0],
            [0.0, 2.0, 0.0, 0.0],
            [0.0, 0.0, 2.0, 0.0],
            [0.0, 3.0, 0.0, 1.0],
        ],
        base_color: [0.3, 0.9, 0.4],
        first_patch: first,
        patch_count: 4,
        mesh: Some(test_mesh()),
        material: Default::default(),
        textures: None,
    });
    let object = (f.meta.objects.len() - 1) as u32;
    let old_points = f.points.len();
    for i in 0..3u32 {
        f.points.push(SamplePoint {
            position: [rng.unit(), 3.0 + rng.unit(), 0.1],
            normal: [0.0, 0.0, 1.0],
            uv: [rng.unit(), rng.unit()],
            patch: first + i,
            object,
        });
    }
    let total = f.points.len() as u64;
    let m2 = (spec.map_res as usize).pow(2);
    for _ in 0..4 * m2 {
        let valid = (rng.next_u64() % 5) as usize;
        f.maps.indices.push(std::array::from_fn(|k| {
            if k < valid {
                (rng.next_u64() % total) as u32
            } else {
                INVALID_INDEX
            }
        }));
    }
    // New cubes go after the old sample points' cubes, before the environment cube.
    let extra: Vec<CubeImage> = (0..3).map(|i| f.cubes[i % f.cubes.len()].clone()).collect();
    f.cubes.splice(old_points..old_points, extra);
    f
}

/// Whether Linux's `/proc/locks` lists a `flock` held by process `pid` (it does not in every
/// sandbox): where it does, a busy writer's message must name that process.
pub fn system_lists_flocks_of(pid: u32) -> bool {
    let pid = pid.to_string();
    std::fs::read_to_string("/proc/locks").is_ok_and(|locks| {
        locks.lines().any(|l| {
            let f: Vec<&str> = l.split_whitespace().collect();
            f.get(1) == Some(&"FLOCK") && f.get(4) == Some(&pid.as_str())
        })
    })
}
