//! The ground-truth renderer against closed forms: a flat patch under a uniform environment
//! reflects the environment exactly (mirror), leaves albedo × L (diffuse), and reflects
//! L × the Ashikhmin–Shirley directional albedo, by quadrature (glossy, `AsLobe::albedo_quadrature`).

use std::path::PathBuf;
use std::sync::atomic::{AtomicU32, Ordering};

use glam::DVec3;
use oslf_scene::scene::Scene;
use oslf_trace::ashikhmin_shirley::AsLobe;
use oslf_trace::ground_truth::{compose, GroundTruth, Term, TruthSettings};

const ENV: [f32; 3] = [0.5, 0.6, 0.8];
const ALBEDO: [f32; 3] = [0.6, 0.5, 0.4];

/// A flat 2×2 bicubic patch in the plane z = 0 under a uniform sky, seen obliquely from the
/// side its normal faces.
fn plane_scene() -> Scene {
    static NEXT: AtomicU32 = AtomicU32::new(0);
    // Under Cargo's target tmp; the next run replaces it.
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!(
        "ground_truth/plane-{}",
        NEXT.fetch_add(1, Ordering::Relaxed)
    ));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let mut text = String::from("1\n");
    text += &(1..=16)
        .map(|i| i.to_string())
        .collect::<Vec<_>>()
        .join(",");
    text += "\n16\n";
    for i in 0..4 {
        for j in 0..4 {
            text += &format!(
                "{},{},0\n",
                -1.0 + 2.0 * i as f32 / 3.0,
                -1.0 + 2.0 * j as f32 / 3.0
            );
        }
    }
    std::fs::write(dir.join("plane.txt"), text).unwrap();
    let scene = format!(
        r#"
[camera]
position = [0.2, -1.3, 1.4]
target = [0.0, 0.0, 0.0]
vfov = 50.0

[environment]
uniform = {ENV:?}

[[object]]
name = "plane"
patches = "plane.txt"
material = {{ color = {ALBEDO:?} }}
"#
    );
    let path: PathBuf = dir.join("plane.toml");
    let mut s = Scene::from_str(&scene, &path, None).unwrap();
    // The test needs the normal to face the camera (+z); flip the view otherwise.
    let n = s.objects[0].patches[0].normal(0.5, 0.5);
    if n.z < 0.0 {
        let c = s.camera.as_mut().unwrap();
        c.position.z = -c.position.z;
    }
    s
}

fn settings(spp: u32) -> TruthSettings {
    TruthSettings {
        width: 16,
        height: 12,
        spp,
        seed: 3,
    }
}

#[test]
fn mirror_of_a_flat_patch_in_a_uniform_sky_is_the_sky() {
    let scene = plane_scene();
    let truth = GroundTruth::new(&scene, scene.camera.unwrap()).unwrap();
    let image = truth.render(Term::Mirror, &settings(4)).unwrap();
    let covered = image.pixels.iter().filter(|p| p[3] == 1.0).count();
    assert!(covered > 100, "the patch covers {covered} of 192 pixels");
    for p in image.pixels.iter().filter(|p| p[3] == 1.0) {
        for k in 0..3 {
            assert!((p[k] - ENV[k]).abs() < 1e-6, "{p:?}");
        }
    }
    // Off the object: zero, alpha 0.
    assert!(image
        .pixels
        .iter()
        .filter(|p| p[3] == 0.0)
        .all(|p| p[..3] == [0.0; 3]));
}

#[test]
fn the_diffuse_patch_leaves_albedo_times_the_sky() {
    let scene = plane_scene();
    let truth = GroundTruth::new(&scene, scene.camera.unwrap()).unwrap();
    let image = truth.render(Term::Recon, &settings(256)).unwrap();
    let on: Vec<_> = image.pixels.iter().filter(|p| p[3] == 1.0).collect();
    for k in 0..3 {
        let mean = on.iter().map(|p| f64::from(p[k])).sum::<f64>() / on.len() as f64;
        let expected = f64::from(ALBEDO[k] * ENV[k]);
        assert!(
            (mean / expected - 1.0).abs() < 0.01,
            "channel {k}: {mean} vs {expected}"
        );
    }
    // recon + C_s · mirror (Eq. 4.12), C_s = the albedo.
    let mirror = truth.render(Term::Mirror, &settings(1)).unwrap();
    let full = compose(&image, &mirror).unwrap();
    for ((f, r), m) in full.pixels.iter().zip(&image.pixels).zip(&mirror.pixels) {
        for k in 0..3 {
            assert!((f[k] - (r[k] + ALBEDO[k] * m[k])).abs() < 1e-6);
        }
    }
}

