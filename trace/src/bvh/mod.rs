//! Triangle scene acceleration: one obvhs compressed wide BVH (CWBVH) over every triangle of
//! every instance, with a watertight ray–triangle test.
//!
//! Robustness (rays start at sample points a tiny ε above surfaces, scenes may sit far from
//! the origin):
//! - the ray–triangle test is the watertight test of Woop, Benthin and Wald (JCGT 2013) with
//!   pbrt-v3's conservative rounding-error bound on `t`: a hit is reported only if `t` is
//!   provably positive, so a ray started exactly on a surface never re-hits it at `t ≈ 0`,
//!   while hits at `t` far below any fixed epsilon are still found;
//! - the node test is obvhs's SIMD slab test, changed to clip at `t = 0` instead of obvhs's
//!   fixed `1e-4` (which would cull geometry closer than `1e-4` to the origin), to use exact
//!   reciprocal directions, and to widen every slab by its own rounding error.
//!
//! Speed, without changing a result bit: where the CPU has AVX2 (detected at run time) the
//! traversals are compiled for it and test a node's 8 children in one 256-bit vector, each
//! lane by the same operations as the SSE test; the triangle test computes the three
//! corners' sheared coordinates and edge functions in SSE vectors, lane by lane as the scalar
//! test (`tests`); shadow rays first try the triangles that blocked the thread's last two
//! blocked shadow rays of the same stream ([`Intersector::occluded_in_stream`]).
//!
//! Packets ([`TriangleScene::intersect_packet`]): the primary rays of a cube-map tile leave
//! one point in nearly one direction, so they enter nearly the same nodes and triangles. A
//! packet traverses the BVH once for up to [`PACKET`] rays: each node is loaded and its
//! quantised child planes converted once, then slab-tested against every ray still in it
//! (each ray against its own closest `t`, lane by lane the single-ray test); a child is
//! visited with the rays that enter it, a leaf's triangles are tested against exactly those
//! rays. Every ray gets the closest hit the single-ray traversal gives it (the same triangle
//! test, so the same bits; only among triangles hit at bit-identical `t` may a different one
//! be reported, the tie being broken by visiting order in both). Each ray of a packet first
//! tries the triangle the same ray of the thread's previous packet hit and, where it hits it,
//! culls nodes beyond that distance from the start; triangles are still accepted as without
//! it, so the hits are exactly those without it.

use std::time::{Duration, Instant};

use glam::{UVec2, Vec2, Vec3, Vec3A};
use obvhs::aabb::Aabb;
use obvhs::bvh2::reinsertion::ReinsertionOptimizer;
use obvhs::cwbvh::bvh2_to_cwbvh::bvh2_to_cwbvh;
use obvhs::cwbvh::node::CwBvhNode;
use obvhs::cwbvh::CwBvh;
use obvhs::ploc::PlocBuilder;
use obvhs::BvhBuildParams;

mod instances;
mod node;
mod prepared_ray;
mod triangle;

pub use instances::scene_instances;
use node::*;
pub use node::{PACKET, SLAB_PAD};
pub use oslf_scene::tolerance::SELF_TOLERANCE;
use prepared_ray::PreparedRay;
use triangle::*;

use crate::ray::{Intersector, Ray, SurfaceHit, OCCLUSION_STREAMS};
use oslf_geometry::mesh::Mesh;
use oslf_scene::{BakeError, Result};

/// A world-space mesh with the material and OSLF object its triangles belong to.
#[derive(Clone, Debug, Default)]
pub struct Instance {
    /// What the triangles are, for messages: the shape's name, or `object "NAME"`.
    pub name: String,
    /// Geometry, already in world space.
    pub mesh: Mesh,
    /// Index into the scene's material list.
    pub material: u32,
    /// OSLF object index, or [`crate::ray::ENVIRONMENT_OBJECT`].
    pub object: u32,
}

/// Per-triangle shading data, stored in BVH order.
#[derive(Clone, Copy, Debug)]
struct TriangleAttributes {
    normals: [Vec3; 3],
    uvs: [Vec2; 3],
    geometric_normal: Vec3,
    material: u32,
    object: u32,
    /// Index of the triangle in the concatenation of all instances' triangle lists.
    global: u32,
}

/// One triangle of a [`TriangleScene`] with what a hit on it reports: what another tracer of
/// the same scene (the GPU path tracer of `oslf-bake-gpu`) uploads.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TriangleRecord {
    pub corners: [Vec3; 3],
    /// Vertex normals at the corners.
    pub normals: [Vec3; 3],
    pub uvs: [Vec2; 3],
    /// The unit normal of the triangle's plane, by its winding.
    pub geometric_normal: Vec3,
    pub material: u32,
    pub object: u32,
    /// [`SurfaceHit::triangle`] of hits on it.
    pub global: u32,
}

/// The binary BVH over `aabbs` (one primitive each, in order) that [`build_cwbvh`] converts:
/// obvhs's PLOC with its slow-build settings (no pre-splitting), then reinsertion.
fn build_bvh2(aabbs: &[Aabb]) -> obvhs::bvh2::Bvh2 {
    let params = BvhBuildParams {
        pre_split: false,
        ..BvhBuildParams::slow_build()
    };
    let mut bvh2 = PlocBuilder::with_capacity(aabbs.len()).build(
        params.ploc_search_distance,
        aabbs,
        (0..aabbs.len() as u32).collect(),
        params.sort_precision,
        params.search_depth_threshold,
    );
    ReinsertionOptimizer::default().run(&mut bvh2, params.reinsertion_batch_ratio, None);
    bvh2
}

