//! The store's objects as triangles for the G-buffer pass: Bézier patches tessellated, and
//! triangle-mesh objects as they are. Every vertex carries its sample-map
//! id and parameters (u, v) — a patch's (u, v), or a mesh's atlas uv with the atlas grid, from
//! which the G-buffer shader picks the page per fragment — so the shading pass can find its
//! sample-map texel.

use glam::{DAffine3, DMat4, DVec3, Vec3};
use oslf_format::Store;
use oslf_geometry::bezier::TESSELLATION_ERROR;
use oslf_geometry::BezierPatch;

oslf_gpu::gpu_struct! {
    /// One vertex as `GVertex` in gbuffer.wgsl: position and map id + 1 (exact as `f32` below
    /// 2²⁴), the unit normal and u, then v, the atlas grid `k` (`v[1]`) and a textured mesh's
    /// texture coordinates (`v[2..4]`; 0 for a Bézier patch's `k` and coordinates, then the
    /// tangent of a mesh with a normal texture,
    /// whose id is its map. For a mesh, the id is the object's first map and (u, v) its atlas uv:
    /// the G-buffer shader adds the page `py·k + px` per fragment and makes (u, v) page-local).
    /// gbuffer.wgsl's `GVertex`, declared from these fields ([`GVertex::wgsl`]).
    #[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
    pub struct GVertex as "GVertex" {
        pub position_patch: [f32; 4],
        pub normal_u: [f32; 4],
        pub v: [f32; 4],
        /// A textured mesh's tangent (world space, unit) with the bitangent's sign in `w`,
        /// where it has a normal texture; zero elsewhere.
        pub tangent: [f32; 4],
    }
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
    /// World position of this mesh's coordinate origin: the centre of the bounds of the
    /// control points and mesh vertices, as f32.
    pub origin: Vec3,
    /// One entry per sample map of the store (indexed by map): a Bézier patch transformed to
    /// world space minus `origin` (in f64, then rounded), or, for a page of a mesh object's
    /// atlas, a patch of zero control points (its ∂x/∂u is zero, so the shaders build the
    /// anisotropic tangent frame from the normal alone).
    pub patches: Vec<BezierPatch>,
    /// The base colour C_s of each map's object (indexed by map).
    pub colors: Vec<Vec3>,
    /// The pbr mode's material of each map's object (indexed by map): metallic, GGX α (at
    /// least `oslf_shading::ggx::MIN_ALPHA`), 1 for a metallic-roughness material (else 0: the parameters'
    /// factors apply), 0.
    pub materials: Vec<[f32; 4]>,
    /// The emitted radiance of each map's object (indexed by map; linear RGB, w 0): its
    /// material record's emission, times its emissive texture where it has one.
    pub emissions: Vec<[f32; 4]>,
    /// Vertices, patch after patch, then each mesh object's (in object order).
    pub vertices: Vec<GVertex>,
    /// Triangle list (three indices per triangle).
    pub indices: Vec<u32>,
    /// The G-buffer pass's draws: ranges of `indices` and the object each belongs to (whose
    /// textures it binds; all Bézier patches form one range, of the first Bézier object).
    pub draws: Vec<(std::ops::Range<u32>, u32)>,
    /// The tolerance the patches were tessellated to: how far their flat triangles may lie
    /// from the surface (the shading pass refines each pixel's point onto its patch within a
    /// multiple of it; `surface_hit` in shade/patch.wgsl).
    pub max_error: f32,
    /// Bounds of the control points and mesh vertices relative to `origin`.
    relative_lo: Vec3,
    relative_hi: Vec3,
}

impl ObjectMesh {
    /// The tessellation every view of `store` draws (the renderer's G-buffer, the web page,
    /// an engine's proxy of the object): [`ObjectMesh::from_store`] within the bake's ε ×
    /// [`TESSELLATION_ERROR`] (ε/50), the tessellation the bake and the ground truth trace, so
    /// that the object's outline is theirs; the shading pass then refines each pixel's point
    /// onto the patch itself.
    pub fn of_store(store: &Store) -> Self {
        Self::from_store(store, store.meta().bake.epsilon * TESSELLATION_ERROR)
    }

