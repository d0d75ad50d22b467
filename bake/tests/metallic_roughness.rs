//! glTF's metallic-roughness BRDF: the specification's formulas on a table of inputs, energy
//! (white furnace), and its sampling against uniform sampling of the same integral.

use glam::{Vec2, Vec3};
use oslf_scene::metallic_roughness::MetallicRoughness;
use oslf_shading::random::Rng;
use oslf_shading::warp::sample_uniform_sphere;

fn mr(c: [f32; 3], metallic: f32, roughness: f32) -> MetallicRoughness {
    MetallicRoughness {
        base_color: Vec3::from(c),
        metallic,
        roughness,
    }
}

/// Values written out from glTF 2.0 Appendix B by an independent program (f64): base colour,
/// metallic, roughness, view and light directions (normal +z), BRDF.
/// Base colour, metallic, roughness, view, light, BRDF.
type Case = ([f32; 3], f32, f32, [f32; 3], [f32; 3], [f32; 3]);

#[test]
fn the_brdf_is_the_gltf_specifications() {
    #[rustfmt::skip]
    let table: [Case; 6] = [
        ([0.9, 0.6, 0.2], 1.0, 0.3, [0.2873479, 0.0, 0.9578263], [-0.2860388, 0.0953463, 0.9534626], [5.691204, 3.794136, 1.264713]),
        ([0.9, 0.6, 0.2], 0.0, 0.3, [0.2873479, 0.0, 0.9578263], [-0.2860388, 0.0953463, 0.9534626], [0.527963, 0.4362898, 0.3140588]),
        ([0.5, 0.5, 0.5], 0.5, 0.7, [0.9116846, 0.2279212, 0.3418817], [-0.1270001, -0.6350006, 0.7620008], [0.125759; 3]),
        ([1.0, 1.0, 1.0], 1.0, 0.05, [0.4472136, 0.0, 0.8944272], [-0.4472136, 0.0, 0.8944272], [15915.48; 3]),
        ([0.2, 0.8, 0.4], 0.25, 1.0, [0.0, 0.9761871, 0.2169305], [0.9525793, -0.2721655, 0.1360828], [0.06560577, 0.2362516, 0.1224877]),
        ([0.0, 0.0, 0.0], 0.0, 0.15, [0.9938837, 0.0, 0.1104315], [-0.9923721, 0.0551318, 0.1102636], [0.5215926; 3]),
    ];
    for (c, metallic, roughness, v, l, want) in table {
        let got = mr(c, metallic, roughness).eval(Vec3::Z, Vec3::from(v), Vec3::from(l));
        for k in 0..3 {
            assert!(
                (got[k] - want[k]).abs() <= 2e-4 * want[k],
                "{c:?} m{metallic} r{roughness}: {got} vs {want:?}"
            );
        }
    }
    // Below the surface on either side: nothing.
    let m = mr([0.5; 3], 0.5, 0.5);
    let up = Vec3::new(0.0, 0.6, 0.8);
    assert_eq!(m.eval(Vec3::Z, up, -up), Vec3::ZERO);
    assert_eq!(m.eval(Vec3::Z, -up, up), Vec3::ZERO);
    assert_eq!(m.pdf(Vec3::Z, up, -up), 0.0);
}

/// Mean and standard error of `n` draws.
fn mean_se(n: u32, mut draw: impl FnMut(u32) -> f64) -> (f64, f64) {
    let (mut s, mut s2) = (0.0, 0.0);
    for i in 0..n {
        let x = draw(i);
        assert!(x.is_finite());
        s += x;
        s2 += x * x;
    }
    let mean = s / f64::from(n);
    let var = (s2 / f64::from(n) - mean * mean).max(0.0);
    (mean, (var / f64::from(n)).sqrt())
}

