//! Surface reconstruction (3.11–3.12, §6.3). As shade/reconstruct.wgsl, function for function.

use glam::Vec3;
use oslf_format::INVALID_INDEX;

use super::blend::Candidates;
use super::{CubeTexels, Shader};

#[allow(clippy::needless_range_loop, clippy::neg_cmp_op_on_partial_ord)]
impl<C: CubeTexels> Shader<'_, C> {
    pub(super) fn recon_choice(&self, c: &Candidates, n: Vec3, resident_only: bool) -> usize {
        let (mut best, mut best_dot) = (4usize, -2.0f32);
        for j in 0..4 {
            if c.idx[j] == INVALID_INDEX {
                continue;
            }
            if resident_only && !self.is_resident(c.idx[j]) {
                continue;
            }
            let d = n.dot(c.s[j]);
            if d >= self.uniform.cos_phi_shader {
                return j;
            }
            if d > best_dot {
                best_dot = d;
                best = j;
            }
        }
        best
    }

    /// The mean, weighted by ⟨n, s_j⟩, over the candidates in front of `x` that see it (as
    /// `recon_visible`).
    pub(super) fn recon_visible(&self, c: &Candidates, x: Vec3, n: Vec3) -> Option<Vec3> {
        let (mut acc, mut count) = (Vec3::ZERO, 0.0f32);
        for j in 0..4 {
            let i = c.idx[j];
            let cos_j = n.dot(c.s[j]);
            if i == INVALID_INDEX || cos_j <= 0.0 {
                continue;
            }
            let d = x - self.samples[i as usize];
            let mut missing = false;
            let seen = self.depth_toward(i, d, false, &mut missing);
            if missing || d.length() > seen * (1.0 + self.uniform.depth_thickness) {
                continue;
            }
            if let Some(l) = self.depth_lookup(i, (d, 1.0), 0.0) {
                acc += l * cos_j;
                count += cos_j;
            }
        }
        (count > 0.0).then(|| acc / count)
    }

    pub(super) fn recon(&self, c: &Candidates, x: Vec3, n: Vec3) -> Vec3 {
        if self.uniform.depth_steps > 0 {
            if let Some(m) = self.recon_visible(c, x, n) {
                return m;
            }
        }
        let ideal = self.recon_choice(c, n, false);
        if ideal == 4 {
            return Vec3::ZERO;
        }
        let i = c.idx[ideal];
        if let Some(l) = self.lookup(i, x - self.samples[i as usize]) {
            return l;
        }
        let j = self.recon_choice(c, n, true);
        if j == 4 {
            return Vec3::ZERO;
        }
        let i = c.idx[j];
        self.lookup(i, x - self.samples[i as usize])
            .unwrap_or(Vec3::ZERO)
    }
}
