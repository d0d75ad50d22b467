//! CPU and GPU captures of the same cubes compute the same thing.
//!
//! Each case is a small scene exercising one part of the estimator (light kinds, environment
//! kinds, textures, metallic-roughness materials, emitters, bounces 0–2, the distance channel,
//! the environment-map baseline's view without the objects). Two checks per case:
//! - **paired, same seed**: the GPU draws the CPU's random numbers, so texel by texel the two
//!   agree except where rounding flipped a decision of a path; at most 3 % of the texels may
//!   differ by more than 10⁻³ (relative), the rays traced agree within 1 %, and per face and
//!   per 4 × 4 block the mean of the texel differences is within 4 standard errors of 0
//!   (estimated from those differences; at least 2 × 10⁻⁴ of the block's mean, the rounding
//!   of WGSL's transcendental functions);
//! - **independent seeds**: 8 seeds on each device; per face and block, the difference of
//!   the two devices' mean luminance is within 6 standard errors (estimated from the seeds'
//!   spread) — the Monte Carlo agreement of two estimators of the same expectation.

mod common;

use common::sphere_on_ground;
use glam::Vec3;
use oslf_bake::device::CubeJob;
use oslf_bake_gpu::scene::GpuScene;
use oslf_bake_gpu::GpuCapture;
use oslf_format::CubeImage;
use oslf_scene::environment::{Environment, LatLongMap, Sky};
use oslf_scene::light::Light;
use oslf_scene::material::{Material, Model};
use oslf_scene::shapes;
use oslf_scene::texture::{ImageTexture, Texture};
use oslf_shading::random::Rng;
use oslf_trace::bvh::{Instance, TriangleScene};
use oslf_trace::capture::{capture_cube_with_noise, CaptureSettings};
use oslf_trace::integrator::Integrator;
use oslf_trace::ray::ENVIRONMENT_OBJECT;

/// A case: geometry, materials, lights, environment.
struct Case {
    name: &'static str,
    instances: Vec<Instance>,
    materials: Vec<Material>,
    lights: Vec<Light>,
    environment: Environment,
}

fn image(w: u32, h: u32, seed: u64, scale: f32) -> ImageTexture {
    let mut rng = Rng::new(seed, 1);
    let pixels = (0..w * h)
        .map(|_| Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * scale)
        .collect();
    ImageTexture::from_pixels(w, h, pixels).unwrap()
}

fn metallic_roughness(base: Vec3, metallic: f32, roughness: f32) -> Material {
    Material {
        model: Model::MetallicRoughness {
            metallic,
            roughness,
        },
        ..Material::lambertian(base)
    }
}

fn cases() -> Vec<Case> {
    let sun = Light::Sun {
        direction: Vec3::new(0.3, -0.4, 0.8).normalize(),
        irradiance: Vec3::splat(3.0),
        angular_radius: 0.05,
    };
    let mut ceiling = shapes::cuboid(Vec3::new(2.0, 2.0, 0.1)).unwrap();
    ceiling.positions.iter_mut().for_each(|p| p.z += 2.5);
    let mut checker = Material::lambertian(Vec3::ZERO);
    checker.albedo = Texture::Checker {
        a: Vec3::new(0.9, 0.2, 0.1),
        b: Vec3::new(0.1, 0.3, 0.8),
        scale: 4.0,
    };
    let mut textured = Material::lambertian(Vec3::ZERO);
    textured.albedo = Texture::Image(image(7, 5, 3, 1.0).into());
    let mut mr_textured = metallic_roughness(Vec3::new(0.8, 0.7, 0.5), 1.0, 1.0);
    mr_textured.metallic_roughness_texture = Some(Texture::Image(image(6, 6, 4, 1.0).into()));
    let mut emitter = Material::lambertian(Vec3::splat(0.3));
    emitter.emission = Vec3::new(4.0, 3.0, 2.0);
    let map = LatLongMap::from_pixels(16, 8, image(16, 8, 5, 2.0).pixels, 1.5, 30.0).unwrap();
    let sky = Sky::new(Vec3::new(0.4, 0.3, 0.6), 3.0, 1.0).unwrap();
    vec![
        Case {
            // Constant and checker textures without an image: the shader compiles without
            // the image lookup (capture.wgsl's TEXTURE_KINDS).
            name: "sun and constant sky, Lambertian, a checker ground",
            instances: sphere_on_ground(24, vec![]),
            materials: vec![
                Material::lambertian(Vec3::new(0.2, 0.6, 0.3)),
                checker.clone(),
            ],
            lights: vec![sun.clone()],
            environment: Environment::Constant(Vec3::new(0.3, 0.4, 0.6)),
        },
        Case {
            name: "point and spot lights, checker and image textures",
            instances: sphere_on_ground(24, vec![]),
            materials: vec![checker, textured],
            lights: vec![
                Light::Point {
                    position: Vec3::new(1.5, 1.0, 2.0),
                    intensity: Vec3::new(6.0, 5.0, 4.0),
                },
                Light::Spot {
                    position: Vec3::new(-1.0, -1.5, 2.5),
                    direction: Vec3::new(0.3, 0.5, -1.0).normalize(),
                    intensity: Vec3::new(9.0, 9.0, 12.0),
                    inner_angle: 0.3,
                    outer_angle: 0.6,
                },
            ],
            environment: Environment::Constant(Vec3::ZERO),
        },
        Case {
            name: "lat-long map, metallic-roughness with a texture",
            instances: sphere_on_ground(24, vec![]),
            materials: vec![
                metallic_roughness(Vec3::new(0.9, 0.6, 0.3), 1.0, 0.3),
                mr_textured,
            ],
            lights: vec![],
            environment: Environment::LatLong(map.into()),
        },
        Case {
            name: "Preetham sky and its sun, dielectric",
            instances: sphere_on_ground(24, vec![]),
            materials: vec![
                metallic_roughness(Vec3::new(0.2, 0.5, 0.8), 0.0, 0.5),
                Material::lambertian(Vec3::splat(0.4)),
            ],
            lights: vec![sky.sun_light(Vec3::splat(2.0), 0.01)],
            environment: Environment::Sky(sky.into()),
        },
        Case {
            name: "an emitting ceiling in the dark",
            instances: sphere_on_ground(
                24,
                vec![Instance {
                    name: "ceiling".into(),
                    mesh: ceiling,
                    material: 2,
                    object: ENVIRONMENT_OBJECT,
                }],
            ),
            materials: vec![
                Material::lambertian(Vec3::splat(0.7)),
                Material::lambertian(Vec3::splat(0.5)),
                emitter,
            ],
            lights: vec![],
            environment: Environment::Constant(Vec3::ZERO),
        },
    ]
}

