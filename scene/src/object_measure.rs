//! What the bake's chosen settings read of an object ([`measure`]): its size, its area, the
//! gaps in front of its surface, its curvature and the lobes of its material (the smoothest and
//! the typical). [`crate::bake_defaults`] turns them into settings.

use glam::Vec3;
use oslf_geometry::mesh::Mesh;

use crate::material::{Material, Model};
use crate::scene::{OslfObject, Shape};

/// The quantile of the gaps in front of an object's surface that [`ObjectMeasure::clearance`]
/// reports (the bake's ε is at most half of it: `bake_defaults::EPSILON_PER_CLEARANCE`).
pub const CLEARANCE_QUANTILE: f32 = 0.05;

/// What the rules read of one object.
#[derive(Clone, Debug)]
pub struct ObjectMeasure {
    /// Diagonal of its bounding box (world space).
    pub size: f32,
    /// Surface area (patches tessellated).
    pub area: f32,
    /// The [`CLEARANCE_QUANTILE`] of the gaps in front of its surface, contacts aside;
    /// `None` where no other surface is near.
    pub clearance: Option<f32>,
    /// The narrowest GGX width α of its material (0 for a Lambertian object, which the
    /// runtime's mirror and glossy modes reflect at any lobe), and the roughness it came from.
    pub alpha: f32,
    pub roughness: Option<f32>,
    /// The area median of its roughness over its surface (the factor where it has no
    /// roughness texture), and its GGX α: what most of its pixels reflect with.
    pub typical_alpha: f32,
    pub typical_roughness: Option<f32>,
    /// How sharply its surface typically curves: the [`CURVATURE_QUANTILE`] of the
    /// normal's turn per length along its smooth edges (1/radius; 0 for a flat object).
    pub curvature: f32,
}

/// The share of an object's smooth edges that curve less than [`ObjectMeasure::curvature`]:
/// the median, its typical curvature. Thin parts (a teapot's spout and handle, at 10× the
/// body's) need more points, not a larger ε: what a uniform spacing cannot give them, the
/// points added where texels find fewer than four do.
pub const CURVATURE_QUANTILE: f32 = 0.5;

/// The bounds of the points that define `object` (world space).
fn object_bounds(object: &OslfObject) -> (Vec3, Vec3) {
    object
        .points()
        .fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), p| {
            (lo.min(p), hi.max(p))
        })
}

/// The diagonal of `object`'s bounding box (world space): the size the rules scale with.
pub fn object_size(object: &OslfObject) -> f32 {
    let (lo, hi) = object_bounds(object);
    (hi - lo).length()
}

/// What the rules read of `object` among `shapes`; gaps narrower than `contact_per_size` × its
/// size are contacts ([`clearance`]).
pub fn measure(
    object: &OslfObject,
    shapes: &[Shape],
    materials: &[Material],
    contact_per_size: f32,
) -> ObjectMeasure {
    let surface = surface_mesh(object);
    let (lo, hi) = object_bounds(object);
    let size = (hi - lo).length();
    let material = materials.get(object.material as usize);
    let (alpha, roughness) = material.map_or((0.0, None), material_alpha);
    let typical_roughness = material.and_then(|m| typical_roughness(m, &surface));
    let typical_alpha = typical_roughness.map_or(0.0, |r| r * r);
    ObjectMeasure {
        size,
        area: surface.area() as f32,
        clearance: clearance(&surface, (lo, hi), size, contact_per_size, shapes),
        alpha,
        roughness,
        typical_alpha,
        typical_roughness,
        curvature: curvature(&surface),
    }
}

/// The object's surface as triangles: a mesh as it is, patches at 8 × 8 quads.
fn surface_mesh(object: &OslfObject) -> Mesh {
    let mut mesh = object
        .mesh
        .as_ref()
        .map_or_else(Mesh::new, |m| m.mesh.clone());
    for p in &object.patches {
        mesh.append(&p.tessellate(8));
    }
    mesh
}

