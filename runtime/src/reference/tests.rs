use std::f32::consts::PI;

use oslf_format::INVALID_INDEX;

use super::blend::Candidates;
use super::*;
use oslf_shading::fresnel::schlick as fresnel;

/// The constants of a store without sample points, maps or distances: environment cube
/// `env_cube`, faces of `cube_res`².
pub(super) fn store_constants(env_cube: u32, cube_res: u32) -> crate::uniform::StoreConstants {
    crate::uniform::StoreConstants {
        sample_count: 0,
        env_cube,
        map_res: 1,
        index16: true,
        cube_res,
        slots_per_texture: 1,
        mip_levels: 1,
        has_depth: false,
        origin: [0.0; 3],
        fitted_box: None,
        min_object_metallic: None,
        irradiance_base: None,
        surface_error: 0.0,
    }
}

#[test]
fn tangent_frames_are_unit_and_orthogonal_even_where_du_vanishes() {
    for n in [
        Vec3::Z,
        -Vec3::Z,
        Vec3::new(0.6, 0.0, -0.8),
        Vec3::new(-1e-8, 1.0, 0.0).normalize(),
    ] {
        for du in [Vec3::ZERO, n * 3.0, Vec3::X, Vec3::new(1e-30, 0.0, 0.0)] {
            let t = tangent_frame(n, du);
            assert!(t.is_finite(), "{n} {du}");
            assert!((t.length() - 1.0).abs() < 1e-5, "{n} {du} {t}");
            assert!(t.dot(n).abs() < 1e-5, "{n} {du} {t}");
        }
    }
}

/// No cube is ever available.
struct NoCubes;

impl CubeTexels for NoCubes {
    fn texel(&self, _: u32, _: usize, _: u32, _: u32, _: u32) -> Option<Vec3> {
        None
    }
    fn depth(&self, _: u32, _: usize, _: u32, _: u32) -> Option<f32> {
        None
    }
    fn resident(&self, _: u32) -> bool {
        false
    }
}

#[test]
fn camera_rays_are_the_cameras_directions_through_pixel_centres() {
    use crate::params::Background;
    use crate::shading::ShadingParams;
    use crate::uniform::ShadeUniform;
    use oslf_geometry::Camera;
    let k = store_constants(u32::MAX, 1);
    for (camera, (w, h)) in [
        (
            Camera {
                position: Vec3::new(5.5, -6.5, 4.5),
                target: Vec3::new(0.0, 0.0, 1.0),
                up: Vec3::Z,
                vfov_deg: 36.0,
            },
            (96, 72),
        ),
        (
            Camera {
                position: Vec3::new(0.0, 0.0, 3.0),
                target: Vec3::ZERO,
                up: Vec3::Y,
                vfov_deg: 150.0,
            },
            (7, 300),
        ),
    ] {
        let uniform = ShadeUniform::new(
            &ShadingParams::default(),
            glam::Mat4::IDENTITY,
            &camera,
            [w, h],
            &k,
            Background::Env,
        );
        let shader = bare_shader(uniform, &[], &NoCubes);
        for (i, j) in [
            (0, 0),
            (w - 1, 0),
            (w / 2, h / 2),
            (0, h - 1),
            (w - 1, h - 1),
        ] {
            let want = camera.direction(i as f32 + 0.5, j as f32 + 0.5, w, h);
            let got = shader.camera_ray(i, j);
            assert!((got - want).length() < 1e-6, "{i},{j}: {got} vs {want}");
        }
    }
}