/// Where cubes are captured: just above the sphere (a sample point), and away from it.
const ORIGINS: [Vec3; 2] = [Vec3::new(0.3, 0.2, 0.97), Vec3::new(2.0, -2.5, 1.5)];

fn luminance(c: [f32; 3]) -> f32 {
    0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2]
}

/// The mean luminance of each face's 4 × 4 blocks (faces of side `res`, a multiple of 4).
fn block_means(cube: &CubeImage) -> Vec<f64> {
    let res = cube.resolution as usize;
    let mut out = Vec::new();
    for face in &cube.faces {
        for by in 0..res / 4 {
            for bx in 0..res / 4 {
                let mut s = 0.0;
                for y in 0..4 {
                    for x in 0..4 {
                        s += f64::from(luminance(face[(by * 4 + y) * res + bx * 4 + x]));
                    }
                }
                out.push(s / 16.0);
            }
        }
    }
    out
}

struct Devices {
    cpu_full: TriangleScene,
    cpu_without_objects: TriangleScene,
    gpu: GpuCapture,
}

fn devices(case: &Case, bounces: u32) -> Devices {
    let cpu_full = TriangleScene::build(case.instances.clone()).unwrap();
    let cpu_without_objects = TriangleScene::build(
        case.instances
            .iter()
            .filter(|i| i.object == ENVIRONMENT_OBJECT)
            .cloned()
            .collect(),
    )
    .unwrap();
    let packed = GpuScene::new(
        &cpu_full.triangles(),
        &case.materials,
        &case.lights,
        &case.environment,
    )
    .unwrap();
    let gpu = oslf_gpu::Gpu::headless().expect("a wgpu adapter (lavapipe in CI)");
    Devices {
        cpu_full,
        cpu_without_objects,
        gpu: GpuCapture::new(gpu, &packed, bounces).unwrap(),
    }
}

/// The CPU's and the GPU's capture of cube `index` at `origin`.
fn both(
    case: &Case,
    d: &Devices,
    bounces: u32,
    job: CubeJob,
    settings: &CaptureSettings,
) -> ((CubeImage, u64), (CubeImage, u64)) {
    let geometry = if job.sees_objects {
        &d.cpu_full
    } else {
        &d.cpu_without_objects
    };
    let integrator = Integrator::new(
        geometry,
        &case.materials,
        &case.lights,
        &case.environment,
        bounces,
    );
    let (cpu, cpu_rays, _) = capture_cube_with_noise(&integrator, job.origin, job.index, settings);
    let mut gpu = d.gpu.capture_cubes(&[job], settings).unwrap();
    let (g, g_rays, _) = gpu.remove(0);
    ((cpu, cpu_rays.total()), (g, g_rays.total()))
}

