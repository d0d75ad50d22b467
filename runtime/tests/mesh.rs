//! Triangle-mesh objects: a synthetic store holding a Bézier plane and a
//! bent grid whose 2×2 atlas pages point at sample points with distinct cube colours. The GPU
//! matches the CPU reference in every mode and blend; each pixel reads the sample map of the
//! atlas page its atlas uv falls in; both objects render.

use crate::common;
use crate::common::knobs::Knobs;

use oslf_format::{
    encode_cube, BakeParams, CameraInfo, CubeImage, Encoding, MeshInfo, ObjectInfo, Patch,
    SampleMaps, SamplePoint, StoreMeta, StoreWriter, INVALID_INDEX,
};
use oslf_runtime::reference::StoreCubes;
use oslf_runtime::{Blend, CacheConfig, Gpu, Mode, RenderOptions, Renderer, Source};

const W: u32 = 96;
const H: u32 = 72;
const EPS: f32 = 0.02;
/// The mesh's object-to-world translation along x; the plane's is −1.1.
const MESH_X: f32 = 0.1;
/// Atlas grid k.
const K: u32 = 2;
/// Segments of the grid per side: 7, so triangles straddle the page border at 0.5 and the page
/// is chosen per fragment.
const SEGMENTS: u32 = 7;
/// Cube colour of each page, `py·k + px`: (0,0) red, (1,0) green, (0,1) blue, (1,1) yellow;
/// the Bézier plane's points are grey.
const PAGE_COLORS: [[f32; 3]; 4] = [
    [1.0, 0.1, 0.1],
    [0.1, 1.0, 0.1],
    [0.1, 0.1, 1.0],
    [1.0, 1.0, 0.1],
];
const GREY: [f32; 3] = [0.6, 0.6, 0.6];

/// The bend of the grid: z as a function of object-space x, and its slope.
fn bend(x: f32) -> (f32, f32) {
    (0.2 * x * (1.0 - x), 0.2 * (1.0 - 2.0 * x))
}

fn normal_at(x: f32) -> [f32; 3] {
    let (_, dz) = bend(x);
    let l = (dz * dz + 1.0).sqrt();
    [-dz / l, 0.0, 1.0 / l]
}

fn translate(x: f32) -> [[f32; 4]; 4] {
    [
        [1.0, 0.0, 0.0, 0.0],
        [0.0, 1.0, 0.0, 0.0],
        [0.0, 0.0, 1.0, 0.0],
        [x, 0.0, 0.0, 1.0],
    ]
}

/// The bent grid over `[0, 1]²` (object space) with atlas uv = (x, y).
fn grid_mesh() -> MeshInfo {
    let n = SEGMENTS + 1;
    let mut m = MeshInfo {
        atlas_grid: K,
        positions: Vec::new(),
        normals: Vec::new(),
        uvs: Vec::new(),
        triangles: Vec::new(),
    };
    for j in 0..n {
        for i in 0..n {
            let (x, y) = (i as f32 / SEGMENTS as f32, j as f32 / SEGMENTS as f32);
            m.positions.push([x, y, bend(x).0]);
            m.normals.push(normal_at(x));
            m.uvs.push([x, y]);
        }
    }
    for j in 0..SEGMENTS {
        for i in 0..SEGMENTS {
            let a = j * n + i;
            // Counter-clockwise seen from +z.
            m.triangles.push([a, a + 1, a + n + 1]);
            m.triangles.push([a, a + n + 1, a + n]);
        }
    }
    m
}

/// Sample maps whose every texel lists `points` (global indices with their local uv) sorted by
/// distance to the texel centre.
fn map_of(points: &[(u32, [f32; 2])], res: u32) -> Vec<[u32; 4]> {
    let mut out = Vec::new();
    for y in 0..res {
        for x in 0..res {
            let c = [(x as f32 + 0.5) / res as f32, (y as f32 + 0.5) / res as f32];
            let mut p: Vec<(f32, u32)> = points
                .iter()
                .map(|(i, uv)| ((uv[0] - c[0]).powi(2) + (uv[1] - c[1]).powi(2), *i))
                .collect();
            p.sort_by(|a, b| a.partial_cmp(b).unwrap());
            out.push(std::array::from_fn(|k| {
                p.get(k).map_or(INVALID_INDEX, |v| v.1)
            }));
        }
    }
    out
}