#[test]
fn background_pixels_have_alpha_zero_and_no_non_finite_colour() {
    use crate::params::Background;
    use crate::shading::ShadingParams;
    use crate::uniform::ShadeUniform;
    let k = store_constants(0, 1);
    let camera = oslf_geometry::Camera {
        position: Vec3::new(0.0, -3.0, 0.0),
        target: Vec3::ZERO,
        up: Vec3::Z,
        vfov_deg: 40.0,
    };
    for (bg, want) in [
        (Background::None, [0.0; 4]),
        (Background::Color([0.5, 1.0, 3.0]), [0.5, 1.0, 3.0, 0.0]),
        // Not resident: black, never a stale or non-finite value.
        (Background::Env, [0.0; 4]),
    ] {
        let shader = Shader {
            uniform: ShadeUniform::new(
                &ShadingParams::default(),
                glam::Mat4::IDENTITY,
                &camera,
                [4, 3],
                &k,
                bg,
            ),
            samples: &[],
            irradiance: &[],
            patches: &[],
            colors: &[],
            materials: &[],
            emissions: &[],
            maps: &[],
            cubes: &NoCubes,
            feedback: &[],
            prefiltered: &super::NoPrefiltered,
        };
        assert_eq!(shader.shade(1, 2, &GTexel::default()), want, "{bg:?}");
    }
}

/// shade.wgsl's seam table (SEAM_LO, SEAM_HI, read from its source and decoded as its
/// `seam_texel` does) gives the texel `seam_coords` finds by projection, for every texel
/// one off a face's edge (corners aside), on faces of 1 to 1024 texels.
#[test]
fn shader_seam_table_matches_the_projection() {
    // The module's own text (the assembled file prints the numbers its own way).
    let src = include_str!("../shade/seams.wgsl");
    let table = |name: &str| -> [u32; 4] {
        let head = format!("const {name} = vec4<u32>(");
        let at = src.find(&head).expect(name) + head.len();
        let body = &src[at..at + src[at..].find(')').unwrap()];
        let v: Vec<u32> = body
            .split(',')
            .map(|w| {
                let w = w.trim().trim_end_matches('u');
                u32::from_str_radix(w.trim_start_matches("0x"), 16).unwrap()
            })
            .collect();
        v.try_into().unwrap()
    };
    let (lo, hi) = (table("SEAM_LO"), table("SEAM_HI"));
    let shader = |face: usize, x: i32, y: i32, n: i32| -> (usize, (i32, i32)) {
        let in_x = x >= 0 && x < n;
        let (e, a) = if in_x {
            (if y >= n { 3 } else { 2 }, x)
        } else {
            (if x >= n { 1 } else { 0 }, y.clamp(0, n - 1))
        };
        let code = if face == 5 {
            hi[e]
        } else {
            lo[e] >> (6 * face)
        } & 63;
        let along = if code & 16 != 0 { n - 1 - a } else { a };
        let fixed = if code & 32 != 0 { n - 1 } else { 0 };
        let c = if code & 8 != 0 {
            (along, fixed)
        } else {
            (fixed, along)
        };
        ((code & 7) as usize, c)
    };
    for n in [1, 2, 3, 4, 6, 8, 16, 48, 64, 256, 1024] {
        for face in 0..6 {
            for a in 0..n {
                for (x, y) in [(-1, a), (n, a), (a, -1), (a, n)] {
                    assert_eq!(
                        shader(face, x, y, n),
                        seam_coords(face, (x, y), n),
                        "face {face}, texel ({x}, {y}) of {n}"
                    );
                }
            }
        }
    }
}

#[test]
fn face_points_invert_face_st() {
    for face in 0..6 {
        for (s, t) in [(0.5, 0.5), (0.1, 0.8), (0.97, 0.03), (0.02, 0.99)] {
            let p = face_point(face, s, t);
            let (f, s2, t2) = face_st(p);
            assert_eq!(f, face, "{face} {s} {t}");
            assert!(
                (s2 - s).abs() < 1e-6 && (t2 - t).abs() < 1e-6,
                "{face} {s} {t}"
            );
            let want = Vec3::from_array(oslf_format::cube::face_st_to_direction(face, s, t));
            assert!((p.normalize() - want).length() < 1e-6, "{face} {s} {t}");
        }
    }
}

/// A resident cube of resolution `n` whose texels are a smooth (linear) function of the
/// directions through their centres.
struct SmoothCube(u32);

