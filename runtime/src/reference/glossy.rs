//! Ashikhmin–Shirley (chapter 5) and glTF's metallic-roughness BRDF by Monte Carlo. As
//! shade/glossy.wgsl, function for function.

use std::cmp::Ordering;
use std::f32::consts::PI;

use glam::{Vec2, Vec3};
use oslf_format::INVALID_INDEX;
use oslf_shading::fresnel::{schlick, schlick_weight};
use oslf_shading::ggx;
use oslf_shading::sh;

use super::blend::Candidates;
use super::depth::low_hit;
use super::random::filter_rows;
use super::{CubeTexels, Shader};

pub(super) struct AsSample {
    pub(super) l: Vec3,
    pub(super) weight: Vec3,
    /// log2(M p(l)).
    pub(super) lpdf: f32,
}

#[allow(clippy::needless_range_loop, clippy::neg_cmp_op_on_partial_ord)]
impl<C: CubeTexels> Shader<'_, C> {
    #[allow(clippy::too_many_arguments)]
    pub(super) fn sample_as(
        &self,
        xi1: f32,
        xi2: f32,
        n: Vec3,
        t: Vec3,
        b: Vec3,
        v: Vec3,
        nv: f32,
    ) -> AsSample {
        let u = &self.uniform;
        let q = ((xi1 * 4.0) as u32).min(3);
        let xq = xi1 * 4.0 - q as f32;
        let half_angle = 0.5 * PI * xq;
        let mut phi =
            ((u.nu + 1.0).sqrt() * half_angle.sin()).atan2((u.nv + 1.0).sqrt() * half_angle.cos());
        phi = match q {
            1 => PI - phi,
            2 => PI + phi,
            3 => 2.0 * PI - phi,
            _ => phi,
        };
        let (cp, sp) = (phi.cos(), phi.sin());
        let e = u.nu * cp * cp + u.nv * sp * sp;
        let cos_theta = (1.0 - xi2).powf(1.0 / (e + 1.0));
        let sin_theta = (1.0 - cos_theta * cos_theta).max(0.0).sqrt();
        let h = t * (sin_theta * cp) + b * (sin_theta * sp) + n * cos_theta;
        let vh = v.dot(h);
        let l = 2.0 * vh * h - v;
        // Eq. 5.8 and 5.11 as in shade.wgsl.
        let lpdf = (u.m as f32).log2() + 0.5 * ((u.nu + 1.0) * (u.nv + 1.0)).log2()
            - (2.0 * PI).log2()
            + e / (e + 1.0) * (1.0 - xi2).log2()
            - (4.0 * vh.max(1e-30)).log2();
        let nl = n.dot(l);
        let weight = if vh > 0.0 && nl > 0.0 {
            schlick(u.rs, vh) * nl / nv.max(nl)
        } else {
            0.0
        };
        AsSample {
            l,
            weight: Vec3::splat(weight),
            lpdf,
        }
    }

    /// glTF's GGX lobe: a visible normal drawn at (ξ1, ξ2) (Heitz 2018), `v` reflected about
    /// it.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn sample_ggx(
        &self,
        xi1: f32,
        xi2: f32,
        n: Vec3,
        t: Vec3,
        b: Vec3,
        v: Vec3,
        nv: f32,
        base: Vec3,
        pbr: Vec2,
    ) -> AsSample {
        let u = &self.uniform;
        let a = pbr.y;
        let a2 = a * a;
        let vl = Vec3::new(v.dot(t), v.dot(b), nv);
        // (ξ1, ξ2) = (φ/2π, r²) on the disc, as `filter_xi` lays its strata out.
        let hl = ggx::sample_visible_normal(vl, a, xi2, xi1);
        let h = t * hl.x + b * hl.y + n * hl.z;
        let vh = v.dot(h);
        let l = 2.0 * vh * h - v;
        let nl = n.dot(l);
        // D(h) with its denominator as α²(n·h)² + |n × h|² (exact at a narrow lobe's peak).
        let d = ggx::distribution_denominator(a2, hl.z, hl.x * hl.x + hl.y * hl.y);
        let g1v = ggx::smith_g1(a2, nv);
        // p(l) = G₁(v) D(h) / (4 n·v); the lookup reads PBR_LOD_BIAS levels off its share
        // (sample_lod's ½ log2(1 / (M p)), so 2·bias off log2(M p)).
        let lpdf = (u.m as f32).log2() + g1v.max(1e-30).log2() + a2.log2()
            - (PI * d * d).max(1e-30).log2()
            - (4.0 * nv.max(1e-30)).log2()
            - 2.0 * super::PBR_LOD_BIAS;
        let mut weight = Vec3::ZERO;
        if vh > 0.0 && nl > 0.0 && nv > 0.0 {
            // f ⟨n,l⟩ / p(l) = F(⟨v,h⟩) G₁(l): separable Smith, G = G₁(l) G₁(v).
            let g1l = ggx::smith_g1(a2, nl);
            let k5 = schlick_weight(vh);
            let metal = base + (Vec3::ONE - base) * k5;
            let dielectric = Vec3::splat(schlick(ggx::DIELECTRIC_F0, vh));
            weight = dielectric.lerp(metal, pbr.x) * g1l;
        }
        AsSample { l, weight, lpdf }
    }

    /// A cosine-weighted direction at (ξ1, r²) = (φ/2π, r²) on the disc, with weight 0:
    /// p(l) = ⟨n,l⟩ / π.
    fn cosine_sample(&self, xi1: f32, r2: f32, n: Vec3, t: Vec3, b: Vec3) -> AsSample {
        let phi = 2.0 * PI * xi1;
        let rad = r2.sqrt();
        let z = (1.0 - r2).max(0.0).sqrt();
        let l = t * (rad * phi.cos()) + b * (rad * phi.sin()) + n * z;
        let nl = n.dot(l);
        let lpdf = (self.uniform.m as f32).log2() + (nl.max(1e-30) / PI).log2();
        AsSample {
            l,
            weight: Vec3::ZERO,
            lpdf,
        }
    }

    /// glTF's diffuse base of a dielectric, cosine-weighted: f ⟨n,l⟩ / p(l) =
    /// (1 − metallic)(1 − F(⟨v,h⟩)) C.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn sample_pbr_diffuse(
        &self,
        xi1: f32,
        r2: f32,
        n: Vec3,
        t: Vec3,
        b: Vec3,
        v: Vec3,
        base: Vec3,
        pbr: Vec2,
    ) -> AsSample {
        let mut out = self.cosine_sample(xi1, r2, n, t, b);
        let h = (v + out.l).normalize_or(n);
        let fr = schlick(ggx::DIELECTRIC_F0, v.dot(h).abs());
        if n.dot(out.l) > 0.0 && n.dot(v) > 0.0 {
            out.weight = base * ((1.0 - pbr.x) * (1.0 - fr));
        }
        out
    }

    #[allow(clippy::too_many_arguments)]
    pub(super) fn sample_diffuse(
        &self,
        xi1: f32,
        r2: f32,
        n: Vec3,
        t: Vec3,
        b: Vec3,
        nv: f32,
    ) -> AsSample {
        let u = &self.uniform;
        let mut out = self.cosine_sample(xi1, r2, n, t, b);
        let nl = n.dot(out.l);
        let fv = 1.0 - (1.0 - 0.5 * nv.max(0.0)).powf(5.0);
        let fl = 1.0 - (1.0 - 0.5 * nl.max(0.0)).powf(5.0);
        if nl > 0.0 {
            out.weight = Vec3::splat(28.0 / 23.0 * u.rd * (1.0 - u.rs) * fv * fl);
            // Eq. 5.4 × π
        }
        out
    }

    /// The radiance of sample `s` for the shaded point `x` from `cube` (or, per direction,
    /// `cube` = INVALID, the blend, `low_hit`s for x's normal `n` left out), as
    /// `sample_radiance`; `fresh` and `seed` as `depth_iterate`. `None` when a face was not
    /// available.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn sample_radiance(
        &self,
        c: &Candidates,
        cube: u32,
        wn: [f32; 4],
        x: Vec3,
        n: Vec3,
        s: &AsSample,
        fresh: bool,
        seed: &mut f32,
    ) -> Option<Vec3> {
        let u = &self.uniform;
        let lod = self.sample_lod(s.l, s.lpdf);
        if u.order == 1 && cube == INVALID_INDEX {
            let w = if u.blend != 4 {
                self.blend_weights(c, s.l)
            } else {
                wn
            };
            return Some(
                self.blend_read(c, w, x, s.l, lod, Some(n))
                    .unwrap_or_else(|| self.env_read(x, s.l, lod)),
            );
        }
        let d = if cube == u.env_cube {
            self.env_dir(x, s.l)
        } else if u.depth_steps > 0 {
            self.depth_iterate(cube, x, s.l, fresh, seed)
        } else {
            s.l
        };
        self.read_dir(cube, d, lod)
    }

    /// Cube `cube` towards `d` at mip level `lod` (with mips; else level 0), as `read_dir`.
    fn read_dir(&self, cube: u32, d: Vec3, lod: f32) -> Option<Vec3> {
        if self.uniform.mip_levels > 1 {
            self.lookup_levels(cube, d, lod)
        } else {
            self.lookup(cube, d)
        }
    }

    /// The specular sample of the mode: Ashikhmin–Shirley, or glTF's GGX with terms & 16.
    #[allow(clippy::too_many_arguments)]
    fn sample_spec(
        &self,
        xi1: f32,
        xi2: f32,
        n: Vec3,
        t: Vec3,
        b: Vec3,
        v: Vec3,
        nv: f32,
        base: Vec3,
        pbr: Vec2,
    ) -> AsSample {
        if self.uniform.terms & 16 != 0 {
            return self.sample_ggx(xi1, xi2, n, t, b, v, nv, base, pbr);
        }
        self.sample_as(xi1, xi2, n, t, b, v, nv)
    }

    /// The diffuse sample of the mode: the term 5.4, or glTF's diffuse base with terms & 16.
    #[allow(clippy::too_many_arguments)]
    fn sample_diff(
        &self,
        xi1: f32,
        xi2: f32,
        n: Vec3,
        t: Vec3,
        b: Vec3,
        v: Vec3,
        nv: f32,
        base: Vec3,
        pbr: Vec2,
    ) -> AsSample {
        if self.uniform.terms & 16 != 0 {
            return self.sample_pbr_diffuse(xi1, xi2, n, t, b, v, base, pbr);
        }
        self.sample_diffuse(xi1, xi2, n, t, b, nv)
    }

    /// Per point visible, the candidate whose cube sample `s` of candidate `k` (cube `cube`)
    /// reads (as `stand_in`).
    pub(super) fn stand_in(
        &self,
        c: &Candidates,
        k: u32,
        cube: u32,
        w: [f32; 4],
        x: Vec3,
        s: &AsSample,
    ) -> u32 {
        let o = |cube: u32| x - self.samples[cube as usize];
        if cube == self.uniform.env_cube || !self.depth_hidden(cube, o(cube), s.l) {
            return k;
        }
        heaviest_other(c, k, w, |other| {
            (!self.depth_hidden(other, o(other), s.l)).then_some(())
        })
        .map_or(k, |(j, ())| j)
    }

    /// Per point searched, where sample `s` of candidate `k` (cube `cube`) is read, as
    /// `searched`: the candidate whose cube is read and the direction from its point; `None`
    /// for a hit lower above x's tangent plane (normal `n`) than LOW_HIT times the point's
    /// distance from x, which is read as per point reads it.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn searched(
        &self,
        c: &Candidates,
        k: u32,
        cube: u32,
        w: [f32; 4],
        x: Vec3,
        n: Vec3,
        s: &AsSample,
    ) -> Option<(u32, Vec3)> {
        let p = self.samples[cube as usize];
        let (d, seen) = self.depth_search(cube, x, s.l);
        if low_hit(p, (d, seen), x, s.l, n) {
            return None;
        }
        if seen >= 0.0 {
            return Some((k, d));
        }
        heaviest_other(c, k, w, |other| {
            let (d, seen) = self.depth_search(other, x, s.l);
            (seen >= 0.0).then_some(d)
        })
        .or(Some((k, d)))
    }

    #[allow(clippy::too_many_arguments)]
    pub(super) fn integrate(
        &self,
        c: &Candidates,
        cube: u32,
        j: u32,
        pixel: u32,
        x: Vec3,
        n: Vec3,
        t: Vec3,
        b: Vec3,
        v: Vec3,
        nv: f32,
        base: Vec3,
        pbr: Vec2,
        w: [f32; 4],
    ) -> (Vec3, bool) {
        let u = &self.uniform;
        let diffuse = u.has_diffuse() && !u.reads_irradiance();
        let mut acc = Vec3::ZERO;
        let mut ok = true;
        let wn = self.blend_weights(c, n);
        // Per kind of sample (specular, diffuse): `depth_iterate`'s seed, and whether the row
        // has had its fresh sample (its first one above the surface).
        let mut seed = [0.0f32; 2];
        let mut fresh = [true; 2];
        let rows = filter_rows(u.m, u.mip_levels > 1);
        for i in 0..u.m {
            if i % rows == 0 {
                fresh = [true; 2];
            }
            for k in 0..2 {
                if k == 1 && !diffuse {
                    continue;
                }
                let [x1, x2] = self.sample_xi(pixel, i, j, 2 * k);
                let s = if k == 0 {
                    self.sample_spec(x1, x2, n, t, b, v, nv, base, pbr)
                } else {
                    self.sample_diff(x1, x2, n, t, b, v, nv, base, pbr)
                };
                if !(s.weight.max_element() > 0.0) {
                    continue;
                }
                let seen = if u.order == 3 && u.depth_steps > 0 && cube != u.env_cube {
                    self.searched(c, j, cube, w, x, n, &s)
                } else {
                    None
                };
                if let Some((e, d)) = seen {
                    let read = if e == j { cube } else { c.idx[e as usize] };
                    let li = self.read_dir(read, d, self.sample_lod(s.l, s.lpdf));
                    acc += li.unwrap_or_else(|| {
                        ok = false;
                        Vec3::ZERO
                    }) * s.weight;
                    continue;
                }
                // A hidden sample reads its stand-in as a fresh one, leaving this row's seed.
                let e = if u.order == 2 && u.depth_steps > 0 {
                    self.stand_in(c, j, cube, w, x, &s)
                } else {
                    j
                };
                let own = e == j;
                let (read, fresh_e) = if own {
                    (cube, fresh[k as usize])
                } else {
                    (c.idx[e as usize], true)
                };
                let mut seed_e = if own { seed[k as usize] } else { 0.0 };
                let li = self
                    .sample_radiance(c, read, wn, x, n, &s, fresh_e, &mut seed_e)
                    .unwrap_or_else(|| {
                        ok = false;
                        Vec3::ZERO
                    });
                if own {
                    seed[k as usize] = seed_e;
                    fresh[k as usize] = false;
                }
                acc += li * s.weight;
            }
        }
        (acc / u.m.max(1) as f32, ok)
    }

    /// Cube `cube`'s stored spherical-harmonic coefficients.
    fn cube_sh(&self, cube: u32) -> [Vec3; 9] {
        self.irradiance
            .get(cube as usize)
            .copied()
            .unwrap_or([Vec3::ZERO; 9])
    }

    /// The diffuse part read from the stored irradiance (shade/glossy.wgsl).
    fn diffuse_irradiance(
        &self,
        c: &Candidates,
        use_env: bool,
        n: Vec3,
        nv: f32,
        base: Vec3,
        pbr: Vec2,
    ) -> Vec3 {
        let u = &self.uniform;
        let bands = if u.terms & 16 != 0 {
            sh::COSINE
        } else {
            sh::AS_DIFFUSE
        };
        let mut e = Vec3::ZERO;
        let mut wsum = 0.0;
        if !use_env {
            let w = self.blend_weights(c, n);
            for k in 0..4 {
                if w[k] > 0.0 && c.idx[k] != INVALID_INDEX {
                    e += sh::convolve(&self.cube_sh(c.idx[k]), bands, n) * w[k];
                    wsum += w[k];
                }
            }
        }
        if wsum > 0.0 {
            e /= wsum;
        } else if u.env_cube != INVALID_INDEX {
            e = sh::convolve(&self.cube_sh(u.env_cube), bands, n);
        }
        if u.terms & 16 != 0 {
            if !(nv > 0.0) {
                return Vec3::ZERO;
            }
            return e
                * base
                * ((1.0 - pbr.x) * (1.0 - ggx::DIELECTRIC_F0) * sh::fresnel_cosine_weight(nv));
        }
        let fv = 1.0 - (1.0 - 0.5 * nv.max(0.0)).powf(5.0);
        e * (28.0 / 23.0 * u.rd * (1.0 - u.rs) * fv) // Eq. 5.4 × π
    }

    #[allow(clippy::too_many_arguments)]
    pub(super) fn glossy(
        &self,
        c: &Candidates,
        pixel: u32,
        x: Vec3,
        n: Vec3,
        t: Vec3,
        v: Vec3,
        r: Vec3,
        base: Vec3,
        pbr: Vec2,
    ) -> Vec3 {
        let u = &self.uniform;
        if u.split_sum != 0 {
            return self.split_sum(x, n, v, r, base, pbr);
        }
        let b = n.cross(t);
        let nv = n.dot(v);
        let use_env = u.source != 0 || c.count == 0;
        let diffuse = if u.reads_irradiance() {
            self.diffuse_irradiance(c, use_env, n, nv, base, pbr)
        } else {
            Vec3::ZERO
        };
        if use_env {
            if u.env_cube == INVALID_INDEX {
                return diffuse;
            }
            return self
                .integrate(
                    c, u.env_cube, 4, pixel, x, n, t, b, v, nv, base, pbr, [0.0; 4],
                )
                .0
                + diffuse;
        }
        if u.order == 1 {
            return self
                .integrate(
                    c,
                    INVALID_INDEX,
                    4,
                    pixel,
                    x,
                    n,
                    t,
                    b,
                    v,
                    nv,
                    base,
                    pbr,
                    [0.0; 4],
                )
                .0
                + diffuse;
        }
        let axis = if u.blend == 4 { n } else { r };
        let w = self.blend_weights(c, axis);
        let mut acc = Vec3::ZERO;
        let mut wsum = 0.0;
        for j in 0..4 {
            if w[j] > 0.0 {
                let (est, ok) = self.integrate(
                    c, c.idx[j], j as u32, pixel, x, n, t, b, v, nv, base, pbr, w,
                );
                if ok {
                    acc += est * w[j];
                    wsum += w[j];
                }
            }
        }
        if wsum > 0.0 {
            return acc / wsum + diffuse;
        }
        if u.env_cube == INVALID_INDEX {
            return diffuse;
        }
        self.integrate(
            c, u.env_cube, 4, pixel, x, n, t, b, v, nv, base, pbr, [0.0; 4],
        )
        .0 + diffuse
    }
}

/// The candidate other than `k` of largest weight `w` (its first in index order on a tie) for
/// which `pick` of its cube gives a value, with that value: `stand_in`'s and `searched`'s loop.
fn heaviest_other<T>(
    c: &Candidates,
    k: u32,
    w: [f32; 4],
    mut pick: impl FnMut(u32) -> Option<T>,
) -> Option<(u32, T)> {
    let mut best = None;
    let mut best_w = 0.0f32;
    for (j, (&other, &wj)) in (0u32..).zip(c.idx.iter().zip(&w)) {
        if j == k || other == INVALID_INDEX || wj.partial_cmp(&best_w) != Some(Ordering::Greater) {
            continue;
        }
        if let Some(t) = pick(other) {
            best = Some((j, t));
            best_w = wj;
        }
    }
    best
}