fn paired(case: &Case, bounces: u32, job: CubeJob, cpu: &CubeImage, gpu: &CubeImage) {
    let what = format!("{}, bounces {bounces}, {job:?}", case.name);
    let texels: Vec<([f32; 3], [f32; 3])> = cpu
        .faces
        .iter()
        .flatten()
        .zip(gpu.faces.iter().flatten())
        .map(|(a, b)| (*a, *b))
        .collect();
    assert!(
        texels
            .iter()
            .flat_map(|(_, g)| g)
            .all(|c| c.is_finite() && *c >= 0.0),
        "{what}: a GPU texel is negative or not finite"
    );
    let differing = texels
        .iter()
        .filter(|(a, b)| (0..3).any(|c| (a[c] - b[c]).abs() > 1e-3 * a[c].abs().max(1e-2)))
        .count();
    assert!(
        differing * 100 <= 3 * texels.len(),
        "{what}: {differing} of {} texels differ",
        texels.len()
    );
    // Per face and 4 × 4 block: the mean difference within 4 standard errors.
    let res = cpu.resolution as usize;
    for (face, (a, b)) in cpu.faces.iter().zip(&gpu.faces).enumerate() {
        for by in 0..res / 4 {
            for bx in 0..res / 4 {
                let d: Vec<f64> = (0..16)
                    .map(|i| (by * 4 + i / 4) * res + bx * 4 + i % 4)
                    .map(|t| f64::from(luminance(a[t])) - f64::from(luminance(b[t])))
                    .collect();
                let mean = d.iter().sum::<f64>() / 16.0;
                let var = d.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / 15.0;
                let scale = (0..16)
                    .map(|i| f64::from(luminance(a[(by * 4 + i / 4) * res + bx * 4 + i % 4])))
                    .sum::<f64>()
                    / 16.0;
                // WGSL specifies acos and exp only to about 10⁻⁴ (the sky's model uses both):
                // rounding of that size is no estimator difference.
                let se = (var / 16.0).sqrt().max(2e-4 * scale.max(1e-3));
                assert!(
                    mean.abs() <= 4.0 * se,
                    "{what}: face {face} block ({bx}, {by}): mean difference {mean} vs standard error {se}"
                );
            }
        }
    }
    if let (Some(dc), Some(dg)) = (&cpu.distance, &gpu.distance) {
        for (face, (a, b)) in dc.iter().zip(dg).enumerate() {
            for (t, (x, y)) in a.iter().zip(b).enumerate() {
                assert!(
                    (x - y).abs() <= 1e-5 * x.abs().max(1.0) || (*x == f32::MAX && *y == f32::MAX),
                    "{what}: distance of face {face} texel {t}: CPU {x}, GPU {y}"
                );
            }
        }
    }
}

#[test]
fn gpu_capture_is_the_cpu_capture_texel_by_texel() {
    for case in cases() {
        for bounces in [0, 1, 2] {
            let d = devices(&case, bounces);
            for (i, origin) in ORIGINS.into_iter().enumerate() {
                for sees_objects in [true, false] {
                    let settings = CaptureSettings {
                        resolution: 8,
                        samples_per_texel: 9,
                        target_noise: 0.0,
                        denoise: false,
                        distance_channel: i == 0,
                        seed: 11 + bounces as u64,
                    };
                    let job = CubeJob {
                        origin,
                        index: i as u32 * 7 + 3,
                        sees_objects,
                    };
                    let ((cpu, cpu_rays), (gpu, gpu_rays)) =
                        both(&case, &d, bounces, job, &settings);
                    assert!(
                        cpu_rays.abs_diff(gpu_rays) * 100 <= cpu_rays,
                        "{}: {cpu_rays} CPU rays, {gpu_rays} GPU rays",
                        case.name
                    );
                    paired(&case, bounces, job, &cpu, &gpu);
                }
            }
        }
    }
}

/// Cube `index` at the first origin, which sees the objects.
fn first_origin_job(index: u32) -> CubeJob {
    CubeJob {
        origin: ORIGINS[0],
        index,
        sees_objects: true,
    }
}