impl CubeTexels for SmoothCube {
    fn depth(&self, _: u32, _: usize, _: u32, _: u32) -> Option<f32> {
        None
    }
    fn texel(&self, _: u32, face: usize, _: u32, x: u32, y: u32) -> Option<Vec3> {
        assert!(face < 6 && x < self.0 && y < self.0, "{face} {x} {y}");
        let d = Vec3::from_array(oslf_format::cube::texel_direction(face, x, y, self.0));
        Some(Vec3::splat(0.5) + d * Vec3::new(0.4, 0.3, 0.2))
    }
    fn resident(&self, _: u32) -> bool {
        true
    }
}

/// A shader with no patches or sample maps: for the parts that need only cubes.
pub(super) fn bare_shader<'a, C: CubeTexels>(
    uniform: ShadeUniform,
    samples: &'a [Vec3],
    cubes: &'a C,
) -> Shader<'a, C> {
    Shader {
        uniform,
        samples,
        irradiance: &[],
        patches: &[],
        colors: &[],
        materials: &[],
        emissions: &[],
        maps: &[],
        cubes,
        feedback: &[],
        prefiltered: &super::NoPrefiltered,
    }
}

/// Filtered samples for M = n² are the grid's stratum centres through the concentric map:
/// mapped back to the square (the map's inverse), sample i lands at the centre of cell i;
/// every (ξ1, ξ2) lies in [0, 1)², and other M take the Hammersley set.
#[test]
fn filtered_samples_are_concentric_stratum_centres() {
    for n in [1u32, 2, 3, 4, 5, 8, 16] {
        let m = n * n;
        for i in 0..m {
            let [x1, x2] = filter_xi(i, m, false, 0);
            assert!(
                (0.0..1.0).contains(&x1) && (0.0..1.0).contains(&x2),
                "{m} {i}"
            );
            // Polar (r, φ) on the disc back to the square [-1, 1]² (Shirley & Chiu).
            let (r, mut phi) = (x2.sqrt(), 2.0 * PI * x1);
            if phi > 1.75 * PI {
                phi -= 2.0 * PI;
            }
            let (a, b) = if phi < 0.25 * PI {
                (r, r * phi / (0.25 * PI))
            } else if phi < 0.75 * PI {
                (-r * (phi - 0.5 * PI) / (0.25 * PI), r)
            } else if phi < 1.25 * PI {
                (-r, -r * (phi - PI) / (0.25 * PI))
            } else {
                (r * (phi - 1.5 * PI) / (0.25 * PI), -r)
            };
            let cell = |c: f32| (c + 1.0) * 0.5 * n as f32;
            let (ca, cb) = (cell(a), cell(b));
            assert!(
                (ca - ((i % n) as f32 + 0.5)).abs() < 1e-4
                    && (cb - ((i / n) as f32 + 0.5)).abs() < 1e-4,
                "m {m} sample {i}: cell ({ca}, {cb})"
            );
        }
    }
    assert_eq!(filter_xi(3, 12, false, 0), [3.5 / 12.0, 0.75]);
}

/// The shading normal is the patch's own (as the geometry crate evaluates it, to f32
/// rounding), facing as the interpolated normal it is given, and that normal where the
/// patch's degenerates (an atlas page's zero control points) or turns more than 25° away.
#[test]
fn patch_normals_are_the_patchs_own_facing_as_the_vertex_normal() {
    let teapot = oslf_geometry::bezier::newell_teapot();
    let mut compared = 0;
    for p in &teapot {
        for (u, v) in [(0.3, 0.6), (0.5, 0.5), (0.9, 0.15), (0.05, 0.95)] {
            let exact = p.normal(u, v);
            let du = patch_du(p, u, v);
            let dv = patch_dv(p, u, v);
            if du.cross(dv).length() < 1e-3 * du.length() * dv.length() {
                continue; // near a collapsed edge: f32 derivatives lose digits
            }
            let tilt = (exact + Vec3::new(0.05, -0.03, 0.02)).normalize();
            let n = patch_normal(p, u, v, tilt);
            assert!((n - exact).length() < 1e-4, "{n} {exact}");
            let flipped = patch_normal(p, u, v, -tilt);
            assert!((flipped + exact).length() < 1e-4, "{flipped} {exact}");
            let far = (exact + tilt.any_orthonormal_vector()).normalize();
            assert_eq!(patch_normal(p, u, v, far), far);
            compared += 1;
        }
    }
    assert!(compared > 100, "{compared}");
    let page = BezierPatch::new([Vec3::ZERO; 16]);
    assert_eq!(patch_normal(&page, 0.5, 0.5, Vec3::Y), Vec3::Y);
}