#[test]
fn the_glossy_term_is_the_lobe_albedo_times_the_sky() {
    let scene = plane_scene();
    let camera = scene.camera.unwrap();
    let truth = GroundTruth::new(&scene, camera).unwrap();
    let patch = scene.objects[0].patches[0];
    for lobe in [
        AsLobe {
            rs: 1.0,
            nu: 10.0,
            nv: 10.0,
        },
        AsLobe {
            rs: 0.3,
            nu: 10.0,
            nv: 200.0,
        },
    ] {
        let s = settings(1024);
        let image = truth.render(Term::Glossy(lobe), &s).unwrap();
        let mut checked = 0;
        for y in 0..s.height {
            for x in (0..s.width).step_by(3) {
                let Some((ray, hit)) = truth.primary_hit(x, y, s.width, s.height) else {
                    continue;
                };
                // The frame the ground truth documents: the Bézier normal, ∂x/∂u made orthogonal.
                let n = patch.normal(hit.uv.x, hit.uv.y);
                let (du, _) = patch.partials(hit.uv.x, hit.uv.y);
                let t = (du - n * n.dot(du)).normalize();
                let b = n.cross(t);
                let view = -ray.dir;
                let v = DVec3::new(view.dot(t).into(), view.dot(b).into(), view.dot(n).into());
                let albedo = lobe.albedo_quadrature(v, 600, 1200);
                let p = image.pixels[(y * s.width + x) as usize];
                for k in 0..3 {
                    let expected = albedo * f64::from(ENV[k]);
                    let got = f64::from(p[k]);
                    assert!(
                        (got / expected - 1.0).abs() < 0.03,
                        "{lobe:?} pixel ({x}, {y}) channel {k}: {got} vs {expected}"
                    );
                }
                checked += 1;
            }
        }
        assert!(checked > 20);
    }
}

/// The pbr term of a flat patch under a uniform sky is the sky times the directional albedo
/// of glTF's BRDF with the patch's base colour, by midpoint quadrature of that BRDF (not its
/// sampling).
#[test]
fn the_pbr_term_is_the_brdf_albedo_times_the_sky() {
    use oslf_scene::metallic_roughness::MetallicRoughness;
    let scene = plane_scene();
    let truth = GroundTruth::new(&scene, scene.camera.unwrap()).unwrap();
    let patch = scene.objects[0].patches[0];
    for (metallic, roughness) in [(1.0, 0.3), (0.0, 0.5), (0.5, 0.8)] {
        let s = settings(1024);
        let image = truth
            .render(
                Term::Pbr {
                    metallic,
                    roughness,
                    object_material: false,
                },
                &s,
            )
            .unwrap();
        let brdf = MetallicRoughness {
            base_color: glam::Vec3::from(ALBEDO),
            metallic,
            roughness,
        };
        let mut checked = 0u32;
        let mut ratio = [0.0f64; 3];
        for y in 0..s.height {
            for x in (0..s.width).step_by(4) {
                let Some((ray, hit)) = truth.primary_hit(x, y, s.width, s.height) else {
                    continue;
                };
                let n = patch.normal(hit.uv.x, hit.uv.y);
                let frame = oslf_shading::warp::Frame::from_normal(n);
                let view = -ray.dir;
                let (nt, np) = (300, 300);
                let mut albedo = DVec3::ZERO;
                for i in 0..nt {
                    let mu = (i as f64 + 0.5) / nt as f64;
                    let r = (1.0 - mu * mu).sqrt();
                    for j in 0..np {
                        let phi = std::f64::consts::TAU * (j as f64 + 0.5) / np as f64;
                        let l = DVec3::new(r * phi.cos(), r * phi.sin(), mu).as_vec3();
                        albedo += brdf.eval(n, view, frame.to_world(l)).as_dvec3() * mu;
                    }
                }
                albedo *= std::f64::consts::TAU / (nt * np) as f64;
                let p = image.pixels[(y * s.width + x) as usize];
                for k in 0..3 {
                    let expected = albedo[k] * f64::from(ENV[k]);
                    let got = f64::from(p[k]);
                    // One pixel's 1 024 samples: within 10 %; the mean ratio below within 1.5 %.
                    assert!(
                        (got / expected - 1.0).abs() < 0.1,
                        "m{metallic} r{roughness} pixel ({x}, {y}) channel {k}: {got} vs {expected}"
                    );
                    ratio[k] += got / expected;
                }
                checked += 1;
            }
        }
        assert!(checked > 15, "{checked}");
        for (k, r) in ratio.iter().enumerate() {
            let mean = r / f64::from(checked);
            assert!(
                (mean - 1.0).abs() < 0.015,
                "m{metallic} r{roughness} channel {k}: mean ratio {mean} over {checked} pixels"
            );
        }
    }
    let e = truth
        .render(
            Term::Pbr {
                metallic: 1.5,
                roughness: 0.2,
                object_material: false,
            },
            &settings(1),
        )
        .unwrap_err()
        .to_string();
    assert!(e.contains("metallic 1.5"), "{e}");
}