/// The GPU's cubes are denoised as the CPU's are (the same `oslf_trace::denoise`, run on the
/// read-back texels, with variances from the GPU's f32 luminance sums): the denoised captures
/// agree texel by texel as the raw ones do, and the filter changed the GPU's cube. (Before the
/// filter's noise floor, rounding in those sums made the two filter differently: one texel in
/// 14 of the lat-long case differed by more than 10⁻³, up to 10 %.)
#[test]
fn gpu_capture_is_denoised_as_the_cpu_capture_is() {
    let mut changed = 0;
    for case in cases() {
        let bounces = 1;
        let d = devices(&case, bounces);
        let job = first_origin_job(5);
        let settings = |denoise| CaptureSettings {
            resolution: 16,
            samples_per_texel: 4,
            target_noise: 0.0,
            denoise,
            distance_channel: true,
            seed: 21,
        };
        let ((cpu, _), (gpu, _)) = both(&case, &d, bounces, job, &settings(true));
        paired(&case, bounces, job, &cpu, &gpu);
        let ((_, _), (raw, _)) = both(&case, &d, bounces, job, &settings(false));
        let texels = raw.faces.iter().flatten().zip(gpu.faces.iter().flatten());
        changed += texels.filter(|(a, b)| a != b).count();
    }
    assert!(changed > 100, "the filter changed {changed} GPU texels");
}

/// Fixed samples per texel, and adaptive sampling to a target (the same stopping rule on
/// both devices, `oslf_trace::noise::converged`): the cubes agree within their noise, and an
/// adaptive capture spends the same rays on both within 5 %.
#[test]
fn gpu_and_cpu_captures_agree_within_their_noise_on_independent_seeds() {
    const SEEDS: u64 = 8;
    for (case, (samples_per_texel, target_noise)) in cases().into_iter().flat_map(|c| {
        let c = std::rc::Rc::new(c);
        [(16, 0.0), (64, 0.15)].map(|s| (c.clone(), s))
    }) {
        let bounces = 1;
        let d = devices(&case, bounces);
        let job = first_origin_job(4);
        // Per device, per block: the block means of each seed.
        let mut runs: [Vec<Vec<f64>>; 2] = Default::default();
        let mut rays = [0u64; 2];
        for s in 0..SEEDS {
            let settings = |seed| CaptureSettings {
                resolution: 8,
                samples_per_texel,
                target_noise,
                denoise: false,
                distance_channel: false,
                seed,
            };
            // Different seeds on the two devices: independent estimates.
            let ((cpu, cpu_rays), _) = both(&case, &d, bounces, job, &settings(100 + s));
            let ((_, _), (gpu, gpu_rays)) = both(&case, &d, bounces, job, &settings(200 + s));
            runs[0].push(block_means(&cpu));
            runs[1].push(block_means(&gpu));
            rays[0] += cpu_rays;
            rays[1] += gpu_rays;
        }
        assert!(
            rays[0].abs_diff(rays[1]) * 20 <= rays[0],
            "{} at {samples_per_texel} samples, target {target_noise}: {} CPU rays, {} GPU rays",
            case.name,
            rays[0],
            rays[1]
        );
        let blocks = runs[0][0].len();
        let stats = |r: &Vec<Vec<f64>>, b: usize| {
            let n = r.len() as f64;
            let mean = r.iter().map(|v| v[b]).sum::<f64>() / n;
            let var = r.iter().map(|v| (v[b] - mean).powi(2)).sum::<f64>() / (n - 1.0);
            (mean, var / n)
        };
        for b in 0..blocks {
            let (mc, vc) = stats(&runs[0], b);
            let (mg, vg) = stats(&runs[1], b);
            let se = (vc + vg).sqrt().max(1e-6 * mc.abs().max(1e-3));
            assert!(
                (mc - mg).abs() <= 6.0 * se,
                "{}: block {b}: CPU {mc}, GPU {mg}, standard error {se}",
                case.name
            );
        }
    }
}

#[test]
fn gpu_preview_is_the_cpu_preview_pixel_by_pixel() {
    let camera = oslf_geometry::camera::Camera {
        position: Vec3::new(3.5, -2.5, 1.8),
        target: Vec3::new(0.0, 0.0, 0.0),
        up: Vec3::Z,
        vfov_deg: 40.0,
    };
    let (w, h) = (24, 16);
    for case in cases() {
        let d = devices(&case, 1);
        let integrator = Integrator::new(
            &d.cpu_full,
            &case.materials,
            &case.lights,
            &case.environment,
            1,
        );
        // 5 samples per pixel: strata of a 3 × 2 grid, one left out.
        let (cpu, _) = oslf_trace::preview::render(&integrator, &camera, w, h, 5, 9);
        let gpu = d.gpu.preview(&camera, w, h, 5, 9).unwrap();
        assert_eq!(gpu.len(), cpu.len());
        let differ = cpu
            .iter()
            .zip(&gpu)
            .filter(|(a, b)| (**a - **b).abs().max_element() > 1e-3 * a.max_element().max(1e-2))
            .count();
        assert!(
            differ * 100 <= 3 * cpu.len(),
            "{}: {differ} of {} pixels differ",
            case.name,
            cpu.len()
        );
        assert!(
            gpu.iter().any(|p| p.max_element() > 0.01),
            "{}: black",
            case.name
        );
    }
}
