//! Built-in environment shapes (floor, boxes, cylinders, spheres, surfaces of revolution).
//!
//! All shapes are Z-up like the teapot data, have outward unit normals and triangles wound
//! counter-clockwise around them. Texture coordinates are in *world units* (scene length
//! units along the surface), so a checker texture of period `p` gives squares of side `p` on
//! every shape; per-shape details are documented on each function.

use std::f32::consts::TAU;

use glam::{Vec2, Vec3};

use crate::{BakeError, Result};
use oslf_geometry::mesh::Mesh;

/// Largest accepted segment count.
pub const MAX_SEGMENTS: u32 = 1 << 16;

/// Profile vertices whose two segments meet at more than this angle (degrees) get split
/// normals (a crease); smaller angles are smoothed.
pub const CREASE_ANGLE_DEGREES: f32 = 30.0;

fn positive(name: &str, x: f32) -> Result<()> {
    if x.is_finite() && x > 0.0 {
        Ok(())
    } else {
        Err(BakeError::Invalid(format!(
            "{name} must be positive and finite, got {x}"
        )))
    }
}

fn segment_count(segments: u32) -> Result<()> {
    if (3..=MAX_SEGMENTS).contains(&segments) {
        Ok(())
    } else {
        Err(BakeError::Invalid(format!(
            "segments must be in 3..={MAX_SEGMENTS}, got {segments}"
        )))
    }
}

/// Adds one rectangle `centre ± a ± b` with normal `a × b` (normalized) and uv in world units
/// from the `centre - a - b` corner.
fn push_quad(mesh: &mut Mesh, centre: Vec3, a: Vec3, b: Vec3) {
    let base = mesh.positions.len() as u32;
    let n = a.cross(b).normalize_or(Vec3::Z);
    let (la, lb) = (2.0 * a.length(), 2.0 * b.length());
    let corners = [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)];
    for (s, t) in corners {
        mesh.positions.push(centre + a * s + b * t);
        mesh.normals.push(n);
        mesh.uvs
            .push(Vec2::new((s + 1.0) * 0.5 * la, (t + 1.0) * 0.5 * lb));
    }
    mesh.triangles.push([base, base + 1, base + 2]);
    mesh.triangles.push([base, base + 2, base + 3]);
}

/// A rectangle in the xy plane centred at the origin, normal `+z` (a floor).
/// uv = `(x + size.x/2, y + size.y/2)`.
pub fn plane(size: Vec2) -> Result<Mesh> {
    positive("plane width", size.x)?;
    positive("plane depth", size.y)?;
    let mut m = Mesh::new();
    push_quad(
        &mut m,
        Vec3::ZERO,
        Vec3::X * size.x * 0.5,
        Vec3::Y * size.y * 0.5,
    );
    Ok(m)
}

/// An axis-aligned box centred at the origin with edge lengths `size`; 24 vertices (flat
/// faces). Each face's uv is world units from one of its corners.
pub fn cuboid(size: Vec3) -> Result<Mesh> {
    positive("cuboid size x", size.x)?;
    positive("cuboid size y", size.y)?;
    positive("cuboid size z", size.z)?;
    let h = size * 0.5;
    let (x, y, z) = (Vec3::X * h.x, Vec3::Y * h.y, Vec3::Z * h.z);
    let mut m = Mesh::new();
    // (face centre, a, b) with a × b along the outward normal.
    for (c, a, b) in [
        (x, y, z),
        (-x, z, y),
        (y, z, x),
        (-y, x, z),
        (z, x, y),
        (-z, y, x),
    ] {
        push_quad(&mut m, c, a, b);
    }
    Ok(m)
}

/// A cylinder of `radius` around the z axis from `z = 0` to `z = height`, with `segments`
/// facets around, optionally closed by flat caps. uv as for [`revolution`].
pub fn cylinder(radius: f32, height: f32, segments: u32, capped: bool) -> Result<Mesh> {
    positive("cylinder radius", radius)?;
    positive("cylinder height", height)?;
    let (r, h) = (radius, height);
    let profile: Vec<Vec2> = if capped {
        vec![
            Vec2::new(0.0, 0.0),
            Vec2::new(r, 0.0),
            Vec2::new(r, h),
            Vec2::new(0.0, h),
        ]
    } else {
        vec![Vec2::new(r, 0.0), Vec2::new(r, h)]
    };
    revolution(&profile, segments)
}

/// A sphere of `radius` centred at the origin: `segments` facets around the z axis and
/// `max(segments / 2, 2)` rings from pole to pole. Normals are exact (`p / radius`); uv as for
/// [`revolution`] (u along the equator, v = arc length from the south pole).
pub fn sphere(radius: f32, segments: u32) -> Result<Mesh> {
    positive("sphere radius", radius)?;
    segment_count(segments)?;
    let rings = (segments / 2).max(2);
    let profile: Vec<Vec2> = (0..=rings)
        .map(|k| {
            let theta =
                -std::f32::consts::FRAC_PI_2 + std::f32::consts::PI * k as f32 / rings as f32;
            if k == 0 || k == rings {
                // Exactly on the axis at the poles.
                Vec2::new(0.0, radius * theta.sin().signum())
            } else {
                Vec2::new(radius * theta.cos(), radius * theta.sin())
            }
        })
        .collect();
    let mut m = revolution(&profile, segments)?;
    for (n, p) in m.normals.iter_mut().zip(&m.positions) {
        *n = (*p / radius).normalize_or(*n);
    }
    Ok(m)
}

