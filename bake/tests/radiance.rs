//! Light transport tests: sampling triplets, image loading, closed-form radiance (point light,
//! sun, furnaces, a multi-bounce sphere), robustness far from the origin, and determinism.
//!
//! The intersectors are analytic (infinite planes, spheres) and defined here.

use std::f32::consts::{FRAC_1_PI, PI};
use std::sync::Arc;

use glam::{Vec2, Vec3};
use oslf_geometry::camera::Camera;
use oslf_scene::environment::{Environment, LatLongMap, Sky, SUN_ANGULAR_RADIUS};
use oslf_scene::light::Light;
use oslf_scene::material::{Material, Model};
use oslf_scene::sampling::*;
use oslf_scene::texture::{load_linear_rgb, ImageTexture, Texture};
use oslf_scene::BakeError;
use oslf_shading::color::{linear_to_srgb, luminance, srgb_to_linear};
use oslf_shading::random::*;
use oslf_shading::warp::*;
use oslf_trace::integrator::{Integrator, RayStats};
use oslf_trace::preview::render;
use oslf_trace::ray::{Intersector, Ray, SurfaceHit};

// ---------------------------------------------------------------------------------------------
// Analytic geometry

/// An infinite plane through `point` with normal `normal`.
#[derive(Clone, Copy)]
struct Plane {
    point: Vec3,
    normal: Vec3,
    material: u32,
}

/// A sphere; the normal points outwards (the integrator flips it for hits from inside).
#[derive(Clone, Copy)]
struct Sphere {
    center: Vec3,
    radius: f32,
    material: u32,
}

enum Shape {
    Plane(Plane),
    Sphere(Sphere),
}

impl Shape {
    fn hit(&self, ray: &Ray, t_max: f32) -> Option<SurfaceHit> {
        let (t, n, material) = match self {
            Shape::Plane(p) => {
                let denom = p.normal.dot(ray.dir);
                if denom == 0.0 {
                    return None;
                }
                let t = p.normal.dot(p.point - ray.origin) / denom;
                (t, p.normal, p.material)
            }
            Shape::Sphere(s) => {
                // Relative to the centre for accuracy far from the origin.
                let oc = ray.origin - s.center;
                let b = oc.dot(ray.dir);
                let c = oc.length_squared() - s.radius * s.radius;
                let disc = b * b - c;
                if disc < 0.0 {
                    return None;
                }
                let sq = disc.sqrt();
                let t0 = -b - sq;
                let t1 = -b + sq;
                let t = if t0 > 0.0 { t0 } else { t1 };
                let p = oc + ray.dir * t;
                (t, p / s.radius, s.material)
            }
        };
        if !(t > 0.0 && t < t_max) {
            return None;
        }
        let n = n.normalize();
        Some(SurfaceHit {
            t,
            position: ray.at(t),
            geometric_normal: n,
            shading_normal: n,
            uv: Vec2::ZERO,
            material,
            object: 0,
            triangle: 0,
            extent: ray.at(t).abs().max_element(),
        })
    }
}

struct Scene(Vec<Shape>);

impl Intersector for Scene {
    fn intersect(&self, ray: &Ray, t_max: f32) -> Option<SurfaceHit> {
        let mut best: Option<SurfaceHit> = None;
        for s in &self.0 {
            let limit = best.map_or(t_max, |b| b.t);
            if let Some(h) = s.hit(ray, limit) {
                best = Some(h);
            }
        }
        best
    }
    fn occluded(&self, ray: &Ray, t_max: f32) -> bool {
        self.0.iter().any(|s| s.hit(ray, t_max).is_some())
    }
}

fn ground(z: f32) -> Scene {
    Scene(vec![Shape::Plane(Plane {
        point: Vec3::new(0.0, 0.0, z),
        normal: Vec3::Z,
        material: 0,
    })])
}

fn lambert(a: f32) -> Vec<Material> {
    vec![Material::lambertian(Vec3::splat(a))]
}

/// Mean radiance of `n` paths along `ray`.
fn mean_radiance<I: Intersector>(
    integ: &Integrator<I>,
    ray: &Ray,
    n: u32,
    seed: u64,
) -> (Vec3, RayStats) {
    let mut stats = RayStats::default();
    // f64 accumulation: 40 000 f32 additions would bias the mean by ~10⁻⁴.
    let mut sum = glam::DVec3::ZERO;
    for i in 0..n {
        let mut rng = Rng::new(seed, i as u64);
        let s = integ.radiance(ray, &mut rng, &mut stats);
        assert!(s.radiance.is_finite(), "non-finite radiance");
        sum += s.radiance.as_dvec3();
    }
    ((sum / n as f64).as_vec3(), stats)
}

fn rel_err(a: f32, b: f32) -> f32 {
    (a - b).abs() / b.abs().max(1e-12)
}

/// Midpoint-rule integral of a function over the sphere (θ, φ grid).
fn integrate_sphere(n_theta: usize, f: impl Fn(Vec3) -> f64) -> f64 {
    let n_phi = 2 * n_theta;
    let dt = std::f64::consts::PI / n_theta as f64;
    let dp = 2.0 * std::f64::consts::PI / n_phi as f64;
    let mut sum = 0.0;
    for i in 0..n_theta {
        let theta = (i as f64 + 0.5) * dt;
        for j in 0..n_phi {
            let phi = (j as f64 + 0.5) * dp;
            let d = Vec3::new(
                (theta.sin() * phi.cos()) as f32,
                (theta.sin() * phi.sin()) as f32,
                theta.cos() as f32,
            );
            sum += f(d) * theta.sin() * dt * dp;
        }
    }
    sum
}

/// A 16 × 8 lat-long map with random texels, zero below the horizon if `upper_only`.
fn random_latlong(upper_only: bool, rotation: f32) -> LatLongMap {
    let (w, h) = (16u32, 8u32);
    let mut rng = Rng::new(77, 1);
    let pixels: Vec<Vec3> = (0..w * h)
        .map(|i| {
            let row = i / w;
            if upper_only && row >= h / 2 {
                Vec3::ZERO
            } else {
                Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 4.0
            }
        })
        .collect();
    LatLongMap::from_pixels(w, h, pixels, 1.5, rotation).unwrap()
}

// ---------------------------------------------------------------------------------------------
// Sampling triplets

#[test]
fn cosine_hemisphere_triplet() {
    let integral = integrate_sphere(400, |d| cosine_hemisphere_pdf(d.z) as f64);
    assert!((integral - 1.0).abs() < 1e-3, "{integral}");
    let mut rng = Rng::new(1, 1);
    for _ in 0..10_000 {
        let u = rng.next_vec2();
        let w = sample_cosine_hemisphere(u);
        assert!((w.length() - 1.0).abs() < 1e-5 && w.z >= 0.0);
        let back = invert_cosine_hemisphere(w);
        assert!(
            (back - u).abs().max_element() < 2e-4,
            "{u} -> {w} -> {back}"
        );
    }
    // Mean of cos θ under cos/π is 2/3.
    let mean: f32 = (0..100_000)
        .map(|_| sample_cosine_hemisphere(rng.next_vec2()).z)
        .sum::<f32>()
        / 1e5;
    assert!((mean - 2.0 / 3.0).abs() < 3e-3, "{mean}");
    assert_eq!(cosine_hemisphere_pdf(-0.5), 0.0);
}

