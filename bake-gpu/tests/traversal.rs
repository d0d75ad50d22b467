//! The GPU traversal finds the CPU BVH's closest hits: the same triangle, at the same
//! distance up to rounding, on random rays through a scene with small and large, near and
//! far triangles, on rays aimed at its triangles' shared edges and corners, and on rays
//! leaving its surfaces; its any-hit queries agree with the closest hits on occlusion.

mod common;

use glam::Vec3;
use oslf_bake_gpu::capture::{QueryHit, QueryRay};
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
            any_hit: false,
        });
    }
    // Rays aimed exactly at shared edges' midpoints and at corners (watertightness).
    let records = scene.triangles();
    for i in 0..1500 {
        let t = &records[(rng.next_f32() * records.len() as f32) as usize % records.len()];
        let [a, b, c] = t.corners;
        let target = match i % 3 {
            0 => (a + b) * 0.5,
            1 => (b + c) * 0.5,
            _ => c,
        };
        let o = (rng.next_vec3() - Vec3::splat(0.5)) * Vec3::new(8.0, 8.0, 6.0);
        rays.push(QueryRay {
            origin: o,
            dir: (target - o).normalize(),
            t_max: f32::MAX,
            objects: true,
            any_hit: false,
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
                any_hit: false,
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
    let corners: std::collections::HashMap<u32, [Vec3; 3]> =
        records.iter().map(|t| (t.global, t.corners)).collect();
    let mut hits = 0;
    let mut shared = 0;
    for (i, (r, g)) in rays.iter().zip(&gpu_hits).enumerate() {
        let cpu_scene = if r.objects { &scene } else { &without_objects };
        let cpu = cpu_scene.intersect(&Ray::new(r.origin, r.dir), r.t_max);
        let cpu_global = cpu.map(|h| (h.t, h.triangle));
        // The scene without objects numbers its triangles from 0: map back by position.
        let cpu_global = match (cpu_global, r.objects) {
            (Some((t, tri)), false) => Some((t, tri + sphere_triangles())),
            (c, _) => c,
        };
        match (cpu_global, g.hit) {
            (None, None) => {}
            (Some((tc, ic)), Some((tg, ig))) => {
                hits += 1;
                // Through a shared edge or corner both triangles are hit, at distances that
                // may round apart by an ulp: either is the closest hit there.
                assert!(
                    ic == ig || shares_corner(&corners, ic, ig),
                    "ray {i} {r:?}: CPU triangle {ic} at {tc}, GPU {ig} at {tg}"
                );
                shared += usize::from(ic != ig);
                assert!(
                    (tc - tg).abs() <= 1e-5 * tc.max(1.0),
                    "ray {i}: t {tc} vs {tg}"
                );
            }
            (c, g) => panic!("ray {i} {r:?}: CPU {c:?}, GPU {g:?}"),
        }
        assert!(
            g.nodes >= 1 || !r.dir.is_finite(),
            "ray {i}: no node tested"
        );
    }
    assert!(hits > 2500, "only {hits} rays hit something");
    assert!(
        shared * 100 < hits,
        "{shared} of {hits} hits on another triangle of an edge"
    );
    // Any-hit queries: occluded exactly where a closest hit exists, and never more work.
    let shadow: Vec<QueryRay> = rays
        .iter()
        .map(|r| QueryRay {
            any_hit: true,
            ..*r
        })
        .collect();
    let any = capture.trace(&shadow).unwrap();
    for (i, ((r, a), c)) in shadow.iter().zip(&any).zip(&gpu_hits).enumerate() {
        assert_eq!(
            a.hit.is_some(),
            c.hit.is_some(),
            "ray {i} {r:?}: any-hit {a:?}, closest {c:?}"
        );
        let cpu_scene = if r.objects { &scene } else { &without_objects };
        assert_eq!(
            a.hit.is_some(),
            cpu_scene.occluded(&Ray::new(r.origin, r.dir), r.t_max),
            "ray {i}: GPU any-hit against the CPU's"
        );
        assert!(
            a.nodes <= c.nodes && a.triangles <= c.triangles,
            "ray {i}: {a:?} vs {c:?}"
        );
    }
    let per_ray = |h: &[QueryHit], f: fn(&QueryHit) -> u32| {
        h.iter().map(|q| f64::from(f(q))).sum::<f64>() / h.len() as f64
    };
    println!(
        "{} rays: closest {:.2} nodes and {:.2} triangles per ray, any-hit {:.2} and {:.2}",
        rays.len(),
        per_ray(&gpu_hits, |q| q.nodes),
        per_ray(&gpu_hits, |q| q.triangles),
        per_ray(&any, |q| q.nodes),
        per_ray(&any, |q| q.triangles),
    );
}

fn shares_corner(corners: &std::collections::HashMap<u32, [Vec3; 3]>, a: u32, b: u32) -> bool {
    let (Some(a), Some(b)) = (corners.get(&a), corners.get(&b)) else {
        return false;
    };
    a.iter().any(|p| b.contains(p))
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
