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

use crate::mesh::Mesh;
use crate::ray::{Intersector, Ray, SurfaceHit, OCCLUSION_STREAMS};
use crate::{BakeError, Result};

/// A world-space mesh with the material and OSLF object its triangles belong to.
#[derive(Clone, Debug, Default)]
pub struct Instance {
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

/// Traversal stack depth of obvhs's `traverse!` (its `TRAVERSAL_STACK_SIZE`).
const MAX_BVH_DEPTH: usize = 32;

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
                .map_err(|e| BakeError::Invalid(format!("instance {k}: {e}")))?;
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
                format!("all {global} triangles of the scene have zero area")
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
        let params = BvhBuildParams {
            pre_split: false,
            ..BvhBuildParams::slow_build()
        };
        let mut bvh2 = PlocBuilder::with_capacity(aabbs.len()).build(
            params.ploc_search_distance,
            &aabbs,
            (0..aabbs.len() as u32).collect(),
            params.sort_precision,
            params.search_depth_threshold,
        );
        ReinsertionOptimizer::default().run(&mut bvh2, params.reinsertion_batch_ratio, None);
        let bvh = bvh2_to_cwbvh(&bvh2, params.max_prims_per_leaf.clamp(1, 3), true, false);
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
        if vertices_bvh.len() != vertices.len() || bvh.nodes.is_empty() {
            return Err(BakeError::Invalid(format!(
                "BVH build produced {} primitives for {} triangles",
                vertices_bvh.len(),
                vertices.len()
            )));
        }
        let depth = cwbvh_depth(&bvh.nodes);
        if depth > MAX_BVH_DEPTH {
            return Err(BakeError::Invalid(format!(
                "degenerate geometry: BVH depth {depth} exceeds {MAX_BVH_DEPTH}"
            )));
        }
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

/// Most rays traversed together by [`TriangleScene::intersect_packet`] (bits of a `u32` mask).
pub const PACKET: usize = 16;

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
        let mut t_cull = [t_max; PACKET];
        let seeds = LAST_PACKET_HITS.with(|l| l.get());
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
fn cwbvh_depth(nodes: &[CwBvhNode]) -> usize {
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

/// A triangle's corners by coordinate (`x[i]` is corner `i`'s x; lane 3 is 0), so that the
/// triangle test loads each coordinate of all three corners as one SSE vector.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(16))]
struct Corners {
    x: [f32; 4],
    y: [f32; 4],
    z: [f32; 4],
}

impl Corners {
    fn new(v: &[Vec3; 3]) -> Self {
        Corners {
            x: [v[0].x, v[1].x, v[2].x, 0.0],
            y: [v[0].y, v[1].y, v[2].y, 0.0],
            z: [v[0].z, v[1].z, v[2].z, 0.0],
        }
    }

    fn vertices(&self) -> [Vec3; 3] {
        [0, 1, 2].map(|i| Vec3::new(self.x[i], self.y[i], self.z[i]))
    }
}

/// Per-ray constants of the watertight test and the node test.
#[derive(Clone, Copy)]
struct PreparedRay {
    origin: Vec3,
    dir: Vec3,
    /// Rows of the permute-and-shear transform: `x' = rx·p`, `y' = ry·p`, `z' = p[kz]`.
    rx: Vec3,
    ry: Vec3,
    rz: Vec3,
    /// `1 / d[kz]`.
    sz: f32,
    /// Reciprocal direction for the slab test (tiny components clamped to ±1e20).
    inv_dir: Vec3A,
    /// Distance from a triangle's plane within which the origin counts as on the triangle.
    self_tolerance: f32,
    /// Byte offsets of the near and far child planes per axis (see [`plane_offsets`]).
    #[cfg_attr(
        not(all(target_arch = "x86_64", target_feature = "sse2")),
        allow(dead_code)
    )]
    planes: [[usize; 2]; 3],
    /// The same choice as indices into `min x, max x, min y, max y, min z, max z`.
    #[cfg_attr(not(target_arch = "x86_64"), allow(dead_code))]
    plane_index: [[usize; 2]; 3],
}

