//! Sample maps (thesis §3.3): per map (a Bézier patch or a mesh atlas page, [`crate::surface`])
//! and texel, the four nearest OSLF sample points that lie
//! within φ_samplemap of the texel's normal (Eq. 3.9–3.10) AND are visible from the texel's
//! surface point — checked by casting a ray, which enforces the free-space condition the thesis
//! could only hope for (its lid artefact, §6.3).

use std::num::NonZero;

use glam::Vec3;
use kiddo::{ImmutableKdTree, SquaredEuclidean};
use oslf_format::{SampleMaps, SamplePoint, INVALID_INDEX};
use rayon::prelude::*;

use crate::surface::MapDomain;
use oslf_trace::ray::{Intersector, Ray};

/// Visibility rays start this fraction of ε above the texel's point on the patch: above the
/// tessellation error (at most ε/50), well below the sample points at ε.
pub const VISIBILITY_LIFT: f32 = 0.05;

/// Counts over all used texels of all sample maps (atlas texels no chart touches are not
/// counted: they hold no index and no fragment ever reads them).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub struct SampleMapStats {
    pub texels: u64,
    /// Texels with fewer than four valid indices.
    pub short: u64,
    /// Texels with no valid index at all.
    pub empty: u64,
    /// Visibility rays cast.
    pub rays: u64,
}

/// Candidate counts tried per texel, nearest first; a texel that finds four acceptable points
/// among the first `k` stops there. Only the [`MAX_CANDIDATES`] nearest points are considered:
/// points farther than that are too far to represent the texel's light field.
const CANDIDATE_STEPS: [usize; 2] = [16, MAX_CANDIDATES];

/// How many of a texel's nearest sample points are examined at most.
pub const MAX_CANDIDATES: usize = 64;

/// A spatial index over sample-point positions.
pub struct PointIndex<'a> {
    points: &'a [SamplePoint],
    tree: ImmutableKdTree<f32, 3>,
}

impl<'a> PointIndex<'a> {
    pub fn new(points: &'a [SamplePoint]) -> Self {
        let positions: Vec<[f32; 3]> = points.iter().map(|p| p.position).collect();
        PointIndex {
            points,
            tree: ImmutableKdTree::new_from_slice(&positions),
        }
    }

    /// The `k` nearest points to `q` as (squared distance, index), sorted by distance then index.
    pub fn nearest(&self, q: Vec3, k: usize) -> Vec<(f32, u32)> {
        let k = k.min(self.points.len());
        let Some(k) = NonZero::new(k) else {
            return Vec::new();
        };
        let mut out: Vec<(f32, u32)> = self
            .tree
            .nearest_n::<SquaredEuclidean>(&q.to_array(), k)
            .into_iter()
            .map(|n| (n.distance, n.item as u32))
            .collect();
        out.sort_unstable_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        out
    }
}

/// The four indices of one texel at surface point `x` with unit normal `n`, and the number of
/// visibility rays cast.
pub fn texel_indices(
    index: &PointIndex,
    geometry: &impl Intersector,
    x: Vec3,
    n: Vec3,
    cos_phi: f32,
    lift: f32,
) -> ([u32; 4], u64) {
    let mut found = [INVALID_INDEX; 4];
    let mut count = 0;
    let mut rays = 0;
    let origin = x + n * lift;
    let mut tried = 0;
    for &k in &CANDIDATE_STEPS {
        let candidates = index.nearest(x, k);
        for &(_, i) in &candidates[tried..] {
            let s = Vec3::from_array(index.points[i as usize].position);
            if candidate(geometry, x, n, origin, s, cos_phi, &mut rays) != Some(true) {
                continue;
            }
            found[count] = i;
            count += 1;
            if count == 4 {
                return (found, rays);
            }
        }
        tried = candidates.len();
        if tried == index.points.len() {
            break;
        }
    }
    (found, rays)
}

/// Whether sample point `s` can serve the texel at `x` (unit normal `n`): `None` outside the
/// cone of Eq. 3.10 (in the upper hemisphere, away from the horizon), else whether it is
/// visible from `origin` (the texel's point lifted off the surface). Counts the ray it casts.
fn candidate(
    geometry: &impl Intersector,
    x: Vec3,
    n: Vec3,
    origin: Vec3,
    s: Vec3,
    cos_phi: f32,
    rays: &mut u64,
) -> Option<bool> {
    let to_s = s - x;
    let len = to_s.length();
    if len.is_nan() || len <= 0.0 || n.dot(to_s / len) <= cos_phi {
        return None;
    }
    let d = s - origin;
    let dist = d.length();
    if dist > 0.0 {
        *rays += 1;
        if geometry.occluded(&Ray::new(origin, d / dist), dist * (1.0 - 1e-4)) {
            return Some(false);
        }
    }
    Some(true)
}

