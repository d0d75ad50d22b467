//! Chart segmentation: adjacent triangles merged into charts that lay flat without overlap.
//!
//! Triangles are adjacent across an edge shared by exactly two triangles that wind it in
//! opposite directions (a manifold, consistently oriented edge; vertices are matched by
//! position, so split normals and uvs do not cut the mesh). Charts grow from seeds in triangle
//! order: each takes the unassigned neighbour whose normal is nearest the seed's (ties: lower
//! index) while
//!
//! - its normal is within [`MAX_CHART_ANGLE_DEG`] of the seed's (the chart is projected on the
//!   seed's plane: this bounds the projection's area distortion by 1/cos of that angle),
//! - its projection overlaps none of the chart's triangles (a surface that turns back over
//!   itself, such as a spiral ramp, is cut into several charts),
//! - the chart stays within `max_extent` texels across and [`MAX_CHART_TRIANGLES`] triangles.
//!
//! Then the charts' outlines are refined, which matters where triangles are large against the
//! texel (their zigzag outlines leave notches that no neighbouring chart fills):
//!
//! - **notches filled**: a triangle that borders its own chart on at most one edge and another
//!   chart on two moves to that chart, where the tests above let the chart take it (rounds of
//!   this until none moves, at most [`SMOOTH_ROUNDS`]);
//! - **teeth split off**: a triangle that still borders its own chart on at most one edge, and
//!   covers at least [`TOOTH_TEXELS`] texels, becomes a chart of its own (never a chart's seed,
//!   nor a triangle of a chart of two). Its chart's outline is straighter, and the small chart
//!   fills a hole that the packing leaves between large ones.
//!
//! A triangle of zero area is a chart of its own. Everything is sequential and free of
//! hashing: the same mesh gives the same charts.

use std::cmp::Reverse;
use std::collections::BinaryHeap;

use glam::{DVec2, DVec3};

use super::{bbox, corners3};
use crate::Mesh;

/// Largest angle between a chart triangle's normal and its chart's axis.
pub const MAX_CHART_ANGLE_DEG: f64 = 35.0;

/// Most triangles in one chart (bounds the cost of the overlap test while growing).
pub const MAX_CHART_TRIANGLES: usize = 2048;

/// Rounds of notch filling (it stops early when a round moves no triangle).
pub const SMOOTH_ROUNDS: usize = 8;

/// Least area (texels at the asked density) of a tooth split off as a chart of its own: a
/// smaller triangle would cost the packing more than its notch (on a fine scan every triangle
/// is below a texel, and none is split).
pub const TOOTH_TEXELS: f64 = 4.0;

const NONE: u32 = u32::MAX;

/// A chart: its triangles (the seed first) and the unit axis it is projected along (zero for
/// the chart of a degenerate triangle).
pub(super) struct Chart {
    pub triangles: Vec<u32>,
    pub axis: DVec3,
}