impl PreparedRay {
    /// `None` for a ray that cannot hit anything (non-finite or zero direction, non-finite
    /// origin, `t_max` not positive or NaN).
    #[inline(always)]
    fn new(ray: &Ray, t_max: f32) -> Option<Self> {
        let (o, d) = (ray.origin, ray.dir);
        if !o.is_finite() || !d.is_finite() || d == Vec3::ZERO || t_max.is_nan() || t_max <= 0.0 {
            return None;
        }
        let a = d.abs();
        // kz: the axis of the largest |d| component; kx = kz + 1, ky = kz + 2 (mod 3).
        let kz = if a.x > a.y {
            if a.x > a.z {
                0
            } else {
                2
            }
        } else if a.y > a.z {
            1
        } else {
            2
        };
        let (ex, ey, ez, dx, dy, dz) = match kz {
            0 => (Vec3::Y, Vec3::Z, Vec3::X, d.y, d.z, d.x),
            1 => (Vec3::Z, Vec3::X, Vec3::Y, d.z, d.x, d.y),
            _ => (Vec3::X, Vec3::Y, Vec3::Z, d.x, d.y, d.z),
        };
        let sx = -dx / dz;
        let sy = -dy / dz;
        let inv = |c: f32| {
            if c.abs() < 1e-20 {
                if c < 0.0 {
                    -1e20
                } else {
                    1e20
                }
            } else {
                1.0 / c
            }
        };
        Some(Self {
            origin: o,
            dir: d,
            rx: ex + ez * sx,
            ry: ey + ez * sy,
            rz: ez,
            sz: 1.0 / dz,
            inv_dir: Vec3A::new(inv(d.x), inv(d.y), inv(d.z)),
            self_tolerance: SELF_TOLERANCE * o.abs().max_element(),
            planes: plane_offsets(d),
            plane_index: {
                let neg = |c: f32| usize::from(c < 0.0);
                let (nx, ny, nz) = (neg(d.x), neg(d.y), neg(d.z));
                [[nx, 1 - nx], [2 + ny, 3 - ny], [4 + nz, 5 - nz]]
            },
        })
    }
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

/// A ray–triangle hit: distance and barycentric weights of the three corners.
#[derive(Clone, Copy, Debug)]
struct TriHit {
    t: f32,
    barycentric: [f32; 3],
}

/// pbrt's γ(n) = nε / (1 − nε) for f32 (ε = 2⁻²⁴).
const fn gamma(n: f32) -> f32 {
    let e = f32::EPSILON * 0.5;
    n * e / (1.0 - n * e)
}

/// Watertight ray–triangle intersection (Woop, Benthin, Wald 2013; pbrt-v3 §3.6.2) with
/// `t` in `(δ_t, t_max)`, δ_t the conservative rounding-error bound of `t`.
///
/// SSE version of [`intersect_triangle_scalar`]: the three corners' sheared coordinates and
/// edge functions in one vector each, every lane by the same operations in the same order as
/// the scalar code (so the same bits: `tests::simd_triangle_test_is_the_scalar_one`); the
/// rest, reached by few candidates, is the scalar code.
#[cfg(target_arch = "x86_64")]
#[inline(always)]
fn intersect_triangle(
    c: &Corners,
    plane: &[f32; 4],
    r: &PreparedRay,
    t_max: f32,
) -> Option<TriHit> {
    use std::arch::x86_64::*;
    // SAFETY: SSE2 is part of x86_64; the loads read the 16-byte-aligned `[f32; 4]` fields
    // of `*c`.
    let (xs, ys, e) = unsafe {
        let px = _mm_sub_ps(_mm_load_ps(c.x.as_ptr()), _mm_set1_ps(r.origin.x));
        let py = _mm_sub_ps(_mm_load_ps(c.y.as_ptr()), _mm_set1_ps(r.origin.y));
        let pz = _mm_sub_ps(_mm_load_ps(c.z.as_ptr()), _mm_set1_ps(r.origin.z));
        // `Vec3::dot`: (a.x·b.x + a.y·b.y) + a.z·b.z.
        let dot = |a: Vec3| {
            _mm_add_ps(
                _mm_add_ps(
                    _mm_mul_ps(_mm_set1_ps(a.x), px),
                    _mm_mul_ps(_mm_set1_ps(a.y), py),
                ),
                _mm_mul_ps(_mm_set1_ps(a.z), pz),
            )
        };
        let xs = dot(r.rx);
        let ys = dot(r.ry);
        // Lane i: x_{i+1}·y_{i+2} − y_{i+1}·x_{i+2} (indices mod 3).
        let x12 = _mm_shuffle_ps::<0b11_00_10_01>(xs, xs);
        let y20 = _mm_shuffle_ps::<0b11_01_00_10>(ys, ys);
        let y12 = _mm_shuffle_ps::<0b11_00_10_01>(ys, ys);
        let x20 = _mm_shuffle_ps::<0b11_01_00_10>(xs, xs);
        let e = _mm_sub_ps(_mm_mul_ps(x12, y20), _mm_mul_ps(y12, x20));
        let zero = _mm_setzero_ps();
        let neg = _mm_movemask_ps(_mm_cmplt_ps(e, zero)) & 7;
        let pos = _mm_movemask_ps(_mm_cmpgt_ps(e, zero)) & 7;
        let on_edge = _mm_movemask_ps(_mm_cmpeq_ps(e, zero)) & 7;
        if on_edge == 0 && neg != 0 && pos != 0 {
            return None;
        }
        let mut out = [[0f32; 4]; 3];
        _mm_storeu_ps(out[0].as_mut_ptr(), xs);
        _mm_storeu_ps(out[1].as_mut_ptr(), ys);
        _mm_storeu_ps(out[2].as_mut_ptr(), e);
        (out[0], out[1], out[2])
    };
    let [x0, x1, x2, _] = xs;
    let [y0, y1, y2, _] = ys;
    let [e0, e1, e2, _] = e;
    let p = c.vertices().map(|v| v - r.origin);
    intersect_triangle_finish(p, [x0, x1, x2], [y0, y1, y2], [e0, e1, e2], plane, r, t_max)
}

/// Watertight ray–triangle intersection: the portable version of the SSE one.
#[cfg(not(target_arch = "x86_64"))]
#[inline(always)]
fn intersect_triangle(
    c: &Corners,
    plane: &[f32; 4],
    r: &PreparedRay,
    t_max: f32,
) -> Option<TriHit> {
    intersect_triangle_scalar(&c.vertices(), plane, r, t_max)
}

/// Watertight ray–triangle intersection (Woop, Benthin, Wald 2013; pbrt-v3 §3.6.2) with
/// `t` in `(δ_t, t_max)`, δ_t the conservative rounding-error bound of `t`.
#[cfg_attr(target_arch = "x86_64", allow(dead_code))]
#[inline(always)]
fn intersect_triangle_scalar(
    v: &[Vec3; 3],
    plane: &[f32; 4],
    r: &PreparedRay,
    t_max: f32,
) -> Option<TriHit> {
    let p0 = v[0] - r.origin;
    let p1 = v[1] - r.origin;
    let p2 = v[2] - r.origin;
    let (x0, x1, x2) = (r.rx.dot(p0), r.rx.dot(p1), r.rx.dot(p2));
    let (y0, y1, y2) = (r.ry.dot(p0), r.ry.dot(p1), r.ry.dot(p2));
    let e0 = x1 * y2 - y1 * x2;
    let e1 = x2 * y0 - y2 * x0;
    let e2 = x0 * y1 - y0 * x1;
    intersect_triangle_finish(
        [p0, p1, p2],
        [x0, x1, x2],
        [y0, y1, y2],
        [e0, e1, e2],
        plane,
        r,
        t_max,
    )
}

/// The watertight test from the corners relative to the origin `p`, their sheared `x` and
/// `y` and the edge functions `e` on.
#[inline(always)]
fn intersect_triangle_finish(
    [p0, p1, p2]: [Vec3; 3],
    [x0, x1, x2]: [f32; 3],
    [y0, y1, y2]: [f32; 3],
    [mut e0, mut e1, mut e2]: [f32; 3],
    plane: &[f32; 4],
    r: &PreparedRay,
    t_max: f32,
) -> Option<TriHit> {
    if e0 == 0.0 || e1 == 0.0 || e2 == 0.0 {
        // Exact edge functions on (near) edges: what makes the test watertight.
        let (x0, x1, x2) = (f64::from(x0), f64::from(x1), f64::from(x2));
        let (y0, y1, y2) = (f64::from(y0), f64::from(y1), f64::from(y2));
        e0 = (x1 * y2 - y1 * x2) as f32;
        e1 = (x2 * y0 - y2 * x0) as f32;
        e2 = (x0 * y1 - y0 * x1) as f32;
    }
    if (e0 < 0.0 || e1 < 0.0 || e2 < 0.0) && (e0 > 0.0 || e1 > 0.0 || e2 > 0.0) {
        return None;
    }
    let det = e0 + e1 + e2;
    if det == 0.0 {
        return None;
    }
    let z0 = r.rz.dot(p0) * r.sz;
    let z1 = r.rz.dot(p1) * r.sz;
    let z2 = r.rz.dot(p2) * r.sz;
    let t_scaled = e0 * z0 + e1 * z1 + e2 * z2;
    // t in (0, t_max), exclusive at both ends.
    if det < 0.0 && (t_scaled >= 0.0 || t_scaled <= t_max * det) {
        return None;
    }
    if det > 0.0 && (t_scaled <= 0.0 || t_scaled >= t_max * det) {
        return None;
    }
    let inv_det = 1.0 / det;
    let t = t_scaled * inv_det;
    // Conservative bound on the rounding error of t (pbrt-v3, "Conservative Ray–Bounds
    // Intersections" / triangle t error): reject hits not provably in front of the origin.
    let max_zt = z0.abs().max(z1.abs()).max(z2.abs());
    let delta_z = gamma(3.0) * max_zt;
    let max_xt = x0.abs().max(x1.abs()).max(x2.abs());
    let max_yt = y0.abs().max(y1.abs()).max(y2.abs());
    let delta_x = gamma(5.0) * (max_xt + max_zt);
    let delta_y = gamma(5.0) * (max_yt + max_zt);
    let delta_e = 2.0 * (gamma(2.0) * max_xt * max_yt + delta_y * max_xt + delta_x * max_yt);
    let max_e = e0.abs().max(e1.abs()).max(e2.abs());
    let delta_t =
        3.0 * (gamma(3.0) * max_e * max_zt + delta_e * max_zt + delta_z * max_e) * inv_det.abs();
    if t.is_nan() || t <= delta_t {
        return None;
    }
    // Self-intersection guard: a ray whose origin lies on this triangle's plane up to the
    // rounding of a computed surface point (a few ulps of the origin's coordinates) started
    // on this surface and must not re-hit it.
    let n = Vec3::new(plane[0], plane[1], plane[2]);
    let plane_distance = t * r.dir.dot(n).abs();
    if plane_distance <= r.self_tolerance * plane[3] {
        return None;
    }
    Some(TriHit {
        t,
        barycentric: [e0 * inv_det, e1 * inv_det, e2 * inv_det],
    })
}

/// The unnormalised normal of a triangle and its length (see `TriangleScene::planes`).
fn triangle_plane(v: &[Vec3; 3]) -> [f32; 4] {
    let n = (v[1] - v[0]).cross(v[2] - v[0]);
    [n.x, n.y, n.z, n.length()]
}

/// Relative self-intersection tolerance: 4 ulps (2⁻²¹) of the origin's largest coordinate
/// (≈1.4e-6 for a teapot at the origin, so ε down to 1e-6 of its size still works).
pub const SELF_TOLERANCE: f32 = 1.0 / (1u32 << 21) as f32;

/// Relative rounding error allowed for in each slab distance (a few ulps).
const SLAB_PAD: f32 = 1e-6;

/// The CWBVH node test: which of the node's 8 children the ray enters within `[0, t_max]`.
/// Same as obvhs's `CwBvhNode::intersect_ray_simd` except for the clip at 0 (not 1e-4), the
/// exact reciprocal direction and the per-axis rounding pad.
/// `AVX2`: use [`node_hits_avx2`]; only inside a function compiled with AVX2.
#[inline(always)]
fn intersect_node<const AVX2: bool>(
    node: &CwBvhNode,
    r: &PreparedRay,
    t_max: f32,
    oct_inv4: u32,
) -> u32 {
    let extent = node.compute_extent();
    let adj_dir_inv = extent * r.inv_dir;
    let adj_origin = (Vec3A::from(node.p) - Vec3A::from(r.origin)) * r.inv_dir;
    let pad = (adj_origin.abs() + adj_dir_inv.abs() * 255.0) * SLAB_PAD;
    #[cfg(target_arch = "x86_64")]
    if AVX2 {
        // SAFETY: `AVX2` is true only in `intersect_avx2` / `occluded_avx2`, AVX2 functions
        // called only where the CPU has AVX2.
        return unsafe { node_hits_avx2(node, adj_dir_inv, adj_origin, pad, r, t_max, oct_inv4) };
    }
    let mut lanes = node_lanes(node, adj_dir_inv, adj_origin, pad, r, t_max);
    if lanes == 0 {
        return 0;
    }
    let (child_bits8, bit_index8) = node.get_child_and_index_bits(oct_inv4);
    let mut hit_mask = 0u32;
    while lanes != 0 {
        let child = lanes.trailing_zeros() as usize;
        lanes &= lanes - 1;
        let child_bits = obvhs::cwbvh::node::extract_byte64(child_bits8, child);
        let bit_index = obvhs::cwbvh::node::extract_byte64(bit_index8, child);
        hit_mask |= child_bits << bit_index;
    }
    hit_mask
}

/// Byte offsets in [`CwBvhNode`] of the quantised child planes.
const CHILD_MIN_X: usize = std::mem::offset_of!(CwBvhNode, child_min_x);
const CHILD_MAX_X: usize = std::mem::offset_of!(CwBvhNode, child_max_x);
const CHILD_MIN_Y: usize = std::mem::offset_of!(CwBvhNode, child_min_y);
const CHILD_MAX_Y: usize = std::mem::offset_of!(CwBvhNode, child_max_y);
const CHILD_MIN_Z: usize = std::mem::offset_of!(CwBvhNode, child_min_z);
const CHILD_MAX_Z: usize = std::mem::offset_of!(CwBvhNode, child_max_z);

/// Offsets of the near and far planes per axis for a ray direction: `(near, far)` is
/// `(min, max)` for a non-negative component and `(max, min)` for a negative one.
fn plane_offsets(d: Vec3) -> [[usize; 2]; 3] {
    let pick = |neg: bool, lo: usize, hi: usize| if neg { [hi, lo] } else { [lo, hi] };
    [
        pick(d.x < 0.0, CHILD_MIN_X, CHILD_MAX_X),
        pick(d.y < 0.0, CHILD_MIN_Y, CHILD_MAX_Y),
        pick(d.z < 0.0, CHILD_MIN_Z, CHILD_MAX_Z),
    ]
}

/// The node test's per-ray constants, as in [`intersect_node`]: the reciprocal direction and
/// the origin in the node's quantised frame, and the rounding pad of each slab.
#[inline(always)]
fn node_frame(node: &CwBvhNode, r: &PreparedRay) -> (Vec3A, Vec3A, Vec3A) {
    let extent = node.compute_extent();
    let adj_dir_inv = extent * r.inv_dir;
    let adj_origin = (Vec3A::from(node.p) - Vec3A::from(r.origin)) * r.inv_dir;
    let pad = (adj_origin.abs() + adj_dir_inv.abs() * 255.0) * SLAB_PAD;
    (adj_dir_inv, adj_origin, pad)
}

/// A packet's node test (no AVX2): bit `r` of `child_rays[c]` set if ray `r` of `mask`
/// enters child `c` within `[0, t_best[r]]`, by [`node_lanes`] per ray.
#[cfg_attr(target_arch = "x86_64", inline)]
fn packet_node(
    node: &CwBvhNode,
    prs: &[PreparedRay; PACKET],
    mask: u32,
    t_best: &[f32; PACKET],
    child_rays: &mut [u32; 8],
) {
    let mut m = mask;
    while m != 0 {
        let r = m.trailing_zeros() as usize;
        m &= m - 1;
        let (adj_dir_inv, adj_origin, pad) = node_frame(node, &prs[r]);
        let mut lanes = node_lanes(node, adj_dir_inv, adj_origin, pad, &prs[r], t_best[r]);
        while lanes != 0 {
            let c = lanes.trailing_zeros() as usize;
            lanes &= lanes - 1;
            child_rays[c] |= 1 << r;
        }
    }
}

/// [`packet_node`] with AVX2: the node's 48 quantised planes are converted to floats once,
/// then each ray tests all 8 children in one vector, lane by lane the operations of
/// [`node_hits_avx2`] (so the same entered children).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[inline]
fn packet_node_avx2(
    node: &CwBvhNode,
    prs: &[PreparedRay; PACKET],
    mask: u32,
    t_best: &[f32; PACKET],
    child_rays: &mut [u32; 8],
) {
    use std::arch::x86_64::*;
    let base = (node as *const CwBvhNode).cast::<u8>();
    // Plane vectors indexed as `PreparedRay::planes` orders them: min x, max x, min y, ….
    let offsets = [
        CHILD_MIN_X,
        CHILD_MAX_X,
        CHILD_MIN_Y,
        CHILD_MAX_Y,
        CHILD_MIN_Z,
        CHILD_MAX_Z,
    ];
    // SAFETY: every offset is that of an `[u8; 8]` field of `CwBvhNode`, so each 8-byte
    // unaligned load stays inside `*node`.
    let planes = offsets.map(|offset| {
        _mm256_cvtepi32_ps(_mm256_cvtepu8_epi32(unsafe {
            _mm_loadl_epi64(base.add(offset).cast::<__m128i>())
        }))
    });
    let mut m = mask;
    while m != 0 {
        let r = m.trailing_zeros() as usize;
        m &= m - 1;
        let ray = &prs[r];
        let (a, o, p) = node_frame(node, ray);
        let axis = |axis: usize, a: f32, o: f32, p: f32| {
            let (a, o, p) = (_mm256_set1_ps(a), _mm256_set1_ps(o), _mm256_set1_ps(p));
            let near = planes[ray.plane_index[axis][0]];
            let far = planes[ray.plane_index[axis][1]];
            (
                _mm256_sub_ps(_mm256_add_ps(_mm256_mul_ps(near, a), o), p),
                _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(far, a), o), p),
            )
        };
        let (x0, x1) = axis(0, a.x, o.x, p.x);
        let (y0, y1) = axis(1, a.y, o.y, p.y);
        let (z0, z1) = axis(2, a.z, o.z, p.z);
        let tmin = _mm256_max_ps(
            _mm256_max_ps(x0, y0),
            _mm256_max_ps(z0, _mm256_setzero_ps()),
        );
        let tmax = _mm256_min_ps(
            _mm256_min_ps(x1, y1),
            _mm256_min_ps(z1, _mm256_set1_ps(t_best[r])),
        );
        let mut lanes = _mm256_movemask_ps(_mm256_cmp_ps::<_CMP_LE_OQ>(tmin, tmax)) as u32;
        while lanes != 0 {
            let c = lanes.trailing_zeros() as usize;
            lanes &= lanes - 1;
            child_rays[c] |= 1 << r;
        }
    }
}

