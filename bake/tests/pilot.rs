//! The pilot cubes' leave-one-out prediction error (`placement = "adaptive"`), against
//! cubes whose radiance and distances are known.

use glam::Vec3;
use oslf_bake::pilot::{prediction_errors, Pilot};
use oslf_format::cube::{texel_direction, FACES};
use oslf_format::CubeImage;

const RES: u32 = 8;
/// The radiance of escaped rays.
const SKY: f32 = 1.0;

/// A pilot at `position` facing up whose cube sees the plane z = 1, radiance
/// `radiance(Some(hit))` at the point `hit`, and the sky below the horizon, `radiance(None)`
/// (distance `f32::MAX`), with its distances where `distances`.
fn pilot(
    position: Vec3,
    noise: f32,
    distances: bool,
    radiance: impl Fn(Option<Vec3>) -> f32,
) -> Pilot {
    let mut cube = CubeImage::black(RES, distances);
    for face in 0..FACES {
        for y in 0..RES {
            for x in 0..RES {
                let d = Vec3::from_array(texel_direction(face, x, y, RES));
                let t = if d.z > 1e-3 {
                    (1.0 - position.z) / d.z
                } else {
                    f32::MAX
                };
                let k = (y * RES + x) as usize;
                let v = radiance((t < f32::MAX).then(|| position + d * t));
                cube.faces[face][k] = [v; 3];
                if let Some(planes) = cube.distance.as_mut() {
                    planes[face][k] = t;
                }
            }
        }
    }
    Pilot {
        position,
        normal: Vec3::Z,
        object: 0,
        cube,
        noise,
    }
}

/// A pilot at `centre` and four neighbours `spacing` away in ±x and ±y.
fn four_around(
    centre: Vec3,
    spacing: f32,
    noise: f32,
    distances: bool,
    radiance: impl Fn(Option<Vec3>) -> f32 + Copy,
) -> Vec<Pilot> {
    grid(centre, spacing, noise, distances, radiance, false)
}

/// A pilot at `centre` and four neighbours: as [`four_around`], or, `one_sided`, at the corner
/// of a grid: (1, 0), (0, 1), (1, 1) and (2, 0) spacings away, as at the edge of an object
/// (four symmetric neighbours' direction-only lookups cancel the parallax to first order;
/// one-sided ones do not).
fn grid(
    centre: Vec3,
    spacing: f32,
    noise: f32,
    distances: bool,
    radiance: impl Fn(Option<Vec3>) -> f32 + Copy,
    one_sided: bool,
) -> Vec<Pilot> {
    let mut pilots = vec![pilot(centre, noise, distances, radiance)];
    let offsets = if one_sided {
        [(1.0, 0.0), (0.0, 1.0), (1.0, 1.0), (2.0, 0.0)]
    } else {
        [(1.0, 0.0), (-1.0, 0.0), (0.0, 1.0), (0.0, -1.0)]
    };
    for (dx, dy) in offsets {
        let p = centre + Vec3::new(dx, dy, 0.0) * spacing;
        pilots.push(pilot(p, noise, distances, radiance));
    }
    pilots
}

#[test]
fn equal_views_predict_each_other_exactly() {
    let pilots = four_around(Vec3::ZERO, 0.1, 0.0, true, |_| SKY);
    for e in prediction_errors(&pilots) {
        assert!(e.abs() < 1e-5, "{e}");
    }
}

#[test]
fn a_view_twice_as_bright_as_its_neighbours_errs_by_half_less_its_noise() {
    // The centre sees 1 everywhere, its neighbours 0.5: RMS difference 0.5 of its RMS 1.
    let mut pilots = four_around(Vec3::ZERO, 0.1, 0.0, true, |_| 0.5);
    pilots[0] = pilot(Vec3::ZERO, 0.0, true, |_| 1.0);
    let e = prediction_errors(&pilots)[0];
    assert!((e - 0.5).abs() < 1e-4, "{e}");
    // Noise explains part of it: 0.25 − 0.3² − 4 · (0.1 / 4)² of the squared error is left.
    for p in pilots.iter_mut() {
        p.noise = if p.position == Vec3::ZERO { 0.3 } else { 0.1 };
    }
    let e = prediction_errors(&pilots)[0];
    let expected = (0.25f32 - 0.09 - 4.0 * 0.025 * 0.025).sqrt();
    assert!((e - expected).abs() < 1e-4, "{e} against {expected}");
    // Noise that explains it all leaves a tenth of the error, never less.
    pilots[0].noise = 1.0;
    let e = prediction_errors(&pilots)[0];
    assert!((e - 0.05).abs() < 1e-4, "{e}");
}

#[test]
fn a_pilot_nothing_predicts_errs_by_one() {
    let mut pilots = four_around(Vec3::ZERO, 0.1, 0.0, true, |_| 1.0);
    // Another object's and a pilot facing away: neither predicts the centre.
    for p in &mut pilots[1..3] {
        p.object = 1;
    }
    for p in &mut pilots[3..] {
        p.normal = -Vec3::Z;
    }
    assert_eq!(prediction_errors(&pilots)[0], 1.0);
}

#[test]
fn distances_reproject_a_near_ceiling_that_directions_alone_do_not() {
    // A ceiling 0.2 above the points, its radiance varying across it near them and levelling
    // off far away (where an 8² cube's texels, point-sampled here unlike a capture's, would
    // alias a pattern that went on varying).
    let ceiling = |hit: Option<Vec3>| {
        hit.map_or(SKY, |h| {
            1.5 + (3.0 * h.x.tanh()).sin() + 0.5 * (2.0 * h.y.tanh()).cos()
        })
    };
    let centre = Vec3::new(0.0, 0.0, 0.8);
    let with = prediction_errors(&grid(centre, 0.05, 0.0, true, ceiling, true))[0];
    let without = prediction_errors(&grid(centre, 0.05, 0.0, false, ceiling, true))[0];
    assert!(
        with < 0.5 * without,
        "reprojected {with} against directions alone {without}"
    );
    // A far ceiling changes little between points: the error is lower than a near one's.
    let far = |hit: Option<Vec3>| ceiling(hit.map(|h| h * 0.01));
    let far_error = prediction_errors(&grid(centre, 0.05, 0.0, false, far, true))[0];
    assert!(far_error < 0.5 * without, "far {far_error}, near {without}");
}
