//! What the GPU bake's tests share: a small scene's geometry.

#![allow(dead_code)]

use glam::Vec3;
use oslf_scene::shapes;
use oslf_trace::bvh::Instance;
use oslf_trace::ray::ENVIRONMENT_OBJECT;

/// A unit sphere of `segments` (OSLF object 0, material 0) resting above an 8 × 8 ground slab
/// (environment, material 1), then `extra`.
pub fn sphere_on_ground(segments: u32, extra: Vec<Instance>) -> Vec<Instance> {
    let mut v = vec![Instance {
        name: "sphere".into(),
        mesh: shapes::sphere(1.0, segments).unwrap(),
        material: 0,
        object: 0,
    }];
    let mut ground = shapes::cuboid(Vec3::new(8.0, 8.0, 0.2)).unwrap();
    ground.positions.iter_mut().for_each(|p| p.z -= 1.1);
    v.push(Instance {
        name: "ground".into(),
        mesh: ground,
        material: 1,
        object: ENVIRONMENT_OBJECT,
    });
    v.extend(extra);
    v
}