/// Bit `c` set if child `c`'s box is entered within `[0, t_max]` (SSE version).
#[cfg(all(target_arch = "x86_64", target_feature = "sse2"))]
#[inline(always)]
fn node_lanes(
    node: &CwBvhNode,
    adj_dir_inv: Vec3A,
    adj_origin: Vec3A,
    pad: Vec3A,
    r: &PreparedRay,
    t_max: f32,
) -> u32 {
    use std::arch::x86_64::*;
    let base = (node as *const CwBvhNode).cast::<u8>();
    // SAFETY: SSE2 is enabled (cfg above). Every offset is that of an `[u8; 8]` field of
    // `CwBvhNode` (see `plane_offsets`), so each 8-byte unaligned load stays inside `*node`.
    unsafe {
        let zero = _mm_setzero_si128();
        // The 8 quantised planes at `offset` as two vectors of 4 floats (children 0–3, 4–7).
        let planes = |offset: usize| {
            let bytes = _mm_loadl_epi64(base.add(offset).cast::<__m128i>());
            let words = _mm_unpacklo_epi8(bytes, zero);
            (
                _mm_cvtepi32_ps(_mm_unpacklo_epi16(words, zero)),
                _mm_cvtepi32_ps(_mm_unpackhi_epi16(words, zero)),
            )
        };
        let axis = |offsets: [usize; 2], a: f32, o: f32, p: f32| {
            let (near0, near1) = planes(offsets[0]);
            let (far0, far1) = planes(offsets[1]);
            let (a, o, p) = (_mm_set1_ps(a), _mm_set1_ps(o), _mm_set1_ps(p));
            let t0 = |q| _mm_sub_ps(_mm_add_ps(_mm_mul_ps(q, a), o), p);
            let t1 = |q| _mm_add_ps(_mm_add_ps(_mm_mul_ps(q, a), o), p);
            (t0(near0), t0(near1), t1(far0), t1(far1))
        };
        let (x00, x01, x10, x11) = axis(r.planes[0], adj_dir_inv.x, adj_origin.x, pad.x);
        let (y00, y01, y10, y11) = axis(r.planes[1], adj_dir_inv.y, adj_origin.y, pad.y);
        let (z00, z01, z10, z11) = axis(r.planes[2], adj_dir_inv.z, adj_origin.z, pad.z);
        let lo = _mm_setzero_ps();
        let hi = _mm_set1_ps(t_max);
        let tmin0 = _mm_max_ps(_mm_max_ps(x00, y00), _mm_max_ps(z00, lo));
        let tmax0 = _mm_min_ps(_mm_min_ps(x10, y10), _mm_min_ps(z10, hi));
        let tmin1 = _mm_max_ps(_mm_max_ps(x01, y01), _mm_max_ps(z01, lo));
        let tmax1 = _mm_min_ps(_mm_min_ps(x11, y11), _mm_min_ps(z11, hi));
        let m0 = _mm_movemask_ps(_mm_cmple_ps(tmin0, tmax0)) as u32;
        let m1 = _mm_movemask_ps(_mm_cmple_ps(tmin1, tmax1)) as u32;
        m0 | (m1 << 4)
    }
}