/// Splits `mesh` into charts (see the [module documentation](self)); `texel_size` and
/// `max_extent` (texels) bound a chart's size.
pub(super) fn segment(mesh: &Mesh, texel_size: f64, max_extent: f64) -> Vec<Chart> {
    let n = mesh.triangles.len();
    let neighbours = neighbours(mesh);
    let normals: Vec<Option<DVec3>> = mesh
        .triangles
        .iter()
        .map(|t| {
            let p = corners3(mesh, t);
            (p[1] - p[0]).cross(p[2] - p[0]).try_normalize()
        })
        .collect();
    let cos_max = MAX_CHART_ANGLE_DEG.to_radians().cos();
    let mut chart_of = vec![NONE; n];
    let mut tried = vec![NONE; n];
    let mut charts = Vec::new();
    for seed in 0..n {
        if chart_of[seed] != NONE {
            continue;
        }
        let id = charts.len() as u32;
        chart_of[seed] = id;
        let Some(axis) = normals[seed] else {
            charts.push(Chart {
                triangles: vec![seed as u32],
                axis: DVec3::ZERO,
            });
            continue;
        };
        let (u, v) = basis(axis);
        let project = |t: usize| {
            corners3(mesh, &mesh.triangles[t]).map(|p| DVec2::new(p.dot(u), p.dot(v)) / texel_size)
        };
        let mut flat = vec![project(seed)];
        let mut boxes = vec![bbox(&flat[0])];
        let (mut lo, mut hi) = boxes[0];
        let mut members = vec![seed as u32];
        let mut heap = BinaryHeap::new();
        let push = |heap: &mut BinaryHeap<_>, t: usize, chart_of: &[u32]| {
            for &nb in &neighbours[t] {
                if nb != NONE && chart_of[nb as usize] == NONE {
                    if let Some(nn) = normals[nb as usize] {
                        let cost = (1.0 - nn.dot(axis)).max(0.0);
                        heap.push(Reverse((cost.to_bits(), nb)));
                    }
                }
            }
        };
        push(&mut heap, seed, &chart_of);
        while let Some(Reverse((_, t))) = heap.pop() {
            let t = t as usize;
            if members.len() >= MAX_CHART_TRIANGLES {
                break;
            }
            if chart_of[t] != NONE || tried[t] == id {
                continue;
            }
            tried[t] = id;
            let Some(nt) = normals[t] else { continue };
            if nt.dot(axis) < cos_max {
                continue;
            }
            let p = project(t);
            let b = bbox(&p);
            let (nlo, nhi) = (lo.min(b.0), hi.max(b.1));
            if (nhi - nlo).max_element() > max_extent {
                continue;
            }
            let hit = boxes
                .iter()
                .zip(&flat)
                .any(|(q, f)| boxes_meet(b, *q) && overlap(&p, f));
            if hit {
                continue;
            }
            chart_of[t] = id;
            members.push(t as u32);
            flat.push(p);
            boxes.push(b);
            (lo, hi) = (nlo, nhi);
            push(&mut heap, t, &chart_of);
        }
        charts.push(Chart {
            triangles: members,
            axis,
        });
    }
    let mut refine = Refine {
        mesh,
        neighbours: &neighbours,
        normals: &normals,
        chart_of,
        texel_size,
        max_extent,
        cos_max,
    };
    refine.fill_notches(&mut charts);
    refine.split_teeth(&mut charts);
    charts
}

/// What refining the charts' outlines reads and keeps up to date.
struct Refine<'a> {
    mesh: &'a Mesh,
    neighbours: &'a [[u32; 3]],
    normals: &'a [Option<DVec3>],
    chart_of: Vec<u32>,
    texel_size: f64,
    max_extent: f64,
    cos_max: f64,
}

