//! Blending the candidates of a texel (chapter 4). As shade/blend.wgsl, function for function.

use glam::Vec3;
use oslf_format::INVALID_INDEX;

use super::depth::low_hit;
use super::{CubeTexels, Shader, HIT_AGREE};

/// Candidates of a texel: the sample map's four entries with their directions from x.
#[derive(Clone, Copy, Debug)]
pub(super) struct Candidates {
    pub(super) idx: [u32; 4],
    pub(super) s: [Vec3; 4],
    pub(super) count: u32,
}

#[allow(clippy::needless_range_loop, clippy::neg_cmp_op_on_partial_ord)]
impl<C: CubeTexels> Shader<'_, C> {
    pub(super) fn candidates(&self, patch: u32, u: f32, v: f32, x: Vec3, n: Vec3) -> Candidates {
        let m = self.uniform.map_res;
        let tx = ((u.clamp(0.0, 1.0) * m as f32) as u32).min(m - 1);
        let ty = ((v.clamp(0.0, 1.0) * m as f32) as u32).min(m - 1);
        let raw = self
            .maps
            .get(patch as usize)
            .and_then(|map| map.get(tx, ty))
            .unwrap_or([INVALID_INDEX; 4]);
        let mut c = Candidates {
            idx: [INVALID_INDEX; 4],
            s: [n; 4],
            count: 0,
        };
        for j in 0..4 {
            let idx = raw[j];
            if idx != INVALID_INDEX && idx < self.uniform.sample_count {
                c.idx[j] = idx;
                let d = self.samples[idx as usize] - x;
                let l2 = d.dot(d);
                if l2 > 0.0 {
                    c.s[j] = d / l2.sqrt();
                }
                c.count += 1;
            }
        }
        c
    }

    pub(super) fn is_resident(&self, cube: u32) -> bool {
        self.cubes.resident(cube)
    }

    pub(super) fn blend_weights(&self, c: &Candidates, a: Vec3) -> [f32; 4] {
        let u = &self.uniform;
        let mut w = [0.0f32; 4];
        let (mut best, mut best_dot, mut first) = (0usize, -2.0f32, 4usize);
        for j in 0..4 {
            if c.idx[j] == INVALID_INDEX {
                continue;
            }
            if first == 4 {
                first = j;
            }
            let d = a.dot(c.s[j]);
            if d > best_dot {
                best_dot = d;
                best = j;
            }
        }
        if first == 4 {
            return w;
        }
        match u.blend {
            0 => w[first] = 1.0, // Eq. 4.3
            1 => w[best] = 1.0,  // Eq. 4.4-4.5
            _ => {
                for j in 0..4 {
                    if c.idx[j] == INVALID_INDEX {
                        continue;
                    }
                    if u.blend == 2 || u.blend_n == 0.0 {
                        w[j] = 1.0; // Eq. 4.9
                    } else if best_dot > 0.0 {
                        let r = a.dot(c.s[j]).max(0.0) / best_dot;
                        if r > 0.0 {
                            w[j] = r.powf(u.blend_n); // Eq. 4.10, 4.11
                        }
                    }
                }
                if best_dot <= 0.0 && u.blend != 2 && u.blend_n != 0.0 {
                    w[best] = 1.0;
                }
            }
        }
        w
    }

    /// Blended radiance towards `dir` for the ray from `x` at mip level `lod`, each candidate
    /// depth-corrected when the uniform asks, a `low_hit` left out where `low` gives x's normal
    /// (as `blend_read`: `low` and `n`).
    pub(super) fn blend_read(
        &self,
        c: &Candidates,
        w: [f32; 4],
        x: Vec3,
        dir: Vec3,
        lod: f32,
        low: Option<Vec3>,
    ) -> Option<Vec3> {
        let depth = self.uniform.depth_steps > 0;
        let (mut acc, mut wsum, mut hidden, mut hsum) = (Vec3::ZERO, 0.0, Vec3::ZERO, 0.0);
        let mut near = 3.4e38f32;
        for j in 0..4 {
            if w[j] > 0.0 {
                let (l, status) = if depth {
                    let mut h = self.depth_search(c.idx[j], x, dir);
                    let p = self.samples[c.idx[j] as usize];
                    if low.is_some_and(|n| low_hit(p, h, x, dir, n)) {
                        h = (dir, 0.0);
                    }
                    if h.1 > 0.0 {
                        near = near.min((h.0 + p - x).dot(dir));
                    }
                    (self.depth_lookup(c.idx[j], h, lod), h.1)
                } else {
                    (self.lookup_lod(c.idx[j], dir, lod), 1.0)
                };
                if let Some(l) = l {
                    if status >= 0.0 {
                        acc += l * w[j];
                        wsum += w[j];
                    } else {
                        hidden += l * w[j];
                        hsum += w[j];
                    }
                }
            }
        }
        if depth && near < 3.4e38 {
            // The candidates' common hit (as `blend_read`).
            let hit = x + dir * near;
            let (mut cacc, mut csum) = (Vec3::ZERO, 0.0);
            for j in 0..4 {
                if w[j] > 0.0 {
                    let d = hit - self.samples[c.idx[j] as usize];
                    let dl = d.length();
                    let mut missing = false;
                    let seen = self.depth_toward(c.idx[j], d, false, &mut missing);
                    if !missing
                        && (dl - seen).abs() <= HIT_AGREE * self.uniform.depth_thickness * dl
                    {
                        if let Some(l) = self.depth_lookup(c.idx[j], (d, 1.0), lod) {
                            cacc += l * w[j];
                            csum += w[j];
                        }
                    }
                }
            }
            if csum > 0.0 {
                return Some(cacc / csum);
            }
        }
        if wsum > 0.0 {
            return Some(acc / wsum);
        }
        (hsum > 0.0).then(|| hidden / hsum)
    }

    /// The environment cube's lookup direction for the ray from `x` along `dir` (as `env_dir`).
    pub(super) fn env_dir(&self, x: Vec3, dir: Vec3) -> Vec3 {
        let u = &self.uniform;
        if u.source != 2 {
            return dir;
        }
        let v = |a: [f32; 4]| Vec3::from_slice(&a[..3]);
        crate::probe::parallax_dir(x, dir, v(u.probe_pos), v(u.box_min), v(u.box_max))
    }

    /// The environment cube for the ray from `x` along `dir` at `lod` (as `env_read`).
    pub(super) fn env_read(&self, x: Vec3, dir: Vec3, lod: f32) -> Vec3 {
        if self.uniform.env_cube == INVALID_INDEX {
            return Vec3::ZERO;
        }
        self.lookup_lod(self.uniform.env_cube, self.env_dir(x, dir), lod)
            .unwrap_or(Vec3::ZERO)
    }
}