#[test]
fn uniform_sphere_triplet() {
    let integral = integrate_sphere(200, |_| uniform_sphere_pdf() as f64);
    assert!((integral - 1.0).abs() < 1e-4, "{integral}");
    let mut rng = Rng::new(2, 2);
    for _ in 0..10_000 {
        let u = rng.next_vec2();
        let w = sample_uniform_sphere(u);
        assert!((w.length() - 1.0).abs() < 1e-5);
        let back = invert_uniform_sphere(w);
        let du = (back - u).abs();
        // u.y wraps at 1.
        assert!(
            du.x < 1e-4 && (du.y < 1e-4 || du.y > 1.0 - 1e-4),
            "{u} {back}"
        );
    }
}

#[test]
fn distribution2d_matches_histogram() {
    let (w, h) = (4usize, 3usize);
    let func = [
        1.0, 2.0, 0.0, 4.0, //
        0.0, 0.0, 0.0, 0.0, //
        3.0, 1.0, 5.0, 0.5,
    ];
    let d = Distribution2D::new(&func, w, h).unwrap();
    let total: f32 = func.iter().sum();
    let n = 400_000;
    let mut counts = vec![0u32; w * h];
    let mut rng = Rng::new(3, 3);
    for _ in 0..n {
        let u = rng.next_vec2();
        let (p, pdf) = d.sample_continuous(u);
        let (ix, iy) = ((p.x * w as f32) as usize, (p.y * h as f32) as usize);
        counts[iy * w + ix] += 1;
        assert!(pdf > 0.0 && (pdf - d.pdf(p)).abs() < 1e-4 * pdf);
        let back = d.invert(p);
        assert!((back - u).abs().max_element() < 1e-4, "{u} {back}");
    }
    for i in 0..w * h {
        let expected = func[i] / total;
        let got = counts[i] as f32 / n as f32;
        // 5 sigma of a binomial proportion.
        let sigma = (expected * (1.0 - expected) / n as f32).sqrt();
        assert!(
            (got - expected).abs() <= 5.0 * sigma + 1e-6,
            "cell {i}: {got} vs {expected}"
        );
        // The density of a cell is func / mean(func).
        let centre = Vec2::new(
            ((i % w) as f32 + 0.5) / w as f32,
            ((i / w) as f32 + 0.5) / h as f32,
        );
        let mean = total / (w * h) as f32;
        assert!((d.pdf(centre) - func[i] / mean).abs() < 1e-4);
    }
    // pdf integrates to 1.
    let mut integral = 0.0f64;
    for iy in 0..300 {
        for ix in 0..400 {
            integral += d.pdf(Vec2::new(
                (ix as f32 + 0.5) / 400.0,
                (iy as f32 + 0.5) / 300.0,
            )) as f64;
        }
    }
    integral /= 120_000.0;
    assert!((integral - 1.0).abs() < 1e-4, "{integral}");
}

fn check_environment_triplet(env: &Environment, tolerance: f64) {
    let integral = integrate_sphere(320, |d| env.environment_pdf(d) as f64);
    assert!(
        (integral - 1.0).abs() < tolerance,
        "pdf integrates to {integral}"
    );
    let mut rng = Rng::new(4, 4);
    let mut max_err = 0.0f32;
    for _ in 0..20_000 {
        let u = rng.next_vec2();
        let (dir, pdf) = env.sample_environment(u);
        assert!(dir.is_finite() && pdf.is_finite() && pdf >= 0.0);
        if pdf == 0.0 {
            continue;
        }
        assert!((dir.length() - 1.0).abs() < 1e-4);
        let pdf2 = env.environment_pdf(dir);
        assert!(rel_err(pdf2, pdf) < 1e-2, "pdf {pdf} vs {pdf2} at {dir}");
        let back = env.invert_environment(dir);
        let mut du = (back - u).abs();
        if du.x > 0.5 {
            du.x = 1.0 - du.x; // uniform sphere wraps in u.y, lat-long in u.x
        }
        if du.y > 0.5 {
            du.y = 1.0 - du.y;
        }
        max_err = max_err.max(du.max_element());
    }
    assert!(max_err < 1e-3, "invert(sample(u)) off by {max_err}");
    // Poles and degenerate directions give finite values.
    for d in [Vec3::Z, -Vec3::Z, Vec3::ZERO, Vec3::NAN] {
        assert!(env.environment_pdf(d).is_finite());
        assert!(env.eval(d).is_finite());
        assert!(env.invert_environment(d).is_finite());
    }
}

#[test]
fn environment_triplets() {
    check_environment_triplet(&Environment::Constant(Vec3::ONE), 1e-4);
    check_environment_triplet(
        &Environment::LatLong(Arc::new(random_latlong(false, 0.0))),
        1e-3,
    );
    check_environment_triplet(
        &Environment::LatLong(Arc::new(random_latlong(true, 33.0))),
        1e-3,
    );
    let sky = Sky::new(Vec3::new(1.0, 0.5, 0.6), 3.0, 2.0).unwrap();
    check_environment_triplet(&Environment::Sky(Arc::new(sky)), 2e-3);
}

#[test]
fn latlong_convention_and_importance() {
    // One bright texel: samples land in it and eval there is the texel value times scale.
    let (w, h) = (8u32, 4u32);
    let mut pixels = vec![Vec3::ZERO; 32];
    pixels[w as usize + 6] = Vec3::new(1.0, 2.0, 3.0); // row 1, column 6
    let map = LatLongMap::from_pixels(w, h, pixels, 2.0, 0.0).unwrap();
    // Column 6 centre: u = 6.5/8 -> φ = 2π(u - ½) = 0.625π; row 1 centre: θ = 1.5/4 π.
    let (theta, phi) = (1.5 / 4.0 * PI, 0.625 * PI);
    let d = Vec3::new(
        theta.sin() * phi.cos(),
        theta.sin() * phi.sin(),
        theta.cos(),
    );
    assert_eq!(map.eval(d), Vec3::new(2.0, 4.0, 6.0));
    assert!((map.direction_to_uv(d) - Vec2::new(6.5 / 8.0, 1.5 / 4.0)).length() < 1e-5);
    assert!((map.uv_to_direction(Vec2::new(6.5 / 8.0, 1.5 / 4.0)) - d).length() < 1e-5);
    // Zenith is row 0; +x is the centre column.
    assert!((map.direction_to_uv(Vec3::X) - Vec2::new(0.5, 0.5)).length() < 1e-6);
    assert!(map.direction_to_uv(Vec3::Z).y < 1e-6);
    let env = Environment::LatLong(Arc::new(map));
    let mut rng = Rng::new(5, 5);
    for _ in 0..1000 {
        let (dir, pdf) = env.sample_environment(rng.next_vec2());
        assert!(pdf > 0.0);
        assert_eq!(env.eval(dir), Vec3::new(2.0, 4.0, 6.0));
    }
    // Rotation by 90° turns the map counter-clockwise: the texel now appears at φ + 90°.
    let mut pixels = vec![Vec3::ZERO; 32];
    pixels[w as usize + 6] = Vec3::ONE;
    let rotated = LatLongMap::from_pixels(w, h, pixels, 1.0, 90.0).unwrap();
    let phi2 = phi + 0.5 * PI;
    let d2 = Vec3::new(
        theta.sin() * phi2.cos(),
        theta.sin() * phi2.sin(),
        theta.cos(),
    );
    assert_eq!(rotated.eval(d2), Vec3::ONE);
    assert_eq!(rotated.eval(d), Vec3::ZERO);
    // Bad inputs.
    assert!(LatLongMap::from_pixels(2, 2, vec![Vec3::ONE; 3], 1.0, 0.0).is_err());
    assert!(LatLongMap::from_pixels(1, 1, vec![Vec3::NAN], 1.0, 0.0).is_err());
    assert!(LatLongMap::from_pixels(1, 1, vec![Vec3::ONE], -1.0, 0.0).is_err());
}