impl Refine<'_> {
    /// How many of triangle `t`'s neighbours are in chart `c`.
    fn bordering(&self, t: usize, c: u32) -> usize {
        self.neighbours[t]
            .iter()
            .filter(|&&nb| nb != NONE && self.chart_of[nb as usize] == c)
            .count()
    }

    /// `t`'s corners projected on the plane of `axis`, in texels.
    fn project(&self, t: usize, axis: DVec3) -> [DVec2; 3] {
        let (u, v) = basis(axis);
        corners3(self.mesh, &self.mesh.triangles[t])
            .map(|p| DVec2::new(p.dot(u), p.dot(v)) / self.texel_size)
    }

    /// Whether `chart` can take triangle `t`: the tests of growing (normal within the angle,
    /// triangle count, extent, no overlap in projection).
    fn takes(&self, chart: &Chart, t: usize) -> bool {
        let Some(nt) = self.normals[t] else {
            return false;
        };
        if chart.axis == DVec3::ZERO
            || nt.dot(chart.axis) < self.cos_max
            || chart.triangles.len() >= MAX_CHART_TRIANGLES
        {
            return false;
        }
        let p = self.project(t, chart.axis);
        let b = bbox(&p);
        let (mut lo, mut hi) = b;
        for &q in &chart.triangles {
            let f = self.project(q as usize, chart.axis);
            let bq = bbox(&f);
            (lo, hi) = (lo.min(bq.0), hi.max(bq.1));
            if boxes_meet(b, bq) && overlap(&p, &f) {
                return false;
            }
        }
        (hi - lo).max_element() <= self.max_extent
    }

    /// Moves each triangle bordering its chart on at most one edge and another chart on two
    /// into that chart, where it takes it; in rounds (see the module documentation).
    fn fill_notches(&mut self, charts: &mut [Chart]) {
        for _ in 0..SMOOTH_ROUNDS {
            let mut moved = false;
            for t in 0..self.mesh.triangles.len() {
                let a = self.chart_of[t];
                if self.bordering(t, a) > 1 || charts[a as usize].triangles[0] == t as u32 {
                    continue;
                }
                let Some(b) = self.neighbours[t].iter().find_map(|&nb| {
                    let c = *self.chart_of.get(nb as usize)?;
                    (c != a && self.bordering(t, c) >= 2).then_some(c)
                }) else {
                    continue;
                };
                if !self.takes(&charts[b as usize], t) {
                    continue;
                }
                charts[a as usize].triangles.retain(|&q| q != t as u32);
                charts[b as usize].triangles.push(t as u32);
                self.chart_of[t] = b;
                moved = true;
            }
            if !moved {
                break;
            }
        }
    }

    /// Splits off the teeth of the charts as charts of their own (see the module
    /// documentation). A tooth borders at most one triangle of its chart, so the rest stays
    /// connected.
    fn split_teeth(&mut self, charts: &mut Vec<Chart>) {
        let min_area = TOOTH_TEXELS * self.texel_size * self.texel_size;
        for c in 0..charts.len() {
            if charts[c].triangles.len() <= 2 {
                continue;
            }
            let members = std::mem::take(&mut charts[c].triangles);
            let mut kept = Vec::with_capacity(members.len());
            for (k, &t) in members.iter().enumerate() {
                let p = corners3(self.mesh, &self.mesh.triangles[t as usize]);
                let area = 0.5 * (p[1] - p[0]).cross(p[2] - p[0]).length();
                if k == 0 || self.bordering(t as usize, c as u32) > 1 || area < min_area {
                    kept.push(t);
                    continue;
                }
                self.chart_of[t as usize] = charts.len() as u32;
                charts.push(Chart {
                    triangles: vec![t],
                    axis: self.normals[t as usize].unwrap_or(DVec3::ZERO),
                });
            }
            charts[c].triangles = kept;
        }
    }
}

/// A right-handed orthonormal basis `(u, v)` with `u × v = n` for unit `n` (Duff et al. 2017,
/// "Building an Orthonormal Basis, Revisited").
pub(super) fn basis(n: DVec3) -> (DVec3, DVec3) {
    let sign = 1f64.copysign(n.z);
    let a = -1.0 / (sign + n.z);
    let b = n.x * n.y * a;
    (
        DVec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x),
        DVec3::new(b, sign + n.y * n.y * a, -n.y),
    )
}

/// Per triangle, its neighbour across each edge (corner `e` to `e + 1`), or [`NONE`]: the
/// other triangle of an edge shared by exactly two triangles winding it oppositely.
fn neighbours(mesh: &Mesh) -> Vec<[u32; 3]> {
    let id = welded(mesh);
    // (low vertex, high vertex, triangle, edge, forward)
    let mut edges: Vec<(u32, u32, u32, u8, bool)> = Vec::with_capacity(3 * mesh.triangles.len());
    for (t, tri) in mesh.triangles.iter().enumerate() {
        for e in 0..3 {
            let (a, b) = (id[tri[e] as usize], id[tri[(e + 1) % 3] as usize]);
            if a != b {
                edges.push((a.min(b), a.max(b), t as u32, e as u8, a < b));
            }
        }
    }
    edges.sort_unstable();
    let mut out = vec![[NONE; 3]; mesh.triangles.len()];
    let mut i = 0;
    while i < edges.len() {
        let mut j = i + 1;
        while j < edges.len() && edges[j].0 == edges[i].0 && edges[j].1 == edges[i].1 {
            j += 1;
        }
        if j - i == 2 && edges[i].4 != edges[i + 1].4 && edges[i].2 != edges[i + 1].2 {
            let (x, y) = (edges[i], edges[i + 1]);
            out[x.2 as usize][x.3 as usize] = y.2;
            out[y.2 as usize][y.3 as usize] = x.2;
        }
        i = j;
    }
    out
}

