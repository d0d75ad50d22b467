//! Chart parametrisation: a chart's triangles laid flat in texel units.
//!
//! A chart is projected on the plane normal to its axis ([`super::segment`] keeps its
//! triangles within an angle of it and free of overlap there). Projection shrinks a triangle's
//! area by the cosine of its tilt, so the chart is scaled by `1/√(min cos)`: every triangle
//! gets at least `1/texel_size²` texels per unit area. The chart is then turned so that its
//! bounding rectangle is the smallest one aligned with an edge of its convex hull (one such is
//! the smallest of all), and moved to the first quadrant with its bounding-box minimum at the
//! origin.
//!
//! A degenerate triangle (zero area, a chart of its own) is laid as a segment along `+x`, its
//! longest edge, or a point.

use glam::{DVec2, DVec3};

use super::corners3;
use super::segment::{basis, Chart};
use crate::Mesh;

/// A chart laid flat: per chart triangle (in [`Chart::triangles`] order) its corners, in
/// texels, and the size of the bounding rectangle (its minimum is the origin).
pub(super) struct Flat {
    pub corners: Vec<[DVec2; 3]>,
    pub size: DVec2,
}

pub(super) fn flatten(mesh: &Mesh, chart: &Chart, texel_size: f64) -> Flat {
    let corners3 = |t: u32| corners3(mesh, &mesh.triangles[t as usize]);
    let mut corners: Vec<[DVec2; 3]> = if chart.axis == DVec3::ZERO {
        chart
            .triangles
            .iter()
            .map(|&t| segment_layout(corners3(t)))
            .collect()
    } else {
        let (u, v) = basis(chart.axis);
        let min_cos = chart
            .triangles
            .iter()
            .filter_map(|&t| {
                let p = corners3(t);
                (p[1] - p[0]).cross(p[2] - p[0]).try_normalize()
            })
            .fold(1f64, |m, n| m.min(n.dot(chart.axis)))
            .max(1e-3);
        let scale = 1.0 / (texel_size * min_cos.sqrt());
        chart
            .triangles
            .iter()
            .map(|&t| corners3(t).map(|p| DVec2::new(p.dot(u), p.dot(v)) * scale))
            .collect()
    };
    let direction = best_direction(&corners);
    for tri in &mut corners {
        *tri = tri.map(|c| direction.rotate(c));
    }
    let (lo, hi) = bounds(corners.iter().flatten().copied());
    for tri in &mut corners {
        *tri = tri.map(|c| (c - lo).max(DVec2::ZERO));
    }
    Flat {
        corners,
        size: (hi - lo).max(DVec2::ZERO),
    }
}

/// A degenerate triangle in texels: its longest edge (first on ties) from the origin along
/// `+x`, the third corner on it.
fn segment_layout(p: [DVec3; 3]) -> [DVec2; 3] {
    let len = [0, 1, 2].map(|e| (p[(e + 1) % 3] - p[e]).length());
    let e = (0..3).fold(0, |b, e| if len[e] > len[b] { e } else { b });
    let (i, j, k) = (e, (e + 1) % 3, (e + 2) % 3);
    let mut out = [DVec2::ZERO; 3];
    if len[e] > 0.0 {
        let dir = (p[j] - p[i]) / len[e];
        out[j] = DVec2::new(len[e], 0.0);
        out[k] = DVec2::new((p[k] - p[i]).dot(dir).clamp(0.0, len[e]), 0.0);
    }
    out
}

/// The unit rotation (as a complex number, for [`DVec2::rotate`]) that turns the chart's
/// smallest hull-edge-aligned bounding rectangle to the axes.
fn best_direction(corners: &[[DVec2; 3]]) -> DVec2 {
    let points: Vec<DVec2> = corners.iter().flatten().copied().collect();
    let hull = convex_hull(points);
    let mut best = (f64::INFINITY, DVec2::X);
    for i in 0..hull.len() {
        let Some(edge) = (hull[(i + 1) % hull.len()] - hull[i]).try_normalize() else {
            continue;
        };
        // Rotating by conj(edge) lays the edge along +x.
        let r = DVec2::new(edge.x, -edge.y);
        let (lo, hi) = bounds(hull.iter().map(|&p| r.rotate(p)));
        let area = (hi - lo).x * (hi - lo).y;
        if area < best.0 {
            best = (area, r);
        }
    }
    best.1
}

/// The smallest and largest coordinates of `points` (infinities for none).
fn bounds(points: impl Iterator<Item = DVec2>) -> (DVec2, DVec2) {
    points.fold(
        (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY)),
        |(lo, hi), p| (lo.min(p), hi.max(p)),
    )
}

/// The convex hull of `points`, counter-clockwise (Andrew's monotone chain); collinear points
/// dropped.
fn convex_hull(mut points: Vec<DVec2>) -> Vec<DVec2> {
    points.sort_by(|a, b| a.x.total_cmp(&b.x).then(a.y.total_cmp(&b.y)));
    points.dedup();
    if points.len() < 3 {
        return points;
    }
    let cross = |o: DVec2, a: DVec2, b: DVec2| (a - o).perp_dot(b - o);
    let mut hull: Vec<DVec2> = Vec::with_capacity(2 * points.len());
    for pass in 0..2 {
        let start = hull.len();
        let iter: Box<dyn Iterator<Item = &DVec2>> = if pass == 0 {
            Box::new(points.iter())
        } else {
            Box::new(points.iter().rev())
        };
        for &p in iter {
            while hull.len() >= start + 2
                && cross(hull[hull.len() - 2], hull[hull.len() - 1], p) <= 0.0
            {
                hull.pop();
            }
            hull.push(p);
        }
        hull.pop();
    }
    hull
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hull_of_a_square_with_inner_points() {
        let pts = vec![
            DVec2::ZERO,
            DVec2::new(2.0, 0.0),
            DVec2::new(1.0, 1.0),
            DVec2::new(2.0, 2.0),
            DVec2::new(0.0, 2.0),
            DVec2::new(1.0, 0.0),
        ];
        let hull = convex_hull(pts);
        assert_eq!(
            hull,
            vec![
                DVec2::ZERO,
                DVec2::new(2.0, 0.0),
                DVec2::new(2.0, 2.0),
                DVec2::new(0.0, 2.0)
            ]
        );
    }

    #[test]
    fn a_tilted_rectangle_is_turned_to_the_axes() {
        let d = DVec2::new(3f64.sqrt() / 2.0, 0.5); // 30°
        let (a, b) = (d * 4.0, d.perp());
        let tris = [[DVec2::ZERO, a, a + b], [DVec2::ZERO, a + b, b]];
        let r = best_direction(&tris);
        let (lo, hi) = bounds(tris.iter().flatten().map(|&p| r.rotate(p)));
        assert!(((hi - lo).x * (hi - lo).y - 4.0).abs() < 1e-9, "{lo} {hi}");
    }
}