/// The compressed wide BVH over `aabbs` (one triangle each, in order) that [`TriangleScene`]
/// and the GPU path tracer (`oslf-bake-gpu`) both traverse: [`build_bvh2`]'s tree converted to
/// 8-wide nodes of up to 3 triangles per leaf. Deterministic, so both build the same tree.
/// Errors where a triangle is lost or the tree is deeper than [`MAX_BVH_DEPTH`].
pub fn build_cwbvh(aabbs: &[Aabb]) -> Result<CwBvh> {
    let bvh2 = build_bvh2(aabbs);
    let params = BvhBuildParams::slow_build();
    let bvh = bvh2_to_cwbvh(&bvh2, params.max_prims_per_leaf.clamp(1, 3), true, false);
    if bvh.primitive_indices.len() != aabbs.len() || bvh.nodes.is_empty() {
        return Err(BakeError::Invalid(format!(
            "BVH build produced {} primitives for {} triangles",
            bvh.primitive_indices.len(),
            aabbs.len()
        )));
    }
    let depth = cwbvh_depth(&bvh.nodes);
    if depth > MAX_BVH_DEPTH {
        return Err(BakeError::Invalid(format!(
            "degenerate geometry: BVH depth {depth} exceeds {MAX_BVH_DEPTH}"
        )));
    }
    Ok(bvh)
}

/// Every triangle of a scene in one CWBVH.
pub struct TriangleScene {
    bvh: CwBvh,
    /// Triangle corners in BVH leaf order (`bvh` primitive slot = index), by coordinate.
    vertices: Vec<Corners>,
    /// Per slot of `vertices`: the unnormalised normal `(v1 − v0) × (v2 − v0)` and its
    /// length, for the self-intersection guard of [`intersect_triangle`] (computed once here
    /// instead of at every accepted hit; the same expression, so the same bits).
    planes: Vec<[f32; 4]>,
    attributes: Vec<TriangleAttributes>,
    /// Slots of `vertices` in input order (for the brute-force reference).
    input_order: Vec<u32>,
    build_time: Duration,
    bounds: (Vec3, Vec3),
    /// Whether the CPU has AVX2, POPCNT, LZCNT and BMI1/2 (then traversal runs
    /// [`TriangleScene::intersect_avx2`]).
    avx2: bool,
}

/// The instances that have triangles, named with their triangle counts (the first eight, then
/// how many more), for the error when all of them have zero area.
fn zero_area_meshes(instances: &[Instance]) -> String {
    const SHOWN: usize = 8;
    let named: Vec<String> = instances
        .iter()
        .filter(|i| !i.mesh.triangles.is_empty())
        .map(|i| {
            let name = if i.name.is_empty() {
                "unnamed"
            } else {
                &i.name
            };
            format!("{name} ({} triangles)", i.mesh.triangles.len())
        })
        .collect();
    let mut text = named[..named.len().min(SHOWN)].join(", ");
    if named.len() > SHOWN {
        text.push_str(&format!(" and {} more", named.len() - SHOWN));
    }
    text
}

/// Deepest CWBVH [`build_cwbvh`] accepts: the stack depth of obvhs's `traverse!` (its
/// `TRAVERSAL_STACK_SIZE`) and of the GPU traversal.
pub const MAX_BVH_DEPTH: usize = 32;

impl TriangleScene {
    /// Builds the BVH over all instances' triangles. Instances must be valid meshes
    /// ([`Mesh::validate`]); zero-area triangles are dropped. Fails if nothing is left.
    pub fn build(instances: Vec<Instance>) -> Result<TriangleScene> {
        let mut vertices = Vec::new();
        let mut attributes = Vec::new();
        let mut global = 0u64;
        for (k, inst) in instances.iter().enumerate() {
            inst.mesh
                .validate()
                .map_err(|e| BakeError::Invalid(format!("instance {k} ({}): {e}", inst.name)))?;
            for t in &inst.mesh.triangles {
                let g = global;
                global += 1;
                let [a, b, c] = t.map(|i| inst.mesh.positions[i as usize]);
                let Some(gn) = (b - a).cross(c - a).try_normalize() else {
                    continue; // zero area (or too small to have a normal)
                };
                let g = u32::try_from(g)
                    .map_err(|_| BakeError::Invalid("scene has more than 2^32 triangles".into()))?;
                vertices.push([a, b, c]);
                attributes.push(TriangleAttributes {
                    normals: t.map(|i| inst.mesh.normals[i as usize]),
                    uvs: t.map(|i| inst.mesh.uvs[i as usize]),
                    geometric_normal: gn,
                    material: inst.material,
                    object: inst.object,
                    global: g,
                });
            }
        }
        if vertices.is_empty() {
            return Err(BakeError::Invalid(if global == 0 {
                "scene has no triangles".into()
            } else {
                format!(
                    "all {global} triangles of the scene have zero area: {}",
                    zero_area_meshes(&instances)
                )
            }));
        }
        if vertices.len() >= (u32::MAX / 2) as usize {
            return Err(BakeError::Invalid("scene has too many triangles".into()));
        }
        let start = Instant::now();
        let aabbs: Vec<Aabb> = vertices
            .iter()
            .map(|v| Aabb::from_points(&v.map(Vec3A::from)))
            .collect();
        let bvh = build_cwbvh(&aabbs)?;
        // Put the triangles in leaf order so a primitive slot indexes them directly.
        let vertices_bvh: Vec<[Vec3; 3]> = bvh
            .primitive_indices
            .iter()
            .map(|&i| vertices[i as usize])
            .collect();
        let attributes_bvh: Vec<TriangleAttributes> = bvh
            .primitive_indices
            .iter()
            .map(|&i| attributes[i as usize])
            .collect();
        let planes = vertices_bvh.iter().map(triangle_plane).collect();
        let vertices_bvh: Vec<Corners> = vertices_bvh.iter().map(Corners::new).collect();
        let build_time = start.elapsed();
        let mut input_order = vec![0u32; vertices.len()];
        for (slot, &i) in bvh.primitive_indices.iter().enumerate() {
            input_order[i as usize] = slot as u32;
        }
        let bounds = vertices.iter().flatten().fold(
            (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)),
            |(lo, hi), p| (lo.min(*p), hi.max(*p)),
        );
        Ok(TriangleScene {
            bvh,
            vertices: vertices_bvh,
            planes,
            attributes: attributes_bvh,
            input_order,
            build_time,
            bounds,
            #[cfg(target_arch = "x86_64")]
            avx2: std::arch::is_x86_feature_detected!("avx2")
                && std::arch::is_x86_feature_detected!("popcnt")
                && std::arch::is_x86_feature_detected!("lzcnt")
                && std::arch::is_x86_feature_detected!("bmi1")
                && std::arch::is_x86_feature_detected!("bmi2"),
            #[cfg(not(target_arch = "x86_64"))]
            avx2: false,
        })
    }

    /// The scene's (non-degenerate) triangles in input order: instance by instance, each
    /// instance's in its own order, zero-area ones left out.
    pub fn triangles(&self) -> Vec<TriangleRecord> {
        self.input_order
            .iter()
            .map(|&slot| {
                let a = &self.attributes[slot as usize];
                TriangleRecord {
                    corners: self.vertices[slot as usize].vertices(),
                    normals: a.normals,
                    uvs: a.uvs,
                    geometric_normal: a.geometric_normal,
                    material: a.material,
                    object: a.object,
                    global: a.global,
                }
            })
            .collect()
    }

    /// Number of (non-degenerate) triangles in the BVH.
    pub fn triangle_count(&self) -> usize {
        self.vertices.len()
    }

    /// Wall time of the BVH construction proper (bounding boxes, PLOC, reinsertion, CWBVH
    /// conversion and reordering).
    pub fn build_time(&self) -> Duration {
        self.build_time
    }

    /// Axis-aligned bounds `(min, max)` of all triangles.
    pub fn bounds(&self) -> (Vec3, Vec3) {
        self.bounds
    }

    /// Closest hit by testing every triangle (in input order): the reference for tests.
    pub fn intersect_brute_force(&self, ray: &Ray, t_max: f32) -> Option<SurfaceHit> {
        let pr = PreparedRay::new(ray, t_max)?;
        let mut best: Option<(usize, TriHit)> = None;
        let mut t_best = t_max;
        for &slot in &self.input_order {
            let slot = slot as usize;
            if let Some(h) =
                intersect_triangle(&self.vertices[slot], &self.planes[slot], &pr, t_best)
            {
                t_best = h.t;
                best = Some((slot, h));
            }
        }
        best.map(|(slot, h)| self.surface_hit(slot, &h))
    }

    fn surface_hit(&self, slot: usize, h: &TriHit) -> SurfaceHit {
        let a = &self.attributes[slot];
        let [p0, p1, p2] = self.vertices[slot].vertices();
        let [b0, b1, b2] = h.barycentric;
        let gn = a.geometric_normal;
        let mut sn = (a.normals[0] * b0 + a.normals[1] * b1 + a.normals[2] * b2).normalize_or(gn);
        if sn.dot(gn) < 0.0 {
            sn = -sn;
        }
        SurfaceHit {
            t: h.t,
            position: p0 * b0 + p1 * b1 + p2 * b2,
            geometric_normal: gn,
            shading_normal: sn,
            uv: a.uvs[0] * b0 + a.uvs[1] * b1 + a.uvs[2] * b2,
            material: a.material,
            object: a.object,
            triangle: a.global,
            extent: p0.abs().max(p1.abs()).max(p2.abs()).max_element(),
        }
    }
}