/// The synthetic store's path, written once per test binary (the tests run in parallel).
fn mesh_store() -> std::path::PathBuf {
    static PATH: std::sync::OnceLock<std::path::PathBuf> = std::sync::OnceLock::new();
    PATH.get_or_init(|| write_mesh_store(None)).clone()
}

/// The same store with the grid textured ([`grid_textures`]).
fn textured_store() -> std::path::PathBuf {
    static PATH: std::sync::OnceLock<std::path::PathBuf> = std::sync::OnceLock::new();
    PATH.get_or_init(|| write_mesh_store(Some(grid_textures())))
        .clone()
}

/// Texture coordinates of the grid at atlas uv (x, y): affine, so a pixel's follow from its
/// atlas uv, and past [0, 1] so lookups repeat.
fn texcoord_at(x: f32, y: f32) -> [f32; 2] {
    [2.0 * x - 0.3, 1.5 * y + 0.25]
}

/// A 5×3 base-colour texture of varied sRGB codes, a 3×2 metallic-roughness one (roughness
/// 0.1–0.9, metallic 0–1), a 2×2 normal texture, a 4×3 occlusion one (strength 0.6) and a
/// 3×3 emissive one over the grid.
fn grid_textures() -> oslf_format::ObjectTextures {
    use oslf_format::{TextureImage, TextureKind};
    let image = |w: u32, h: u32, f: &dyn Fn(u32) -> [u8; 4]| TextureImage {
        width: w,
        height: h,
        texels: (0..w * h).map(f).collect(),
    };
    let base = image(5, 3, &|i| {
        [
            (i * 53 % 256) as u8,
            (i * 97 % 256) as u8,
            (255 - i * 17) as u8,
            255,
        ]
    });
    let mr = image(3, 2, &|i| [0, (25 + i * 40) as u8, (i * 51) as u8, 255]);
    // Tilted normals, x and y both ways, scaled by 0.8.
    let tilts = [
        [160, 128, 240],
        [100, 150, 230],
        [128, 128, 255],
        [180, 90, 220],
    ];
    let normal = image(2, 2, &|i| {
        let [r, g, b] = tilts[i as usize];
        [r, g, b, 255]
    });
    let glow = image(3, 3, &|i| {
        [(i * 80 % 256) as u8, 200, (40 + i * 20) as u8, 255]
    });
    let occlusion = image(4, 3, &|i| [(20 + i * 21) as u8, 0, 255, 255]);
    let uvs = grid_mesh().uvs;
    oslf_format::ObjectTextures {
        texcoords: uvs.iter().map(|uv| texcoord_at(uv[0], uv[1])).collect(),
        // Along +x, which the shaders make orthogonal to the bent grid's normals.
        tangents: vec![[1.0, 0.0, 0.0, 1.0]; uvs.len()],
        normal_scale: 0.8,
        occlusion_strength: 0.6,
        images: vec![
            (TextureKind::BaseColor, base),
            (TextureKind::MetallicRoughness, mr),
            (TextureKind::Normal, normal),
            (TextureKind::Occlusion, occlusion),
            (TextureKind::Emissive, glow),
        ],
    }
}

