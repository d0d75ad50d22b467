//! CPU and GPU captures of the same cubes agree (the same estimator, the same random
//! numbers): probe of what differs.

use glam::Vec3;
use oslf_bake::bvh::{Instance, TriangleScene};
use oslf_bake::capture::{capture_cube_with_noise, CaptureSettings};
use oslf_bake::device::CubeJob;
use oslf_bake::environment::Environment;
use oslf_bake::integrator::Integrator;
use oslf_bake::light::Light;
use oslf_bake::material::Material;
use oslf_bake::ray::ENVIRONMENT_OBJECT;
use oslf_bake::shapes;
use oslf_bake_gpu::scene::GpuScene;
use oslf_bake_gpu::GpuCapture;

#[test]
fn probe() {
    let mut instances = vec![Instance {
        name: "sphere".into(),
        mesh: shapes::sphere(1.0, 32).unwrap(),
        material: 0,
        object: 0,
    }];
    let mut ground = shapes::cuboid(Vec3::new(8.0, 8.0, 0.2)).unwrap();
    ground.positions.iter_mut().for_each(|p| p.z -= 1.1);
    instances.push(Instance {
        name: "ground".into(),
        mesh: ground,
        material: 1,
        object: ENVIRONMENT_OBJECT,
    });
    let scene = TriangleScene::build(instances).unwrap();
    let materials = vec![
        Material::lambertian(Vec3::new(0.2, 0.6, 0.3)),
        Material::lambertian(Vec3::splat(0.5)),
    ];
    let lights = [Light::Sun {
        direction: Vec3::new(0.3, -0.4, 0.8).normalize(),
        irradiance: Vec3::splat(3.0),
        angular_radius: 0.01,
    }];
    let env = Environment::Constant(Vec3::new(0.3, 0.4, 0.6));
    let settings = CaptureSettings {
        resolution: 8,
        samples_per_texel: 16,
        distance_channel: true,
        seed: 17,
    };
    let integrator = Integrator::new(&scene, &materials, &lights, &env, 2);
    let origin = Vec3::new(0.3, 0.2, 0.96);
    let (cpu, cpu_stats, _) = capture_cube_with_noise(&integrator, origin, 5, &settings);
    let packed = GpuScene::new(&scene.triangles(), &materials, &lights, &env).unwrap();
    let gpu = GpuCapture::new(oslf_runtime::Gpu::headless().unwrap(), &packed, 2).unwrap();
    let out = gpu
        .capture_cubes(
            &[CubeJob {
                origin,
                index: 5,
                sees_objects: true,
            }],
            &settings,
        )
        .unwrap();
    let (g, g_stats, _) = &out[0];
    println!("stats cpu {cpu_stats:?} gpu {g_stats:?}");
    let mut worst = 0f32;
    let mut differ = 0;
    for f in 0..6 {
        for (a, b) in cpu.faces[f].iter().zip(&g.faces[f]) {
            let d = (0..3)
                .map(|c| (a[c] - b[c]).abs() / a[c].abs().max(1e-3))
                .fold(0.0, f32::max);
            worst = worst.max(d);
            if d > 1e-3 {
                differ += 1;
            }
        }
    }
    println!("worst {worst} differ {differ} of {}", 6 * 64);
    println!("cpu {:?}\ngpu {:?}", &cpu.faces[4][..4], &g.faces[4][..4]);
    println!(
        "dist cpu {:?}\ngpu {:?}",
        &cpu.distance.as_ref().unwrap()[4][..4],
        &g.distance.as_ref().unwrap()[4][..4]
    );
}