impl Intersector for TriangleScene {
    fn intersect(&self, ray: &Ray, t_max: f32) -> Option<SurfaceHit> {
        #[cfg(target_arch = "x86_64")]
        if self.avx2 {
            // SAFETY: `avx2` is true only where the CPU has these features (`build`).
            return unsafe { self.intersect_avx2(ray, t_max) };
        }
        self.intersect_impl::<false>(ray, t_max)
    }

    fn occluded(&self, ray: &Ray, t_max: f32) -> bool {
        self.occluded_in_stream(ray, t_max, 0)
    }

    fn occluded_in_stream(&self, ray: &Ray, t_max: f32, stream: usize) -> bool {
        let stream = stream.min(OCCLUSION_STREAMS - 1);
        #[cfg(target_arch = "x86_64")]
        if self.avx2 {
            // SAFETY: `avx2` is true only where the CPU has these features (`build`).
            return unsafe { self.occluded_avx2(ray, t_max, stream) };
        }
        self.occluded_impl::<false>(ray, t_max, stream)
    }

    fn intersect_packet(&self, rays: &[Ray], t_max: f32, hits: &mut [Option<SurfaceHit>]) {
        assert_eq!(rays.len(), hits.len(), "one hit slot per ray");
        for (rays, hits) in rays.chunks(PACKET).zip(hits.chunks_mut(PACKET)) {
            #[cfg(target_arch = "x86_64")]
            if self.avx2 {
                // SAFETY: `avx2` is true only where the CPU has these features (`build`).
                unsafe { self.intersect_packet_avx2(rays, t_max, hits) };
                continue;
            }
            self.intersect_packet_impl::<false>(rays, t_max, hits);
        }
    }
}

/// The node-culling bound of a packet's ray relative to the `t` at which its seed triangle
/// is hit (see [`TriangleScene::intersect_packet`]): far above the rounding of `t`.
const SEED_CULL_MARGIN: f32 = 1.0 + 1.0 / 65536.0;

impl TriangleScene {
    /// [`Intersector::intersect`] compiled for AVX2: the node test takes all 8 children in
    /// one 256-bit vector (the same operations per lane as the SSE test, so the same lanes).
    /// Nothing else may differ: Rust never contracts `a * b + c` into a fused multiply–add.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,popcnt,lzcnt,bmi1,bmi2")]
    fn intersect_avx2(&self, ray: &Ray, t_max: f32) -> Option<SurfaceHit> {
        self.intersect_impl::<true>(ray, t_max)
    }

    /// [`Intersector::occluded`] compiled for AVX2 (see [`Self::intersect_avx2`]).
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,popcnt,lzcnt,bmi1,bmi2")]
    fn occluded_avx2(&self, ray: &Ray, t_max: f32, stream: usize) -> bool {
        self.occluded_impl::<true>(ray, t_max, stream)
    }

    /// [`Intersector::intersect_packet`] for at most [`PACKET`] rays, compiled for AVX2 (see
    /// [`Self::intersect_avx2`]).
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,popcnt,lzcnt,bmi1,bmi2")]
    fn intersect_packet_avx2(&self, rays: &[Ray], t_max: f32, hits: &mut [Option<SurfaceHit>]) {
        self.intersect_packet_impl::<true>(rays, t_max, hits)
    }