/// The shading pass's point is where the pixel's ray meets the patch itself (as the geometry
/// crate's f64 `refine_hit` finds it, to f32 rounding), not where it meets the flat triangles
/// of a tessellation up to `tol` off the surface; the G-buffer's point stays where there is no
/// patch (an atlas page), no tolerance or no direction.
#[test]
fn a_gbuffer_point_refines_onto_its_patch_along_the_pixels_ray() {
    use oslf_geometry::bezier::REFINE_REACH;
    let teapot = oslf_geometry::bezier::newell_teapot();
    let tol = 0.01; // the teapot is 6 units wide
    let (mut refined, mut chord_sum, mut left_sum) = (0, 0.0f32, 0.0f32);
    for p in teapot.iter().take(16) {
        let mesh = p.tessellate(p.tessellation_level(tol));
        for tri in mesh.triangles.iter().step_by(5) {
            let [a, b, c] = tri.map(|i| i as usize);
            let w = Vec3::new(0.3, 0.45, 0.25);
            let flat = mesh.positions[a] * w.x + mesh.positions[b] * w.y + mesh.positions[c] * w.z;
            let uv = mesh.uvs[a] * w.x + mesh.uvs[b] * w.y + mesh.uvs[c] * w.z;
            let n = (mesh.normals[a] + mesh.normals[b] + mesh.normals[c]).normalize();
            // A camera above the surface, looking down at 35° from its normal.
            let d = (-n + n.any_orthonormal_vector() * 0.7).normalize();
            let Some((eu, ev, exact)) = p.refine_hit(flat, d, (uv.x, uv.y), REFINE_REACH * tol)
            else {
                continue;
            };
            let hit = surface_hit(p, flat, (uv.x, uv.y), d, tol);
            if hit.x == flat {
                continue; // at a patch border, f32 and f64 may part
            }
            refined += 1;
            chord_sum += (flat - exact).length();
            left_sum += (hit.x - exact).length();
            assert!((hit.x - exact).length() < 1e-4, "{} {exact}", hit.x);
            assert!((hit.u - eu).abs() < 1e-4 && (hit.v - ev).abs() < 1e-4);
        }
    }
    assert!(refined > 200, "{refined} refined");
    assert!(
        left_sum < 0.01 * chord_sum,
        "{left_sum} left of {chord_sum}"
    );
    // Where it cannot refine, the G-buffer's point stays.
    let p = &teapot[0];
    let (x, uv) = (p.eval(0.4, 0.6), (0.4, 0.6));
    let keep = SurfacePoint { x, u: 0.4, v: 0.6 };
    let page = BezierPatch::new([Vec3::ZERO; 16]);
    assert_eq!(surface_hit(&page, x, uv, -Vec3::Z, tol), keep);
    let off = x + p.normal(0.4, 0.6) * 0.5;
    let kept = SurfacePoint { x: off, ..keep };
    assert_eq!(surface_hit(p, off, uv, -p.normal(0.4, 0.6), tol), kept);
    assert_eq!(surface_hit(p, off, uv, -p.normal(0.4, 0.6), 0.0), kept);
    assert_eq!(surface_hit(p, off, uv, Vec3::NAN, 1.0), kept);
    // From 0.5 above along the normal it is found when the tolerance reaches that far.
    let found = surface_hit(p, off, uv, -p.normal(0.4, 0.6), 0.1);
    assert!((found.x - x).length() < 1e-4, "{found:?}");
}