#[test]
fn sky_is_plausible() {
    let sun = Vec3::new(0.0, 1.0, 0.5).normalize();
    let sky = Sky::new(sun, 3.0, 1.5).unwrap();
    let zenith = sky.eval(Vec3::Z);
    assert!((luminance(zenith) - 1.5).abs() < 0.02, "{zenith}");
    assert!(zenith.z > zenith.x, "zenith should be blue: {zenith}");
    // Brighter towards the sun than away from it at the same elevation.
    let towards = sky.eval(Vec3::new(0.0, 1.0, 0.6).normalize());
    let away = sky.eval(Vec3::new(0.0, -1.0, 0.6).normalize());
    assert!(
        luminance(towards) > 2.0 * luminance(away),
        "{towards} {away}"
    );
    // Horizon (away from the sun) brighter than zenith.
    let horizon = sky.eval(Vec3::new(-1.0, 0.0, 0.02).normalize());
    assert!(luminance(horizon) > luminance(zenith), "{horizon} {zenith}");
    // Ground: constant, dim, finite.
    let g = sky.eval(Vec3::new(0.3, 0.2, -0.9).normalize());
    assert_eq!(g, sky.ground_radiance());
    assert!(g.min_element() > 0.0 && luminance(g) < luminance(zenith));
    for i in 0..1000 {
        let d = sample_uniform_sphere(Rng::new(i, 0).next_vec2());
        let l = sky.eval(d);
        assert!(l.is_finite() && l.min_element() >= 0.0);
    }
    // Sun below the horizon and extreme turbidities stay finite; bad values are errors.
    for t in [1.7, 10.0] {
        let s = Sky::new(Vec3::new(1.0, 0.0, -0.3), t, 1.0).unwrap();
        assert!(s.eval(Vec3::new(1.0, 0.0, 0.01)).is_finite());
    }
    assert!(Sky::new(Vec3::ZERO, 3.0, 1.0).is_err());
    assert!(Sky::new(Vec3::Z, 0.5, 1.0).is_err());
    assert!(Sky::new(Vec3::Z, 3.0, f32::NAN).is_err());
    let light = sky.sun_light(Vec3::splat(3.0), SUN_ANGULAR_RADIUS);
    assert!(light.validate().is_ok());
}

// ---------------------------------------------------------------------------------------------
// Images

#[test]
fn image_loading() {
    let dir = tempfile::tempdir().unwrap();
    let temp_path = |name: &str| dir.path().join(name);
    // 8-bit PNG, sRGB-encoded.
    let png = temp_path("t.png");
    let mut img = image::RgbImage::new(3, 2);
    img.put_pixel(0, 0, image::Rgb([128, 0, 255]));
    img.put_pixel(2, 1, image::Rgb([255, 64, 10]));
    img.save(&png).unwrap();
    let (w, h, px) = load_linear_rgb(&png).unwrap();
    assert_eq!((w, h), (3, 2));
    let expect = Vec3::new(srgb_to_linear(128.0 / 255.0), 0.0, 1.0);
    assert!((px[0] - expect).length() < 1e-6, "{}", px[0]);
    assert!((px[5].y - srgb_to_linear(64.0 / 255.0)).abs() < 1e-6);
    assert!((linear_to_srgb(px[0].x) - 128.0 / 255.0).abs() < 1e-5);

    // EXR, linear, values above 1 kept.
    let exr_path = temp_path("t.exr");
    exr::prelude::write_rgb_file(&exr_path, 4, 3, |x, y| (x as f32 * 2.5, y as f32, 0.25f32))
        .unwrap();
    let tex = ImageTexture::load(&exr_path).unwrap();
    assert_eq!((tex.width, tex.height), (4, 3));
    assert_eq!(tex.pixels[2 * 4 + 3], Vec3::new(7.5, 2.0, 0.25));
    // Texture lookup at a texel centre: texel (3, 2) is the bottom row, v = 1 - 2.5/3.
    let t = Texture::Image(Arc::new(tex));
    let c = t.eval(Vec2::new(3.5 / 4.0, 1.0 - 2.5 / 3.0));
    assert!((c - Vec3::new(7.5, 2.0, 0.25)).length() < 1e-5, "{c}");

    // Radiance HDR, linear.
    let hdr = temp_path("t.hdr");
    let buf = image::Rgb32FImage::from_fn(2, 2, |x, y| image::Rgb([x as f32 * 3.0, 0.5, y as f32]));
    image::DynamicImage::ImageRgb32F(buf).save(&hdr).unwrap();
    let (_, _, px) = load_linear_rgb(&hdr).unwrap();
    assert!(
        (px[1] - Vec3::new(3.0, 0.5, 0.0)).length() < 0.05,
        "{}",
        px[1]
    );

    // NaN and negative pixels are rejected, naming the pixel.
    let bad = temp_path("bad.exr");
    exr::prelude::write_rgb_file(&bad, 3, 3, |x, y| {
        if (x, y) == (2, 1) {
            (0.0f32, f32::NAN, 0.0f32)
        } else {
            (1.0, 1.0, 1.0)
        }
    })
    .unwrap();
    match load_linear_rgb(&bad) {
        Err(BakeError::BadPixel {
            x: 2, y: 1, path, ..
        }) => assert_eq!(path, bad),
        other => panic!("expected BadPixel, got {other:?}"),
    }
    let neg = temp_path("neg.exr");
    exr::prelude::write_rgb_file(&neg, 2, 1, |x, _| (0.0f32, -(x as f32), 0.0f32)).unwrap();
    assert!(matches!(
        load_linear_rgb(&neg),
        Err(BakeError::BadPixel { x: 1, y: 0, .. })
    ));
    // A latlong map from a bad file reports the file.
    assert!(LatLongMap::load(&bad, 1.0, 0.0).is_err());

    // Missing and garbage files.
    let missing = temp_path("missing.png");
    assert!(matches!(
        load_linear_rgb(&missing),
        Err(BakeError::Input(oslf_util::UtilError::Input { .. }))
    ));
    let garbage = temp_path("garbage.png");
    std::fs::write(&garbage, b"this is not an image at all").unwrap();
    let err = load_linear_rgb(&garbage).unwrap_err();
    assert!(matches!(err, BakeError::Image { .. }), "{err:?}");
    assert!(err.to_string().contains("garbage.png"));
    let tiny = temp_path("tiny.exr");
    std::fs::write(&tiny, [0x76u8, 0x2f]).unwrap();
    assert!(matches!(
        load_linear_rgb(&tiny),
        Err(BakeError::Image { .. })
    ));
}

