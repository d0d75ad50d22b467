//! The environment cube prefiltered the way engines light a glossy object from one probe (the
//! split-sum approximation, Karis 2013, "Real Shading in Unreal Engine 4"): the baseline of
//! the pbr mode that [`crate::GlossyFilter::SplitSum`] shades with.
//!
//! - **Specular levels**: level `k` of `L = log2(n) − 1` ([`specular_levels`], n the cube's
//!   resolution; down to 4 texels a side) holds, at `n >> k` texels a side, the environment convolved with the GGX lobe of perceptual
//!   roughness `r_k = k / (L − 1)` under the split sum's assumption n = v = r: for each texel's
//!   direction `r`, Σ L(l) ⟨r,l⟩ / Σ ⟨r,l⟩ over [`SPECULAR_SAMPLES`] half-vectors drawn from
//!   D(h)⟨r,h⟩ (Hammersley points), each read at the mip level whose texels subtend its share
//!   of the lobe (filtered importance sampling, as the runtime's glossy samples). Level 0 is the
//!   cube itself (roughness 0: a mirror).
//! - **Irradiance**: the cube convolved with the cosine lobe, ∫ L(l) max(⟨n,l⟩, 0) dl / π, at
//!   `n` texels a side, summed exactly over the texels of the cube's
//!   [`IRRADIANCE_SOURCE`]-texel level: what a Lambertian surface of albedo 1 reflects.
//!
//! The shader reads level `roughness · (L − 1)` between the two nearest levels, bilinear
//! across face edges (shade/split_sum.wgsl; its CPU twin reference/split_sum.rs), and scales it
//! by the split sum's second factor, the GGX BRDF's directional albedo, from the analytic fit
//! engines use (Karis 2014, "Physically Based Shading on Mobile"). Everything here is
//! deterministic and independent of the thread count.

use glam::Vec3;
use oslf_format::cube::{face_st_to_direction, CubeImage, FACES};
use oslf_shading::ggx;
use rayon::prelude::*;

use crate::reference::{face_st, seam_bilinear, seam_taps, PrefilteredTexels};

/// GGX samples per texel of a specular level.
pub const SPECULAR_SAMPLES: u32 = 256;

/// Texels a side of the cube level the irradiance is summed over (or the cube's own
/// resolution, when smaller).
pub const IRRADIANCE_SOURCE: u32 = 8;

/// The prefiltered environment: specular levels and irradiance, each six faces of RGB texels,
/// row 0 first (as [`CubeImage`]).
#[derive(Clone, Debug, PartialEq)]
pub struct PrefilteredEnv {
    /// The cube's resolution `n` (level 0's, and the irradiance's).
    pub resolution: u32,
    /// Per level `k`, per face, `max(n >> k, 1)²` texels.
    pub specular: Vec<[Vec<Vec3>; FACES]>,
    /// Per face, `n²` texels: irradiance ÷ π.
    pub irradiance: [Vec<Vec3>; FACES],
}

/// Texels a side of level `k` of a cube of resolution `n`.
pub fn level_size(n: u32, k: u32) -> u32 {
    (n >> k).max(1)
}

/// Mip levels of a cube of resolution `n`: down to one texel.
pub fn level_count(n: u32) -> u32 {
    32 - n.max(1).leading_zeros()
}

/// Specular levels of a cube of resolution `n`: down to 4 texels a side (the roughest lobe
/// still varies across a face; 8 → 2 levels, 32 → 4, 64 → 5), or 1.
pub fn specular_levels(n: u32) -> u32 {
    level_count(n).saturating_sub(2).max(1)
}

impl PrefilteredEnv {
    /// Prefilters `cube` (see the [module documentation](self)).
    pub fn new(cube: &CubeImage) -> PrefilteredEnv {
        let n = cube.resolution.max(1);
        let mips = mip_chain(cube);
        let levels = specular_levels(n);
        let specular = (0..levels)
            .map(|k| {
                if k == 0 {
                    return mips[0].clone();
                }
                let roughness = k as f32 / (levels - 1) as f32;
                face_map(level_size(n, k), |dir| ggx_convolve(&mips, dir, roughness))
            })
            .collect();
        let source = mips
            .iter()
            .find(|level| level_side(level) <= IRRADIANCE_SOURCE)
            .unwrap_or(&mips[0]);
        let irradiance = face_map(n, |dir| cosine_convolve(source, dir));
        PrefilteredEnv {
            resolution: n,
            specular,
            irradiance,
        }
    }

    /// A one-texel black environment: what the shader binds when no split sum is drawn.
    pub fn black() -> PrefilteredEnv {
        let face = || std::array::from_fn(|_| vec![Vec3::ZERO]);
        PrefilteredEnv {
            resolution: 1,
            specular: vec![face()],
            irradiance: face(),
        }
    }

