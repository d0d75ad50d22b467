//! Vertex normals for meshes whose files give none (or whose scene file asks for other ones):
//! the rule ([`NormalRule`]: flat, smooth, or smooth within a crease angle), what an object got
//! and why ([`NormalsUsed`], for the bake summary), and the computation ([`shade`]).
//!
//! Vertices are welded by exact position for the computation (a uv seam is not an edge of the
//! surface), and split where their normals differ: the output has one vertex per (input
//! vertex, smoothing group).

use std::collections::HashMap;

use glam::{Vec2, Vec3};

use oslf_geometry::mesh::Mesh;

/// The crease angle OBJ meshes without normals get (degrees): faces meeting at more than this
/// stay sharp. 30° keeps a box's and a cylinder's cap edges sharp and smooths a cylinder of
/// 12 or more segments.
pub const DEFAULT_CREASE_DEG: f32 = 30.0;

/// How vertex normals are computed from the triangles.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum NormalRule {
    /// Each triangle's face normal at its three corners (every edge sharp).
    Flat,
    /// One normal per position: the angle-weighted mean of every face around it.
    Smooth,
    /// Smooth across edges whose faces' normals differ by at most `crease_deg` degrees;
    /// sharp across the others (and across boundary and non-manifold edges between faces
    /// beyond the angle).
    Crease { crease_deg: f32 },
}

impl std::fmt::Display for NormalRule {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            NormalRule::Flat => write!(f, "flat"),
            NormalRule::Smooth => write!(f, "smooth"),
            NormalRule::Crease { crease_deg } => write!(f, "crease {crease_deg}°"),
        }
    }
}

/// The normals a mesh object got and why: for the bake summary and report.
#[derive(Clone, Debug, PartialEq)]
pub struct NormalsUsed {
    /// The rule the normals were computed by; `None` where the file's normals are used.
    pub rule: Option<NormalRule>,
    /// Why, naming the file: `box.obj has no normals; the default for OBJ`.
    pub reason: String,
}

impl std::fmt::Display for NormalsUsed {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self.rule {
            Some(rule) => write!(f, "{rule} ({})", self.reason),
            None => write!(f, "from the file ({})", self.reason),
        }
    }
}

/// The unit face normal of each triangle (zero for a degenerate one) and the interior angle
/// at each of its corners.
fn faces(positions: &[Vec3], triangles: &[[u32; 3]]) -> (Vec<Vec3>, Vec<[f32; 3]>) {
    triangles
        .iter()
        .map(|t| {
            let p = t.map(|i| positions[i as usize]);
            let n = (p[1] - p[0]).cross(p[2] - p[0]).try_normalize();
            let angles = std::array::from_fn(|k| {
                let (a, b) = (p[(k + 1) % 3] - p[k], p[(k + 2) % 3] - p[k]);
                a.angle_between(b)
            });
            match n {
                Some(n) if angles.iter().all(|a| a.is_finite()) => (n, angles),
                _ => (Vec3::ZERO, [0.0; 3]),
            }
        })
        .unzip()
}

/// Union–find over triangle corners (corner `3 t + k`).
struct Groups(Vec<usize>);

impl Groups {
    fn root(&mut self, mut i: usize) -> usize {
        while self.0[i] != i {
            self.0[i] = self.0[self.0[i]];
            i = self.0[i];
        }
        i
    }
    fn join(&mut self, a: usize, b: usize) {
        let (ra, rb) = (self.root(a), self.root(b));
        if ra != rb {
            self.0[ra.max(rb)] = ra.min(rb);
        }
    }
}

/// A triangle meeting an edge: (triangle, its corner at the edge's first end, at its second).
type EdgeCorners = (usize, usize, usize);

/// The smoothing groups of the corners: corners at one welded position are joined when their
/// faces share an edge (through that position) that the rule smooths across, or, for
/// [`NormalRule::Smooth`], always.
fn smoothing_groups(
    weld: &[u32],
    triangles: &[[u32; 3]],
    face_normals: &[Vec3],
    rule: NormalRule,
) -> Groups {
    let mut groups = Groups((0..3 * triangles.len()).collect());
    let min_cos = match rule {
        NormalRule::Flat => return groups,
        NormalRule::Smooth => {
            let mut first: HashMap<u32, usize> = HashMap::new();
            for (c, &v) in triangles.iter().flatten().enumerate() {
                let f = *first.entry(weld[v as usize]).or_insert(c);
                groups.join(f, c);
            }
            return groups;
        }
        // A little slack so that coplanar faces with rounding in their normals join at 0°.
        NormalRule::Crease { crease_deg } => crease_deg.to_radians().cos() - 1e-5,
    };
    // The corners of each edge (welded positions, smaller first).
    let mut edges: HashMap<(u32, u32), Vec<EdgeCorners>> = HashMap::new();
    for (t, tri) in triangles.iter().enumerate() {
        for k in 0..3 {
            let (ka, kb) = (k, (k + 1) % 3);
            let (a, b) = (weld[tri[ka] as usize], weld[tri[kb] as usize]);
            let entry = if a < b {
                (t, 3 * t + ka, 3 * t + kb)
            } else {
                (t, 3 * t + kb, 3 * t + ka)
            };
            edges.entry((a.min(b), a.max(b))).or_default().push(entry);
        }
    }
    for around in edges.values() {
        for (i, &(t1, a1, b1)) in around.iter().enumerate() {
            for &(t2, a2, b2) in &around[i + 1..] {
                let (n1, n2) = (face_normals[t1], face_normals[t2]);
                if n1 != Vec3::ZERO && n2 != Vec3::ZERO && n1.dot(n2) >= min_cos {
                    groups.join(a1, a2);
                    groups.join(b1, b2);
                }
            }
        }
    }
    groups
}