    /// The closest hits of at most [`PACKET`] rays, traversing the BVH once for all of them
    /// (see the module documentation); `AVX2` as in [`Self::intersect_impl`].
    #[inline(always)]
    fn intersect_packet_impl<const AVX2: bool>(
        &self,
        rays: &[Ray],
        t_max: f32,
        hits: &mut [Option<SurfaceHit>],
    ) {
        let n = rays.len().min(PACKET).min(hits.len());
        // Rays that cannot hit anything (and the slots past `n`) hold a placeholder that no
        // mask bit selects.
        let placeholder =
            PreparedRay::new(&Ray::new(Vec3::ZERO, Vec3::Z), 1.0).expect("a valid placeholder ray");
        let mut active = 0u32;
        let prs: [PreparedRay; PACKET] = std::array::from_fn(|i| {
            match rays
                .get(i)
                .filter(|_| i < n)
                .and_then(|r| PreparedRay::new(r, t_max))
            {
                Some(pr) => {
                    active |= 1 << i;
                    pr
                }
                None => placeholder,
            }
        });
        if active == 0 {
            hits[..n].fill(None);
            return;
        }
        let mut t_best = [t_max; PACKET];
        let mut best: [Option<(usize, TriHit)>; PACKET] = [None; PACKET];
        // Nodes are culled at `t_cull[r]`, at most `t_best[r]`: each ray first tries the
        // triangle that the same ray of this thread's last packet hit (a cube-map tile's next
        // packet samples the same texels, so it is often hit again) and, if it is hit at `t`,
        // skips every node entered only beyond `t` (1 + 2⁻¹⁶), as it would once that
        // triangle were found. Triangles are still accepted against `t_best` alone, which
        // starts at `t_max` as in the single-ray traversal: that a triangle beyond the bound
        // is never tested only drops candidates that a closer hit replaces anyway, so the
        // hits are the same, ties between triangles at bit-identical `t` included
        // (`tests::packet_seeds_do_not_change_hits`).
        let seeds = LAST_PACKET_HITS.with(|l| l.get());
        let mut t_cull = self.seed_culls(&prs, active, t_max, &seeds);
        // Children in the octant order of the first ray (obvhs's single-ray order: the slot
        // `k ^ octant` k-th), so the nearer children of most rays come first.
        let d = prs[active.trailing_zeros() as usize].dir;
        let octant =
            (usize::from(d.x < 0.0) << 2) | (usize::from(d.y < 0.0) << 1) | usize::from(d.z < 0.0);
        // Each visit pops one entry and pushes at most 8, and the depth is at most
        // MAX_BVH_DEPTH (`build`), so 8 entries per level suffice.
        let mut stack = [(0u32, 0u32); 8 * MAX_BVH_DEPTH];
        stack[0] = (0, active);
        let mut depth = 1;
        while depth > 0 {
            depth -= 1;
            let (index, mask) = stack[depth];
            let node = &self.bvh.nodes[index as usize];
            let mut child_rays = [0u32; 8];
            #[cfg(target_arch = "x86_64")]
            if AVX2 {
                // SAFETY: `AVX2` is true only in `intersect_packet_avx2`, an AVX2 function
                // called only where the CPU has AVX2.
                unsafe { packet_node_avx2(node, &prs, mask, &t_cull, &mut child_rays) };
            } else {
                packet_node(node, &prs, mask, &t_cull, &mut child_rays);
            }
            #[cfg(not(target_arch = "x86_64"))]
            packet_node(node, &prs, mask, &t_cull, &mut child_rays);
            // Leaves first (their hits shorten the rays before the inner children's tests).
            for k in 0..8 {
                let slot = k ^ octant;
                let rays_in = child_rays[slot];
                if rays_in == 0 || node.imask & (1 << slot) != 0 {
                    continue;
                }
                // A leaf's meta: first triangle's offset in the low 5 bits, the count in
                // unary in the top 3 (an empty slot: 0, no triangles).
                let meta = node.child_meta[slot];
                let first = node.primitive_base_idx as usize + usize::from(meta & 0x1f);
                for slot in first..first + (meta >> 5).count_ones() as usize {
                    let (corners, plane) = (&self.vertices[slot], &self.planes[slot]);
                    let mut m = rays_in;
                    while m != 0 {
                        let r = m.trailing_zeros() as usize;
                        m &= m - 1;
                        if let Some(h) = intersect_triangle(corners, plane, &prs[r], t_best[r]) {
                            t_best[r] = h.t;
                            t_cull[r] = t_cull[r].min(h.t);
                            best[r] = Some((slot, h));
                        }
                    }
                }
            }
            // Inner children, the first in octant order on top of the stack. Child nodes are
            // stored in slot order from `child_base_idx`.
            for k in (0..8).rev() {
                let slot = k ^ octant;
                let rays_in = child_rays[slot];
                if rays_in == 0 || node.imask & (1 << slot) == 0 {
                    continue;
                }
                let before = u32::from(node.imask) & ((1u32 << slot) - 1);
                stack[depth] = (node.child_base_idx + before.count_ones(), rays_in);
                depth += 1;
            }
        }
        let mut seeds = seeds;
        for (seed, best) in seeds.iter_mut().zip(&best) {
            if let Some((slot, _)) = best {
                *seed = *slot as u32;
            }
        }
        LAST_PACKET_HITS.with(|l| l.set(seeds));
        for (hit, best) in hits[..n].iter_mut().zip(best) {
            *hit = best.map(|(slot, h)| self.surface_hit(slot, &h));
        }
    }

    /// The cull distance of each active ray of a packet: where it hits the triangle its
    /// `seeds` entry names (the same ray's hit in this thread's last packet), times
    /// `SEED_CULL_MARGIN`; else `t_max`.
    #[inline(always)]
    fn seed_culls(
        &self,
        prs: &[PreparedRay; PACKET],
        active: u32,
        t_max: f32,
        seeds: &[u32; PACKET],
    ) -> [f32; PACKET] {
        let mut t_cull = [t_max; PACKET];
        let mut m = active;
        while m != 0 {
            let r = m.trailing_zeros() as usize;
            m &= m - 1;
            let slot = seeds[r] as usize;
            if slot < self.vertices.len() {
                if let Some(h) =
                    intersect_triangle(&self.vertices[slot], &self.planes[slot], &prs[r], t_max)
                {
                    t_cull[r] = (h.t * SEED_CULL_MARGIN).min(t_max);
                }
            }
        }
        t_cull
    }