/// The directional albedo `∫ f cos dωᵢ` of `m` seen from `wo`, by its own sampling (green
/// channel): mean and standard error.
fn albedo_sampled(m: &MetallicRoughness, wo: Vec3, n: u32, seed: u64) -> (f64, f64) {
    let mut rng = Rng::new(seed, 0);
    mean_se(n, |_| {
        let lobe = rng.next_f32();
        match m.sample(Vec3::Z, wo, lobe, rng.next_vec2()) {
            Some(s) => {
                assert!(s.wi.z > 0.0 && s.pdf > 0.0);
                let expect = m.eval(Vec3::Z, wo, s.wi) * s.wi.z / m.pdf(Vec3::Z, wo, s.wi);
                assert!((s.weight - expect).abs().max_element() <= 1e-4 * expect.max_element());
                f64::from(s.weight.y)
            }
            None => 0.0,
        }
    })
}

/// White furnace. Metals reflect at most what arrives, at every roughness and angle, and a
/// white metal at roughness 0 reflects all of it. glTF's dielectric weights its diffuse base by
/// Fresnel at the half vector rather than the view, so it reflects more than arrives at grazing
/// views (1.30 for a smooth one seen 78° from the normal); near the normal it conserves energy
/// too.
#[test]
fn white_furnace_albedo_is_at_most_one_and_one_for_a_smooth_metal() {
    for roughness in [0.0, 0.05, 0.15, 0.3, 0.6, 1.0] {
        for metallic in [0.0, 0.5, 1.0] {
            for z in [0.99f32, 0.8, 0.6, 0.4, 0.2, 0.1] {
                if metallic < 1.0 && z < 0.8 {
                    continue;
                }
                let wo = Vec3::new((1.0 - z * z).sqrt(), 0.0, z);
                let m = mr([1.0; 3], metallic, roughness);
                let (albedo, se) = albedo_sampled(&m, wo, 40_000, 7);
                assert!(
                    albedo <= 1.0 + 4.0 * se + 1e-6,
                    "r{roughness} m{metallic} {wo}: {albedo} ± {se}"
                );
                if metallic == 1.0 && roughness == 0.0 {
                    assert!(
                        (albedo - 1.0).abs() <= 4.0 * se + 2e-3,
                        "{wo}: {albedo} ± {se}"
                    );
                }
            }
        }
    }
    // Energy falls with roughness for a metal (single scattering): at α = 1 and normal
    // incidence, ∫ D V cos = ∫₀¹ μ/(1 + μ) dμ = 1 − ln 2.
    let m = mr([1.0; 3], 1.0, 1.0);
    let (albedo, se) = albedo_sampled(&m, Vec3::Z, 100_000, 9);
    assert!(
        (albedo - (1.0 - 2f64.ln())).abs() <= 4.0 * se,
        "{albedo} ± {se}"
    );
}

/// The same albedo by uniform sampling of the sphere, which shares nothing with the BRDF's
/// sampling: the two estimates agree within their standard errors, so `sample` and `pdf` are
/// consistent and unbiased.
#[test]
fn importance_sampling_agrees_with_uniform_sampling() {
    for (roughness, metallic, z) in [
        (0.3, 1.0, 0.8),
        (0.6, 0.0, 0.5),
        (0.45, 0.5, 0.3),
        (1.0, 0.25, 0.9),
    ] {
        let wo = Vec3::new((1.0f32 - z * z).sqrt(), 0.0, z);
        let m = mr([0.8, 0.5, 0.3], metallic, roughness);
        let (a, sa) = albedo_sampled(&m, wo, 100_000, 3);
        let mut rng = Rng::new(5, 1);
        let (b, sb) = mean_se(400_000, |_| {
            let wi = sample_uniform_sphere(Vec2::new(rng.next_f32(), rng.next_f32()));
            f64::from(m.eval(Vec3::Z, wo, wi).y * wi.z.max(0.0)) * 4.0 * std::f64::consts::PI
        });
        let tol = 4.0 * (sa * sa + sb * sb).sqrt();
        assert!(
            (a - b).abs() <= tol,
            "r{roughness} m{metallic}: {a} ± {sa} vs {b} ± {sb}"
        );
    }
}
