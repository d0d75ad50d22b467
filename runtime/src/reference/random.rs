//! Random numbers: the PCG hash (Jarzynski & Olano 2020) and the glossy samples' (ξ1, ξ2). As shade/random.wgsl, function for function.

use std::f32::consts::PI;

use super::{CubeTexels, Shader};

/// PCG hash (Jarzynski & Olano 2020), as `pcg` in shade.wgsl.
pub fn pcg(v: u32) -> u32 {
    let state = v.wrapping_mul(747796405).wrapping_add(2891336453);
    let word = ((state >> ((state >> 28) + 4)) ^ state).wrapping_mul(277803737);
    (word >> 22) ^ word
}

pub(super) fn rand(pixel: u32, i: u32, j: u32, k: u32) -> f32 {
    let h = pcg(pixel.wrapping_add(pcg(i.wrapping_add(pcg(j.wrapping_mul(8).wrapping_add(k))))));
    (h >> 8) as f32 * (1.0 / 16777216.0)
}

#[allow(clippy::needless_range_loop, clippy::neg_cmp_op_on_partial_ord)]
impl<C: CubeTexels> Shader<'_, C> {
    /// (ξ1, ξ2) of sample `i` of integration `j`, numbers `k` and `k + 1` (as `sample_xi`):
    /// random with ξ1 stratified, or when filtering the fixed set [`filter_xi`] (integration
    /// j's spiral for the pbr mode's GGX samples, k = 0).
    pub(super) fn sample_xi(&self, pixel: u32, i: u32, j: u32, k: u32) -> [f32; 2] {
        let m = self.uniform.m;
        if self.uniform.mip_levels > 1 {
            return filter_xi(i, m, self.uniform.terms & 16 != 0 && k == 0, j);
        }
        [
            (i as f32 + rand(pixel, i, j, k)) / m as f32,
            rand(pixel, i, j, k + 1),
        ]
    }
}

/// (ξ1, ξ2) of filtered glossy sample `i` of `m` (as `filter_xi`): for m = n² the centres of
/// an n × n grid of strata through Shirley & Chiu's concentric map to the disc, as polar
/// coordinates (ξ1 = φ/2π, ξ2 = r²), so that each sample's cell is compact; else the
/// Hammersley set. With `spiral` (the pbr mode's GGX samples) the golden-angle spiral of
/// integration `j`: ξ1 = frac(i (2 − φ) + t), ξ2 = (i + ½ + s)/m, every sample on a radius of
/// its own; candidate j < 4 of a per-point integration turns it by t = j/4 and moves its radii
/// by s = j/4 − 3/8 of a stratum, so that the four candidates' sets interleave into one of 4m
/// directions (the blend of their estimates then integrates the lobe at 4m points for the
/// lookups of m); integration 4 (the blend per direction, the environment) t = s = 0.
pub fn filter_xi(i: u32, m: u32, spiral: bool, j: u32) -> [f32; 2] {
    if spiral {
        let (t, s) = if j < 4 {
            (0.25 * j as f32, 0.25 * j as f32 - 0.375)
        } else {
            (0.0, 0.0)
        };
        let g = i as f32 * 0.381_966_02 + t;
        return [g - g.floor(), (i as f32 + 0.5 + s) / m as f32];
    }
    let n = (m as f32).sqrt().round() as u32;
    if n * n != m {
        return [
            (i as f32 + 0.5) / m as f32,
            i.reverse_bits() as f32 * 2.328_306_4e-10,
        ];
    }
    let a = 2.0 * ((i % n) as f32 + 0.5) / n as f32 - 1.0;
    let b = 2.0 * ((i / n) as f32 + 0.5) / n as f32 - 1.0;
    if a == 0.0 && b == 0.0 {
        return [0.0, 0.0]; // the centre cell of an odd n
    }
    let (mut r, mut phi) = if a.abs() > b.abs() {
        (a, 0.25 * PI * (b / a))
    } else {
        (b, 0.5 * PI - 0.25 * PI * (a / b))
    };
    if r < 0.0 {
        r = -r;
        phi += PI;
    }
    let x1 = phi * (0.5 / PI);
    [x1 - x1.floor(), r * r]
}

/// Samples per row of the filtered set of `m` (as `filter_rows`): n for m = n² when
/// `filtered`, else 1.
pub fn filter_rows(m: u32, filtered: bool) -> u32 {
    let n = (m as f32).sqrt().round() as u32;
    if filtered && n > 0 && n * n == m {
        n
    } else {
        1
    }
}

#[cfg(test)]
mod tests {
    use super::filter_xi;

    /// The pbr mode's filtered GGX samples are the golden-angle spiral: sample i on the radius of its
    /// own equal-area ring, ξ2 = (i + ½)/M, and the angles spread evenly, every eighth of the
    /// circle holding M/8 of them give or take two.
    #[test]
    fn the_pbr_modes_filtered_samples_are_a_golden_angle_spiral() {
        for m in [4u32, 15, 16, 64, 256] {
            let mut sectors = [0u32; 8];
            for i in 0..m {
                let [x1, x2] = filter_xi(i, m, true, 4);
                assert!((0.0..1.0).contains(&x1), "{m} {i}: ξ1 {x1}");
                assert_eq!(x2, (i as f32 + 0.5) / m as f32);
                sectors[(x1 * 8.0) as usize] += 1;
            }
            if m >= 16 {
                for s in sectors {
                    assert!(s.abs_diff(m / 8) <= 2, "M {m}: sectors {sectors:?}");
                }
            }
        }
    }

    /// The four candidates' spirals interleave: together they put one radius in each of 4M
    /// equal-area rings, each candidate's own set still one per ring of M and spread over the
    /// circle, and the samples of one ring across candidates turned a quarter apart.
    #[test]
    fn the_candidates_spirals_interleave() {
        for m in [4u32, 16, 64] {
            let mut rings = vec![0u32; 4 * m as usize];
            for j in 0..4 {
                let mut sectors = [0u32; 4];
                for i in 0..m {
                    let [x1, x2] = filter_xi(i, m, true, j);
                    assert!((0.0..1.0).contains(&x1) && (0.0..1.0).contains(&x2));
                    assert_eq!((x2 * m as f32) as u32, i, "M {m} candidate {j} sample {i}");
                    rings[(x2 * 4.0 * m as f32) as usize] += 1;
                    sectors[(x1 * 4.0) as usize] += 1;
                    let [y1, _] = filter_xi(i, m, true, 4);
                    let turn = (x1 - y1).rem_euclid(1.0);
                    let off = (turn - 0.25 * j as f32).abs();
                    assert!(
                        !(1e-5..=1.0 - 1e-5).contains(&off),
                        "M {m} candidate {j}: turned {turn}"
                    );
                }
                assert!(
                    sectors.iter().all(|&s| s.abs_diff(m / 4) <= 1),
                    "M {m} candidate {j}: {sectors:?}"
                );
            }
            assert!(rings.iter().all(|&r| r == 1), "M {m}: {rings:?}");
        }
    }
}