// ---------------------------------------------------------------------------------------------
// Closed forms

/// A ray that hits the plane z = `z0` at `q` from direction `omega` (unit, pointing up).
fn ray_to(q: Vec3, omega: Vec3, eps: f32) -> Ray {
    Ray::new(q + omega * eps, -omega)
}

#[test]
fn point_light_over_lambertian_plane() {
    // L_o = (a/π) I cos θ / r², exact (no Monte Carlo: direct only, no environment).
    let a = 0.6;
    let intensity = Vec3::new(10.0, 5.0, 2.0);
    let light_pos = Vec3::new(0.3, -0.2, 2.0);
    let scene = ground(0.0);
    let materials = lambert(a);
    let lights = [Light::Point {
        position: light_pos,
        intensity,
    }];
    let env = Environment::Constant(Vec3::ZERO);
    let integ = Integrator::new(&scene, &materials, &lights, &env, 0);
    let mut rng = Rng::new(0, 0);
    for (q, omega) in [
        (Vec3::new(0.0, 0.0, 0.0), Vec3::Z),
        (
            Vec3::new(1.0, 2.0, 0.0),
            Vec3::new(0.3, 0.1, 1.0).normalize(),
        ),
        (
            Vec3::new(-3.0, 0.5, 0.0),
            Vec3::new(-0.8, 0.0, 0.2).normalize(),
        ),
        (Vec3::new(0.3, -0.2, 0.0), Vec3::new(0.0, 0.6, 0.8)),
    ] {
        let mut stats = RayStats::default();
        let s = integ.radiance(&ray_to(q, omega, 0.1), &mut rng, &mut stats);
        let d = light_pos - q;
        let expected = a * FRAC_1_PI * intensity * (d.normalize().z / d.length_squared());
        assert!(
            (s.radiance - expected).abs().max_element() < 1e-3 * expected.max_element(),
            "{q}: {} vs {expected}",
            s.radiance
        );
        assert!((s.distance - 0.1).abs() < 1e-5);
        assert_eq!(
            stats,
            RayStats {
                closest: 1,
                shadow: 1,
                ..Default::default()
            }
        );
    }
    // Seen from below, the plane (two-sided) is unlit by a light above it.
    let mut stats = RayStats::default();
    let s = integ.radiance(&ray_to(Vec3::ZERO, -Vec3::Z, 0.1), &mut rng, &mut stats);
    assert_eq!(s.radiance, Vec3::ZERO);
    // An escaping ray sees the (black) environment and counts one ray.
    let mut stats = RayStats::default();
    let s = integ.radiance(&Ray::new(Vec3::Z, Vec3::Z), &mut rng, &mut stats);
    assert_eq!((s.radiance, s.distance), (Vec3::ZERO, f32::MAX));
    assert_eq!(
        stats,
        RayStats {
            closest: 1,
            shadow: 0,
            ..Default::default()
        }
    );
}

#[test]
fn point_light_shadowed_by_sphere() {
    let mut scene = ground(0.0);
    scene.0.push(Shape::Sphere(Sphere {
        center: Vec3::new(0.0, 0.0, 1.0),
        radius: 0.5,
        material: 0,
    }));
    let materials = lambert(0.5);
    let lights = [Light::Point {
        position: Vec3::new(0.0, 0.0, 3.0),
        intensity: Vec3::ONE,
    }];
    let env = Environment::Constant(Vec3::ZERO);
    let integ = Integrator::new(&scene, &materials, &lights, &env, 0);
    let mut stats = RayStats::default();
    let s = integ.radiance(
        &Ray::new(Vec3::new(0.1, 0.0, 0.1), -Vec3::Z),
        &mut Rng::new(0, 0),
        &mut stats,
    );
    assert_eq!(s.radiance, Vec3::ZERO);
}

#[test]
fn sun_over_lambertian_plane_and_visible_disc() {
    // L_o = (a/π) E cos θ, exact; the disc is seen only by primary rays.
    let a = 0.8;
    let e = Vec3::new(3.0, 2.5, 2.0);
    let sun_dir = Vec3::new(0.5, 0.2, 0.7).normalize();
    let alpha = 0.05;
    let scene = ground(0.0);
    let materials = lambert(a);
    let lights = [Light::Sun {
        direction: sun_dir,
        irradiance: e,
        angular_radius: alpha,
    }];
    let env = Environment::Constant(Vec3::ZERO);
    let integ = Integrator::new(&scene, &materials, &lights, &env, 3);
    let mut rng = Rng::new(0, 0);
    let expected = a * FRAC_1_PI * e * sun_dir.z;
    for (q, omega) in [
        (Vec3::ZERO, Vec3::Z),
        (Vec3::new(5.0, -7.0, 0.0), sun_dir), // looking straight back at the sun
        (
            Vec3::new(-1.0, 1.0, 0.0),
            Vec3::new(-0.5, 0.0, 0.3).normalize(),
        ),
    ] {
        let mut stats = RayStats::default();
        let s = integ.radiance(&ray_to(q, omega, 0.01), &mut rng, &mut stats);
        // Only the sun lights the plane; bounces from an infinite plane never return.
        assert!(
            (s.radiance - expected).abs().max_element() < 1e-4 * expected.max_element(),
            "{} vs {expected}",
            s.radiance
        );
    }
    // The disc: E / (π sin²α) inside, nothing outside; integrated over the disc = E.
    let mut stats = RayStats::default();
    let s = integ.radiance(&Ray::new(Vec3::Z, sun_dir), &mut rng, &mut stats);
    let disc = e / (PI * alpha.sin() * alpha.sin());
    assert!((s.radiance - disc).abs().max_element() < 1e-4 * disc.max_element());
    let off = Frame::from_normal(sun_dir).to_world(Vec3::new(
        (1.5 * alpha).sin(),
        0.0,
        (1.5 * alpha).cos(),
    ));
    let s = integ.radiance(&Ray::new(Vec3::Z, off), &mut rng, &mut stats);
    assert_eq!(s.radiance, Vec3::ZERO);
    // ∫_disc L cos dω (sun overhead) = E.
    let overhead = Light::Sun {
        direction: Vec3::Z,
        irradiance: e,
        angular_radius: alpha,
    };
    // Midpoint rule over the cap θ < 2α (the disc is symmetric in φ).
    let n = 20_000;
    let dt = 2.0 * alpha as f64 / n as f64;
    let integral: f64 = (0..n)
        .map(|i| {
            let t = (i as f64 + 0.5) * dt;
            let d = Vec3::new(t.sin() as f32, 0.0, t.cos() as f32);
            overhead.disc_radiance(d).x as f64 * t.cos() * t.sin() * dt * 2.0 * std::f64::consts::PI
        })
        .sum();
    assert!(rel_err(integral as f32, e.x) < 1e-3, "{integral}");
}

