//! The parallax-corrected baseline's proxy box (Lagarde & Zanuttini 2012, "Local image-based
//! lighting with parallax-corrected cubemaps"): engines place a box around the room and
//! intersect each reflected ray with it before looking up the probe's cube. Here the box is
//! either given ([`crate::ShadingParams::proxy_box`]) or fitted to the environment cube's own
//! distance channel: on each of the six faces, the median distance along the face's axis of
//! the points the cube's texels see.

use glam::Vec3;
use oslf_format::Store;

use crate::face::FAR_DISTANCE;

/// Half-extent given to a box side whose face sees nothing but escaped rays (open sky): far
/// enough that the correction vanishes there.
pub const OPEN_SIDE: f32 = 1.0e4;

/// Fits the proxy box around `centre` (world space, where the environment cube was captured)
/// to the environment cube's distances: `None` when the store has no environment cube or no
/// distance channel.
pub fn fit_proxy_box(store: &Store, centre: Vec3) -> crate::Result<Option<[[f32; 3]; 2]>> {
    let Some(env) = store.env_cube_index() else {
        return Ok(None);
    };
    if !store.header().has_distance() {
        return Ok(None);
    }
    let image = store
        .read_cube(env)
        .map_err(|error| crate::RuntimeError::Cube { cube: env, error })?;
    let Some(distance) = &image.distance else {
        return Ok(None);
    };
    let res = image.resolution;
    let mut lo = [0.0f32; 3];
    let mut hi = [0.0f32; 3];
    for (face, plane) in distance.iter().enumerate() {
        // Face order px, nx, py, ny, pz, nz: axis face / 2, positive for even faces.
        let axis = face / 2;
        let mut along: Vec<f32> = Vec::new();
        for y in 0..res {
            for x in 0..res {
                let d = plane[(y * res + x) as usize];
                if d.is_finite() && d < FAR_DISTANCE {
                    let dir = Vec3::from_array(oslf_format::cube::texel_direction(face, x, y, res));
                    along.push(d * dir[axis].abs());
                }
            }
        }
        let extent = if along.is_empty() {
            OPEN_SIDE
        } else {
            along.sort_by(f32::total_cmp);
            along[along.len() / 2].max(1e-3)
        };
        if face % 2 == 0 {
            hi[axis] = centre[axis] + extent;
        } else {
            lo[axis] = centre[axis] - extent;
        }
    }
    Ok(Some([lo, hi]))
}

/// The direction from the probe at `probe` towards where the ray from `x` along `d` leaves the
/// box `[lo, hi]` (as `parallax_dir` in shade.wgsl); `d` itself when `x` is not inside the box.
pub fn parallax_dir(x: Vec3, d: Vec3, probe: Vec3, lo: Vec3, hi: Vec3) -> Vec3 {
    let inside = x.cmpgt(lo).all() && x.cmplt(hi).all();
    if !inside {
        return d;
    }
    let mut t = f32::MAX;
    for k in 0..3 {
        if d[k] > 1e-12 {
            t = t.min((hi[k] - x[k]) / d[k]);
        } else if d[k] < -1e-12 {
            t = t.min((lo[k] - x[k]) / d[k]);
        }
    }
    if !(t > 0.0 && t < f32::MAX) {
        return d;
    }
    x + d * t - probe
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rays_from_the_centre_keep_their_direction_and_offset_rays_bend() {
        let (lo, hi) = (Vec3::splat(-2.0), Vec3::splat(2.0));
        let d = Vec3::new(1.0, 0.0, 0.0);
        assert_eq!(
            parallax_dir(Vec3::ZERO, d, Vec3::ZERO, lo, hi),
            Vec3::new(2.0, 0.0, 0.0)
        );
        // From (0, 1, 0) along +x the wall x = 2 is met at (2, 1, 0): seen from the centre at 26.6°.
        let p = parallax_dir(Vec3::Y, d, Vec3::ZERO, lo, hi);
        assert_eq!(p, Vec3::new(2.0, 1.0, 0.0));
        // Outside the box: unchanged.
        assert_eq!(parallax_dir(Vec3::splat(3.0), d, Vec3::ZERO, lo, hi), d);
    }
}