/// Of the [`MAX_CANDIDATES`] sample points nearest the texel at `x` (unit normal `n`), how many
/// lie within the cone of Eq. 3.10 and how many of those are visible, as [`texel_indices`]
/// judges them: why a texel found fewer than four ([`crate::coverage`]).
pub fn texel_candidates(
    index: &PointIndex,
    geometry: &impl Intersector,
    x: Vec3,
    n: Vec3,
    cos_phi: f32,
    lift: f32,
) -> (usize, usize) {
    let origin = x + n * lift;
    let mut rays = 0;
    let (mut in_cone, mut visible) = (0, 0);
    for (_, i) in index.nearest(x, MAX_CANDIDATES) {
        let s = Vec3::from_array(index.points[i as usize].position);
        match candidate(geometry, x, n, origin, s, cos_phi, &mut rays) {
            None => {}
            Some(seen) => {
                in_cone += 1;
                visible += usize::from(seen);
            }
        }
    }
    (in_cone, visible)
}

/// The unseen test probes the directions within this angle of a texel's normal: a view more
/// grazing than this sees its surface foreshortened below a sixth of its area, through a gap
/// narrower than ε.
pub const UNSEEN_CONE_DEG: f32 = 80.0;

/// Whether no view reaches the surface at `origin` (lifted off it along its unit normal `n`):
/// each of `directions`, turned into `n`'s hemisphere, that lies within [`UNSEEN_CONE_DEG`] of
/// `n` meets a surface within `reach`, or first meets one from behind (a surface facing the
/// way the probe goes: `origin` lies inside a solid, as a face resting flat on a table top
/// lies in the top's slab, which a grazing probe may cross farther than `reach`).
pub fn enclosed(
    geometry: &impl Intersector,
    origin: Vec3,
    n: Vec3,
    reach: f32,
    directions: &[Vec3],
) -> bool {
    let cos_cone = UNSEEN_CONE_DEG.to_radians().cos();
    let mut probed = 0;
    for &d in directions {
        let d = if d.dot(n) < 0.0 { -d } else { d };
        if d.dot(n) < cos_cone {
            continue;
        }
        probed += 1;
        let ray = Ray::new(origin, d);
        if geometry.occluded(&ray, reach) {
            continue;
        }
        match geometry.intersect(&ray, f32::INFINITY) {
            Some(hit) if hit.geometric_normal.dot(d) > 0.0 => {}
            _ => return false,
        }
    }
    probed > 0
}

/// Used texels with fewer than four indices, as (map, x, y): those with none first (no point
/// reconstructs them at all), then the others, each in storage order.
pub fn short_texels(maps: &SampleMaps, domains: &[MapDomain]) -> Vec<(u32, u32, u32)> {
    let res = maps.resolution as usize;
    let empty = maps
        .indices
        .iter()
        .enumerate()
        .filter(|(_, t)| t[0] == INVALID_INDEX);
    let short = maps
        .indices
        .iter()
        .enumerate()
        .filter(|(_, t)| t[0] != INVALID_INDEX && t[3] == INVALID_INDEX);
    empty
        .chain(short)
        .map(|(i, _)| {
            let map = i / (res * res);
            let texel = i % (res * res);
            (map as u32, (texel % res) as u32, (texel / res) as u32)
        })
        .filter(|&(map, x, y)| domains.get(map as usize).is_some_and(|d| d.covers(x, y)))
        .collect()
}

/// Builds every map's sample map at `resolution`² texels (row-major, texel (x, y) centred on
/// u = (x + ½)/res, v = (y + ½)/res). Atlas texels no chart touches hold no index.
/// `progress` advances by one per texel row (`maps × resolution` rows in all).
pub fn build(
    maps: &[MapDomain],
    points: &[SamplePoint],
    geometry: &impl Intersector,
    resolution: u32,
    phi_samplemap_deg: f32,
    epsilon: f32,
    progress: &dyn oslf_trace::progress::Progress,
) -> (SampleMaps, SampleMapStats) {
    let index = PointIndex::new(points);
    let cos_phi = phi_samplemap_deg.to_radians().cos();
    let res = resolution as usize;
    // Written in place, row by row in parallel: at 4096² the map is 256 MiB of u32 indices,
    // and per-row vectors gathered afterwards would hold it twice.
    let mut indices = vec![[INVALID_INDEX; 4]; maps.len() * res * res];
    let (rays, unused): (u64, u64) = indices
        .par_chunks_mut(res.max(1))
        .enumerate()
        .map(|(row, texels)| {
            let map = maps[row / res];
            let y = (row % res) as u32;
            let (mut rays, mut unused) = (0, 0);
            for (x, out) in texels.iter_mut().enumerate() {
                let Some((p, n)) = map.texel(x as u32, y, resolution) else {
                    unused += 1;
                    continue;
                };
                let lift = epsilon * VISIBILITY_LIFT;
                let (ids, r) = texel_indices(&index, geometry, p, n, cos_phi, lift);
                rays += r;
                *out = ids;
            }
            progress.advance(1);
            (rays, unused)
        })
        .reduce(|| (0, 0), |a, b| (a.0 + b.0, a.1 + b.1));
    let mut stats = SampleMapStats {
        rays,
        ..Default::default()
    };
    for t in &indices {
        stats.texels += 1;
        if t[3] == INVALID_INDEX {
            stats.short += 1;
        }
        if t[0] == INVALID_INDEX {
            stats.empty += 1;
        }
    }
    // Unused atlas texels hold no index but are not short.
    stats.texels -= unused;
    stats.short -= unused;
    stats.empty -= unused;
    (
        SampleMaps {
            resolution,
            indices,
        },
        stats,
    )
}