/// A surface of revolution about the z axis: `profile` lists `(radius, z)` points, swept
/// through `segments` facets around the axis (use it for teacups, vases, ...).
///
/// Orientation: the outward side is to the *right* of the direction of travel along the
/// profile in the (radius, z) half-plane, i.e. list the solid's cross-section
/// counter-clockwise (a cup: bottom centre → outer bottom edge → up the outside → over the
/// rim → down the inside → inner bottom centre). Points must be finite with radius ≥ 0;
/// repeated consecutive points are skipped. Normals are smoothed across profile vertices
/// whose segments turn by less than [`CREASE_ANGLE_DEGREES`] and split otherwise.
///
/// uv: `u = φ · r_max` (arc length at the largest profile radius, `φ` the angle around z),
/// `v` = arc length along the profile from its first point.
pub fn revolution(profile: &[Vec2], segments: u32) -> Result<Mesh> {
    segment_count(segments)?;
    if let Some((i, p)) = profile
        .iter()
        .enumerate()
        .find(|(_, p)| !p.is_finite() || p.x < 0.0)
    {
        return Err(BakeError::Invalid(format!(
            "profile point {i} {p} must be finite with radius >= 0"
        )));
    }
    let mut pts: Vec<Vec2> = Vec::with_capacity(profile.len());
    for &p in profile {
        if pts.last() != Some(&p) {
            pts.push(p);
        }
    }
    if pts.len() < 2 {
        return Err(BakeError::Invalid(
            "a surface of revolution needs at least 2 distinct profile points".into(),
        ));
    }
    if pts.iter().all(|p| p.x == 0.0) {
        return Err(BakeError::Invalid(
            "a surface of revolution needs a profile point off the axis".into(),
        ));
    }
    let r_max = pts.iter().map(|p| p.x).fold(0.0, f32::max);
    // Outward 2D normal (radius, z) of each segment: right-hand side of travel.
    let seg_n: Vec<Vec2> = pts
        .windows(2)
        .map(|w| {
            let d = w[1] - w[0];
            Vec2::new(d.y, -d.x).normalize_or(Vec2::X)
        })
        .collect();
    let mut arc = vec![0.0f32; pts.len()];
    for k in 1..pts.len() {
        arc[k] = arc[k - 1] + (pts[k] - pts[k - 1]).length();
    }
    let cos_crease = CREASE_ANGLE_DEGREES.to_radians().cos();
    let vertex_normal = |s: usize, other: Option<usize>| -> Vec2 {
        match other {
            Some(o) if seg_n[s].dot(seg_n[o]) >= cos_crease => {
                (seg_n[s] + seg_n[o]).normalize_or(seg_n[s])
            }
            _ => seg_n[s],
        }
    };
    // Angles: the last column repeats the first exactly so the seam is watertight.
    let cols = segments as usize;
    let trig: Vec<(f32, f32, f32)> = (0..=cols)
        .map(|j| {
            let jj = if j == cols { 0 } else { j };
            let phi = TAU * jj as f32 / cols as f32;
            (phi.cos(), phi.sin(), TAU * j as f32 / cols as f32)
        })
        .collect();
    let mut m = Mesh::new();
    for s in 0..seg_n.len() {
        let ends = [
            (pts[s], arc[s], vertex_normal(s, s.checked_sub(1))),
            (
                pts[s + 1],
                arc[s + 1],
                vertex_normal(s, (s + 1 < seg_n.len()).then_some(s + 1)),
            ),
        ];
        let base = m.positions.len() as u32;
        for (p, v, n2) in ends {
            for &(c, sn, phi) in &trig {
                m.positions.push(Vec3::new(p.x * c, p.x * sn, p.y));
                m.normals
                    .push(Vec3::new(n2.x * c, n2.x * sn, n2.y).normalize_or(Vec3::Z));
                m.uvs.push(Vec2::new(phi * r_max, v));
            }
        }
        let row = cols as u32 + 1;
        for j in 0..cols as u32 {
            let (a0, a1) = (base + j, base + j + 1);
            let (b0, b1) = (base + row + j, base + row + j + 1);
            if pts[s].x > 0.0 {
                m.triangles.push([a0, a1, b0]);
            }
            if pts[s + 1].x > 0.0 {
                m.triangles.push([b0, a1, b1]);
            }
        }
    }
    Ok(m)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rejects_bad_arguments() {
        assert!(plane(Vec2::new(0.0, 1.0)).is_err());
        assert!(cuboid(Vec3::new(1.0, f32::NAN, 1.0)).is_err());
        assert!(cylinder(1.0, 1.0, 2, true).is_err());
        assert!(sphere(-1.0, 16).is_err());
        assert!(revolution(&[Vec2::new(1.0, 0.0)], 8).is_err());
        assert!(revolution(&[Vec2::new(-1.0, 0.0), Vec2::new(1.0, 1.0)], 8).is_err());
        assert!(revolution(&[Vec2::new(0.0, 0.0), Vec2::new(0.0, 1.0)], 8).is_err());
    }

    #[test]
    fn shapes_validate() {
        for m in [
            plane(Vec2::new(2.0, 3.0)).unwrap(),
            cuboid(Vec3::new(1.0, 2.0, 3.0)).unwrap(),
            cylinder(1.0, 2.0, 12, true).unwrap(),
            sphere(1.0, 12).unwrap(),
        ] {
            m.validate().unwrap();
        }
    }
}