/// The environment background is as continuous across face edges as inside a face: the
/// largest difference between adjacent pixels whose rays lie on different faces is at most
/// `FACTOR` times the largest between adjacent pixels on one face. (Clamped bilinear
/// filtering within each face, as `lookup` does, shows a seam 5-20 times larger.)
#[test]
fn the_env_background_is_continuous_across_face_edges() {
    use crate::params::Background;
    use crate::shading::ShadingParams;
    use crate::uniform::ShadeUniform;
    use oslf_geometry::Camera;
    const FACTOR: f32 = 1.5;
    let (w, h) = (160u32, 120u32);
    for res in [8, 32] {
        let k = store_constants(0, res);
        // Views across edges of every orientation, vertical and horizontal in the image,
        // and across a corner of the cube.
        for (target, up) in [
            (Vec3::new(1.0, 0.05, 1.0), Vec3::Y),
            (Vec3::new(1.0, 1.0, 0.1), Vec3::Z),
            (Vec3::new(-1.0, -1.0, -0.2), Vec3::Z),
            (Vec3::new(0.1, 1.0, 1.0), Vec3::X),
            (Vec3::new(0.2, -1.0, -1.0), Vec3::X),
            (Vec3::new(1.0, 1.0, 1.0), Vec3::Z),
        ] {
            let camera = Camera {
                position: Vec3::ZERO,
                target,
                up,
                vfov_deg: 50.0,
            };
            let shader = Shader {
                uniform: ShadeUniform::new(
                    &ShadingParams::default(),
                    glam::Mat4::IDENTITY,
                    &camera,
                    [w, h],
                    &k,
                    Background::Env,
                ),
                samples: &[],
                irradiance: &[],
                patches: &[],
                colors: &[],
                materials: &[],
                emissions: &[],
                maps: &[],
                cubes: &SmoothCube(res),
                feedback: &[],
                prefiltered: &super::NoPrefiltered,
            };
            let px = |i: u32, j: u32| {
                let c = shader.shade(i, j, &GTexel::default());
                assert!(c.iter().all(|x| x.is_finite()) && c[3] == 0.0, "{c:?}");
                (
                    face_st(shader.camera_ray(i, j)).0,
                    Vec3::new(c[0], c[1], c[2]),
                )
            };
            let img: Vec<_> = (0..h).flat_map(|j| (0..w).map(move |i| (i, j))).collect();
            let img: Vec<_> = img.into_iter().map(|(i, j)| px(i, j)).collect();
            let (mut seam, mut inside, mut seam_pairs) = (0f32, 0f32, 0);
            for j in 0..h {
                for i in 0..w {
                    let a = img[(j * w + i) as usize];
                    for (di, dj) in [(1, 0), (0, 1)] {
                        if i + di >= w || j + dj >= h {
                            continue;
                        }
                        let b = img[((j + dj) * w + i + di) as usize];
                        let d = (a.1 - b.1).abs().max_element();
                        if a.0 == b.0 {
                            inside = inside.max(d);
                        } else {
                            seam = seam.max(d);
                            seam_pairs += 1;
                        }
                    }
                }
            }
            println!("res {res} {target}: across edges {seam:.2e}, inside {inside:.2e}");
            assert!(
                seam_pairs > w.min(h) as usize / 2,
                "{target}: no face edge in view"
            );
            assert!(
                inside > 0.0 && seam <= FACTOR * inside,
                "res {res} {target}: a seam of {seam} where one face varies by {inside}"
            );
        }
    }
}

#[test]
fn fresnel_is_schlick_at_both_ends() {
    assert_eq!(fresnel(0.04, 1.0), 0.04);
    assert!((fresnel(0.04, 0.0) - 1.0).abs() < 1e-6);
    assert!((fresnel(0.04, -0.5) - 1.0).abs() < 1e-6);
}

