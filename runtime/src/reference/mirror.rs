//! Mirror reflection (chapter 4). As shade/mirror.wgsl, function for function.

use glam::Vec3;

use super::blend::Candidates;
use super::{CubeTexels, Shader};

#[allow(clippy::needless_range_loop, clippy::neg_cmp_op_on_partial_ord)]
impl<C: CubeTexels> Shader<'_, C> {
    pub(super) fn mirror(&self, c: &Candidates, x: Vec3, n: Vec3, r: Vec3) -> Vec3 {
        if self.uniform.source != 0 || c.count == 0 {
            return self.env_read(x, r, 0.0);
        }
        let axis = if self.uniform.blend == 4 { n } else { r };
        self.blend_read(c, self.blend_weights(c, axis), x, r, 0.0, None)
            .unwrap_or_else(|| self.env_read(x, r, 0.0))
    }
}