    /// The texels of mip `level` as the shader's texture holds them: 12 layers (the specular
    /// faces, then the irradiance's; black above level 0), `max(n >> level, 1)²` RGBA texels
    /// each.
    pub fn texture_level(&self, level: u32) -> Vec<[f32; 4]> {
        let side = level_size(self.resolution, level);
        (0..2 * FACES)
            .flat_map(|layer| {
                (0..side * side).map(move |i| {
                    let c = self.texel(layer >= FACES, layer % FACES, level, i % side, i / side);
                    [c.x, c.y, c.z, 1.0]
                })
            })
            .collect()
    }
}

impl PrefilteredTexels for PrefilteredEnv {
    fn levels(&self) -> u32 {
        self.specular.len() as u32
    }
    fn side(&self, level: u32) -> u32 {
        level_size(self.resolution, level)
    }
    fn texel(&self, irradiance: bool, face: usize, level: u32, x: u32, y: u32) -> Vec3 {
        let faces = if irradiance {
            (level == 0).then_some(&self.irradiance)
        } else {
            self.specular.get(level as usize)
        };
        let side = level_size(self.resolution, level);
        match faces {
            Some(f) if x < side && y < side => f[face][(y * side + x) as usize],
            _ => Vec3::ZERO,
        }
    }
}

/// Side of a level's faces.
fn level_side(level: &[Vec<Vec3>; FACES]) -> u32 {
    (level[0].len() as f64).sqrt() as u32
}

/// The cube's mip chain: level 0 as given, each next [`crate::face::downsample`] of the one
/// before (the tent weighted by solid angle, as the mips the runtime's glossy samples read).
fn mip_chain(cube: &CubeImage) -> Vec<[Vec<Vec3>; FACES]> {
    let n = cube.resolution.max(1);
    let mut chain: Vec<[Vec<[f32; 3]>; FACES]> = vec![cube.faces.clone()];
    for k in 1..level_count(n) {
        let prev = level_size(n, k - 1);
        let next =
            std::array::from_fn(|f| crate::face::downsample(&chain[k as usize - 1][f], prev));
        chain.push(next);
    }
    chain
        .into_iter()
        .map(|level| level.map(|face| face.into_iter().map(Vec3::from_array).collect()))
        .collect()
}

/// Six faces of `side²` texels, each `f` of its centre's unit direction; in parallel.
fn face_map(side: u32, f: impl Fn(Vec3) -> Vec3 + Sync) -> [Vec<Vec3>; FACES] {
    std::array::from_fn(|face| {
        (0..side * side)
            .into_par_iter()
            .map(|i| {
                let s = ((i % side) as f32 + 0.5) / side as f32;
                let t = ((i / side) as f32 + 0.5) / side as f32;
                f(Vec3::from_array(face_st_to_direction(face, s, t)).normalize())
            })
            .collect()
    })
}

/// `level` towards `dir`, bilinear across face edges (reference/seams.rs's taps: texels off
/// the face from the adjacent face, a cube corner's missing texel the mean of the other three).
fn seamless(level: &[Vec<Vec3>; FACES], dir: Vec3) -> Vec3 {
    let n = level_side(level) as i32;
    let taps = seam_taps(face_st(dir), n);
    let texels = taps.c.map(|(f, (x, y))| level[f][(y * n + x) as usize]);
    seam_bilinear(&taps, texels)
}

/// Trilinear: [`seamless`] on the two levels around `lod`.
fn trilinear(mips: &[[Vec<Vec3>; FACES]], dir: Vec3, lod: f32) -> Vec3 {
    let top = (mips.len() - 1) as f32;
    let l = lod.clamp(0.0, top);
    let l0 = l.floor() as usize;
    let a = seamless(&mips[l0], dir);
    if l0 as f32 >= top {
        return a;
    }
    a.lerp(seamless(&mips[l0 + 1], dir), l - l0 as f32)
}

/// The `i`-th of `count` Hammersley points.
fn hammersley(i: u32, count: u32) -> (f32, f32) {
    (
        i as f32 / count as f32,
        i.reverse_bits() as f32 / 4_294_967_296.0,
    )
}

/// The environment around `r` convolved with GGX at `roughness`, n = v = r.
fn ggx_convolve(mips: &[[Vec<Vec3>; FACES]], r: Vec3, roughness: f32) -> Vec3 {
    let a = ggx::alpha(roughness);
    let a2 = a * a;
    let (t, b) = r.any_orthonormal_pair();
    let n = level_side(&mips[0]) as f32;
    // Solid angle of a level-0 texel (on average over the sphere).
    let texel = 4.0 * std::f32::consts::PI / (6.0 * n * n);
    let (mut sum, mut weight) = (Vec3::ZERO, 0.0);
    for i in 0..SPECULAR_SAMPLES {
        let (xi1, xi2) = hammersley(i, SPECULAR_SAMPLES);
        let phi = 2.0 * std::f32::consts::PI * xi1;
        let cos_h = ggx::sample_distribution_cos(a2, xi2);
        let sin_h = (1.0 - cos_h * cos_h).max(0.0).sqrt();
        let h = t * (sin_h * phi.cos()) + b * (sin_h * phi.sin()) + r * cos_h;
        let l = 2.0 * r.dot(h) * h - r;
        let nl = r.dot(l);
        if nl <= 0.0 {
            continue;
        }
        // p(l) = D(h) ⟨n,h⟩ / (4 ⟨v,h⟩) = D(h) / 4 with n = v.
        let d = ggx::distribution(a2, cos_h, sin_h * sin_h);
        let sample = 1.0 / (SPECULAR_SAMPLES as f32 * d * 0.25).max(1e-30);
        let lod = 0.5 * (sample / texel).log2();
        sum += trilinear(mips, l, lod) * nl;
        weight += nl;
    }
    if weight > 0.0 {
        sum / weight
    } else {
        seamless(&mips[0], r)
    }
}

