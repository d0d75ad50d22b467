//! The object's Bézier patches as triangle meshes for the G-buffer pass: every vertex carries
//! its patch id and patch parameters (u, v), so the shader can find its sample-map texel.

use glam::{Affine3A, Mat4, Vec3};
use oslf_bake::bezier::BezierPatch;
use oslf_format::Store;

/// One vertex as `GVertex` in gbuffer.wgsl: position and patch id + 1 (exact as `f32` below
/// 2²⁴), the unit normal and u, then v.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct GVertex {
    pub position_patch: [f32; 4],
    pub normal_u: [f32; 4],
    pub v: [f32; 4],
}

/// Largest tessellation grid per patch.
pub const MAX_LEVEL: u32 = 64;

/// The tessellated object: world-space patches and their triangles.
pub struct ObjectMesh {
    /// Every patch of the store, transformed to world space, in store order.
    pub patches: Vec<BezierPatch>,
    /// The base colour C_s of each patch's object.
    pub colors: Vec<Vec3>,
    /// Vertices, patch after patch.
    pub vertices: Vec<GVertex>,
    /// Triangle list (three indices per triangle).
    pub indices: Vec<u32>,
}

impl ObjectMesh {
    /// Tessellates every patch of `store` so that the flat triangles stay within
    /// `max_error` of the surface (clamped to `1..=MAX_LEVEL` quads per side). Normals come
    /// from [`BezierPatch::normal`], which takes the limit at collapsed edges (never NaN).
    pub fn from_store(store: &Store, max_error: f32) -> Self {
        let meta = store.meta();
        let mut patches = Vec::with_capacity(meta.patches.len());
        let mut colors = Vec::with_capacity(meta.patches.len());
        for object in &meta.objects {
            let m = Mat4::from_cols_array_2d(&object.transform);
            let affine = Affine3A::from_mat4(m);
            let first = object.first_patch as usize;
            let end = first + object.patch_count as usize;
            for p in &meta.patches[first..end] {
                let patch =
                    BezierPatch::new(p.control_points.map(Vec3::from_array)).transformed(&affine);
                patches.push(patch);
                colors.push(Vec3::from_array(object.base_color));
            }
        }
        let mut vertices = Vec::new();
        let mut indices = Vec::new();
        for (id, patch) in patches.iter().enumerate() {
            let level = patch.tessellation_level(max_error).clamp(1, MAX_LEVEL);
            let mesh = patch.tessellate(level);
            let base = vertices.len() as u32;
            let tag = id as f32 + 1.0;
            for ((p, n), uv) in mesh.positions.iter().zip(&mesh.normals).zip(&mesh.uvs) {
                vertices.push(GVertex {
                    position_patch: [p.x, p.y, p.z, tag],
                    normal_u: [n.x, n.y, n.z, uv.x],
                    v: [uv.y, 0.0, 0.0, 0.0],
                });
            }
            for t in &mesh.triangles {
                indices.extend(t.iter().map(|i| base + i));
            }
        }
        Self {
            patches,
            colors,
            vertices,
            indices,
        }
    }

    /// The centre of the bounding box of all control points.
    pub fn centre(&self) -> Vec3 {
        let (lo, hi) = self.bounds();
        (lo + hi) * 0.5
    }

    /// Axis-aligned bounds of all control points.
    pub fn bounds(&self) -> (Vec3, Vec3) {
        let mut lo = Vec3::splat(f32::INFINITY);
        let mut hi = Vec3::splat(f32::NEG_INFINITY);
        for p in &self.patches {
            for c in p.cp {
                lo = lo.min(c);
                hi = hi.max(c);
            }
        }
        (lo, hi)
    }
}

/// Octahedral encoding of a unit vector (as `oct_encode` in gbuffer.wgsl).
pub fn oct_encode(n: Vec3) -> [f32; 2] {
    let s = n.x.abs() + n.y.abs() + n.z.abs();
    let (px, py) = (n.x / s, n.y / s);
    if n.z < 0.0 {
        let sx = if px >= 0.0 { 1.0 } else { -1.0 };
        let sy = if py >= 0.0 { 1.0 } else { -1.0 };
        [(1.0 - py.abs()) * sx, (1.0 - px.abs()) * sy]
    } else {
        [px, py]
    }
}

/// Octahedral decoding (as `oct_decode` in shade.wgsl).
pub fn oct_decode(e: [f32; 2]) -> Vec3 {
    let mut n = Vec3::new(e[0], e[1], 1.0 - e[0].abs() - e[1].abs());
    if n.z < 0.0 {
        let sx = if n.x >= 0.0 { 1.0 } else { -1.0 };
        let sy = if n.y >= 0.0 { 1.0 } else { -1.0 };
        n = Vec3::new((1.0 - n.y.abs()) * sx, (1.0 - n.x.abs()) * sy, n.z);
    }
    n.normalize()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn octahedral_encoding_round_trips() {
        for d in [
            Vec3::X,
            -Vec3::X,
            Vec3::Y,
            -Vec3::Z,
            Vec3::Z,
            Vec3::new(0.3, -0.5, -0.8).normalize(),
            Vec3::new(-1e-7, 1.0, -1e-7).normalize(),
        ] {
            let r = oct_decode(oct_encode(d));
            assert!((r - d).length() < 1e-6, "{d} -> {r}");
        }
    }
}