    /// The closest hit; `AVX2`: use [`node_lanes_avx2`] (only in an AVX2 function).
    #[inline(always)]
    fn intersect_impl<const AVX2: bool>(&self, ray: &Ray, t_max: f32) -> Option<SurfaceHit> {
        let pr = PreparedRay::new(ray, t_max)?;
        let mut t_best = t_max;
        let mut best: Option<(usize, TriHit)> = None;
        let mut state = self.bvh.new_traversal(Vec3A::from(pr.dir));
        let mut node: &CwBvhNode;
        obvhs::traverse!(
            self.bvh,
            node,
            state,
            intersect_node::<AVX2>(node, &pr, t_best, state.oct_inv4),
            {
                let slot = state.primitive_id as usize;
                if let Some(h) =
                    intersect_triangle(&self.vertices[slot], &self.planes[slot], &pr, t_best)
                {
                    t_best = h.t;
                    best = Some((slot, h));
                    // Most candidates are the final hit: load its shading data while the
                    // traversal goes on.
                    let a = &self.attributes[slot] as *const TriangleAttributes;
                    prefetch(a);
                    prefetch(a.wrapping_byte_add(std::mem::size_of::<TriangleAttributes>() - 1));
                }
            }
        );
        best.map(|(slot, h)| self.surface_hit(slot, &h))
    }

    /// Whether anything is hit; `AVX2` as in [`Self::intersect_impl`]; `stream` below
    /// [`OCCLUSION_STREAMS`] (see [`Intersector::occluded_in_stream`]).
    #[inline(always)]
    fn occluded_impl<const AVX2: bool>(&self, ray: &Ray, t_max: f32, stream: usize) -> bool {
        let Some(pr) = PreparedRay::new(ray, t_max) else {
            return false;
        };
        // The occluders of this thread's last two occluded shadow rays of the same stream
        // first: neighbouring shadow rays are often blocked by the same triangle. (Any
        // triangle hit answers the query, so the answer does not depend on this.)
        let recent = LAST_OCCLUDER.with(|l| l[stream].get());
        for cached in recent.map(|c| c as usize) {
            if cached < self.vertices.len()
                && intersect_triangle(&self.vertices[cached], &self.planes[cached], &pr, t_max)
                    .is_some()
            {
                return true;
            }
        }
        let mut state = self.bvh.new_traversal(Vec3A::from(pr.dir));
        let mut node: &CwBvhNode;
        let mut hit = false;
        'outer: {
            obvhs::traverse!(
                self.bvh,
                node,
                state,
                intersect_node::<AVX2>(node, &pr, t_max, state.oct_inv4),
                {
                    let slot = state.primitive_id as usize;
                    if intersect_triangle(&self.vertices[slot], &self.planes[slot], &pr, t_max)
                        .is_some()
                    {
                        LAST_OCCLUDER.with(|l| l[stream].set([state.primitive_id, recent[0]]));
                        hit = true;
                        break 'outer;
                    }
                }
            );
        }
        hit
    }
}

thread_local! {
    /// Per ray of this thread's last packet: the slot of the triangle it hit (in whichever
    /// scene; `u32::MAX` for none yet).
    static LAST_PACKET_HITS: std::cell::Cell<[u32; PACKET]> =
        const { std::cell::Cell::new([u32::MAX; PACKET]) };
    /// Per shadow-ray stream: the slots of the triangles that occluded this thread's last two
    /// occluded shadow rays of that stream, the latest first (in whichever scene; `u32::MAX`
    /// for none).
    static LAST_OCCLUDER: [std::cell::Cell<[u32; 2]>; OCCLUSION_STREAMS] =
        const { [const { std::cell::Cell::new([u32::MAX; 2]) }; OCCLUSION_STREAMS] };
}

/// Depth (levels of nodes) of a CWBVH.
pub fn cwbvh_depth(nodes: &[CwBvhNode]) -> usize {
    let mut depth = 0;
    let mut stack = vec![(0usize, 1usize)];
    while let Some((i, d)) = stack.pop() {
        depth = depth.max(d);
        let Some(n) = nodes.get(i) else { continue };
        for k in 0..n.imask.count_ones() as usize {
            stack.push((n.child_base_idx as usize + k, d + 1));
        }
    }
    depth
}