/// [`node_lanes`] and the hit mask of [`intersect_node`] with AVX2: all 8 children in one
/// vector. Every lane computes exactly what the SSE version computes for it (`q · a + o ∓ p`
/// in that order, then the same min / max and ordered `<=`), so the lanes are the same bits;
/// the hit mask is obvhs's `get_child_and_index_bits` per lane, OR-ed over the entered ones.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[inline]
fn node_hits_avx2(
    node: &CwBvhNode,
    adj_dir_inv: Vec3A,
    adj_origin: Vec3A,
    pad: Vec3A,
    r: &PreparedRay,
    t_max: f32,
    oct_inv4: u32,
) -> u32 {
    use std::arch::x86_64::*;
    let base = (node as *const CwBvhNode).cast::<u8>();
    // The 8 quantised planes at byte offset `$offset` of the node as 8 floats.
    macro_rules! planes {
        ($offset:expr) => {
            // SAFETY: every offset is that of an `[u8; 8]` field of `CwBvhNode` (see
            // `plane_offsets`), so the 8-byte unaligned load stays inside `*node`.
            _mm256_cvtepi32_ps(_mm256_cvtepu8_epi32(unsafe {
                _mm_loadl_epi64(base.add($offset).cast::<__m128i>())
            }))
        };
    }
    macro_rules! axis {
        ($offsets:expr, $a:expr, $o:expr, $p:expr) => {{
            let (a, o, p) = (_mm256_set1_ps($a), _mm256_set1_ps($o), _mm256_set1_ps($p));
            let near = planes!($offsets[0]);
            let far = planes!($offsets[1]);
            (
                _mm256_sub_ps(_mm256_add_ps(_mm256_mul_ps(near, a), o), p),
                _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(far, a), o), p),
            )
        }};
    }
    let (x0, x1) = axis!(r.planes[0], adj_dir_inv.x, adj_origin.x, pad.x);
    let (y0, y1) = axis!(r.planes[1], adj_dir_inv.y, adj_origin.y, pad.y);
    let (z0, z1) = axis!(r.planes[2], adj_dir_inv.z, adj_origin.z, pad.z);
    let tmin = _mm256_max_ps(
        _mm256_max_ps(x0, y0),
        _mm256_max_ps(z0, _mm256_setzero_ps()),
    );
    let tmax = _mm256_min_ps(
        _mm256_min_ps(x1, y1),
        _mm256_min_ps(z1, _mm256_set1_ps(t_max)),
    );
    let entered = _mm256_castps_si256(_mm256_cmp_ps::<_CMP_LE_OQ>(tmin, tmax));
    if _mm256_testz_si256(entered, entered) != 0 {
        return 0;
    }
    // Per child: meta = node.child_meta[c]; inner children have bits 3 and 4 of meta set, and
    // their bit index is meta ^ (the ray's octant) (24 + slot, traversal order), a leaf's is
    // meta's low 5 bits (its first triangle's offset); the bits are meta >> 5 (1 for an inner
    // child, the unary triangle count for a leaf).
    // SAFETY: `child_meta` is an `[u8; 8]`: the 8-byte unaligned load stays inside it.
    let meta = _mm256_cvtepu8_epi32(unsafe {
        _mm_loadl_epi64(node.child_meta.as_ptr().cast::<__m128i>())
    });
    let bit4 = _mm256_set1_epi32(0x10);
    let inner = _mm256_cmpeq_epi32(
        _mm256_and_si256(_mm256_and_si256(meta, _mm256_slli_epi32::<1>(meta)), bit4),
        bit4,
    );
    let octant = _mm256_set1_epi32((oct_inv4 & 0xff) as i32);
    let bit_index = _mm256_and_si256(
        _mm256_xor_si256(meta, _mm256_and_si256(octant, inner)),
        _mm256_set1_epi32(0x1f),
    );
    let bits = _mm256_and_si256(_mm256_srli_epi32::<5>(meta), _mm256_set1_epi32(7));
    let hits = _mm256_and_si256(_mm256_sllv_epi32(bits, bit_index), entered);
    let h = _mm_or_si128(
        _mm256_castsi256_si128(hits),
        _mm256_extracti128_si256::<1>(hits),
    );
    let h = _mm_or_si128(h, _mm_shuffle_epi32::<0b01_00_11_10>(h));
    let h = _mm_or_si128(h, _mm_shuffle_epi32::<0b10_11_00_01>(h));
    _mm_cvtsi128_si32(h) as u32
}

