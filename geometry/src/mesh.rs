//! Indexed triangle meshes: the common currency between Bézier tessellation, built-in shapes,
//! OBJ files and the BVH.

use glam::{Affine3A, Mat3, Vec2, Vec3};

use crate::{GeometryError, Result};

/// An indexed triangle mesh with one normal and one uv per vertex.
///
/// Triangles are wound counter-clockwise around their outward normal:
/// `(p1 - p0) × (p2 - p0)` points to the side the vertex normals point to.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Mesh {
    /// Vertex positions.
    pub positions: Vec<Vec3>,
    /// Unit vertex normals, one per position.
    pub normals: Vec<Vec3>,
    /// Texture coordinates, one per position.
    pub uvs: Vec<Vec2>,
    /// Vertex indices, three per triangle.
    pub triangles: Vec<[u32; 3]>,
}

impl Mesh {
    /// An empty mesh.
    pub fn new() -> Self {
        Self::default()
    }

    /// Number of triangles.
    pub fn triangle_count(&self) -> usize {
        self.triangles.len()
    }

    /// Applies an affine map: positions by `m`, normals by the inverse transpose of its linear
    /// part (renormalized). A mirroring map (negative determinant) also reverses the winding of
    /// every triangle so that winding and normals stay consistent.
    ///
    /// A singular map (determinant 0) keeps the normals it cannot transform unchanged rather than
    /// producing NaN.
    pub fn transform(&mut self, m: &Affine3A) {
        let linear = Mat3::from(m.matrix3);
        let det = linear.determinant();
        // Inverse transpose = cofactor matrix / det; only the direction matters, so use the
        // cofactor matrix times sign(det), which exists even for singular maps.
        let cofactor = cofactor_matrix(&linear) * if det < 0.0 { -1.0 } else { 1.0 };
        for p in &mut self.positions {
            *p = m.transform_point3(*p);
        }
        for n in &mut self.normals {
            let t = cofactor * *n;
            *n = t.try_normalize().unwrap_or(*n);
        }
        if det < 0.0 {
            for t in &mut self.triangles {
                t.swap(1, 2);
            }
        }
    }

    /// Appends `other`'s vertices and triangles (indices shifted).
    pub fn append(&mut self, other: &Mesh) {
        let base = self.positions.len() as u32;
        self.positions.extend_from_slice(&other.positions);
        self.normals.extend_from_slice(&other.normals);
        self.uvs.extend_from_slice(&other.uvs);
        self.triangles.extend(
            other
                .triangles
                .iter()
                .map(|t| [t[0] + base, t[1] + base, t[2] + base]),
        );
    }

    /// Total surface area of the triangles (indices out of range are skipped).
    pub fn area(&self) -> f64 {
        self.triangles
            .iter()
            .filter_map(|t| self.corners(t))
            .map(|[a, b, c]| 0.5 * f64::from((b - a).cross(c - a).length()))
            .sum()
    }