#[test]
fn convex_furnace_sphere_under_uniform_environment() {
    // A convex Lambertian object under a uniform environment L sees only the environment, so
    // every point reflects a·L whatever the bounce count.
    let (a, l) = (0.7, Vec3::new(1.0, 0.5, 2.0));
    let scene = Scene(vec![Shape::Sphere(Sphere {
        center: Vec3::new(0.0, 0.0, 0.0),
        radius: 1.0,
        material: 0,
    })]);
    let materials = lambert(a);
    let env = Environment::Constant(l);
    for max_bounces in [0, 1, 5] {
        let integ = Integrator::new(&scene, &materials, &[], &env, max_bounces);
        for dir in [Vec3::X, Vec3::new(0.3, -0.4, 0.5).normalize()] {
            let ray = Ray::new(dir * 3.0 + Vec3::new(0.0, 0.1, 0.0), -dir);
            let (mean, stats) = mean_radiance(&integ, &ray, 20_000, 11);
            let expected = a * l;
            assert!(
                (mean - expected).abs().max_element() < 0.01 * expected.max_element(),
                "bounces {max_bounces}: {mean} vs {expected}"
            );
            // Per path: primary + one BSDF ray; ≤ one environment shadow ray. With no bounce
            // the BSDF ray only has to tell whether it escapes: an any-hit query.
            if max_bounces == 0 {
                assert_eq!(stats.closest, 20_000);
                assert!(stats.shadow <= 40_000 && stats.shadow > 25_000);
            } else {
                assert_eq!(stats.closest, 40_000);
                assert!(stats.shadow <= 20_000 && stats.shadow > 5_000);
            }
        }
    }
}

#[test]
fn plane_under_latlong_sky() {
    // An infinite ground plane under a lat-long sky that is zero below the horizon: the
    // leaving radiance is (a/π) E with E = Σ_texels L_texel ∫_texel cos θ dω, where for a texel
    // spanning [θ0, θ1] × Δφ, ∫ cos θ sin θ dθ dφ = Δφ (sin²θ1 − sin²θ0) / 2. For a uniform
    // sky this is a·L. Importance sampling of the map and MIS must reproduce it.
    let a = 0.5;
    let map = random_latlong(true, 20.0);
    let (w, h) = (map.width, map.height);
    let mut e = Vec3::ZERO;
    for y in 0..h / 2 {
        let (t0, t1) = (y as f32 / h as f32 * PI, (y + 1) as f32 / h as f32 * PI);
        let solid = 2.0 * PI / w as f32 * 0.5 * (t1.sin().powi(2) - t0.sin().powi(2));
        for x in 0..w {
            e += map.pixels[(y * w + x) as usize] * solid;
        }
    }
    let expected = a * FRAC_1_PI * e;
    let env = Environment::LatLong(Arc::new(map));
    let scene = ground(0.0);
    let materials = lambert(a);
    let integ = Integrator::new(&scene, &materials, &[], &env, 2);
    let ray = ray_to(
        Vec3::new(0.2, 0.3, 0.0),
        Vec3::new(0.1, 0.2, 0.9).normalize(),
        0.1,
    );
    let (mean, _) = mean_radiance(&integ, &ray, 40_000, 12);
    println!("lat-long plane: mean/expected = {}", mean / expected);
    assert!(
        (mean - expected).abs().max_element() < 0.01 * expected.max_element(),
        "{mean} vs {expected}"
    );

    // Uniform upper hemisphere: exactly a·L.
    let l = Vec3::new(2.0, 1.0, 0.5);
    let pixels: Vec<Vec3> = (0..64 * 32)
        .map(|i| if i / 64 < 16 { l } else { Vec3::ZERO })
        .collect();
    let env = Environment::LatLong(Arc::new(
        LatLongMap::from_pixels(64, 32, pixels, 1.0, 0.0).unwrap(),
    ));
    let integ = Integrator::new(
        integ.geometry,
        integ.materials,
        integ.lights,
        &env,
        integ.max_bounces,
    );
    let (mean, _) = mean_radiance(&integ, &ray, 20_000, 13);
    assert!(
        (mean - a * l).abs().max_element() < 0.01 * (a * l).max_element(),
        "{mean} vs {}",
        a * l
    );
}

/// Inside a closed sphere of radius R and albedo a with a point light of intensity I at its
/// centre.
///
/// Derivation: the light gives every wall point the irradiance E₀ = I/R² at normal incidence,
/// so the once-reflected radiance is uniform, L₀ = (a/π) E₀. Between two points of a sphere,
/// cos θ₁ cos θ₂ / r² = 1/(4R²) (both angles equal the angle of the chord with the normals, and
/// r = 2R cos θ), so the form factor to a patch dA is dA / (4πR²), independent of where one
/// stands: a uniform radiance L leaving the wall gives every wall point irradiance πL. Hence
/// each further bounce multiplies the uniform radiance by a: with k gathered bounces the
/// leaving radiance is L₀ (1 + a + … + a^k) → L₀ / (1 − a).
#[test]
fn closed_sphere_bounce_series() {
    let (a, r, i) = (0.5f32, 2.0f32, Vec3::new(8.0, 4.0, 2.0));
    let scene = Scene(vec![Shape::Sphere(Sphere {
        center: Vec3::ZERO,
        radius: r,
        material: 0,
    })]);
    let materials = lambert(a);
    let lights = [Light::Point {
        position: Vec3::ZERO,
        intensity: i,
    }];
    let env = Environment::Constant(Vec3::ZERO);
    let l0 = a * FRAC_1_PI * i / (r * r);
    let ray = Ray::new(
        Vec3::new(0.5, -0.3, 0.2),
        Vec3::new(0.2, 0.9, -0.3).normalize(),
    );
    for k in [0u32, 1, 2, 3, 6, 60] {
        let integ = Integrator::new(&scene, &materials, &lights, &env, k);
        let series: f32 = (0..=k.min(200)).map(|j| a.powi(j as i32)).sum();
        let expected = l0 * series;
        let (mean, stats) = mean_radiance(&integ, &ray, 40_000, 20 + k as u64);
        println!(
            "closed sphere k = {k}: mean/expected = {:.5}, {:.2} closest + {:.2} shadow rays/path",
            mean.x / expected.x,
            stats.closest as f64 / 40_000.0,
            stats.shadow as f64 / 40_000.0
        );
        // Below the Russian-roulette depth the estimate is exact.
        let tol = if k < 3 { 1e-4 } else { 0.01 };
        assert!(
            (mean - expected).abs().max_element() < tol * expected.max_element(),
            "k = {k}: {mean} vs {expected}"
        );
        if k == 0 {
            assert_eq!(
                stats,
                RayStats {
                    closest: 40_000,
                    shadow: 40_000,
                    ..Default::default()
                }
            );
        }
    }
    let limit = l0 / (1.0 - a);
    println!("closed sphere: L0 = {l0}, limit = {limit}");
}