#[test]
fn ground_truth_does_not_depend_on_the_thread_count() {
    let scene = plane_scene();
    let truth = GroundTruth::new(&scene, scene.camera.unwrap()).unwrap();
    let lobe = AsLobe {
        rs: 1.0,
        nu: 50.0,
        nv: 50.0,
    };
    let run = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| {
            let a = truth.render(Term::Recon, &settings(8)).unwrap();
            let b = truth.render(Term::Glossy(lobe), &settings(8)).unwrap();
            (a.pixels, b.pixels)
        })
    };
    assert_eq!(run(1), run(2));
}

#[test]
fn bad_settings_are_errors() {
    let scene = plane_scene();
    let truth = GroundTruth::new(&scene, scene.camera.unwrap()).unwrap();
    let mut s = settings(1);
    s.width = 0;
    assert!(truth.render(Term::Recon, &s).is_err());
    let bad = AsLobe {
        rs: 1.0,
        nu: f64::NAN,
        nv: 1.0,
    };
    let e = truth
        .render(Term::Glossy(bad), &settings(1))
        .unwrap_err()
        .to_string();
    assert!(e.contains("n_u"), "{e}");
}

/// The teapot's body over a floor of glowing stripes (no sky, so every mirror path ends at an
/// emitter or in the dark: no noise), its patches tessellated by the truth to `epsilon`/50.
fn striped_floor_scene(epsilon: f32) -> Scene {
    let mut text = String::from(
        r#"
[camera]
position = [5.0, -5.0, 3.0]
target = [0.0, 0.0, 0.8]
vfov = 40.0

[[plane]]
size = [12.0, 12.0]
transform = { translate = [0.0, 0.0, -0.1] }
material = { color = [0.0, 0.0, 0.0], emission = [0.2, 0.3, 0.4] }

[[object]]
patches = "newell-teapot"
select = [4, 12]
material = { color = [0.5, 0.5, 0.5] }
"#,
    );
    for k in 0..40 {
        text += &format!(
            "\n[[plane]]\nsize = [0.15, 12.0]\ntransform = {{ translate = [{}, 0.0, -0.09] }}\nmaterial = {{ color = [0.0, 0.0, 0.0], emission = [3.0, 2.0, 1.0] }}\n",
            -6.0 + 0.3 * k as f32
        );
    }
    let path = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("striped.toml");
    let mut scene = Scene::from_str(&text, &path, None).unwrap();
    scene.bake.epsilon = epsilon;
    scene
}

/// The truth shades the patch itself, not its tessellation: the mirror of the stripes in the
/// body, whose reflected rays move with the shading point, is the same with triangles 0.04
/// off the surface (ε = 2) as with triangles 10⁻⁴ off it (ε = 0.005). Shading the
/// triangles' points instead moves the stripes' edges in one pixel in ten.
#[test]
fn the_mirror_does_not_depend_on_the_truths_tessellation() {
    let settings = TruthSettings {
        width: 96,
        height: 72,
        spp: 1,
        seed: 3,
    };
    let render = |epsilon: f32| {
        let scene = striped_floor_scene(epsilon);
        let truth = GroundTruth::new(&scene, scene.camera.unwrap()).unwrap();
        truth.render(Term::Mirror, &settings).unwrap().pixels
    };
    let (coarse, fine) = (render(2.0), render(0.005));
    let (mut both, mut differ, mut bright) = (0, 0, 0);
    for (c, f) in coarse.iter().zip(&fine) {
        if c[3] != 1.0 || f[3] != 1.0 {
            continue;
        }
        both += 1;
        bright += usize::from(f[0] > 1.0);
        if (0..3).any(|k| (c[k] - f[k]).abs() > 1e-3) {
            differ += 1;
        }
    }
    assert!(both > 1500, "the body covers {both} pixels");
    assert!(bright > both / 20, "{bright} of {both} pixels see a stripe");
    // 12 of 1 904 here (where a ray leaves its patch for a neighbour, the triangle's point
    // stays); 184 with the triangles' points.
    assert!(differ * 100 <= both, "{differ} of {both} pixels differ");
}