/// Writes the synthetic store: object 0 a Bézier plane (map 0), object 1 the bent grid (maps
/// 1..5), 4 sample points per map, cubes of the map's colour with per-texel variation, an
/// environment cube, distances.
fn write_mesh_store(textures: Option<oslf_format::ObjectTextures>) -> std::path::PathBuf {
    let name = if textures.is_some() {
        "textured.oslf"
    } else {
        "mesh.oslf"
    };
    let map_res = 8;
    let cube_res = 8;
    let plane = Patch {
        // u along y, v along x: the normal ∂x/∂v × ∂x/∂u is +z.
        control_points: std::array::from_fn(|k| [(k % 4) as f32 / 3.0, (k / 4) as f32 / 3.0, 0.0]),
    };
    let meta = StoreMeta {
        objects: vec![
            ObjectInfo {
                name: "plane".into(),
                transform: translate(-1.1),
                base_color: [0.5, 0.5, 0.5],
                first_patch: 0,
                patch_count: 1,
                mesh: None,
                material: Default::default(),
                textures: None,
            },
            ObjectInfo {
                name: "bent grid".into(),
                transform: translate(MESH_X),
                base_color: [0.9, 0.8, 0.7],
                first_patch: 1,
                patch_count: K * K,
                mesh: Some(grid_mesh()),
                // A rough, partly metallic glTF material: the pbr mode
                // shades this object with it, the plane with the parameters' factors.
                material: oslf_format::ObjectMaterial {
                    model: oslf_format::meta::MATERIAL_METALLIC_ROUGHNESS,
                    metallic: 0.4,
                    roughness: 0.55,
                    // The textured grid glows: this times its emissive texture.
                    emission: if textures.is_some() {
                        [0.6, 0.3, 0.1]
                    } else {
                        [0.0; 3]
                    },
                },
                textures,
            },
        ],
        patches: vec![plane],
        bake: BakeParams {
            epsilon: EPS,
            cube_resolution: cube_res,
            sample_map_resolution: map_res,
            samples_per_texel: 1,
            encoding: Encoding::Rgba16f,
            distance_channel: true,
            ..Default::default()
        },
        camera: Some(CameraInfo {
            position: [0.0, -0.6, 2.2],
            target: [0.0, 0.5, 0.0],
            up: [0.0, 1.0, 0.0],
            vfov_deg: 55.0,
        }),
        has_env_cube: true,
    };
    let quarter = [[0.25f32, 0.25], [0.75, 0.25], [0.25, 0.75], [0.75, 0.75]];
    let mut points = Vec::new();
    let mut colors = Vec::new();
    let mut indices = Vec::new();
    // The plane: uv = (u, v) = (y, x).
    let mut own = Vec::new();
    for uv in quarter {
        own.push((points.len() as u32, uv));
        points.push(SamplePoint {
            position: [-1.1 + uv[1], uv[0], EPS],
            normal: [0.0, 0.0, 1.0],
            uv,
            patch: 0,
            object: 0,
        });
        colors.push(GREY);
    }
    indices.extend(map_of(&own, map_res));
    // The mesh's pages.
    for page in 0..K * K {
        let (px, py) = ((page % K) as f32, (page / K) as f32);
        let mut own = Vec::new();
        for uv in quarter {
            let (x, y) = ((px + uv[0]) / K as f32, (py + uv[1]) / K as f32);
            let n = normal_at(x);
            own.push((points.len() as u32, uv));
            points.push(SamplePoint {
                position: [
                    MESH_X + x + EPS * n[0],
                    y + EPS * n[1],
                    bend(x).0 + EPS * n[2],
                ],
                normal: n,
                uv,
                patch: 1 + page,
                object: 1,
            });
            colors.push(PAGE_COLORS[page as usize]);
        }
        indices.extend(map_of(&own, map_res));
    }
    colors.push([0.3, 0.35, 0.4]); // the environment cube
    let maps = SampleMaps {
        resolution: map_res,
        indices,
    };
    // Under Cargo's target tmp, replaced by the next run: the store outlives the tests that
    // share it (statics are never dropped).
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join(env!("CARGO_CRATE_NAME"));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join(name);
    let mut w = StoreWriter::create(&path, &meta, &points, &maps).unwrap();
    for (cube, c) in colors.iter().enumerate() {
        let mut image = CubeImage::black(cube_res, true);
        for (f, face) in image.faces.iter_mut().enumerate() {
            for (i, t) in face.iter_mut().enumerate() {
                let s = 0.5 + ((f * 7 + i * 13 + cube * 5) % 11) as f32 / 10.0;
                *t = [c[0] * s, c[1] * s, c[2] * s];
            }
        }
        if let Some(d) = image.distance.as_mut() {
            for (f, face) in d.iter_mut().enumerate() {
                for (i, t) in face.iter_mut().enumerate() {
                    *t = 0.5 + ((f + i) % 5) as f32 * 0.3;
                }
            }
        }
        let (encoded, _) = encode_cube(&image, &meta.bake, cube as u32).unwrap();
        w.append(encoded).unwrap();
    }
    w.finish().unwrap();
    path
}

fn open() -> (Renderer, StoreCubes) {
    open_path(&mesh_store())
}

fn open_path(path: &std::path::Path) -> (Renderer, StoreCubes) {
    let store = oslf_format::Store::open(path).unwrap();
    assert_eq!(store.meta().map_count(), 5);
    let cubes = StoreCubes::decode(&store).unwrap();
    let r = Renderer::new(Gpu::headless().unwrap(), store, CacheConfig::default()).unwrap();
    (r, cubes)
}

fn check(r: &mut Renderer, cubes: &StoreCubes, params: Knobs, label: &str) -> Vec<[f32; 4]> {
    common::check_parity(r, cubes, params, (W, H), label)
}