/// The narrowest GGX α of a material and the roughness it comes from: roughness² of the
/// smoothest texel of a roughness texture, or of the factor; a Lambertian material is reflected
/// by the runtime at any lobe, a mirror's included (α = 0, no roughness).
pub fn material_alpha(material: &Material) -> (f32, Option<f32>) {
    let Model::MetallicRoughness { roughness, .. } = material.model else {
        return (0.0, None);
    };
    let r = match &material.metallic_roughness_texture {
        Some(t) => texture_min_green(t),
        None => roughness,
    }
    .clamp(0.0, 1.0);
    (r * r, Some(r))
}

/// The area median of a metallic-roughness material's roughness over `surface` (read at each
/// triangle's centre, in its texture coordinates); `None` for a Lambertian material.
fn typical_roughness(material: &Material, surface: &Mesh) -> Option<f32> {
    let Model::MetallicRoughness { roughness, .. } = material.model else {
        return None;
    };
    let Some(texture) = &material.metallic_roughness_texture else {
        return Some(roughness.clamp(0.0, 1.0));
    };
    let mut samples: Vec<(f32, f32)> = surface
        .triangles
        .iter()
        .filter_map(|t| {
            let [a, b, c] = surface.corners(t)?;
            let uv = t
                .iter()
                .filter_map(|&i| surface.uvs.get(i as usize))
                .sum::<glam::Vec2>()
                / 3.0;
            let area = 0.5 * (b - a).cross(c - a).length();
            Some((texture.eval(uv).y.clamp(0.0, 1.0), area))
        })
        .filter(|(r, a)| r.is_finite() && a.is_finite())
        .collect();
    if samples.is_empty() {
        return Some(texture_min_green(texture).clamp(0.0, 1.0));
    }
    samples.sort_by(|x, y| x.0.total_cmp(&y.0));
    let half = 0.5 * samples.iter().map(|s| s.1).sum::<f32>();
    let mut acc = 0.0;
    samples
        .iter()
        .find(|s| {
            acc += s.1;
            acc >= half
        })
        .or(samples.last())
        .map(|s| s.0)
}

/// The smallest green value of a texture (roughness in glTF's metallic-roughness texture).
fn texture_min_green(t: &crate::texture::Texture) -> f32 {
    use crate::texture::Texture;
    match t {
        Texture::Constant(c) => c.y,
        Texture::Checker { a, b, .. } => a.y.min(b.y),
        Texture::Image(img) => img.pixels.iter().fold(f32::INFINITY, |m, p| m.min(p.y)),
    }
}

/// The [`CURVATURE_QUANTILE`] of |n₁ − n₂| / |p₁ − p₂| over the edges of `surface` whose ends
/// share a vertex pair (hard edges, with vertices of their own, do not count).
fn curvature(surface: &Mesh) -> f32 {
    let mut k: Vec<f32> = surface
        .triangles
        .iter()
        .flat_map(|t| [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])])
        .filter_map(|(a, b)| {
            let (a, b) = (a as usize, b as usize);
            let (pa, pb) = (surface.positions.get(a)?, surface.positions.get(b)?);
            let (na, nb) = (surface.normals.get(a)?, surface.normals.get(b)?);
            let len = (*pa - *pb).length();
            let turn = (na.normalize_or_zero() - nb.normalize_or_zero()).length();
            (len > 0.0 && turn.is_finite()).then_some(turn / len)
        })
        .filter(|k| k.is_finite())
        .collect();
    if k.is_empty() {
        return 0.0;
    }
    k.sort_by(f32::total_cmp);
    k[((k.len() - 1) as f32 * CURVATURE_QUANTILE) as usize]
}

/// Surface points tested for clearance, at most.
const CLEARANCE_POINTS: usize = 2048;

/// Ray–triangle tests of the clearance, at most (beyond 64 points): about a second on one core.
const CLEARANCE_TESTS: usize = 20_000_000;

