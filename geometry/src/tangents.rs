//! MikkTSpace tangents of a triangle mesh (the tangent frame glTF's normal textures are
//! authored against when an asset has no tangents of its own), through `bevy_mikktspace`.

use bevy_mikktspace::{generate_tangents, Geometry, TangentSpace};
use glam::{Vec3, Vec4};

use crate::mesh::Mesh;

/// The mesh as MikkTSpace reads it, with a slot per triangle corner for the result.
struct Corners<'m> {
    mesh: &'m Mesh,
    out: Vec<[Option<TangentSpace>; 3]>,
}

impl Geometry for Corners<'_> {
    fn num_faces(&self) -> usize {
        self.mesh.triangles.len()
    }
    fn num_vertices_of_face(&self, _: usize) -> usize {
        3
    }
    fn position(&self, face: usize, vert: usize) -> [f32; 3] {
        let i = self.mesh.triangles[face][vert] as usize;
        self.mesh.positions[i].to_array()
    }
    fn normal(&self, face: usize, vert: usize) -> [f32; 3] {
        let i = self.mesh.triangles[face][vert] as usize;
        self.mesh.normals[i].to_array()
    }
    fn tex_coord(&self, face: usize, vert: usize) -> [f32; 2] {
        let i = self.mesh.triangles[face][vert] as usize;
        self.mesh.uvs[i].to_array()
    }
    fn set_tangent(&mut self, tangent: Option<TangentSpace>, face: usize, vert: usize) {
        self.out[face][vert] = tangent;
    }
}

/// Per triangle, per corner: the MikkTSpace tangent (unit) with the bitangent's sign in `w`
/// (`bitangent = w · (n × t)`), from the mesh's positions, normals and texture coordinates
/// (`uvs`, v up). A corner MikkTSpace leaves without a tangent (a degenerate triangle with no
/// neighbour to borrow from) gets one orthogonal to its normal, `w` = 1. Needs a valid mesh
/// (indices in range, one normal and uv per position).
pub fn corner_tangents(mesh: &Mesh) -> Vec<[Vec4; 3]> {
    let mut corners = Corners {
        mesh,
        out: vec![[None; 3]; mesh.triangles.len()],
    };
    // The error type has no variants: generation cannot fail.
    let _ = generate_tangents(&mut corners);
    corners
        .out
        .iter()
        .zip(&mesh.triangles)
        .map(|(ts, t)| {
            std::array::from_fn(|c| {
                let n = mesh.normals[t[c] as usize];
                let fallback = || n.any_orthonormal_vector().extend(1.0);
                ts[c].map_or_else(fallback, |s| {
                    let e = s.tangent_encoded();
                    match Vec3::new(e[0], e[1], e[2]).try_normalize() {
                        Some(v) => v.extend(if e[3] < 0.0 { -1.0 } else { 1.0 }),
                        None => fallback(),
                    }
                })
            })
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec2;

    /// A unit quad in the xy plane, normal +z: u along +x gives tangent +x; v along +y gives
    /// w = +1, and a mirrored u (along −x) flips the tangent, a mirrored v the sign.
    #[test]
    fn a_quad_gets_the_texture_axes() {
        let quad = |uv: [Vec2; 4]| Mesh {
            positions: vec![Vec3::ZERO, Vec3::X, Vec3::new(1.0, 1.0, 0.0), Vec3::Y],
            normals: vec![Vec3::Z; 4],
            uvs: uv.to_vec(),
            triangles: vec![[0, 1, 2], [0, 2, 3]],
        };
        let plain = [Vec2::ZERO, Vec2::X, Vec2::ONE, Vec2::Y];
        for (uv, want) in [
            (plain, Vec4::new(1.0, 0.0, 0.0, 1.0)),
            (
                plain.map(|p| Vec2::new(1.0 - p.x, p.y)),
                Vec4::new(-1.0, 0.0, 0.0, -1.0),
            ),
            (
                plain.map(|p| Vec2::new(p.x, 1.0 - p.y)),
                Vec4::new(1.0, 0.0, 0.0, -1.0),
            ),
        ] {
            for t in corner_tangents(&quad(uv)).iter().flatten() {
                assert!((*t - want).length() < 1e-5, "{t} for {want}");
            }
        }
    }
}