#[test]
fn a_mesh_object_matches_the_cpu_reference_in_every_mode_and_blend() {
    let (mut r, cubes) = open();
    let base = Knobs::default();
    check(
        &mut r,
        &cubes,
        Knobs {
            mode: Mode::Recon,
            ..base
        },
        "recon",
    );
    for blend in Blend::ALL {
        for n in [1.0, 4.0] {
            for depth in [false, true] {
                let p = Knobs {
                    mode: Mode::Mirror,
                    blend,
                    blend_n: n,
                    depth,
                    ..base
                };
                check(
                    &mut r,
                    &cubes,
                    p,
                    &format!("mirror {} N={n} depth={depth}", blend.name()),
                );
            }
        }
    }
    check(
        &mut r,
        &cubes,
        Knobs {
            mode: Mode::ReconMirror,
            ..base
        },
        "recon + C_s mirror",
    );
    check(
        &mut r,
        &cubes,
        Knobs {
            mode: Mode::Mirror,
            source: Source::EnvMap,
            ..base
        },
        "mirror envmap",
    );
    // Anisotropic lobes among them: the mesh's tangent frame comes from its normal alone.
    for (p, label) in common::glossy_cases(base) {
        check(&mut r, &cubes, p, &label);
    }
    // The pbr mode with the mesh object's own material (the plane takes the parameters'),
    // and with the parameters' factors for both.
    for object_material in [true, false] {
        for depth in [false, true] {
            let p = Knobs {
                mode: Mode::Pbr,
                metallic: 1.0,
                roughness: 0.2,
                object_material,
                depth,
                ..base
            };
            check(
                &mut r,
                &cubes,
                p,
                &format!("pbr object_material={object_material} depth={depth}"),
            );
        }
    }
}

/// With the store's materials the mesh object is shaded with its own factors: its pixels
/// differ from a render with the parameters' factors, the plane's do not.
#[test]
fn the_pbr_mode_takes_an_objects_material_from_the_store() {
    let (mut r, _) = open();
    let render = |r: &mut Renderer, object_material: bool| {
        let p = Knobs {
            mode: Mode::Pbr,
            metallic: 1.0,
            roughness: 0.2,
            object_material,
            ..Knobs::default()
        };
        let options = RenderOptions {
            width: W,
            height: H,
            ..Default::default()
        };
        let camera = r.default_view();
        r.render(&camera, &p.params(), &options).unwrap().pixels
    };
    let own = render(&mut r, true);
    let flags = render(&mut r, false);
    let gbuffer = r.read_gbuffer().unwrap();
    let (mut mesh_diff, mut plane_diff) = (0, 0);
    for ((a, b), g) in own.iter().zip(&flags).zip(&gbuffer) {
        if g.position_patch[3] < 0.5 {
            continue;
        }
        let differs = (0..3).any(|c| (a[c] - b[c]).abs() > 1e-4);
        if g.position_patch[3] > 1.5 {
            mesh_diff += usize::from(differs);
        } else {
            plane_diff += usize::from(differs);
        }
    }
    assert!(mesh_diff > 100, "only {mesh_diff} mesh pixels changed");
    assert_eq!(plane_diff, 0, "plane pixels changed");
}

/// Renders reconstruction alone; returns the pixels and the G-buffer.
fn recon(r: &mut Renderer) -> (Vec<[f32; 4]>, Vec<oslf_runtime::reference::GTexel>) {
    let options = RenderOptions {
        width: W,
        height: H,
        ..Default::default()
    };
    let camera = r.default_view();
    let params = Knobs {
        mode: Mode::Recon,
        ..Default::default()
    };
    let frame = r.render(&camera, &params.params(), &options).unwrap();
    (frame.pixels, r.read_gbuffer().unwrap())
}

/// The page whose colour `c` shows, if one clearly does.
fn page_of_colour(c: [f32; 4]) -> Option<u32> {
    let [r, g, b, _] = c;
    let hi = |a: f32, o: f32| a > 3.0 * o;
    match (hi(r, b), hi(g, b), hi(r, g), hi(g, r), hi(b, r) && hi(b, g)) {
        (true, true, false, false, _) => Some(3),
        (true, _, true, _, _) => Some(0),
        (_, true, _, true, _) => Some(1),
        (_, _, _, _, true) => Some(2),
        _ => None,
    }
}