/// Bit `c` set if child `c`'s box is entered within `[0, t_max]` (portable version).
#[cfg(not(all(target_arch = "x86_64", target_feature = "sse2")))]
#[inline(always)]
fn node_lanes(
    node: &CwBvhNode,
    adj_dir_inv: Vec3A,
    adj_origin: Vec3A,
    pad: Vec3A,
    r: &PreparedRay,
    t_max: f32,
) -> u32 {
    let neg = (r.dir.x < 0.0, r.dir.y < 0.0, r.dir.z < 0.0);
    let mut mask = 0u32;
    for c in 0..8 {
        let lo = Vec3A::new(
            node.child_min_x[c] as f32,
            node.child_min_y[c] as f32,
            node.child_min_z[c] as f32,
        );
        let hi = Vec3A::new(
            node.child_max_x[c] as f32,
            node.child_max_y[c] as f32,
            node.child_max_z[c] as f32,
        );
        let pick = |n: bool, l: f32, h: f32| if n { (h, l) } else { (l, h) };
        let (nx, fx) = pick(neg.0, lo.x, hi.x);
        let (ny, fy) = pick(neg.1, lo.y, hi.y);
        let (nz, fz) = pick(neg.2, lo.z, hi.z);
        let near = Vec3A::new(nx, ny, nz) * adj_dir_inv + adj_origin - pad;
        let far = Vec3A::new(fx, fy, fz) * adj_dir_inv + adj_origin + pad;
        if near.max_element().max(0.0) <= far.min_element().min(t_max) {
            mask |= 1 << c;
        }
    }
    mask
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::Rng;
    use crate::shapes;

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
                mesh,
                material: 0,
                object: 0,
            });
        }
        instances.push(Instance {
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
            let dir = crate::sampling::sample_uniform_sphere(glam::Vec2::new(u(), u()));
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
            mesh: shapes::cuboid(Vec3::ONE).unwrap(),
            material: 0,
            object: 0,
        }];
        let mut floor = shapes::cuboid(Vec3::new(8.0, 8.0, 0.2)).unwrap();
        for q in &mut floor.positions {
            q.z -= 2.0;
        }
        instances.push(Instance {
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
            mesh,
            material: 0,
            object: 0
        }])
        .is_err());
    }

    #[test]
    fn bad_rays_miss() {
        let s = TriangleScene::build(vec![Instance {
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