/// Each file here and its twin under shade/ hold the functions they share in the same order.
#[test]
fn reference_files_follow_the_shader_files_order() {
    let pairs: [(&str, &str, &str); 13] = [
        (
            "random",
            include_str!("../shade/random.wgsl"),
            include_str!("random.rs"),
        ),
        (
            "feedback",
            include_str!("../shade/feedback.wgsl"),
            include_str!("feedback.rs"),
        ),
        (
            "cube",
            include_str!("../shade/cube.wgsl"),
            include_str!("cube.rs"),
        ),
        (
            "depth",
            include_str!("../shade/depth.wgsl"),
            include_str!("depth.rs"),
        ),
        (
            "patch",
            include_str!("../shade/patch.wgsl"),
            include_str!("patch.rs"),
        ),
        (
            "blend",
            include_str!("../shade/blend.wgsl"),
            include_str!("blend.rs"),
        ),
        (
            "reconstruct",
            include_str!("../shade/reconstruct.wgsl"),
            include_str!("reconstruct.rs"),
        ),
        (
            "mirror",
            include_str!("../shade/mirror.wgsl"),
            include_str!("mirror.rs"),
        ),
        (
            "glossy",
            include_str!("../shade/glossy.wgsl"),
            include_str!("glossy.rs"),
        ),
        (
            "seams",
            include_str!("../shade/seams.wgsl"),
            include_str!("seams.rs"),
        ),
        (
            "split_sum",
            include_str!("../shade/split_sum.wgsl"),
            include_str!("split_sum.rs"),
        ),
        (
            "background",
            include_str!("../shade/background.wgsl"),
            include_str!("background.rs"),
        ),
        (
            "pixel",
            include_str!("../shade/pixel.wgsl"),
            include_str!("pixel.rs"),
        ),
    ];
    // The names of the functions a source defines, in order.
    let fns = |src: &str| -> Vec<String> {
        src.lines()
            .filter_map(|l| {
                let l = l.trim_start();
                let l = l
                    .strip_prefix("pub(super) ")
                    .or(l.strip_prefix("pub "))
                    .unwrap_or(l);
                let name = l.strip_prefix("fn ")?;
                Some(name[..name.find(['(', '<'])?].to_string())
            })
            .collect()
    };
    for (name, wgsl, rust) in pairs {
        let (w, r) = (fns(wgsl), fns(rust));
        let shared_w: Vec<_> = w.iter().filter(|f| r.contains(f)).collect();
        let shared_r: Vec<_> = r.iter().filter(|f| w.contains(f)).collect();
        assert!(
            !shared_w.is_empty() || name == "feedback",
            "{name}: nothing shared"
        );
        assert_eq!(
            shared_w, shared_r,
            "{name}: shade/{name}.wgsl vs reference/{name}.rs"
        );
    }
}

/// A uniform environment of radiance 1, every face resident, no distances.
struct Uniform;

impl CubeTexels for Uniform {
    fn depth(&self, _: u32, _: usize, _: u32, _: u32) -> Option<f32> {
        None
    }
    fn texel(&self, _: u32, _: usize, _: u32, _: u32, _: u32) -> Option<Vec3> {
        Some(Vec3::ONE)
    }
    fn resident(&self, _: u32) -> bool {
        true
    }
}