/// A mesh of `positions`, `uvs` and `triangles` with normals by `rule`, and for each of its
/// vertices the input vertex it came from (to carry other per-vertex data along).
///
/// Each smoothing group's normal is the mean of its faces' normals weighted by the corner
/// angles (independent of how a polygon was triangulated). A vertex whose faces are all
/// degenerate, or whose faces' normals cancel, gets its own face's normal, else +z.
pub fn shade(
    positions: &[Vec3],
    uvs: &[Vec2],
    triangles: &[[u32; 3]],
    rule: NormalRule,
) -> (Mesh, Vec<u32>) {
    let mut weld = Vec::with_capacity(positions.len());
    let mut by_bits: HashMap<[u32; 3], u32> = HashMap::new();
    for p in positions {
        let next = by_bits.len() as u32;
        weld.push(
            *by_bits
                .entry(p.to_array().map(f32::to_bits))
                .or_insert(next),
        );
    }
    let (face_normals, angles) = faces(positions, triangles);
    let mut groups = smoothing_groups(&weld, triangles, &face_normals, rule);
    let mut sums = vec![Vec3::ZERO; 3 * triangles.len()];
    for c in 0..sums.len() {
        let root = groups.root(c);
        sums[root] += angles[c / 3][c % 3] * face_normals[c / 3];
    }
    let mut mesh = Mesh::new();
    let mut source = Vec::new();
    let mut vertex_of: HashMap<(u32, usize), u32> = HashMap::new();
    for (t, tri) in triangles.iter().enumerate() {
        let mut out = [0u32; 3];
        for (k, &v) in tri.iter().enumerate() {
            let root = groups.root(3 * t + k);
            // Flat shading splits every corner; the other rules share a vertex per group.
            let key = match rule {
                NormalRule::Flat => (u32::MAX, 3 * t + k),
                _ => (v, root),
            };
            out[k] = *vertex_of.entry(key).or_insert_with(|| {
                let n = sums[root]
                    .try_normalize()
                    .or(face_normals[t].try_normalize())
                    .unwrap_or(Vec3::Z);
                mesh.positions.push(positions[v as usize]);
                mesh.uvs.push(uvs[v as usize]);
                mesh.normals.push(n);
                source.push(v);
                mesh.positions.len() as u32 - 1
            });
        }
        mesh.triangles.push(out);
    }
    (mesh, source)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two triangles folded along the x axis by `fold` degrees, sharing the edge (0,0,0)-(1,0,0).
    fn hinge(fold: f32) -> (Vec<Vec3>, Vec<[u32; 3]>) {
        let (s, c) = fold.to_radians().sin_cos();
        let positions = vec![
            Vec3::ZERO,
            Vec3::X,
            Vec3::new(0.5, 1.0, 0.0),
            Vec3::new(0.5, -c, s),
        ];
        (positions, vec![[0, 1, 2], [1, 0, 3]])
    }

    #[test]
    fn crease_joins_below_the_angle_and_splits_above() {
        for (fold, rule, shared) in [
            (20.0, NormalRule::Crease { crease_deg: 30.0 }, true),
            (40.0, NormalRule::Crease { crease_deg: 30.0 }, false),
            (40.0, NormalRule::Smooth, true),
            (0.0, NormalRule::Flat, false),
        ] {
            let (p, t) = hinge(fold);
            let (m, source) = shade(&p, &[Vec2::ZERO; 4], &t, rule);
            m.validate().unwrap();
            let expected = match (rule, shared) {
                (NormalRule::Flat, _) => 6,
                (_, true) => 4,
                (_, false) => 6,
            };
            assert_eq!(m.positions.len(), expected, "{fold} {rule}");
            assert_eq!(source.len(), m.positions.len());
            for (i, &s) in source.iter().enumerate() {
                assert_eq!(m.positions[i], p[s as usize]);
            }
        }
    }

    #[test]
    fn a_uv_seam_is_not_a_crease() {
        // The hinge at 20° with its shared edge duplicated (as a uv seam would): still smooth.
        let (mut p, _) = hinge(20.0);
        p.extend([Vec3::ZERO, Vec3::X]);
        let t = vec![[0, 1, 2], [5, 4, 3]];
        let (m, _) = shade(
            &p,
            &[Vec2::ZERO; 6],
            &t,
            NormalRule::Crease { crease_deg: 30.0 },
        );
        assert_eq!(m.positions.len(), 6);
        let n0 = m.normals[m.triangles[0][0] as usize];
        let n1 = m.normals[m.triangles[1][1] as usize];
        assert!((n0 - n1).length() < 1e-6, "{n0} {n1}");
        let face = Vec3::Z;
        assert!(n0.dot(face) < 0.999, "{n0}");
    }

    #[test]
    fn degenerate_triangles_get_a_usable_normal() {
        let p = vec![Vec3::ZERO, Vec3::X, 2.0 * Vec3::X];
        for rule in [
            NormalRule::Flat,
            NormalRule::Smooth,
            NormalRule::Crease { crease_deg: 30.0 },
        ] {
            let (m, _) = shade(&p, &[Vec2::ZERO; 3], &[[0, 1, 2]], rule);
            m.validate().unwrap();
        }
    }
}
