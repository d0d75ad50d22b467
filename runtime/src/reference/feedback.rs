//! Feedback marks: the faces a lookup reads. As shade/feedback.wgsl, function for function.

use std::sync::atomic::Ordering;

use super::{CubeTexels, Shader};

#[allow(clippy::needless_range_loop, clippy::neg_cmp_op_on_partial_ord)]
impl<C: CubeTexels> Shader<'_, C> {
    /// Marks `face` of `cube` as needed in the feedback.
    pub(super) fn mark(&self, cube: u32, face: usize) {
        if let Some(f) = self.feedback.get(cube as usize) {
            f.fetch_or(1 << face, Ordering::Relaxed);
        }
    }
}