#[test]
fn each_pixel_reads_the_atlas_page_its_uv_falls_in() {
    let (mut r, _) = open();
    let (pixels, gbuffer) = recon(&mut r);
    let origin = r.mesh().origin;
    let mut per_page = [0usize; 4];
    let mut checked = 0;
    for (g, p) in gbuffer.iter().zip(&pixels) {
        let id = g.position_patch[3];
        if id < 1.5 {
            continue; // background (0) or the plane (1)
        }
        // Object-space position on the grid: atlas uv = (x, y).
        let x = g.position_patch[0] + origin.x - MESH_X;
        let y = g.position_patch[1] + origin.y;
        let near_border = |v: f32| (v * K as f32 - (v * K as f32).round()).abs() < 0.02;
        if near_border(x) || near_border(y) {
            continue;
        }
        let (px, py) = (
            ((x * K as f32).floor() as u32).min(K - 1),
            ((y * K as f32).floor() as u32).min(K - 1),
        );
        let page = py * K + px;
        assert_eq!(
            id,
            (2 + page) as f32,
            "atlas uv ({x}, {y}) lies in page ({px}, {py})"
        );
        let (lu, lv) = (x * K as f32 - px as f32, y * K as f32 - py as f32);
        assert!(
            (g.normal_uv[2] - lu).abs() < 0.01 && (g.normal_uv[3] - lv).abs() < 0.01,
            "local uv {:?} for ({lu}, {lv})",
            &g.normal_uv[2..]
        );
        assert_eq!(p[3], 1.0);
        assert_eq!(
            page_of_colour(*p),
            Some(page),
            "pixel {p:?} at atlas uv ({x}, {y}) in page ({px}, {py})"
        );
        per_page[page as usize] += 1;
        checked += 1;
    }
    println!("pixels per page {per_page:?}");
    assert!(
        per_page.iter().all(|n| *n > 20),
        "every page is seen: {per_page:?}"
    );
    assert!(checked > 200);
    // In particular page (1, 0): green.
    assert!(per_page[1] > 20);
}

#[test]
fn a_bezier_object_and_a_mesh_object_both_render() {
    let (mut r, _) = open();
    // The bounds take in the mesh's vertices: x from −1.1 (plane) to 1.1 (grid).
    let (lo, hi) = r.mesh().bounds();
    assert!(
        (lo.x + 1.1).abs() < 1e-5 && (hi.x - 1.1).abs() < 1e-5,
        "{lo} {hi}"
    );
    let top = bend(3.0 / SEGMENTS as f32).0;
    assert!((hi.z - top).abs() < 1e-5, "the bend's top vertex: {hi}");
    assert_eq!(r.mesh().patches.len(), 5, "one per sample map");
    assert!(r.mesh().patches[1..]
        .iter()
        .all(|p| p.cp == [glam::Vec3::ZERO; 16]));
    let (pixels, gbuffer) = recon(&mut r);
    let mut plane = 0;
    let mut mesh = 0;
    for (g, p) in gbuffer.iter().zip(&pixels) {
        match g.position_patch[3] {
            1.0 => {
                plane += 1;
                // Grey.
                assert!(
                    p[0] > 0.05
                        && (p[0] - p[1]).abs() < 0.02 * p[0]
                        && (p[0] - p[2]).abs() < 0.02 * p[0],
                    "{p:?}"
                );
            }
            id if id >= 2.0 => {
                assert!(id <= 5.0 && id.fract() == 0.0, "map id {id}");
                mesh += 1;
            }
            _ => assert_eq!(p[3], 0.0),
        }
    }
    println!("plane {plane} pixels, mesh {mesh} pixels");
    assert!(plane > 300 && mesh > 300, "plane {plane}, mesh {mesh}");
}

