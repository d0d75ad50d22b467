//! Depth-corrected lookups (§6.3's RGBZ). As shade/depth.wgsl, function for function.

use std::f32::consts::PI;
use std::sync::atomic::Ordering;

use glam::Vec3;

use super::cube::{face_st, Tap};
use super::{CubeTexels, Shader, DEPTH_ITERATIONS, DEPTH_REFINE, LOOKUP_AGREE, LOW_HIT};
use crate::face::FAR_DISTANCE;

#[allow(clippy::needless_range_loop, clippy::neg_cmp_op_on_partial_ord)]
impl<C: CubeTexels> Shader<'_, C> {
    /// Distance from sample point `cube` to the first hit towards `d` (nearest texel), marking
    /// the face (every face when it is not available and `walk`); sets `missing` then (as
    /// `depth_toward`).
    pub(super) fn depth_toward(&self, cube: u32, d: Vec3, walk: bool, missing: &mut bool) -> f32 {
        let (face, s, t) = face_st(d);
        self.mark(cube, face);
        let n = self.uniform.cube_res;
        let x = ((s * n as f32) as u32).min(n - 1);
        let y = ((t * n as f32) as u32).min(n - 1);
        self.cubes.depth(cube, face, x, y).unwrap_or_else(|| {
            if let Some(f) = self.feedback.get(cube as usize).filter(|_| walk) {
                f.fetch_or(63, Ordering::Relaxed);
            }
            *missing = true;
            FAR_DISTANCE
        })
    }

    /// The ray point at inverse distance `w` seen from `p`: its offset from `p` and
    /// |q − p| − D_p (as `depth_probe`).
    #[allow(clippy::too_many_arguments)]
    pub(super) fn depth_probe(
        &self,
        cube: u32,
        p: Vec3,
        x: Vec3,
        r: Vec3,
        w: f32,
        missing: &mut bool,
    ) -> (Vec3, f32) {
        if !(w > 0.0) {
            return (r, 1.0);
        }
        let d = x + r * (1.0 / w) - p;
        (d, d.length() - self.depth_toward(cube, d, true, missing))
    }

    /// The depth-corrected lookup direction of sample point `cube` for the ray from `x` along
    /// `r`, and its status: 1 hit, 0 none (plain), −1 hidden (as `depth_search`).
    pub(super) fn depth_search(&self, cube: u32, x: Vec3, r: Vec3) -> (Vec3, f32) {
        let u = &self.uniform;
        let p = self.samples[cube as usize];
        let lo = (x - p).length();
        if !(lo > 0.0) {
            return (r, 0.0);
        }
        let mut missing = false;
        let w0 = 1.0 / lo;
        let mut a = self.depth_probe(cube, p, x, r, w0, &mut missing);
        if missing {
            return (r, 0.0);
        }
        if a.1 >= 0.0 {
            return (r, -1.0);
        }
        let span = a.0.normalize().dot(r).clamp(-1.0, 1.0).acos();
        let steps = ((span * u.cube_res as f32 / (0.5 * PI)).ceil() as u32).clamp(1, u.depth_steps);
        let (mut wa, mut wb, mut b) = (w0, 0.0f32, (r, 1.0f32));
        for k in 1..steps {
            let w = w0 * (1.0 - k as f32 / steps as f32);
            let q = self.depth_probe(cube, p, x, r, w, &mut missing);
            if q.1 >= 0.0 {
                wb = w;
                b = q;
                break;
            }
            wa = w;
            a = q;
        }
        for _ in 0..DEPTH_REFINE {
            let wm = 0.5 * (wa + wb);
            let q = self.depth_probe(cube, p, x, r, wm, &mut missing);
            if q.1 >= 0.0 {
                wb = wm;
                b = q;
            } else {
                wa = wm;
                a = q;
            }
        }
        if missing || !(wb > 0.0) {
            return (r, 0.0);
        }
        if b.1 > u.depth_thickness * b.0.length() {
            return (r, -1.0);
        }
        if b.1 - a.1 > 0.0 {
            let ws = wa + (wb - wa) * (-a.1 / (b.1 - a.1));
            if ws > 0.0 {
                return (x + r * (1.0 / ws) - p, 1.0);
            }
        }
        (b.0, 1.0)
    }

    /// Whether sample point `cube` cannot see the ray from x along `l`, o = x − p (as
    /// `depth_hidden`).
    pub(super) fn depth_hidden(&self, cube: u32, o: Vec3, l: Vec3) -> bool {
        let d = o + l * o.length();
        let mut missing = false;
        let seen = self.depth_toward(cube, d, false, &mut missing);
        seen < FAR_DISTANCE && d.length() >= seen
    }

    /// The depth-corrected lookup direction of sample point `cube` for a glossy sample from
    /// `x` along `l` (as `depth_iterate`): for a `fresh` sample DEPTH_ITERATIONS fixed-point
    /// steps on the spheres of the stored distances from `l`, `l` where a step finds nothing
    /// or `x` lies outside, and `seed` set to the distance it converged to (0 for none); for
    /// the others of its row, the sphere of radius `seed`, reading nothing.
    pub(super) fn depth_iterate(
        &self,
        cube: u32,
        x: Vec3,
        l: Vec3,
        fresh: bool,
        seed: &mut f32,
    ) -> Vec3 {
        let o = x - self.samples[cube as usize];
        let (ol, oo) = (o.dot(l), o.dot(o));
        let step = |dist: f32| o + l * ((ol * ol - (oo - dist * dist)).sqrt() - ol);
        if !fresh {
            return if *seed * *seed > oo { step(*seed) } else { l };
        }
        let mut missing = false;
        let mut q = l;
        *seed = 0.0;
        for _ in 0..DEPTH_ITERATIONS {
            let dist = self.depth_toward(cube, q, true, &mut missing);
            if !(dist < FAR_DISTANCE) || !(dist * dist > oo) {
                *seed = 0.0;
                return l;
            }
            q = step(dist);
            *seed = dist;
        }
        q
    }

    /// Radiance of `cube` for the `depth_search` result `h` at level `lod`: on level 0 the
    /// bilinear tap over the texels whose distance agrees with the hit's (as `depth_lookup`).
    pub(super) fn depth_lookup(&self, cube: u32, h: (Vec3, f32), lod: f32) -> Option<Vec3> {
        if lod > 0.0 || h.1 < 0.0 {
            return self.lookup_lod(cube, h.0, lod);
        }
        let (face, s, t) = face_st(h.0);
        self.mark(cube, face);
        let Tap {
            x0,
            y0,
            x1,
            y1,
            wx,
            wy,
        } = Tap::new(self.uniform.cube_res, s, t);
        let dist = if h.1 > 0.0 {
            h.0.length()
        } else {
            FAR_DISTANCE
        };
        let tol = (LOOKUP_AGREE * self.uniform.depth_thickness).min(0.5) * dist;
        let taps = [(x0, y0), (x1, y0), (x0, y1), (x1, y1)];
        let mut w = [
            (1.0 - wx) * (1.0 - wy),
            wx * (1.0 - wy),
            (1.0 - wx) * wy,
            wx * wy,
        ];
        let mut agree = [0.0f32; 4];
        for k in 0..4 {
            let d = self.cubes.depth(cube, face, taps[k].0, taps[k].1)?;
            if (d - dist).abs() <= tol {
                agree[k] = w[k];
            }
        }
        let sum = agree[0] + agree[1] + agree[2] + agree[3];
        if sum > 0.0 {
            w = agree.map(|a| a / sum);
        }
        let mut c = Vec3::ZERO;
        for k in 0..4 {
            c += self.cubes.texel(cube, face, 0, taps[k].0, taps[k].1)? * w[k];
        }
        Some(c)
    }
}

/// Whether `h`, sample point `p`'s `depth_search` result for the ray from `x` along `l`, is a
/// hit lower above x's tangent plane (normal `n`) than LOW_HIT times p's distance from x (as
/// `low_hit`).
pub(super) fn low_hit(p: Vec3, h: (Vec3, f32), x: Vec3, l: Vec3, n: Vec3) -> bool {
    h.1 > 0.0 && (p + h.0 - x).dot(l) * l.dot(n) < LOW_HIT * (x - p).length()
}
