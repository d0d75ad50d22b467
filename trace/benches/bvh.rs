//! BVH throughput: closest-hit rays from points just above the teapot in a gazebo of columns,
//! boxes and balls (~100 k triangles), each hit followed by a shadow ray, on two threads.
//!
//! `cargo bench -p oslf-trace --bench bvh` prints the scene's size, the build time and, per
//! round, rays per second.

use std::f32::consts::TAU;
use std::time::Instant;

use glam::{Affine3A, Vec2, Vec3};
use oslf_geometry::bezier::newell_teapot;
use oslf_geometry::mesh::Mesh;
use oslf_scene::shapes;
use oslf_shading::random::Rng;
use oslf_shading::warp::sample_uniform_sphere;
use oslf_trace::bvh::{Instance, TriangleScene};
use oslf_trace::ray::{Intersector, Ray, ENVIRONMENT_OBJECT};
use rayon::prelude::*;

/// Sample points per round and rays from each.
const POINTS: usize = 1156;
const RAYS_PER_POINT: usize = 2000;

fn environment(mesh: Mesh, material: u32) -> Instance {
    Instance {
        name: String::new(),
        mesh,
        material,
        object: ENVIRONMENT_OBJECT,
    }
}

fn placed(mut mesh: Mesh, at: Vec3) -> Mesh {
    mesh.transform(&Affine3A::from_translation(at));
    mesh
}

/// The teapot at the thesis's tessellation for ε = 0.1, and the gazebo around it.
fn gazebo() -> (Mesh, Vec<Instance>) {
    let mut teapot = Mesh::new();
    for p in newell_teapot() {
        teapot.append(&p.tessellate(p.tessellation_level(0.1 / 50.0)));
    }
    let mut instances = vec![
        Instance {
            name: String::new(),
            mesh: teapot.clone(),
            material: 0,
            object: 0,
        },
        environment(shapes::plane(Vec2::new(40.0, 40.0)).unwrap(), 1),
    ];
    for k in 0..8 {
        let a = k as f32 * TAU / 8.0;
        let column = shapes::cylinder(0.3, 8.0, 96, true).unwrap();
        let block = shapes::cuboid(Vec3::new(1.0, 2.0, 1.5)).unwrap();
        let ball = shapes::sphere(0.6, 96).unwrap();
        instances.push(environment(
            placed(column, 8.0 * Vec3::new(a.cos(), a.sin(), 0.0)),
            2,
        ));
        instances.push(environment(
            placed(block, Vec3::new(5.0 * a.sin(), 5.0 * a.cos(), 0.75)),
            2,
        ));
        let b = a + 0.4;
        instances.push(environment(
            placed(ball, Vec3::new(4.0 * b.cos(), 4.0 * b.sin(), 0.6)),
            2,
        ));
    }
    let roof = shapes::cuboid(Vec3::new(18.0, 18.0, 0.3)).unwrap();
    instances.push(environment(placed(roof, Vec3::new(0.0, 0.0, 8.2)), 3));
    (teapot, instances)
}

/// `n` points `eps` above uniformly chosen triangles of `mesh`.
fn points_above(mesh: &Mesh, eps: f32, n: usize) -> Vec<Vec3> {
    let mut rng = Rng::new(99, 0);
    (0..n)
        .filter_map(|_| {
            let i = rng.next_u32() as usize % mesh.triangles.len();
            let [a, b, c] = mesh.corners(&mesh.triangles[i])?;
            let normal = (b - a).cross(c - a).try_normalize()?;
            let (mut s, mut t) = (rng.next_f32(), rng.next_f32());
            if s + t > 1.0 {
                (s, t) = (1.0 - s, 1.0 - t);
            }
            Some(a + (b - a) * s + (c - a) * t + normal * eps)
        })
        .collect()
}

fn main() {
    let (teapot, instances) = gazebo();
    let scene = TriangleScene::build(instances).unwrap();
    println!(
        "triangles {} (teapot {}), build {:.1} ms",
        scene.triangle_count(),
        teapot.triangles.len(),
        scene.build_time().as_secs_f64() * 1e3
    );
    let points = points_above(&teapot, 0.1, POINTS);
    let light = Vec3::new(3.0, -2.0, 7.0);
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(2)
        .build()
        .unwrap();
    for round in 0..3 {
        let start = Instant::now();
        let rays: u64 = pool.install(|| {
            points
                .par_iter()
                .enumerate()
                .map(|(i, &o)| {
                    let mut rng = Rng::new(round, i as u64);
                    let mut rays = 0u64;
                    for _ in 0..RAYS_PER_POINT {
                        let d = sample_uniform_sphere(rng.next_vec2());
                        rays += 1;
                        if let Some(h) = scene.intersect(&Ray::new(o, d), f32::INFINITY) {
                            let to_light = light - h.position;
                            let dist = to_light.length();
                            rays += 1;
                            scene.occluded(&Ray::new(h.position, to_light / dist), dist);
                        }
                    }
                    rays
                })
                .sum()
        });
        let s = start.elapsed().as_secs_f64();
        println!(
            "round {round}: {rays} rays in {s:.2} s: {:.2} Mrays/s on 2 threads",
            rays as f64 / s / 1e6
        );
    }
}