#[test]
fn robust_far_from_origin() {
    // The point-light plane test, 10⁵ units from the origin (one ulp ≈ 0.0078 there): any
    // self-intersection of a shadow ray would turn a pixel black.
    let base = Vec3::new(1.0e5, -1.0e5, 1.0e5);
    let a = 0.5;
    let scene = ground(base.z);
    let materials = lambert(a);
    let light_pos = base + Vec3::new(1.0, 2.0, 5.0);
    let lights = [Light::Point {
        position: light_pos,
        intensity: Vec3::splat(50.0),
    }];
    let env = Environment::Constant(Vec3::ZERO);
    let integ = Integrator::new(&scene, &materials, &lights, &env, 0);
    let mut rng = Rng::new(0, 0);
    for i in 0..200 {
        let mut r = Rng::new(99, i);
        let q = base + Vec3::new(r.next_f32() * 6.0 - 3.0, r.next_f32() * 6.0 - 3.0, 0.0);
        let omega = Frame::from_normal(Vec3::Z).to_world(sample_cosine_hemisphere(r.next_vec2()));
        let ray = ray_to(q, omega, 0.5);
        let mut stats = RayStats::default();
        let s = integ.radiance(&ray, &mut rng, &mut stats);
        // Coordinates are quantised to 1/128 here, so compare at the hit point actually found.
        assert!(s.distance < f32::MAX, "primary ray missed the plane");
        let p = ray.at(s.distance);
        let d = light_pos - p;
        let expected = a * FRAC_1_PI * 50.0 * d.normalize().z / d.length_squared();
        assert!(
            rel_err(s.radiance.x, expected) < 0.02,
            "{q}: {} vs {expected}",
            s.radiance.x
        );
    }
    // Convex furnace far away.
    let scene = Scene(vec![Shape::Sphere(Sphere {
        center: base,
        radius: 2.0,
        material: 0,
    })]);
    let env = Environment::Constant(Vec3::ONE);
    let integ = Integrator::new(&scene, &materials, &[], &env, 2);
    let ray = Ray::new(base + Vec3::new(2.05, 0.0, 0.0), -Vec3::X);
    let (mean, _) = mean_radiance(&integ, &ray, 20_000, 5);
    assert!(rel_err(mean.x, a) < 0.01, "{mean}");
}

#[test]
fn degenerate_hits_stay_finite() {
    /// Hits with zero normals and out-of-range materials.
    struct Broken;
    impl Intersector for Broken {
        fn intersect(&self, ray: &Ray, _t_max: f32) -> Option<SurfaceHit> {
            Some(SurfaceHit {
                t: 1.0,
                position: ray.at(1.0),
                geometric_normal: Vec3::ZERO,
                shading_normal: Vec3::NAN,
                uv: Vec2::NAN,
                material: if ray.dir.z > 0.0 { 0 } else { 7 },
                object: 0,
                triangle: 0,
                extent: 1.0,
            })
        }
        fn occluded(&self, _ray: &Ray, _t_max: f32) -> bool {
            false
        }
    }
    let materials = vec![Material {
        emission: Vec3::ZERO,
        metallic_roughness_texture: None,
        normal_texture: None,
        emissive_texture: None,
        occlusion_texture: None,
        model: Model::Lambertian,
        albedo: Texture::Checker {
            a: Vec3::splat(0.5),
            b: Vec3::ONE,
            scale: 2.0,
        },
    }];
    let lights = [
        Light::Point {
            position: Vec3::ZERO,
            intensity: Vec3::ONE,
        },
        Light::Sun {
            direction: Vec3::Z,
            irradiance: Vec3::ONE,
            angular_radius: 0.0,
        },
    ];
    let env = Environment::Sky(Arc::new(Sky::new(Vec3::Z, 2.5, 1.0).unwrap()));
    let integ = Integrator::new(&Broken, &materials, &lights, &env, 8);
    for dir in [Vec3::Z, -Vec3::Z, Vec3::X] {
        let (mean, _) = mean_radiance(&integ, &Ray::new(Vec3::ZERO, dir), 100, 1);
        assert!(mean.is_finite());
    }
}

// ---------------------------------------------------------------------------------------------
// Camera and determinism

#[test]
fn camera_rays() {
    let cam = Camera {
        position: Vec3::new(0.0, -5.0, 1.0),
        target: Vec3::new(0.0, 0.0, 1.0),
        up: Vec3::Z,
        vfov_deg: 90.0,
    };
    assert!(cam.validate().is_ok());
    let centre = oslf_trace::preview::primary_ray(&cam, 50.0, 25.0, 100, 50);
    assert!((centre.dir - Vec3::Y).length() < 1e-6);
    assert_eq!(centre.origin, cam.position);
    // Top edge centre: 45° up. Right edge centre: atan(2) to the right (aspect 2).
    let top = oslf_trace::preview::primary_ray(&cam, 50.0, 0.0, 100, 50);
    assert!((top.dir - Vec3::new(0.0, 1.0, 1.0).normalize()).length() < 1e-6);
    let right = oslf_trace::preview::primary_ray(&cam, 100.0, 25.0, 100, 50);
    assert!((right.dir - Vec3::new(2.0, 1.0, 0.0).normalize()).length() < 1e-6);
    // Degenerate cameras are reported but still produce unit rays.
    let bad = Camera {
        target: cam.position,
        vfov_deg: 200.0,
        ..cam
    };
    assert!(bad.validate().is_err());
    assert!(
        (oslf_trace::preview::primary_ray(&bad, 1.0, 1.0, 0, 0)
            .dir
            .length()
            - 1.0)
            .abs()
            < 1e-5
    );
}

fn test_scene() -> (Scene, Vec<Material>, Vec<Light>, Environment) {
    let scene = Scene(vec![
        Shape::Plane(Plane {
            point: Vec3::ZERO,
            normal: Vec3::Z,
            material: 0,
        }),
        Shape::Sphere(Sphere {
            center: Vec3::new(0.0, 0.0, 1.0),
            radius: 1.0,
            material: 1,
        }),
    ]);
    let materials = vec![
        Material {
            emission: Vec3::ZERO,
            metallic_roughness_texture: None,
            normal_texture: None,
            emissive_texture: None,
            occlusion_texture: None,
            model: Model::Lambertian,
            albedo: Texture::Checker {
                a: Vec3::splat(0.8),
                b: Vec3::splat(0.2),
                scale: 4.0,
            },
        },
        Material::lambertian(Vec3::new(0.7, 0.3, 0.2)),
    ];
    let sun = Vec3::new(1.0, -1.0, 1.5).normalize();
    let sky = Sky::new(sun, 3.0, 1.0).unwrap();
    let lights = vec![
        sky.sun_light(Vec3::splat(5.0), SUN_ANGULAR_RADIUS * 4.0),
        Light::Point {
            position: Vec3::new(-2.0, -1.0, 3.0),
            intensity: Vec3::splat(4.0),
        },
    ];
    (scene, materials, lights, Environment::Sky(Arc::new(sky)))
}