/// Asks the CPU to bring the cache line of `p` into L1: a hint, with no effect on results.
#[inline(always)]
fn prefetch<T>(p: *const T) {
    #[cfg(target_arch = "x86_64")]
    // SAFETY: SSE is part of x86_64; a prefetch reads nothing the program sees and cannot
    // fault, whatever the address.
    unsafe {
        std::arch::x86_64::_mm_prefetch::<{ std::arch::x86_64::_MM_HINT_T0 }>(p.cast::<i8>());
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = p;
}

#[cfg(test)]
mod tests {
    use super::*;
    use oslf_scene::shapes;
    use oslf_shading::random::Rng;

    fn same_hit(a: Option<TriHit>, b: Option<TriHit>) -> bool {
        match (a, b) {
            (None, None) => true,
            (Some(a), Some(b)) => {
                a.t.to_bits() == b.t.to_bits()
                    && a.barycentric.map(f32::to_bits) == b.barycentric.map(f32::to_bits)
            }
            _ => false,
        }
    }

    #[test]
    fn simd_triangle_test_is_the_scalar_one() {
        let mut rng = Rng::new(7, 1);
        let mut p =
            |s: f32| Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * s - s / 2.0;
        let mut hits = 0;
        for k in 0..20_000 {
            // Random triangles, some with corners on a grid (rays through shared edges and
            // corners), rays from random points towards a corner, an edge point or anywhere.
            let grid = k % 3 == 0;
            let corner = |p: &mut dyn FnMut(f32) -> Vec3| {
                let v = p(4.0);
                if grid {
                    v.round()
                } else {
                    v
                }
            };
            let v = [corner(&mut p), corner(&mut p), corner(&mut p)];
            if (v[1] - v[0]).cross(v[2] - v[0]).length() == 0.0 {
                continue;
            }
            let o = if k % 5 == 0 { v[0] } else { p(8.0) };
            let target = match k % 4 {
                0 => v[1],
                1 => (v[1] + v[2]) * 0.5,
                _ => p(4.0),
            };
            let Some(dir) = (target - o).try_normalize() else {
                continue;
            };
            let Some(r) = PreparedRay::new(&Ray::new(o, dir), f32::MAX) else {
                continue;
            };
            let c = Corners::new(&v);
            let plane = triangle_plane(&v);
            let simd = intersect_triangle(&c, &plane, &r, f32::MAX);
            let scalar = intersect_triangle_scalar(&v, &plane, &r, f32::MAX);
            assert!(
                same_hit(simd, scalar),
                "{v:?} {o} {dir}: {simd:?} {scalar:?}"
            );
            hits += usize::from(simd.is_some());
        }
        assert!(hits > 1000, "{hits}");
    }

    #[test]
    fn avx2_traversal_is_the_sse_one() {
        let s = test_scene();
        let mut rng = Rng::new(3, 4);
        let mut p = || Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 8.0 - 4.0;
        for _ in 0..20_000 {
            let o = p();
            let Some(dir) = p().try_normalize() else {
                continue;
            };
            let ray = Ray::new(o, dir);
            let t_max = 1.0 + o.length();
            assert_eq!(
                s.intersect(&ray, f32::MAX),
                s.intersect_impl::<false>(&ray, f32::MAX)
            );
            assert_eq!(
                s.occluded(&ray, t_max),
                s.occluded_impl::<false>(&ray, t_max, 0)
            );
        }
    }

    /// Spheres of several sizes inside a box: nested, overlapping and far geometry.
    fn test_scene() -> TriangleScene {
        let mut instances = Vec::new();
        for (k, r) in [1.0f32, 0.3, 2.5].into_iter().enumerate() {
            let mut mesh = shapes::sphere(r, 24).unwrap();
            for q in &mut mesh.positions {
                *q += Vec3::new(k as f32 * 0.7, 0.2, -0.1 * k as f32);
            }
            instances.push(Instance {
                name: String::new(),
                mesh,
                material: 0,
                object: 0,
            });
        }
        instances.push(Instance {
            name: String::new(),
            mesh: shapes::cuboid(Vec3::splat(6.0)).unwrap(),
            material: 1,
            object: 0,
        });
        TriangleScene::build(instances).unwrap()
    }

    /// Checks `intersect_packet` (AVX2 where the CPU has it, and the SSE / portable packet
    /// test) against `intersect`, ray by ray: the same hit, or a hit at the bit-identical `t`
    /// (a tie between triangles, which either traversal may break either way). Returns the
    /// number of hits.
    fn check_packet(s: &TriangleScene, rays: &[Ray], t_max: f32) -> usize {
        let single: Vec<Option<SurfaceHit>> = rays.iter().map(|r| s.intersect(r, t_max)).collect();
        let mut dispatched = vec![None; rays.len()];
        s.intersect_packet(rays, t_max, &mut dispatched);
        let mut portable = vec![None; rays.len()];
        for (r, h) in rays.chunks(PACKET).zip(portable.chunks_mut(PACKET)) {
            s.intersect_packet_impl::<false>(r, t_max, h);
        }
        for packet in [&dispatched, &portable] {
            for ((ray, a), b) in rays.iter().zip(&single).zip(packet) {
                match (a, b) {
                    (None, None) => {}
                    (Some(a), Some(b)) => assert!(
                        a == b || a.t.to_bits() == b.t.to_bits(),
                        "{ray:?} t_max {t_max}: {a:?} vs {b:?}"
                    ),
                    _ => panic!("{ray:?} t_max {t_max}: {a:?} vs {b:?}"),
                }
            }
        }
        single.iter().flatten().count()
    }

    #[test]
    fn occlusion_streams_do_not_change_answers() {
        // Shadow rays of one stream after another (so each stream's cached occluder is a
        // triangle that blocked an unrelated ray) answer exactly as the brute-force test.
        let s = test_scene();
        let mut rng = Rng::new(11, 3);
        let mut u = || rng.next_f32();
        let mut blocked = 0;
        for k in 0..20_000 {
            let origin = Vec3::new(u() * 5.0 - 2.5, u() * 5.0 - 2.5, u() * 5.0 - 2.5);
            let dir = oslf_shading::warp::sample_uniform_sphere(glam::Vec2::new(u(), u()));
            let ray = Ray::new(origin, dir);
            let t_max = if k % 3 == 0 { f32::MAX } else { u() * 4.0 };
            let expected = s.intersect_brute_force(&ray, t_max).is_some();
            let stream = k % (OCCLUSION_STREAMS + 2);
            assert_eq!(
                s.occluded_in_stream(&ray, t_max, stream),
                expected,
                "{ray:?}"
            );
            assert_eq!(
                s.occluded_impl::<false>(&ray, t_max, stream % OCCLUSION_STREAMS),
                expected
            );
            assert_eq!(s.occluded(&ray, t_max), expected);
            blocked += usize::from(expected);
        }
        assert!((2_000..18_000).contains(&blocked), "{blocked}");
    }

    #[test]
    fn packet_traversal_is_the_single_ray_one() {
        let s = test_scene();
        let mut rng = Rng::new(5, 9);
        let mut u = || rng.next_f32();
        let mut hits = 0;
        let mut rays_total = 0;
        for k in 0..3000 {
            // Coherent packets (one origin, directions within a small cone, as a cube-map
            // tile's primary rays), incoherent ones (any origin, any direction, mixed octants),
            // and packets of every length from 1 to 2 × PACKET + 1.
            let n = 1 + k % (2 * PACKET + 1);
            let coherent = k % 2 == 0;
            let o = Vec3::new(u(), u(), u()) * 8.0 - 4.0;
            let axis = Vec3::new(u(), u(), u()) * 2.0 - 1.0;
            let rays: Vec<Ray> = (0..n)
                .map(|_| {
                    let jitter = Vec3::new(u(), u(), u()) * 2.0 - 1.0;
                    let (origin, dir) = if coherent {
                        (o, axis + jitter * 0.05)
                    } else {
                        (Vec3::new(u(), u(), u()) * 8.0 - 4.0, jitter)
                    };
                    Ray::new(origin, dir.try_normalize().unwrap_or(Vec3::X))
                })
                .collect();
            let t_max = match k % 4 {
                0 => f32::MAX,
                1 => f32::INFINITY,
                2 => 0.5 + u() * 4.0,
                _ => 1e-3,
            };
            hits += check_packet(&s, &rays, t_max);
            rays_total += n;
        }
        assert!(hits > rays_total / 4, "{hits} of {rays_total}");
    }

    #[test]
    fn packet_seeds_do_not_change_hits() {
        // The same packets without seeds and with seeds of every kind (the hits of a
        // neighbouring packet, of the packet itself, a triangle each ray misses, a slot past
        // the end) give exactly the same hits, also where a ray meets two triangles at the
        // same `t`: the diagonals and edges of a box's faces, and the coplanar triangles of
        // the floor under the spheres.
        let mut instances = vec![Instance {
            name: String::new(),
            mesh: shapes::cuboid(Vec3::ONE).unwrap(),
            material: 0,
            object: 0,
        }];
        let mut floor = shapes::cuboid(Vec3::new(8.0, 8.0, 0.2)).unwrap();
        for q in &mut floor.positions {
            q.z -= 2.0;
        }
        instances.push(Instance {
            name: String::new(),
            mesh: floor,
            material: 1,
            object: 0,
        });
        for (k, r) in [0.3f32, 0.2].into_iter().enumerate() {
            let mut mesh = shapes::sphere(r, 16).unwrap();
            for q in &mut mesh.positions {
                *q += Vec3::new(1.2 - 2.4 * k as f32, 0.5, -1.2);
            }
            instances.push(Instance {
                name: String::new(),
                mesh,
                material: 0,
                object: 0,
            });
        }
        let scene = TriangleScene::build(instances).unwrap();
        let set_seeds = |seeds: [u32; PACKET]| LAST_PACKET_HITS.with(|l| l.set(seeds));
        let slots = |hits: &[Option<SurfaceHit>]| {
            let mut seeds = [u32::MAX; PACKET];
            for (seed, h) in seeds.iter_mut().zip(hits) {
                if let Some(h) = h {
                    *seed = scene.input_order[h.triangle as usize];
                }
            }
            seeds
        };
        let mut rng = Rng::new(21, 4);
        let mut u = || rng.next_f32();
        let mut previous = [u32::MAX; PACKET];
        let mut hits_total = 0;
        for k in 0..2000 {
            let o = match k % 3 {
                0 => Vec3::new(0.0, 0.0, 3.0),
                1 => Vec3::new(u() * 4.0 - 2.0, u() * 4.0 - 2.0, 2.5),
                _ => Vec3::new(0.05, -0.03, 0.6),
            };
            let rays: Vec<Ray> = (0..PACKET)
                .map(|i| {
                    // Towards points on the box's top diagonal, its edges, and anywhere.
                    let target = match (k + i) % 4 {
                        0 => {
                            let a = u() - 0.5;
                            Vec3::new(a, a, 0.5)
                        }
                        1 => Vec3::new(0.5, u() - 0.5, 0.5),
                        2 => Vec3::new(u() * 6.0 - 3.0, u() * 6.0 - 3.0, -1.9),
                        _ => Vec3::new(u() * 2.0 - 1.0, u() * 2.0 - 1.0, -1.0),
                    };
                    Ray::new(o, (target - o).normalize())
                })
                .collect();
            let t_max = if k % 5 == 0 { 3.0 } else { f32::MAX };
            let mut plain = vec![None; PACKET];
            set_seeds([u32::MAX; PACKET]);
            scene.intersect_packet(&rays, t_max, &mut plain);
            let own = slots(&plain);
            let mut shifted = own;
            shifted.rotate_left(1);
            let wrong = [(k as u32 * 7) % scene.vertices.len() as u32; PACKET];
            let past_end = [scene.vertices.len() as u32 + 3; PACKET];
            for seeds in [previous, own, shifted, wrong, past_end] {
                for avx2 in [true, false] {
                    set_seeds(seeds);
                    let mut seeded = vec![None; PACKET];
                    if avx2 {
                        scene.intersect_packet(&rays, t_max, &mut seeded);
                    } else {
                        scene.intersect_packet_impl::<false>(&rays, t_max, &mut seeded);
                    }
                    assert_eq!(seeded, plain, "packet {k}, seeds {seeds:?}");
                }
            }
            previous = own;
            hits_total += plain.iter().flatten().count();
        }
        assert!(hits_total > 20_000, "{hits_total}");
    }

    #[test]
    fn packet_traversal_edge_cases() {
        let s = test_scene();
        let box_scene = TriangleScene::build(vec![Instance {
            name: String::new(),
            mesh: shapes::cuboid(Vec3::ONE).unwrap(),
            material: 0,
            object: 0,
        }])
        .unwrap();
        let o = Vec3::new(0.0, 0.0, 5.0);
        // Bad rays (zero, NaN or infinite direction or origin) among good ones: they miss,
        // the others are unaffected.
        let mixed = [
            Ray::new(o, -Vec3::Z),
            Ray::new(o, Vec3::ZERO),
            Ray::new(o, Vec3::NAN),
            Ray::new(Vec3::INFINITY, -Vec3::Z),
            Ray::new(o, Vec3::new(0.0, f32::INFINITY, -1.0)),
            Ray::new(o, Vec3::new(0.1, 0.0, -1.0).normalize()),
        ];
        for scene in [&s, &box_scene] {
            assert_eq!(check_packet(scene, &mixed, 10.0), 2);
            // Only bad rays, and bad t_max: nothing hit.
            assert_eq!(check_packet(scene, &mixed[1..5], 10.0), 0);
            assert_eq!(check_packet(scene, &mixed, f32::NAN), 0);
            assert_eq!(check_packet(scene, &mixed, -1.0), 0);
            assert_eq!(check_packet(scene, &mixed, 0.0), 0);
            assert_eq!(check_packet(scene, &[], 10.0), 0);
        }
        // t_max just below and above the hit at t = 4.5 (the box's top face at z = 0.5).
        let down = [Ray::new(o, -Vec3::Z); 3];
        assert_eq!(check_packet(&box_scene, &down, 4.5), 0);
        assert_eq!(check_packet(&box_scene, &down, 4.5001), 3);
        // Rays that miss everything (pointing away), axis-parallel rays and rays with zero
        // components, through the box's edges and corners (grazing, and ties between the two
        // triangles of a face), in one packet.
        let mut rays = vec![Ray::new(o, Vec3::Z), Ray::new(o, Vec3::X)];
        for x in [-0.5f32, -0.25, 0.0, 0.5] {
            for y in [-0.5f32, 0.0, 0.5, 0.500_001] {
                rays.push(Ray::new(Vec3::new(x, y, 5.0), -Vec3::Z));
                rays.push(Ray::new(Vec3::new(5.0, x, y), -Vec3::X));
                // Grazing: along a face, in its plane.
                rays.push(Ray::new(Vec3::new(x, -5.0, 0.5), Vec3::Y));
            }
        }
        let hits = check_packet(&box_scene, &rays, f32::MAX);
        assert!(hits > 16, "{hits}");
        // Origins on the surface (as sample points and path vertices): rays leaving it do
        // not re-hit it (and escape), rays into it see the far side.
        let on_surface: Vec<Ray> = (0..PACKET)
            .map(|i| {
                let p = Vec3::new(-0.4 + 0.05 * i as f32, 0.1, 0.5);
                let dir = if i % 2 == 0 { Vec3::Z } else { -Vec3::Z };
                Ray::new(p, Vec3::new(0.01 * i as f32, 0.0, dir.z).normalize())
            })
            .collect();
        assert_eq!(check_packet(&box_scene, &on_surface, f32::MAX), PACKET / 2);
        // A capture's tile: one origin just above a sphere, a degenerate tile (all rays the
        // same direction), and rays from inside the box in all six axis directions.
        let above = Vec3::new(0.0, 1.2 + 1e-4, 0.0);
        let same = vec![Ray::new(above, -Vec3::Y); PACKET];
        assert_eq!(check_packet(&s, &same, f32::MAX), PACKET);
        let axes: Vec<Ray> = [Vec3::X, -Vec3::X, Vec3::Y, -Vec3::Y, Vec3::Z, -Vec3::Z]
            .map(|d| Ray::new(Vec3::ZERO, d))
            .to_vec();
        assert_eq!(check_packet(&box_scene, &axes, f32::MAX), 6);
    }

    #[test]
    fn single_triangle_scene() {
        let mesh = Mesh {
            positions: vec![Vec3::ZERO, Vec3::X, Vec3::Y],
            normals: vec![Vec3::Z; 3],
            uvs: vec![Vec2::ZERO, Vec2::X, Vec2::Y],
            triangles: vec![[0, 1, 2]],
        };
        let s = TriangleScene::build(vec![Instance {
            name: String::new(),
            mesh,
            material: 3,
            object: 7,
        }])
        .unwrap();
        let ray = Ray::new(Vec3::new(0.25, 0.25, 1.0), -Vec3::Z);
        let h = s.intersect(&ray, f32::INFINITY).unwrap();
        assert!((h.t - 1.0).abs() < 1e-6);
        assert_eq!((h.material, h.object, h.triangle), (3, 7, 0));
        assert!((h.uv - Vec2::new(0.25, 0.25)).length() < 1e-6);
        assert!(s.occluded(&ray, 2.0));
        assert!(!s.occluded(&ray, 1.0)); // t_max exclusive
        assert!(s.intersect(&ray, 0.5).is_none());
    }

    #[test]
    fn rejects_empty_and_degenerate() {
        assert!(TriangleScene::build(vec![]).is_err());
        let mesh = Mesh {
            positions: vec![Vec3::ZERO, Vec3::X, Vec3::X * 2.0],
            normals: vec![Vec3::Z; 3],
            uvs: vec![Vec2::ZERO; 3],
            triangles: vec![[0, 1, 2]],
        };
        assert!(TriangleScene::build(vec![Instance {
            name: String::new(),
            mesh: mesh.clone(),
            material: 0,
            object: 0
        }])
        .is_err());
        // The message names the meshes whose triangles these are.
        let named = |name: &str| Instance {
            name: name.into(),
            mesh: mesh.clone(),
            material: 0,
            object: 0,
        };
        let e = TriangleScene::build(vec![
            named("[[mesh]] \"flat.obj\""),
            named("object \"lid\""),
        ])
        .err()
        .unwrap()
        .to_string();
        assert_eq!(
            e,
            "all 2 triangles of the scene have zero area: [[mesh]] \"flat.obj\" (1 triangles), \
             object \"lid\" (1 triangles)"
        );
        let many = (0..10).map(|i| named(&format!("[[box]] {i}"))).collect();
        let e = TriangleScene::build(many).err().unwrap().to_string();
        assert!(e.ends_with("[[box]] 7 (1 triangles) and 2 more"), "{e}");
    }

    #[test]
    fn bad_rays_miss() {
        let s = TriangleScene::build(vec![Instance {
            name: String::new(),
            mesh: shapes::cuboid(Vec3::ONE).unwrap(),
            material: 0,
            object: 0,
        }])
        .unwrap();
        let o = Vec3::new(0.0, 0.0, 5.0);
        assert!(s.intersect(&Ray::new(o, Vec3::ZERO), 10.0).is_none());
        assert!(s.intersect(&Ray::new(o, Vec3::NAN), 10.0).is_none());
        assert!(s.intersect(&Ray::new(o, -Vec3::Z), f32::NAN).is_none());
        assert!(!s.occluded(&Ray::new(o, -Vec3::Z), -1.0));
        assert!(s.intersect(&Ray::new(o, -Vec3::Z), f32::INFINITY).is_some());
    }
}