    /// Tessellates every Bézier patch of `store` so that the flat triangles stay within
    /// `max_error` of the surface (clamped to `1..=MAX_LEVEL` quads per side), and emits every
    /// mesh object's triangles with world positions (its transform) and world normals (the
    /// inverse transpose of the transform, renormalized; shading interpolates these vertex
    /// normals). Patch normals come from [`BezierPatch::normal`], which takes the limit at
    /// collapsed edges (never NaN).
    pub fn from_store(store: &Store, max_error: f32) -> Self {
        let (world, colors, meshes) = world_objects(store.meta());
        let materials = map_materials(store.meta());
        let emissions = store
            .meta()
            .objects
            .iter()
            .flat_map(|o| {
                let e = o.material.emission;
                std::iter::repeat_n([e[0], e[1], e[2], 0.0], o.patch_count as usize)
            })
            .collect();
        let (lo, hi) = world
            .iter()
            .flatten()
            .flatten()
            .chain(meshes.iter().flat_map(|m| &m.positions))
            .fold(
                (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)),
                |(lo, hi), &c| (lo.min(c), hi.max(c)),
            );
        let empty = lo.x > hi.x;
        let origin = if empty {
            Vec3::ZERO
        } else {
            ((lo + hi) * 0.5).as_vec3()
        };
        let relative = |c: DVec3| (c - origin.as_dvec3()).as_vec3();
        let patches: Vec<BezierPatch> = world
            .iter()
            .map(|cp| match cp {
                Some(cp) => BezierPatch::new(cp.map(relative)),
                None => BezierPatch::new([Vec3::ZERO; 16]),
            })
            .collect();
        let mut vertices = Vec::new();
        let mut indices = Vec::new();
        tessellate_patches(&patches, &world, max_error, &mut vertices, &mut indices);
        let mut draws = Vec::new();
        if let Some(first) = store.meta().objects.iter().position(|o| o.mesh.is_none()) {
            draws.push((0..indices.len() as u32, first as u32));
        }
        for m in &meshes {
            let start = indices.len() as u32;
            m.emit(relative, &mut vertices, &mut indices);
            draws.push((start..indices.len() as u32, m.object));
        }
        let (relative_lo, relative_hi) = if empty {
            (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY))
        } else {
            (relative(lo), relative(hi))
        };
        Self {
            origin,
            patches,
            colors,
            materials,
            emissions,
            vertices,
            indices,
            draws,
            max_error,
            relative_lo,
            relative_hi,
        }
    }

    /// The centre of the bounding box of all control points and mesh vertices (world
    /// space).
    pub fn centre(&self) -> Vec3 {
        let (lo, hi) = self.bounds();
        (lo + hi) * 0.5
    }

    /// Axis-aligned bounds of all control points and mesh vertices (world space).
    pub fn bounds(&self) -> (Vec3, Vec3) {
        let (lo, hi) = self.relative_bounds();
        (lo + self.origin, hi + self.origin)
    }

    /// Axis-aligned bounds of all control points and mesh vertices relative to
    /// [`Self::origin`] (infinite, lo > hi, when there are none).
    pub fn relative_bounds(&self) -> (Vec3, Vec3) {
        (self.relative_lo, self.relative_hi)
    }
}

/// Octahedral encoding of a unit vector (as `oct_encode` in octahedral.wgsl).
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

/// Octahedral decoding (as `oct_decode` in octahedral.wgsl).
pub fn oct_decode(e: [f32; 2]) -> Vec3 {
    let mut n = Vec3::new(e[0], e[1], 1.0 - e[0].abs() - e[1].abs());
    if n.z < 0.0 {
        let sx = if n.x >= 0.0 { 1.0 } else { -1.0 };
        let sy = if n.y >= 0.0 { 1.0 } else { -1.0 };
        n = Vec3::new((1.0 - n.y.abs()) * sx, (1.0 - n.x.abs()) * sy, n.z);
    }
    n.normalize()
}

/// A mesh object in world space (f64 positions, world normals).
struct WorldMesh {
    positions: Vec<DVec3>,
    normals: Vec<Vec3>,
    uvs: Vec<[f32; 2]>,
    triangles: Vec<[u32; 3]>,
    first_map: u32,
    grid: u32,
    /// Its texture coordinates, if it has textures.
    texcoords: Option<Vec<[f32; 2]>>,
    /// Its tangents in world space (unit, w the bitangent's sign), if it has a normal texture.
    tangents: Option<Vec<[f32; 4]>>,
    /// Its index in the store's objects.
    object: u32,
}

impl WorldMesh {
    /// Appends its vertices (positions made `relative` to the mesh's origin) and triangles.
    fn emit(
        &self,
        relative: impl Fn(DVec3) -> Vec3,
        vertices: &mut Vec<GVertex>,
        indices: &mut Vec<u32>,
    ) {
        let base = vertices.len() as u32;
        let tag = self.first_map as f32 + 1.0;
        for (k, ((&p, n), uv)) in self
            .positions
            .iter()
            .zip(&self.normals)
            .zip(&self.uvs)
            .enumerate()
        {
            let p = relative(p);
            let tc = self
                .texcoords
                .as_ref()
                .and_then(|t| t.get(k))
                .copied()
                .unwrap_or_default();
            let tangent = self
                .tangents
                .as_ref()
                .and_then(|t| t.get(k))
                .copied()
                .unwrap_or_default();
            vertices.push(GVertex {
                position_patch: [p.x, p.y, p.z, tag],
                normal_u: [n.x, n.y, n.z, uv[0]],
                v: [uv[1], self.grid as f32, tc[0], tc[1]],
                tangent,
            });
        }
        for t in &self.triangles {
            indices.extend(t.iter().map(|i| base + i));
        }
    }
}