#[test]
fn render_is_deterministic_across_thread_counts() {
    let (scene, materials, lights, env) = test_scene();
    let integ = Integrator::new(&scene, &materials, &lights, &env, 3);
    let cam = Camera {
        position: Vec3::new(0.0, -6.0, 2.0),
        target: Vec3::new(0.0, 0.0, 0.8),
        up: Vec3::Z,
        vfov_deg: 50.0,
    };
    let run = |threads: usize, seed: u64| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| render(&integ, &cam, 40, 30, 4, seed))
    };
    let (img1, stats1) = run(1, 7);
    let (img2, stats2) = run(2, 7);
    let (img3, _) = run(2, 8);
    let bits = |img: &[Vec3]| -> Vec<[u32; 3]> {
        img.iter()
            .map(|c| [c.x.to_bits(), c.y.to_bits(), c.z.to_bits()])
            .collect()
    };
    assert_eq!(img1.len(), 1200);
    assert_eq!(bits(&img1), bits(&img2));
    assert_eq!(stats1, stats2);
    assert_ne!(bits(&img1), bits(&img3));
    assert!(img1.iter().all(|c| c.is_finite() && c.min_element() >= 0.0));
    assert!(stats1.closest >= 1200 * 4);
}

/// Renders the test scene, reports throughput and writes a PNG preview
/// (`$TMPDIR/oslf-radiance-<pid>/preview.png`). Run with `--nocapture` to see the figures.
#[test]
fn render_preview_and_throughput() {
    let (scene, materials, lights, env) = test_scene();
    let integ = Integrator::new(&scene, &materials, &lights, &env, 3);
    let cam = Camera {
        position: Vec3::new(0.0, -6.0, 2.0),
        target: Vec3::new(0.0, 0.0, 0.8),
        up: Vec3::Z,
        vfov_deg: 60.0,
    };
    let (w, h, spp) = (160u32, 120u32, 16u32);
    let start = std::time::Instant::now();
    let (img, stats) = render(&integ, &cam, w, h, spp, 1);
    let secs = start.elapsed().as_secs_f64();
    println!(
        "render {w}x{h} @ {spp} spp: {:.3} s, {} closest + {} shadow rays, {:.2} Mrays/s, \
         {:.2} rays/path",
        secs,
        stats.closest,
        stats.shadow,
        stats.total() as f64 / secs / 1e6,
        stats.total() as f64 / (w * h * spp) as f64
    );
    assert!(img.iter().all(|c| c.is_finite()));
    let png = image::RgbImage::from_fn(w, h, |x, y| {
        let c = img[(y * w + x) as usize];
        let q = |v: f32| (linear_to_srgb(v) * 255.0 + 0.5) as u8;
        image::Rgb([q(c.x), q(c.y), q(c.z)])
    });
    // Kept for viewing, under Cargo's target tmp (the next run replaces it).
    let path = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("radiance-preview.png");
    png.save(&path).unwrap();
    println!("preview: {}", path.display());
}

#[test]
fn validation_rejects_bad_inputs() {
    assert!(Material::lambertian(Vec3::splat(0.5)).validate().is_ok());
    assert!(Material::lambertian(Vec3::new(0.5, 1.2, 0.0))
        .validate()
        .is_err());
    assert!(Material::lambertian(Vec3::new(0.5, f32::NAN, 0.0))
        .validate()
        .is_err());
    let checker = |scale: f32| Material {
        emission: Vec3::ZERO,
        metallic_roughness_texture: None,
        normal_texture: None,
        emissive_texture: None,
        occlusion_texture: None,
        model: Model::Lambertian,
        albedo: Texture::Checker {
            a: Vec3::ZERO,
            b: Vec3::ONE,
            scale,
        },
    };
    assert!(checker(3.0).validate().is_ok());
    assert!(checker(0.0).validate().is_err());
    // Image albedos above 1 are clamped in eval and counted.
    let img = ImageTexture::from_pixels(2, 1, vec![Vec3::splat(1.5), Vec3::splat(0.25)]).unwrap();
    let m = Material {
        emission: Vec3::ZERO,
        metallic_roughness_texture: None,
        normal_texture: None,
        emissive_texture: None,
        occlusion_texture: None,
        model: Model::Lambertian,
        albedo: Texture::Image(Arc::new(img)),
    };
    assert!(m.validate().is_ok());
    assert_eq!(m.clamped_texels(), 1);
    assert_eq!(m.eval(Vec2::new(0.25, 0.5)), Vec3::ONE);

    let point = |p: Vec3, i: Vec3| Light::Point {
        position: p,
        intensity: i,
    };
    assert!(point(Vec3::ZERO, Vec3::ONE).validate().is_ok());
    assert!(point(Vec3::INFINITY, Vec3::ONE).validate().is_err());
    assert!(point(Vec3::ZERO, -Vec3::ONE).validate().is_err());
    let sun = |d: Vec3, a: f32| Light::Sun {
        direction: d,
        irradiance: Vec3::ONE,
        angular_radius: a,
    };
    assert!(sun(Vec3::Z, SUN_ANGULAR_RADIUS).validate().is_ok());
    assert!(sun(Vec3::ZERO, 0.01).validate().is_err());
    assert!(sun(Vec3::Z, 2.0).validate().is_err());
    // A point light at the shading point contributes nothing rather than infinity.
    assert!(point(Vec3::ONE, Vec3::ONE).sample_li(Vec3::ONE).is_none());

    // spp = 0 renders one sample per pixel.
    let scene = ground(0.0);
    let materials = lambert(0.5);
    let env = Environment::Constant(Vec3::ONE);
    let integ = Integrator::new(&scene, &materials, &[], &env, 1);
    let cam = Camera {
        position: Vec3::new(0.0, 0.0, 1.0),
        target: Vec3::ZERO,
        up: Vec3::Y,
        vfov_deg: 40.0,
    };
    let (img, stats) = render(&integ, &cam, 4, 3, 0, 1);
    assert_eq!(img.len(), 12);
    assert_eq!(stats.closest, 24); // primary + BSDF ray per pixel
}

/// A glTF metallic-roughness material of constant base colour, and its BRDF.
fn metallic_roughness(
    base: Vec3,
    metallic: f32,
    roughness: f32,
) -> (
    Vec<Material>,
    oslf_scene::metallic_roughness::MetallicRoughness,
) {
    let materials = vec![Material {
        emission: Vec3::ZERO,
        metallic_roughness_texture: None,
        normal_texture: None,
        emissive_texture: None,
        occlusion_texture: None,
        albedo: Texture::Constant(base),
        model: Model::MetallicRoughness {
            metallic,
            roughness,
        },
    }];
    let brdf = oslf_scene::metallic_roughness::MetallicRoughness {
        base_color: base,
        metallic,
        roughness,
    };
    (materials, brdf)
}

