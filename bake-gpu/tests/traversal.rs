//! The GPU traversal finds the CPU BVH's closest hits: the same triangle, at the same
//! distance up to rounding, on random rays through a scene with small and large, near and
//! far triangles, and on rays leaving its surfaces.

mod common;

use glam::Vec3;
use oslf_bake_gpu::capture::QueryRay;
use oslf_bake_gpu::scene::GpuScene;
use oslf_bake_gpu::GpuCapture;
use oslf_scene::material::Material;
use oslf_scene::shapes;
use oslf_shading::random::Rng;
use oslf_shading::warp::sample_uniform_sphere;
use oslf_trace::bvh::{Instance, TriangleScene};
use oslf_trace::ray::{Intersector, Ray, ENVIRONMENT_OBJECT};

fn instances() -> Vec<Instance> {
    let mut post = shapes::cylinder(0.1, 3.0, 24, true).unwrap();
    post.positions
        .iter_mut()
        .for_each(|p| *p += Vec3::new(1.6, 0.4, -1.0));
    common::sphere_on_ground(
        48,
        vec![Instance {
            name: "post".into(),
            mesh: post,
            material: 1,
            object: ENVIRONMENT_OBJECT,
        }],
    )
}

#[test]
fn gpu_closest_hits_are_the_cpu_bvhs() {
    let scene = TriangleScene::build(instances()).unwrap();
    let materials = vec![Material::lambertian(Vec3::splat(0.5)); 2];
    let env = oslf_scene::environment::Environment::Constant(Vec3::ONE);
    let packed = GpuScene::new(&scene.triangles(), &materials, &[], &env).unwrap();
    let gpu = oslf_gpu::Gpu::headless().expect("a wgpu adapter (lavapipe in CI)");
    let capture = GpuCapture::new(gpu, &packed, 0).unwrap();
    let mut rng = Rng::new(3, 9);
    let mut rays = Vec::new();
    // Rays from points around the scene in random directions, some of them short.
    for i in 0..4000 {
        let o = (rng.next_vec3() - Vec3::splat(0.5)) * Vec3::new(6.0, 6.0, 4.0);
        let d = sample_uniform_sphere(rng.next_vec2());
        let t_max = if i % 5 == 0 { 1.5 } else { f32::MAX };
        rays.push(QueryRay {
            origin: o,
            dir: d,
            t_max,
            objects: i % 7 != 0,
        });
    }
    // Rays leaving the surfaces they start on (the path tracer's secondary rays).
    let starts: Vec<QueryRay> = rays.clone();
    for r in starts.iter().take(2000) {
        if let Some(h) = scene.intersect(&Ray::new(r.origin, r.dir), f32::MAX) {
            let d = sample_uniform_sphere(rng.next_vec2());
            rays.push(QueryRay {
                origin: h.position,
                dir: d,
                t_max: f32::MAX,
                objects: true,
            });
        }
    }
    let without_objects = TriangleScene::build(
        instances()
            .into_iter()
            .filter(|i| i.object == ENVIRONMENT_OBJECT)
            .collect(),
    )
    .unwrap();
    let gpu_hits = capture.trace(&rays).unwrap();
    let mut hits = 0;
    for (i, (r, g)) in rays.iter().zip(&gpu_hits).enumerate() {
        let cpu_scene = if r.objects { &scene } else { &without_objects };
        let cpu = cpu_scene.intersect(&Ray::new(r.origin, r.dir), r.t_max);
        let cpu_global = cpu.map(|h| (h.t, h.triangle));
        // The scene without objects numbers its triangles from 0: map back by position.
        let cpu_global = match (cpu_global, r.objects) {
            (Some((t, tri)), false) => Some((t, tri + sphere_triangles())),
            (c, _) => c,
        };
        match (cpu_global, g) {
            (None, None) => {}
            (Some((tc, ic)), Some((tg, ig))) => {
                hits += 1;
                assert_eq!(
                    ic, *ig,
                    "ray {i} {r:?}: CPU triangle {ic} at {tc}, GPU {ig} at {tg}"
                );
                assert!(
                    (tc - tg).abs() <= 1e-5 * tc.max(1.0),
                    "ray {i}: t {tc} vs {tg}"
                );
            }
            (c, g) => panic!("ray {i} {r:?}: CPU {c:?}, GPU {g:?}"),
        }
    }
    assert!(hits > 1500, "only {hits} rays hit something");
}

fn sphere_triangles() -> u32 {
    shapes::sphere(1.0, 48).unwrap().triangles.len() as u32
}

trait NextVec3 {
    fn next_vec3(&mut self) -> Vec3;
}

impl NextVec3 for Rng {
    fn next_vec3(&mut self) -> Vec3 {
        Vec3::new(self.next_f32(), self.next_f32(), self.next_f32())
    }
}
