//! Side by side with what a Bevy user does today: the store's object drawn by Bevy as a metal
//! `StandardMaterial` lit by the store's environment cube (captured at the object's centre)
//! as Bevy's environment map, infinitely far (on the camera) and as a reflection probe with
//! Bevy's parallax correction; and drawn by the OSLF plugin (the pbr mode). Headless, from the
//! store's camera, at exposure 1 without tonemapping: linear OpenEXR files to compare with
//! `oslf truth` of the same camera (`oslf compare TRUTH.exr bevy-oslf.exr`).
//!
//! ```text
//! cargo run --release -p oslf-bevy --features viewer --example side_by_side --ignore-rust-version -- \
//!     STORE OUT_DIR WIDTH HEIGHT ROUGHNESS [HALF_X HALF_Y HALF_Z [VARIANTS]]
//! ```
//!
//! `HALF_*`: the parallax box's half extents around the capture point (default: the room of
//! `examples/room.toml`, 3 × 3 × 1.5 m). Bevy centres a probe's box on its capture point, so a
//! room whose capture point is off its centre is approximated. `VARIANTS`: which images, a
//! comma-separated list of `probe`, `parallax`, `probe-flat` (a reflection probe without
//! parallax correction, the control) and `oslf` (default: all but `probe-flat`).

#[path = "shared/headless.rs"]
mod headless;

use std::path::{Path, PathBuf};
use std::sync::Arc;

use bevy::asset::RenderAssetUsages;
use bevy::light::{
    GeneratedEnvironmentMapLight, GlobalAmbientLight, LightProbe, ParallaxCorrection,
};
use bevy::mesh::{Indices, PrimitiveTopology};
use bevy::prelude::*;
use bevy::render::render_resource::{
    Extent3d, TextureDimension, TextureFormat, TextureViewDescriptor, TextureViewDimension,
};
use headless::{headless_app, settle_and_capture, spawn_linear_camera};
use oslf_bevy::{OslfObject, Pbr, PbrMaterial, ShadingParams};
use oslf_format::cube::{direction_to_face_st, texel_direction};

/// What one run draws.
#[derive(Clone, Copy, PartialEq, Debug)]
enum Variant {
    /// Bevy's metal, the environment map on the camera (no parallax).
    Probe,
    /// Bevy's metal in a reflection probe with parallax correction.
    Parallax,
    /// Bevy's metal in a reflection probe without it (`ParallaxCorrection::None`): the control
    /// that shows the probe itself draws what `Probe` draws.
    ProbeFlat,
    /// The OSLF plugin.
    Oslf,
}

/// The object's mesh in world space: positions, normals, triangles.
struct ObjectTriangles(Vec<[f32; 3]>, Vec<[f32; 3]>, Vec<u32>);

#[derive(Resource, Clone)]
struct Job {
    variant: Variant,
    camera: oslf_runtime::Camera,
    width: u32,
    height: u32,
    roughness: f32,
    half_extents: Vec3,
    mesh: Arc<ObjectTriangles>,
    color: [f32; 3],
    /// The environment cube in Bevy's layout (z mirrored), RGBA16F bytes, and where it was
    /// captured.
    cube: Arc<(u32, Vec<u8>)>,
    centre: Vec3,
    store_file: String,
}

fn v3(a: glam::Vec3) -> Vec3 {
    Vec3::from_array(a.to_array())
}