/// Per sample map, its object's material as the shader's `PatchGpu.material` holds it.
fn map_materials(meta: &oslf_format::StoreMeta) -> Vec<[f32; 4]> {
    meta.objects
        .iter()
        .flat_map(|o| {
            let m = o.material;
            let alpha = oslf_shading::ggx::alpha(m.roughness);
            let entry = if m.is_metallic_roughness() {
                [m.metallic, alpha, 1.0, 0.0]
            } else {
                [0.0; 4]
            };
            std::iter::repeat_n(entry, o.patch_count as usize)
        })
        .collect()
}

/// Per sample map, its world-space control points (`None` for a page of a mesh's atlas) and
/// its object's base colour; and the mesh objects in world space: each object's transform
/// applied in f64, normals by its inverse transpose.
fn world_objects(
    meta: &oslf_format::StoreMeta,
) -> (Vec<Option<[DVec3; 16]>>, Vec<Vec3>, Vec<WorldMesh>) {
    let maps = meta.map_count();
    let mut world: Vec<Option<[DVec3; 16]>> = Vec::with_capacity(maps);
    let mut colors = Vec::with_capacity(maps);
    let mut meshes = Vec::new();
    for (i, object) in meta.objects.iter().enumerate() {
        let affine = DAffine3::from_mat4(DMat4::from_cols_array_2d(
            &object.transform.map(|c| c.map(f64::from)),
        ));
        let color = Vec3::from_array(object.base_color);
        match &object.mesh {
            None => {
                for p in meta.patches_of(i) {
                    world
                        .push(Some(p.control_points.map(|c| {
                            affine.transform_point3(Vec3::from_array(c).as_dvec3())
                        })));
                    colors.push(color);
                }
            }
            Some(m) => {
                for _ in 0..object.patch_count {
                    world.push(None);
                    colors.push(color);
                }
                let normal_matrix = affine.matrix3.inverse().transpose();
                meshes.push(WorldMesh {
                    positions: m
                        .positions
                        .iter()
                        .map(|&p| affine.transform_point3(Vec3::from_array(p).as_dvec3()))
                        .collect(),
                    normals: m
                        .normals
                        .iter()
                        .map(|&n| {
                            (normal_matrix * Vec3::from_array(n).as_dvec3())
                                .normalize_or(DVec3::Z)
                                .as_vec3()
                        })
                        .collect(),
                    uvs: m.uvs.clone(),
                    triangles: m.triangles.clone(),
                    first_map: object.first_patch,
                    grid: m.atlas_grid,
                    texcoords: object.textures.as_ref().map(|t| t.texcoords.clone()),
                    tangents: object
                        .textures
                        .as_ref()
                        .filter(|t| !t.tangents.is_empty())
                        .map(|t| world_tangents(&affine, &t.tangents)),
                    object: i as u32,
                });
            }
        }
    }
    (world, colors, meshes)
}

/// Object-space tangents in world space: the transform's linear part applied and
/// renormalized, the bitangent's sign flipped where the transform mirrors (the bitangent is
/// `w·(n × t)` with the transformed normal).
fn world_tangents(affine: &DAffine3, tangents: &[[f32; 4]]) -> Vec<[f32; 4]> {
    let mirror = if affine.matrix3.determinant() < 0.0 {
        -1.0
    } else {
        1.0
    };
    tangents
        .iter()
        .map(|t| {
            let w = (affine.matrix3 * DVec3::new(t[0].into(), t[1].into(), t[2].into()))
                .normalize_or(DVec3::X)
                .as_vec3();
            [w.x, w.y, w.z, t[3] * mirror]
        })
        .collect()
}

/// Appends the triangles of every Bézier patch (those with control points in `world`),
/// tessellated to stay within `max_error` of the surface, tagged with its map.
fn tessellate_patches(
    patches: &[BezierPatch],
    world: &[Option<[DVec3; 16]>],
    max_error: f32,
    vertices: &mut Vec<GVertex>,
    indices: &mut Vec<u32>,
) {
    for (id, (patch, cp)) in patches.iter().zip(world).enumerate() {
        if cp.is_none() {
            continue;
        }
        let level = patch.tessellation_level(max_error).clamp(1, MAX_LEVEL);
        let mesh = patch.tessellate(level);
        let base = vertices.len() as u32;
        let tag = id as f32 + 1.0;
        for ((p, n), uv) in mesh.positions.iter().zip(&mesh.normals).zip(&mesh.uvs) {
            vertices.push(GVertex {
                position_patch: [p.x, p.y, p.z, tag],
                normal_u: [n.x, n.y, n.z, uv.x],
                v: [uv.y, 0.0, 0.0, 0.0],
                tangent: [0.0; 4],
            });
        }
        for t in &mesh.triangles {
            indices.extend(t.iter().map(|i| base + i));
        }
    }
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