/// The [`CLEARANCE_QUANTILE`] of the gaps in front of `surface`, over the whole surface: from
/// points of it (triangle centres) along their normals to the nearest triangle of `shapes`
/// within reach (a quarter of the size beyond the object's bounds). Gaps narrower than
/// `contact_per_size` × `size` are contacts (the object rests on the surface, or nearly: no
/// ε sized to the object fits there, and the surface hides them) and count as open, as do
/// points with no surface in reach; `None` where fewer than the quantile's share of the
/// surface faces a gap.
fn clearance(
    surface: &Mesh,
    bounds: (Vec3, Vec3),
    size: f32,
    contact_per_size: f32,
    shapes: &[Shape],
) -> Option<f32> {
    let reach = 0.25 * size;
    let (lo, hi) = (bounds.0 - Vec3::splat(reach), bounds.1 + Vec3::splat(reach));
    let near: Vec<[Vec3; 3]> = shapes
        .iter()
        .flat_map(|s| s.mesh.triangles.iter().filter_map(|t| s.mesh.corners(t)))
        .filter(|[a, b, c]| {
            let (tlo, thi) = (a.min(*b).min(*c), a.max(*b).max(*c));
            tlo.cmple(hi).all() && thi.cmpge(lo).all()
        })
        .collect();
    if near.is_empty() || surface.triangles.is_empty() {
        return None;
    }
    // At most CLEARANCE_TESTS ray–triangle tests: fewer points beside a dense mesh.
    let points = (CLEARANCE_TESTS / near.len()).clamp(64, CLEARANCE_POINTS);
    let stride = surface.triangles.len().div_ceil(points);
    let contact = contact_per_size * size;
    let mut tested = 0usize;
    let mut gaps: Vec<f32> = surface
        .triangles
        .iter()
        .step_by(stride)
        .filter_map(|t| {
            let [a, b, c] = surface.corners(t)?;
            let normals = t.map(|i| {
                surface
                    .normals
                    .get(i as usize)
                    .copied()
                    .unwrap_or(Vec3::ZERO)
            });
            let n = (normals[0] + normals[1] + normals[2]).normalize_or_zero();
            if n == Vec3::ZERO {
                return None;
            }
            tested += 1;
            let p = (a + b + c) / 3.0;
            near.iter()
                .filter_map(|tri| ray_triangle(p, n, tri))
                .reduce(f32::min)
        })
        .filter(|d| *d > contact && *d < reach)
        .collect();
    // Points without a gap in reach (or in contact) count as open: the quantile is of the
    // whole surface.
    let k = (tested as f32 * CLEARANCE_QUANTILE) as usize;
    gaps.sort_by(f32::total_cmp);
    gaps.get(k).copied()
}

/// Distance along the unit direction `d` from `o` to the triangle `[a, b, c]`, if the ray
/// meets it at t > 0 (Möller–Trumbore, either side).
pub fn ray_triangle(o: Vec3, d: Vec3, [a, b, c]: &[Vec3; 3]) -> Option<f32> {
    let (e1, e2) = (*b - *a, *c - *a);
    let p = d.cross(e2);
    let det = e1.dot(p);
    if det.abs() <= f32::MIN_POSITIVE {
        return None;
    }
    let inv = 1.0 / det;
    let s = o - *a;
    let u = s.dot(p) * inv;
    if !(0.0..=1.0).contains(&u) {
        return None;
    }
    let q = s.cross(e1);
    let v = d.dot(q) * inv;
    if v < 0.0 || u + v > 1.0 {
        return None;
    }
    let t = e2.dot(q) * inv;
    (t > 0.0 && t.is_finite()).then_some(t)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rays_meet_triangles_in_front_only() {
        let t = [Vec3::ZERO, Vec3::X, Vec3::Y];
        let o = Vec3::new(0.2, 0.2, 1.0);
        assert_eq!(ray_triangle(o, -Vec3::Z, &t), Some(1.0));
        assert_eq!(ray_triangle(o, Vec3::Z, &t), None);
        assert_eq!(ray_triangle(Vec3::new(0.8, 0.8, 1.0), -Vec3::Z, &t), None);
        assert_eq!(ray_triangle(o, Vec3::X, &t), None);
    }
}