/// One id per distinct vertex position (±0 equal), in order of first appearance after sorting.
fn welded(mesh: &Mesh) -> Vec<u32> {
    let key = |i: u32| {
        mesh.positions[i as usize]
            .to_array()
            .map(|c| if c == 0.0 { 0 } else { c.to_bits() })
    };
    let mut order: Vec<u32> = (0..mesh.positions.len() as u32).collect();
    order.sort_unstable_by_key(|&i| (key(i), i));
    let mut id = vec![0u32; order.len()];
    let mut next = 0u32;
    for w in 0..order.len() {
        if w > 0 && key(order[w]) != key(order[w - 1]) {
            next += 1;
        }
        id[order[w] as usize] = next;
    }
    id
}

fn boxes_meet(a: (DVec2, DVec2), b: (DVec2, DVec2)) -> bool {
    a.0.x <= b.1.x && b.0.x <= a.1.x && a.0.y <= b.1.y && b.0.y <= a.1.y
}

/// Whether the interiors of triangles `p` and `q` overlap (separating axes: the six edge
/// normals; touching along an edge or at a corner is not overlap).
pub(super) fn overlap(p: &[DVec2; 3], q: &[DVec2; 3]) -> bool {
    let scale = p
        .iter()
        .chain(q)
        .fold(0f64, |s, c| s.max(c.x.abs()).max(c.y.abs()))
        .max(1.0);
    let tolerance = 1e-9 * scale;
    for tri in [p, q] {
        for k in 0..3 {
            let axis = (tri[(k + 1) % 3] - tri[k]).perp();
            let length = axis.length();
            if length == 0.0 {
                continue;
            }
            let range = |r: &[DVec2; 3]| {
                let d = r.map(|c| axis.dot(c) / length);
                (d[0].min(d[1]).min(d[2]), d[0].max(d[1]).max(d[2]))
            };
            let ((a0, a1), (b0, b1)) = (range(p), range(q));
            if a1 <= b0 + tolerance || b1 <= a0 + tolerance {
                return false;
            }
        }
    }
    true
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn basis_is_orthonormal_and_right_handed() {
        for n in [
            DVec3::Z,
            -DVec3::Z,
            DVec3::X,
            DVec3::new(0.3, -0.4, 0.8).normalize(),
            DVec3::new(1e-9, 0.0, -1.0).normalize(),
        ] {
            let (u, v) = basis(n);
            assert!((u.length() - 1.0).abs() < 1e-12 && (v.length() - 1.0).abs() < 1e-12);
            assert!(u.dot(v).abs() < 1e-12 && u.dot(n).abs() < 1e-12);
            assert!((u.cross(v) - n).length() < 1e-12, "{n}");
        }
    }

    #[test]
    fn overlap_tells_touching_from_overlapping() {
        let a = [DVec2::ZERO, DVec2::X, DVec2::Y];
        // Sharing an edge, a corner, or apart: no overlap.
        assert!(!overlap(&a, &[DVec2::X, DVec2::ONE, DVec2::Y]));
        assert!(!overlap(
            &a,
            &[DVec2::X, DVec2::new(2.0, 0.0), DVec2::new(1.0, 1.0)]
        ));
        assert!(!overlap(&a, &a.map(|c| c + DVec2::splat(5.0))));
        // Shifted slightly, or itself: overlap.
        assert!(overlap(&a, &a.map(|c| c + DVec2::splat(0.1))));
        assert!(overlap(&a, &a));
    }
}
