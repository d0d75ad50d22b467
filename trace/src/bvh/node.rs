//! The CWBVH node test: which of a node's 8 children a ray (or each ray of a packet) enters,
//! in SSE and AVX2, lane by lane the same operations.

use glam::Vec3A;
use obvhs::cwbvh::node::CwBvhNode;

use super::prepared_ray::{
    PreparedRay, CHILD_MAX_X, CHILD_MAX_Y, CHILD_MAX_Z, CHILD_MIN_X, CHILD_MIN_Y, CHILD_MIN_Z,
};

/// Most rays traversed together by [`crate::ray::Intersector::intersect_packet`] (bits of a
/// `u32` mask).
pub const PACKET: usize = 16;

/// Relative rounding error allowed for in each slab distance (a few ulps).
pub const SLAB_PAD: f32 = 1e-6;

/// The CWBVH node test: which of the node's 8 children the ray enters within `[0, t_max]`.
/// Same as obvhs's `CwBvhNode::intersect_ray_simd` except for the clip at 0 (not 1e-4), the
/// exact reciprocal direction and the per-axis rounding pad.
/// `AVX2`: use [`node_hits_avx2`]; only inside a function compiled with AVX2.
#[inline(always)]
pub(super) fn intersect_node<const AVX2: bool>(
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

/// The node test's per-ray constants, as in [`intersect_node`]: the reciprocal direction and
/// the origin in the node's quantised frame, and the rounding pad of each slab.
#[inline(always)]
pub(super) fn node_frame(node: &CwBvhNode, r: &PreparedRay) -> (Vec3A, Vec3A, Vec3A) {
    let extent = node.compute_extent();
    let adj_dir_inv = extent * r.inv_dir;
    let adj_origin = (Vec3A::from(node.p) - Vec3A::from(r.origin)) * r.inv_dir;
    let pad = (adj_origin.abs() + adj_dir_inv.abs() * 255.0) * SLAB_PAD;
    (adj_dir_inv, adj_origin, pad)
}

/// A packet's node test (no AVX2): bit `r` of `child_rays[c]` set if ray `r` of `mask`
/// enters child `c` within `[0, t_best[r]]`, by [`node_lanes`] per ray.
#[cfg_attr(target_arch = "x86_64", inline)]
pub(super) fn packet_node(
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
pub(super) fn packet_node_avx2(
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
pub(super) fn node_lanes(
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
pub(super) fn node_hits_avx2(
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
pub(super) fn node_lanes(
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