/// glTF 2.0 Appendix B's BRDF times ⟨n,l⟩ (n = +z), written out here in f64.
fn gltf_brdf_cos(
    base: [f64; 3],
    metallic: f64,
    roughness: f64,
    v: [f64; 3],
    l: [f64; 3],
) -> [f64; 3] {
    let (nv, nl) = (v[2], l[2]);
    if nv <= 0.0 || nl <= 0.0 {
        return [0.0; 3];
    }
    let h = [v[0] + l[0], v[1] + l[1], v[2] + l[2]];
    let len = (h[0] * h[0] + h[1] * h[1] + h[2] * h[2]).sqrt();
    let h = h.map(|c| c / len);
    let a2 = (roughness * roughness)
        .max(oslf_shading::ggx::MIN_ALPHA as f64)
        .powi(2);
    let nh = h[2];
    let vh = v[0] * h[0] + v[1] * h[1] + v[2] * h[2];
    let d = a2 / (std::f64::consts::PI * (nh * nh * (a2 - 1.0) + 1.0).powi(2));
    let vis = 1.0
        / ((nl + (a2 + (1.0 - a2) * nl * nl).sqrt()) * (nv + (a2 + (1.0 - a2) * nv * nv).sqrt()));
    let k5 = (1.0 - vh.abs()).powi(5);
    base.map(|c| {
        let metal = vis * d * (c + (1.0 - c) * k5);
        let fr = 0.04 + 0.96 * k5;
        let dielectric = (1.0 - fr) * c / std::f64::consts::PI + fr * vis * d;
        ((1.0 - metallic) * dielectric + metallic * metal) * nl
    })
}

/// The pbr mode under a uniform environment of radiance 1 gives the directional albedo of
/// glTF's BRDF with the object's base colour: its samples' weights and densities are that
/// BRDF's (midpoint quadrature of the formulas above, not the shader's sampling).
#[test]
fn pbr_under_a_uniform_environment_is_the_gltf_albedo() {
    use crate::params::Background;
    use crate::shading::ShadingParams;
    use crate::uniform::ShadeUniform;
    let base = [0.9f64, 0.6, 0.2];
    let camera = oslf_geometry::Camera {
        position: Vec3::new(0.0, -5.0, 1.0),
        target: Vec3::ZERO,
        up: Vec3::Z,
        vfov_deg: 40.0,
    };
    let empty = Candidates {
        idx: [INVALID_INDEX; 4],
        s: [Vec3::ZERO; 4],
        count: 0,
    };
    for (metallic, roughness) in [(1.0f32, 0.3f32), (0.0, 0.5), (0.5, 0.8)] {
        let mut params = ShadingParams::of_mode(crate::Mode::Pbr);
        let material = params.material_mut().unwrap();
        (material.metallic, material.roughness) = (metallic, roughness);
        params.monte_carlo_mut().unwrap().m = 4096;
        let u = ShadeUniform::new(
            &params,
            glam::Mat4::IDENTITY,
            &camera,
            [4, 4],
            &store_constants(0, 8),
            Background::Env,
        );
        let shader = bare_shader(u, &[], &Uniform);
        for vz in [0.9f32, 0.5] {
            let v = Vec3::new((1.0 - vz * vz).sqrt(), 0.0, vz);
            let (n, t) = (Vec3::Z, Vec3::X);
            let r = 2.0 * n.dot(v) * n - v;
            let base32 = Vec3::new(base[0] as f32, base[1] as f32, base[2] as f32);
            let pbr = shader.pbr_material(0);
            let got = shader.glossy(&empty, 7, Vec3::ZERO, n, t, v, r, base32, pbr);
            let (nt, np) = (400, 400);
            let mut want = [0.0f64; 3];
            let vd = [v.x as f64, v.y as f64, v.z as f64];
            for i in 0..nt {
                let mu = (i as f64 + 0.5) / nt as f64;
                let s = (1.0 - mu * mu).sqrt();
                for j in 0..np {
                    let phi = std::f64::consts::TAU * (j as f64 + 0.5) / np as f64;
                    let f = gltf_brdf_cos(
                        base,
                        metallic.into(),
                        roughness.into(),
                        vd,
                        [s * phi.cos(), s * phi.sin(), mu],
                    );
                    for k in 0..3 {
                        want[k] += f[k] * std::f64::consts::TAU / (nt * np) as f64;
                    }
                }
            }
            for k in 0..3 {
                assert!(
                    (f64::from(got[k]) - want[k]).abs() < 0.02 * want[k] + 1e-3,
                    "metallic {metallic} roughness {roughness} v·n {vz}: {got} vs {want:?}"
                );
            }
        }
    }
}