/// A textured object: the G-buffer's material at each of its pixels is the
/// CPU reference's `material_texel` at the pixel's texture coordinates (within 1e-3 per value),
/// its normal the CPU's `mapped_normal` (within 1e-3), and the GPU matches the CPU reference in the pbr mode with and without the store's
/// material, and in the glossy modes.
#[test]
fn a_textured_object_reads_its_textures_per_pixel_and_matches_the_cpu_reference() {
    use oslf_runtime::reference::material::{mapped_normal, material_texel, unpack2x16unorm};
    let (mut r, cubes) = open_path(&textured_store());
    let textures = grid_textures();
    let pbr = Knobs {
        mode: Mode::Pbr,
        metallic: 1.0,
        roughness: 0.2,
        m: 8,
        ..Knobs::default()
    };
    let own = check(&mut r, &cubes, pbr, "pbr, textured");
    let gbuffer = r.read_gbuffer().unwrap();
    let (mut checked, mut worst, mut darkest) = (0, 0f32, 1f32);
    for g in &gbuffer {
        let id = g.position_patch[3];
        if id < 1.5 {
            assert_eq!(g.material[3], 0, "an untextured pixel has texture flags");
            continue;
        }
        let page = (id - 1.5) as u32;
        let (px, py) = ((page % K) as f32, (page / K) as f32);
        let x = (px + g.normal_uv[2]) / K as f32;
        let y = (py + g.normal_uv[3]) / K as f32;
        let want = material_texel(&textures, glam::Vec2::from(texcoord_at(x, y)));
        assert_eq!(g.material[3] & 0xff, want[3] & 0xff, "texture flags");
        for shift in [8, 16, 24] {
            let (a, b) = ((g.material[3] >> shift) & 0xff, (want[3] >> shift) & 0xff);
            assert!(a.abs_diff(b) <= 1, "emissive code {a} against {b}");
        }
        for (got, want) in g.material.iter().zip(&want).take(3) {
            let (a, b) = (unpack2x16unorm(*got), unpack2x16unorm(*want));
            worst = worst.max((a - b).abs().max_element());
        }
        darkest = darkest.min(unpack2x16unorm(g.material[2]).y);
        checked += 1;
    }
    println!("{checked} textured pixels, largest material difference {worst:.2e}");
    assert!(checked > 500, "only {checked} textured pixels");
    assert!(worst < 1e-3, "material differs by {worst}");
    // The occlusion texture (codes 20..251 at strength 0.6) reaches below 0.6.
    assert!(darkest < 0.6, "occlusion never below {darkest}");
    // The textures change the picture: against the untextured store, most grid pixels differ.
    let (mut plain, _) = open();
    let options = RenderOptions {
        width: W,
        height: H,
        ..Default::default()
    };
    let camera = plain.default_view();
    let before = plain
        .render(&camera, &pbr.params(), &options)
        .unwrap()
        .pixels;
    // The normal texture: the textured G-buffer's normal is the CPU's mapped normal of the
    // untextured G-buffer's (the interpolated normal of the same pixel) at the pixel's
    // texture coordinates, with the tangent +x.
    let unmapped = plain.read_gbuffer().unwrap();
    let mut tilted = 0;
    let mut worst_normal = 0f32;
    for (g, p) in gbuffer.iter().zip(&unmapped) {
        if g.position_patch[3] < 1.5 {
            continue;
        }
        let n = oslf_runtime::geometry::oct_decode([p.normal_uv[0], p.normal_uv[1]]);
        let got = oslf_runtime::geometry::oct_decode([g.normal_uv[0], g.normal_uv[1]]);
        let page = (g.position_patch[3] - 1.5) as u32;
        let x = ((page % K) as f32 + g.normal_uv[2]) / K as f32;
        let y = ((page / K) as f32 + g.normal_uv[3]) / K as f32;
        let tc = glam::Vec2::from(texcoord_at(x, y));
        let want = mapped_normal(&textures, tc, n, glam::Vec4::new(1.0, 0.0, 0.0, 1.0));
        worst_normal = worst_normal.max((got - want).length());
        tilted += usize::from(got.dot(n) < 0.999);
    }
    println!("largest mapped-normal difference {worst_normal:.2e}, {tilted} pixels tilted");
    assert!(
        worst_normal < 1e-3,
        "mapped normals differ by {worst_normal}"
    );
    assert!(
        tilted * 10 > checked * 9,
        "only {tilted} of {checked} normals tilted"
    );
    let changed = own
        .iter()
        .zip(&before)
        .zip(&gbuffer)
        .filter(|((a, b), g)| {
            g.position_patch[3] > 1.5 && (0..3).any(|c| (a[c] - b[c]).abs() > 1e-3)
        })
        .count();
    assert!(
        changed * 10 > checked * 9,
        "only {changed} of {checked} pixels changed"
    );
    for (params, label) in [
        (
            Knobs {
                object_material: false,
                ..pbr
            },
            "pbr, textured, the parameters' factors",
        ),
        (
            Knobs {
                mode: Mode::Glossy,
                ..pbr
            },
            "glossy, textured",
        ),
    ] {
        check(&mut r, &cubes, params, label);
    }
}