    /// Axis-aligned bounds `(min, max)` of the positions; `(0, 0)` for an empty mesh.
    pub fn bounds(&self) -> (Vec3, Vec3) {
        if self.positions.is_empty() {
            return (Vec3::ZERO, Vec3::ZERO);
        }
        self.positions.iter().fold(
            (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)),
            |(lo, hi), p| (lo.min(*p), hi.max(*p)),
        )
    }

    /// Checks that the attribute arrays have one entry per vertex, every index is in range and
    /// every value is finite; normals must be non-zero.
    pub fn validate(&self) -> Result<()> {
        let n = self.positions.len();
        if self.normals.len() != n || self.uvs.len() != n {
            return Err(GeometryError::Invalid(format!(
                "mesh has {n} positions but {} normals and {} uvs",
                self.normals.len(),
                self.uvs.len()
            )));
        }
        if let Some(i) = self.positions.iter().position(|p| !p.is_finite()) {
            return Err(GeometryError::Invalid(format!(
                "mesh vertex {i} has a non-finite position {}",
                self.positions[i]
            )));
        }
        if let Some(i) = self
            .normals
            .iter()
            .position(|v| !v.is_finite() || v.length_squared() == 0.0)
        {
            return Err(GeometryError::Invalid(format!(
                "mesh vertex {i} has an unusable normal {}",
                self.normals[i]
            )));
        }
        if let Some(i) = self.uvs.iter().position(|v| !v.is_finite()) {
            return Err(GeometryError::Invalid(format!(
                "mesh vertex {i} has a non-finite uv {}",
                self.uvs[i]
            )));
        }
        if let Some((i, t)) = self
            .triangles
            .iter()
            .enumerate()
            .find(|(_, t)| t.iter().any(|&v| v as usize >= n))
        {
            return Err(GeometryError::Invalid(format!(
                "mesh triangle {i} has index {t:?} out of range (mesh has {n} vertices)"
            )));
        }
        Ok(())
    }

    /// The unit icosphere: the icosahedron subdivided `subdivisions` times (20·4ⁿ triangles,
    /// each split into four with the new vertices projected onto the sphere), wound
    /// counter-clockwise seen from outside; normals equal positions, uvs are zero.
    pub fn icosphere(subdivisions: u32) -> Mesh {
        let t = (1.0 + 5f32.sqrt()) / 2.0;
        let mut positions: Vec<Vec3> = [
            [-1.0, t, 0.0],
            [1.0, t, 0.0],
            [-1.0, -t, 0.0],
            [1.0, -t, 0.0],
            [0.0, -1.0, t],
            [0.0, 1.0, t],
            [0.0, -1.0, -t],
            [0.0, 1.0, -t],
            [t, 0.0, -1.0],
            [t, 0.0, 1.0],
            [-t, 0.0, -1.0],
            [-t, 0.0, 1.0],
        ]
        .iter()
        .map(|&p| Vec3::from_array(p).normalize())
        .collect();
        #[rustfmt::skip]
        let mut triangles: Vec<[u32; 3]> = vec![
            [0, 11, 5], [0, 5, 1], [0, 1, 7], [0, 7, 10], [0, 10, 11],
            [1, 5, 9], [5, 11, 4], [11, 10, 2], [10, 7, 6], [7, 1, 8],
            [3, 9, 4], [3, 4, 2], [3, 2, 6], [3, 6, 8], [3, 8, 9],
            [4, 9, 5], [2, 4, 11], [6, 2, 10], [8, 6, 7], [9, 8, 1],
        ];
        for _ in 0..subdivisions {
            // Edge midpoints by sorted vertex pair: shared by the edge's two triangles.
            let mut midpoints = std::collections::BTreeMap::new();
            let mut mid = |a: u32, b: u32, positions: &mut Vec<Vec3>| {
                *midpoints.entry((a.min(b), a.max(b))).or_insert_with(|| {
                    positions.push((positions[a as usize] + positions[b as usize]).normalize());
                    positions.len() as u32 - 1
                })
            };
            let mut next = Vec::with_capacity(triangles.len() * 4);
            for [a, b, c] in triangles {
                let ab = mid(a, b, &mut positions);
                let bc = mid(b, c, &mut positions);
                let ca = mid(c, a, &mut positions);
                next.extend([[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]);
            }
            triangles = next;
        }
        Mesh {
            normals: positions.clone(),
            uvs: vec![Vec2::ZERO; positions.len()],
            positions,
            triangles,
        }
    }

    /// Replaces the normals by smooth, area-weighted vertex normals computed from the
    /// triangles. A vertex that touches no non-degenerate triangle gets `+z`.
    pub fn compute_smooth_normals(&mut self) {
        let mut acc = vec![Vec3::ZERO; self.positions.len()];
        for t in &self.triangles {
            if let Some([a, b, c]) = self.corners(t) {
                // Cross product length is twice the area: area weighting for free.
                let n = (b - a).cross(c - a);
                if n.is_finite() {
                    for &v in t {
                        acc[v as usize] += n;
                    }
                }
            }
        }
        self.normals = acc
            .into_iter()
            .map(|n| n.try_normalize().unwrap_or(Vec3::Z))
            .collect();
    }

    /// The three corner positions of a triangle, `None` if an index is out of range.
    pub fn corners(&self, t: &[u32; 3]) -> Option<[Vec3; 3]> {
        Some([
            *self.positions.get(t[0] as usize)?,
            *self.positions.get(t[1] as usize)?,
            *self.positions.get(t[2] as usize)?,
        ])
    }
}