/// ∫ L(l) max(⟨n,l⟩, 0) dl / π over the texels of `level`.
fn cosine_convolve(level: &[Vec<Vec3>; FACES], n: Vec3) -> Vec3 {
    let side = level_side(level);
    let mut sum = Vec3::ZERO;
    for (face, texels) in level.iter().enumerate() {
        for (i, &c) in texels.iter().enumerate() {
            let s = ((i as u32 % side) as f32 + 0.5) / side as f32;
            let t = ((i as u32 / side) as f32 + 0.5) / side as f32;
            let d = Vec3::from_array(face_st_to_direction(face, s, t));
            // A texel's solid angle: its area on the unit-distance face, (2/side)², over |p|³
            // for p its centre on that face.
            let p = d / d.abs().max_element();
            let len = p.length();
            let omega = (2.0 / side as f32).powi(2) / (len * len * len);
            sum += c * (n.dot(p / len).max(0.0) * omega);
        }
    }
    sum / std::f32::consts::PI
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cube(n: u32, f: impl Fn(Vec3) -> Vec3) -> CubeImage {
        let mut c = CubeImage::black(n, false);
        for face in 0..FACES {
            for i in 0..n * n {
                let s = ((i % n) as f32 + 0.5) / n as f32;
                let t = ((i / n) as f32 + 0.5) / n as f32;
                let d = Vec3::from_array(face_st_to_direction(face, s, t)).normalize();
                c.faces[face][i as usize] = f(d).to_array();
            }
        }
        c
    }

    #[test]
    fn a_uniform_environment_stays_uniform() {
        // The white furnace: every level and the irradiance of a constant sky are that
        // constant (the irradiance's texel solid angles sum to 4π within 0.5 %).
        let p = PrefilteredEnv::new(&cube(16, |_| Vec3::new(0.5, 1.0, 2.0)));
        assert_eq!(p.specular.len(), 3);
        for (k, level) in p.specular.iter().enumerate() {
            assert_eq!(level[0].len(), (level_size(16, k as u32) as usize).pow(2));
            for c in level.iter().flatten() {
                assert!(
                    (*c - Vec3::new(0.5, 1.0, 2.0)).abs().max_element() < 1e-4,
                    "{k}: {c}"
                );
            }
        }
        for c in p.irradiance.iter().flatten() {
            assert!(
                (*c / Vec3::new(0.5, 1.0, 2.0) - 1.0).abs().max_element() < 5e-3,
                "{c}"
            );
        }
    }

    #[test]
    fn levels_blur_with_roughness_and_irradiance_follows_the_cosine() {
        // A sky bright above (+z) and dark below: level 0 is the cube; the horizon's contrast
        // falls level by level; the irradiance ÷ π of L = 1 + z is 1 + 2/3 facing up
        // (∫ cos θ + cos² θ over the hemisphere, ÷ π) and 1 facing sideways (z is odd there).
        let n = 32;
        let src = cube(n, |d| Vec3::splat(1.0 + d.z));
        let p = PrefilteredEnv::new(&src);
        assert_eq!(
            p.specular[0][4],
            src.faces[4]
                .iter()
                .map(|&c| Vec3::from_array(c))
                .collect::<Vec<_>>()
        );
        let contrast = |k: usize| {
            let level = &p.specular[k];
            seamless(level, Vec3::Z).x - seamless(level, -Vec3::Z).x
        };
        // Level by level while a face has texels enough to resolve the poles (four a side).
        for k in 1..p.specular.len() {
            if level_size(n, k as u32) >= 4 {
                assert!(contrast(k) < contrast(k - 1), "level {k}: {}", contrast(k));
            }
        }
        assert!(contrast(p.specular.len() - 1) < 0.8 * contrast(0));
        let centre = (n / 2 * n + n / 2) as usize;
        let up = p.irradiance[4][centre].x;
        let side = p.irradiance[0][centre].x;
        assert!((up - 5.0 / 3.0).abs() < 0.02, "{up}");
        assert!((side - 1.0).abs() < 0.02, "{side}");
    }

    #[test]
    fn the_same_cube_gives_the_same_levels() {
        let src = cube(8, |d| Vec3::new(d.x.max(0.0), 1.0 + d.y, d.z * d.z));
        assert_eq!(PrefilteredEnv::new(&src), PrefilteredEnv::new(&src));
    }
}
