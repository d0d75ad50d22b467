//! The object's Bézier patches as triangle meshes for the G-buffer pass: every vertex carries
//! its patch id and patch parameters (u, v), so the shader can find its sample-map texel.

use glam::{DAffine3, DMat4, DVec3, Vec3};
use oslf_format::Store;
use oslf_geometry::BezierPatch;

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

/// The tessellated object: its patches and triangles relative to [`ObjectMesh::origin`].
///
/// Object-relative coordinates: the G-buffer stores positions in f32, and 10⁵ units from the
/// world origin f32 positions are 0.0078 apart, a large fraction of ε; the look-up direction
/// from a sample point to the shaded point (Eq. 3.11) then turns by degrees. Relative to the
/// object's centre the same positions keep 24 bits of the object's own size. The renderer
/// subtracts `origin` from the sample points and the camera as well.
pub struct ObjectMesh {
    /// World position of this mesh's coordinate origin: the centre of the control points'
    /// bounds, as f32.
    pub origin: Vec3,
    /// Every patch of the store, transformed to world space minus `origin` (in f64, then
    /// rounded), in store order.
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
        let mut world: Vec<[DVec3; 16]> = Vec::with_capacity(meta.patches.len());
        let mut colors = Vec::with_capacity(meta.patches.len());
        for object in &meta.objects {
            let affine = DAffine3::from_mat4(DMat4::from_cols_array_2d(
                &object.transform.map(|c| c.map(f64::from)),
            ));
            let first = object.first_patch as usize;
            let end = first + object.patch_count as usize;
            for p in &meta.patches[first..end] {
                world.push(
                    p.control_points
                        .map(|c| affine.transform_point3(Vec3::from_array(c).as_dvec3())),
                );
                colors.push(Vec3::from_array(object.base_color));
            }
        }
        let (lo, hi) = world.iter().flatten().fold(
            (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)),
            |(lo, hi), &c| (lo.min(c), hi.max(c)),
        );
        let origin = if world.is_empty() {
            Vec3::ZERO
        } else {
            ((lo + hi) * 0.5).as_vec3()
        };
        let patches: Vec<BezierPatch> = world
            .iter()
            .map(|cp| BezierPatch::new(cp.map(|c| (c - origin.as_dvec3()).as_vec3())))
            .collect();
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
            origin,
            patches,
            colors,
            vertices,
            indices,
        }
    }

    /// The centre of the bounding box of all control points (world space).
    pub fn centre(&self) -> Vec3 {
        let (lo, hi) = self.bounds();
        (lo + hi) * 0.5
    }

    /// Axis-aligned bounds of all control points (world space).
    pub fn bounds(&self) -> (Vec3, Vec3) {
        let (lo, hi) = self.relative_bounds();
        (lo + self.origin, hi + self.origin)
    }

    /// Axis-aligned bounds of all control points relative to [`Self::origin`].
    pub fn relative_bounds(&self) -> (Vec3, Vec3) {
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