fn setup(
    mut commands: Commands,
    job: Res<Job>,
    assets: Res<AssetServer>,
    mut images: ResMut<Assets<Image>>,
    mut meshes: ResMut<Assets<Mesh>>,
    mut materials: ResMut<Assets<StandardMaterial>>,
) {
    let mut camera = spawn_linear_camera(
        &mut commands,
        &mut images,
        &job.camera,
        (job.width, job.height),
        Msaa::Off,
    );
    let (res, bytes) = &*job.cube;
    let mut cube = Image::new(
        Extent3d {
            width: *res,
            height: *res,
            depth_or_array_layers: 6,
        },
        TextureDimension::D2,
        bytes.clone(),
        TextureFormat::Rgba16Float,
        RenderAssetUsages::RENDER_WORLD,
    );
    cube.texture_view_descriptor = Some(TextureViewDescriptor {
        dimension: Some(TextureViewDimension::Cube),
        ..default()
    });
    let environment = GeneratedEnvironmentMapLight {
        environment_map: images.add(cube),
        intensity: 1.0,
        ..default()
    };
    match job.variant {
        Variant::Probe => {
            camera.insert(environment);
        }
        Variant::Parallax | Variant::ProbeFlat => {
            // A uniform scale (the probe's region, a cube around the box) with the box's half
            // extents in light-probe space, as Bevy's `ParallaxCorrection` docs do it: Bevy
            // reads the cube through the probe's transform, so a non-uniform scale would skew
            // every reflected direction, with or without parallax correction.
            let size = 2.0 * job.half_extents.max_element();
            let correction = if job.variant == Variant::Parallax {
                ParallaxCorrection::Custom(job.half_extents / size)
            } else {
                ParallaxCorrection::None
            };
            commands.spawn((
                LightProbe::default(),
                environment,
                correction,
                Transform::from_translation(job.centre).with_scale(Vec3::splat(size)),
            ));
        }
        Variant::Oslf => {
            let params = ShadingParams::Pbr(Pbr {
                material: PbrMaterial {
                    metallic: 1.0,
                    roughness: job.roughness,
                    object_material: false,
                },
                ..default()
            });
            commands
                .spawn(OslfObject::new(assets.load(job.store_file.clone())).with_params(params));
        }
    }
    if job.variant != Variant::Oslf {
        let ObjectTriangles(positions, normals, indices) = &*job.mesh;
        let mesh = Mesh::new(
            PrimitiveTopology::TriangleList,
            RenderAssetUsages::RENDER_WORLD,
        )
        .with_inserted_attribute(Mesh::ATTRIBUTE_POSITION, positions.clone())
        .with_inserted_attribute(Mesh::ATTRIBUTE_NORMAL, normals.clone())
        .with_inserted_indices(Indices::U32(indices.clone()));
        let [r, g, b] = job.color;
        commands.spawn((
            Mesh3d(meshes.add(mesh)),
            MeshMaterial3d(materials.add(StandardMaterial {
                base_color: Color::linear_rgb(r, g, b),
                metallic: 1.0,
                // Bevy clamps it to 0.089 in its shader.
                perceptual_roughness: job.roughness,
                ..default()
            })),
        ));
    }
}

/// Runs one variant until its frame settles (the environment map filtered; the OSLF cache
/// without misses) and returns its linear RGBA pixels.
fn run(job: Job, dir: &Path) -> Option<Vec<[f32; 4]>> {
    let mut app = headless_app(dir, Default::default());
    // Bevy's default ambient light (80 cd/m²) would add to the metal at exposure 1: the
    // environment map is the only light, as in the bake.
    app.insert_resource(GlobalAmbientLight::NONE)
        .insert_resource(job.clone())
        .add_systems(Startup, setup);
    app.finish();
    app.cleanup();
    if matches!(job.variant, Variant::Parallax | Variant::ProbeFlat) && !probes_usable(&app) {
        println!(
            "{:?}: skipped: Bevy draws reflection probes only with binding arrays \
             (TEXTURE_BINDING_ARRAY and non-uniform indexing), which this adapter lacks; it \
             ignores the probe",
            job.variant
        );
        return None;
    }
    // The environment map is filtered over the first frames; the OSLF object's cache settles.
    Some(match job.variant {
        Variant::Oslf => settle_and_capture(&mut app, 200, true),
        _ => settle_and_capture(&mut app, 20, false),
    })
}

/// Whether Bevy draws reflection probes on this device (`bevy_pbr`'s own test: texture binding
/// arrays with non-uniform indexing and room for them); otherwise only a camera's environment
/// map is used.
fn probes_usable(app: &App) -> bool {
    use bevy::render::settings::WgpuFeatures;
    let device = app
        .world()
        .resource::<bevy::render::renderer::RenderDevice>();
    let limits = device.limits();
    device.features().contains(
        WgpuFeatures::TEXTURE_BINDING_ARRAY
            | WgpuFeatures::SAMPLED_TEXTURE_AND_STORAGE_BUFFER_ARRAY_NON_UNIFORM_INDEXING,
    ) && limits.max_binding_array_elements_per_shader_stage >= 16
        && limits.max_binding_array_sampler_elements_per_shader_stage >= 16
}