/// The cofactor matrix of `m` (`det(m) * inverse(m)^T` for invertible `m`).
fn cofactor_matrix(m: &Mat3) -> Mat3 {
    let (c0, c1, c2) = (m.x_axis, m.y_axis, m.z_axis);
    Mat3::from_cols(c1.cross(c2), c2.cross(c0), c0.cross(c1))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn unit_triangle() -> Mesh {
        Mesh {
            positions: vec![Vec3::ZERO, Vec3::X, Vec3::Y],
            normals: vec![Vec3::Z; 3],
            uvs: vec![Vec2::ZERO; 3],
            triangles: vec![[0, 1, 2]],
        }
    }

    #[test]
    fn transform_normals_inverse_transpose() {
        let mut m = unit_triangle();
        // A shear: normals must stay perpendicular to the transformed surface.
        let a = Affine3A::from_cols_array(&[
            1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.7, 0.3, 2.0, 5.0, 6.0, 7.0,
        ]);
        m.normals = vec![Vec3::new(1.0, 1.0, 1.0).normalize(); 3];
        let tangent = Vec3::new(1.0, -1.0, 0.0);
        m.transform(&a);
        let t = a.transform_vector3(tangent);
        assert!(m.normals[0].dot(t).abs() < 1e-6);
        assert!((m.normals[0].length() - 1.0).abs() < 1e-6);
    }

    #[test]
    fn mirror_flips_winding() {
        let mut m = unit_triangle();
        m.transform(&Affine3A::from_scale(Vec3::new(1.0, 1.0, -1.0)));
        let [a, b, c] = m.corners(&m.triangles[0]).unwrap();
        let gn = (b - a).cross(c - a).normalize();
        assert!(gn.dot(m.normals[0]) > 0.99, "{gn} vs {}", m.normals[0]);
        // Singular map: no NaN.
        m.transform(&Affine3A::from_scale(Vec3::new(1.0, 1.0, 0.0)));
        assert!(m.normals.iter().all(|n| n.is_finite()));
    }

    #[test]
    fn append_area_validate() {
        let mut m = unit_triangle();
        m.append(&unit_triangle());
        assert_eq!(m.triangles[1], [3, 4, 5]);
        assert!((m.area() - 1.0).abs() < 1e-9);
        m.validate().unwrap();
        m.triangles.push([0, 1, 6]);
        assert!(m.validate().is_err());
        m.triangles.pop();
        m.positions[0].x = f32::NAN;
        assert!(m.validate().is_err());
    }

    #[test]
    fn icosphere_is_a_closed_outward_unit_sphere() {
        for n in 0..3 {
            let m = Mesh::icosphere(n);
            assert_eq!(m.triangles.len(), 20 * 4usize.pow(n));
            // Euler: V − E + F = 2 with E = 3F/2.
            assert_eq!(m.positions.len(), 2 + m.triangles.len() / 2);
            assert!(m.positions.iter().all(|p| (p.length() - 1.0).abs() < 1e-6));
            m.validate().unwrap();
            for t in &m.triangles {
                let [a, b, c] = m.corners(t).unwrap();
                let outward = (b - a).cross(c - a).dot(a + b + c);
                assert!(outward > 0.0, "triangle {t:?} winds inward");
            }
            // Its area approaches 4π from below.
            let area = m.area();
            assert!(area < 4.0 * std::f64::consts::PI && area > 0.6 * 4.0 * std::f64::consts::PI);
        }
    }
}
