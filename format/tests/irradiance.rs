//! The irradiance section of format 1.1 against the cubes it came from, and format 1.0 stores,
//! which have none, read as before.

use crate::common::*;
use glam::Vec3;
use oslf_format::irradiance::{irradiance, project};
use oslf_format::*;
use std::path::Path;

/// Each cube's record is the projection of its faces as the store decodes them, bit for bit,
/// and the section is the same whatever the encoding.
#[test]
fn each_record_is_the_projection_of_its_stored_cube() {
    for encoding in [Encoding::Rgb9e5, Encoding::Rgba16f, Encoding::Bc6h] {
        let f = fixture(Spec {
            encoding,
            cube_res: 8,
            env: true,
            ..Spec::default()
        });
        let (_dir, path) = temp_store("irr.oslf");
        write(&path, &f);
        let store = Store::open(&path).unwrap();
        let sh = store
            .irradiance()
            .expect("a format 1.1 store has irradiance");
        assert_eq!(sh.len(), store.cube_count() as usize);
        for cube in 0..store.cube_count() {
            let c = store.read_cube(cube).unwrap();
            assert_eq!(
                project(c.resolution, &c.faces, cube).unwrap(),
                sh[cube as usize],
                "{encoding} cube {cube}"
            );
            // The irradiance ÷ π facing +z within the cube's own range of radiance.
            let e = irradiance(&sh[cube as usize], Vec3::Z);
            let most = c
                .faces
                .iter()
                .flatten()
                .map(|t| t[0].max(t[1]).max(t[2]))
                .fold(0.0, f32::max);
            assert!(
                e.is_finite() && e.min_element() >= 0.0 && e.max_element() <= most * 1.01,
                "{e} {most}"
            );
        }
        store.verify().unwrap();
    }
}

/// The analytic environments through the whole writer and reader: a furnace (uniform
/// radiance) gives its radiance facing any way; L = 1 + z gives 5/3 facing up and 1 sideways,
/// within what the RGBA16F encoding and 16² faces allow.
#[test]
fn analytic_environments_give_their_irradiance() {
    let mut f = fixture(Spec {
        encoding: Encoding::Rgba16f,
        cube_res: 16,
        distance: false,
        env: false,
        ..Spec::default()
    });
    let n = 16;
    for (k, cube) in f.cubes.iter_mut().enumerate() {
        for (face, texels) in cube.faces.iter_mut().enumerate() {
            for (i, t) in texels.iter_mut().enumerate() {
                let d =
                    Vec3::from_array(cube::texel_direction(face, i as u32 % n, i as u32 / n, n));
                *t = if k == 0 { [0.75; 3] } else { [1.0 + d.z; 3] };
            }
        }
    }
    let (_dir, path) = temp_store("analytic.oslf");
    write(&path, &f);
    let store = Store::open(&path).unwrap();
    let sh = store.irradiance().unwrap();
    for d in [Vec3::Z, Vec3::X, Vec3::new(0.0, -0.6, -0.8)] {
        assert!(
            (irradiance(&sh[0], d) - Vec3::splat(0.75))
                .abs()
                .max_element()
                < 1e-3
        );
    }
    let up = irradiance(&sh[1], Vec3::Z).x;
    let side = irradiance(&sh[1], Vec3::NEG_X).x;
    assert!((up - 5.0 / 3.0).abs() < 3e-3, "{up}");
    assert!((side - 1.0).abs() < 3e-3, "{side}");
}

/// A store of the format 1.0 writer (`tests/data/v1.0-rgb9e5.oslf`, commit a467aaf) opens,
/// verifies and reads as before, with no irradiance.
#[test]
fn a_format_1_0_store_reads_without_irradiance() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/v1.0-rgb9e5.oslf");
    let bytes = std::fs::read(&path).unwrap();
    assert_eq!(bytes[8..12], VERSION_1_0.to_le_bytes());
    for store in each_reader(&path) {
        assert_eq!(store.header().version, VERSION_1_0);
        assert!(store.irradiance().is_none());
        assert_eq!(store.cube_count(), 25);
        assert_eq!(store.env_cube_index(), Some(24));
        store.verify().unwrap();
        let c = store.read_cube(24).unwrap();
        assert!(c.faces.iter().flatten().any(|t| t[0] > 0.0));
    }
}