/// The environment cube as Bevy samples it: Bevy's shaders look up (x, y, −z) ("cubemaps are
/// left-handed"), so texel direction d of the image holds the store's radiance towards
/// (d.x, d.y, −d.z).
fn bevy_cube(image: &oslf_format::CubeImage) -> (u32, Vec<u8>) {
    let n = image.resolution;
    let mut bytes = Vec::with_capacity(6 * (n * n) as usize * 8);
    for face in 0..6 {
        for y in 0..n {
            for x in 0..n {
                let [dx, dy, dz] = texel_direction(face, x, y, n);
                let (f, s, t) = direction_to_face_st([dx, dy, -dz]);
                let (sx, sy) = (
                    ((s * n as f32) as u32).min(n - 1),
                    ((t * n as f32) as u32).min(n - 1),
                );
                let [r, g, b] = image.faces[f][(sy * n + sx) as usize];
                for v in [r, g, b, 1.0] {
                    bytes.extend_from_slice(&half::f16::from_f32(v).to_le_bytes());
                }
            }
        }
    }
    (n, bytes)
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if args.len() < 5 {
        eprintln!(
            "usage: side_by_side STORE OUT_DIR WIDTH HEIGHT ROUGHNESS [HALF_X HALF_Y HALF_Z \
             [VARIANTS]]"
        );
        std::process::exit(2);
    }
    let store_path = PathBuf::from(&args[0]);
    let out = PathBuf::from(&args[1]);
    let num = |i: usize, d: f32| args.get(i).map_or(d, |a| a.parse().expect("a number"));
    let (width, height, roughness) = (num(2, 0.0) as u32, num(3, 0.0) as u32, num(4, 0.0));
    let half_extents = Vec3::new(num(5, 3.0), num(6, 3.0), num(7, 1.5));
    let store = oslf_format::Store::open(&store_path).expect("opening the store");
    let env = store
        .env_cube_index()
        .expect("the store has no environment cube");
    let cube = bevy_cube(&store.read_cube(env).expect("reading the environment cube"));
    let renderer = oslf_runtime::Renderer::new(
        oslf_runtime::Gpu::headless().expect("a GPU"),
        store,
        Default::default(),
    )
    .expect("a renderer");
    let camera = renderer.default_view();
    let m = renderer.mesh();
    let origin = m.origin;
    let positions = m
        .vertices
        .iter()
        .map(|v| (glam::Vec3::from_slice(&v.position_patch[..3]) + origin).to_array())
        .collect();
    let normals = m
        .vertices
        .iter()
        .map(|v| [v.normal_u[0], v.normal_u[1], v.normal_u[2]])
        .collect();
    // The bake captures the environment cube at the centre of the object's bounds.
    let centre = v3(m.centre());
    let job = Job {
        variant: Variant::Probe,
        camera,
        width,
        height,
        roughness,
        half_extents,
        mesh: Arc::new(ObjectTriangles(positions, normals, m.indices.clone())),
        color: m.colors[0].to_array(),
        cube: Arc::new(cube),
        centre,
        store_file: store_path
            .file_name()
            .unwrap()
            .to_string_lossy()
            .into_owned(),
    };
    let dir = store_path.parent().unwrap().canonicalize().unwrap();
    std::fs::create_dir_all(&out).unwrap();
    let wanted = args.get(8).map_or("probe,parallax,oslf", String::as_str);
    if let Some(w) = wanted
        .split(',')
        .find(|w| !["probe", "parallax", "probe-flat", "oslf"].contains(w))
    {
        eprintln!("side_by_side: unknown variant {w:?} (probe, parallax, probe-flat or oslf)");
        std::process::exit(2);
    }
    for (variant, word) in [
        (Variant::Probe, "probe"),
        (Variant::Parallax, "parallax"),
        (Variant::ProbeFlat, "probe-flat"),
        (Variant::Oslf, "oslf"),
    ] {
        if !wanted.split(',').any(|w| w == word) {
            continue;
        }
        let Some(pixels) = run(
            Job {
                variant,
                ..job.clone()
            },
            &dir,
        ) else {
            continue;
        };
        let name = match variant {
            Variant::Probe => "bevy-probe",
            Variant::Parallax => "bevy-probe-parallax",
            Variant::ProbeFlat => "bevy-probe-flat",
            Variant::Oslf => "bevy-oslf",
        };
        let path = out.join(format!("{name}.exr"));
        oslf_util::image_file::write_exr_rgba(&path, width, height, &pixels).unwrap();
        println!("{}", path.display());
    }
}