/// A metallic-roughness floor under a uniform sky L reflects `L · ∫ f cos dωᵢ` towards every
/// view (nothing else to see, so at any bounce count). The integral is a midpoint quadrature
/// of the BRDF over the hemisphere, independent of the integrator's sampling; the path tracer's
/// mean agrees with it within four standard errors estimated from its samples.
#[test]
fn metallic_roughness_floor_under_a_uniform_sky() {
    let l = Vec3::new(1.0, 0.8, 0.5);
    let base = Vec3::new(0.9, 0.7, 0.4);
    for (metallic, roughness) in [(1.0, 0.5), (0.0, 0.4), (0.5, 0.8)] {
        let (materials, brdf) = metallic_roughness(base, metallic, roughness);
        let scene = ground(0.0);
        let env = Environment::Constant(l);
        for omega in [Vec3::Z, Vec3::new(0.6, 0.2, 0.5).normalize()] {
            // ∫ f cos dω by the midpoint rule in (cos θ, φ): dω = d(cos θ) dφ.
            let (nt, np) = (600, 600);
            let mut albedo = glam::DVec3::ZERO;
            for i in 0..nt {
                let mu = (i as f64 + 0.5) / nt as f64;
                let s = (1.0 - mu * mu).sqrt();
                for j in 0..np {
                    let phi = 2.0 * std::f64::consts::PI * (j as f64 + 0.5) / np as f64;
                    let wi = glam::DVec3::new(s * phi.cos(), s * phi.sin(), mu).as_vec3();
                    albedo += brdf.eval(Vec3::Z, omega, wi).as_dvec3() * mu;
                }
            }
            albedo *= 2.0 * std::f64::consts::PI / (nt * np) as f64;
            let expected = l.as_dvec3() * albedo;
            for max_bounces in [0, 2] {
                let integ = Integrator::new(&scene, &materials, &[], &env, max_bounces);
                let ray = ray_to(Vec3::new(0.2, -0.1, 0.0), omega, 0.5);
                let n = 40_000u32;
                let (mut sum, mut sum2) = (glam::DVec3::ZERO, glam::DVec3::ZERO);
                let mut stats = RayStats::default();
                for i in 0..n {
                    let mut rng = Rng::new(17, u64::from(i));
                    let r = integ
                        .radiance(&ray, &mut rng, &mut stats)
                        .radiance
                        .as_dvec3();
                    assert!(r.is_finite());
                    sum += r;
                    sum2 += r * r;
                }
                let mean = sum / f64::from(n);
                let se = ((sum2 / f64::from(n) - mean * mean).max(glam::DVec3::ZERO)
                    / f64::from(n))
                .powf(0.5);
                for k in 0..3 {
                    assert!(
                        (mean[k] - expected[k]).abs() <= 4.0 * se[k] + 1e-3 * expected[k],
                        "m{metallic} r{roughness} {omega} bounces {max_bounces}: {mean} ± {se} vs {expected}"
                    );
                }
            }
        }
    }
}

/// A point light over a metallic-roughness floor, direct light only: `L = f(ωₒ, ωₗ) I cos/r²`
/// exactly (no Monte Carlo), with `f` the glTF BRDF.
#[test]
fn point_light_over_a_metallic_roughness_floor() {
    let base = Vec3::new(0.9, 0.6, 0.3);
    let (metallic, roughness) = (0.7, 0.35);
    let (materials, brdf) = metallic_roughness(base, metallic, roughness);
    let intensity = Vec3::new(10.0, 5.0, 2.0);
    let light_pos = Vec3::new(0.3, -0.2, 2.0);
    let lights = [Light::Point {
        position: light_pos,
        intensity,
    }];
    let scene = ground(0.0);
    let env = Environment::Constant(Vec3::ZERO);
    let integ = Integrator::new(&scene, &materials, &lights, &env, 0);
    let mut rng = Rng::new(0, 0);
    for (q, omega) in [
        (Vec3::ZERO, Vec3::Z),
        (
            Vec3::new(-0.4, 0.2, 0.0),
            Vec3::new(-0.5, 0.3, 0.8).normalize(),
        ),
        (
            Vec3::new(1.0, 2.0, 0.0),
            Vec3::new(0.3, 0.1, 1.0).normalize(),
        ),
    ] {
        let mut stats = RayStats::default();
        let s = integ.radiance(&ray_to(q, omega, 0.1), &mut rng, &mut stats);
        let d = light_pos - q;
        let expected = brdf.eval(Vec3::Z, omega, d.normalize())
            * intensity
            * (d.normalize().z / d.length_squared());
        assert!(
            (s.radiance - expected).abs().max_element() < 1e-4 * expected.max_element(),
            "{q}: {} vs {expected}",
            s.radiance
        );
    }
}

/// Emitting surfaces: a ray that meets one sees its emission, and a Lambertian floor under an
/// infinite emitting ceiling (black, radiance Le) reflects a·Le exactly, at any bounce count
/// (every cosine-weighted sample meets the ceiling; its black surface reflects nothing back).
#[test]
fn an_emitting_ceiling_lights_the_floor() {
    let (a, le) = (0.6, Vec3::new(2.0, 1.0, 0.5));
    let scene = Scene(vec![
        Shape::Plane(Plane {
            point: Vec3::ZERO,
            normal: Vec3::Z,
            material: 0,
        }),
        Shape::Plane(Plane {
            point: Vec3::new(0.0, 0.0, 3.0),
            normal: -Vec3::Z,
            material: 1,
        }),
    ]);
    let materials = vec![
        Material::lambertian(Vec3::splat(a)),
        Material {
            emission: le,
            ..Material::lambertian(Vec3::ZERO)
        },
    ];
    let env = Environment::Constant(Vec3::ZERO);
    for max_bounces in [0, 1, 3] {
        let integ = Integrator::new(&scene, &materials, &[], &env, max_bounces);
        let mut rng = Rng::new(4, 0);
        let mut stats = RayStats::default();
        let up = Ray::new(Vec3::new(0.0, 0.0, 1.0), Vec3::Z);
        let s = integ.radiance(&up, &mut rng, &mut stats);
        assert_eq!(s.radiance, le, "bounces {max_bounces}");
        for omega in [Vec3::Z, Vec3::new(0.5, -0.3, 0.7).normalize()] {
            let (mean, stats) = mean_radiance(&integ, &ray_to(Vec3::ZERO, omega, 0.5), 1000, 9);
            assert!(
                (mean - a * le).abs().max_element() < 1e-5,
                "bounces {max_bounces}: {mean} vs {}",
                a * le
            );
            // Primary + the sample that finds the ceiling, both closest-hit queries.
            assert_eq!(stats.closest, 2000, "bounces {max_bounces}");
        }
    }
    // Without emitters the last vertex keeps its any-hit query, and the floor is black.
    let dark = vec![
        Material::lambertian(Vec3::splat(a)),
        Material::lambertian(Vec3::ZERO),
    ];
    let integ = Integrator::new(&scene, &dark, &[], &env, 0);
    let (mean, stats) = mean_radiance(&integ, &ray_to(Vec3::ZERO, Vec3::Z, 0.5), 100, 9);
    assert_eq!((mean, stats.closest), (Vec3::ZERO, 100));
}
