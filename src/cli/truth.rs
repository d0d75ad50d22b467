//! `oslf truth`: ray-traced ground truth for the runtime's modes (see
//! `oslf_trace::ground_truth`).

use std::path::{Path, PathBuf};

use anyhow::bail;
use glam::Vec3;
use oslf_scene::scene::Scene;
use oslf_trace::ashikhmin_shirley::AsLobe;
use oslf_trace::cube_floor::{CubeFloor, FloorLookup};
use oslf_trace::ground_truth::{compose, GroundTruth, Term, TruthImage, TruthSettings};
use oslf_util::door::Door;
use oslf_util::image_file;

use super::paths::{declare_scene, InputPath, OutputPrefix};

/// Render the ground truth a runtime image is judged against: the scene's camera, one ray per
/// pixel centre onto the OSLF object alone, shaded with the bake's path tracer in the scene the
/// store was baked from. Writes OpenEXR (linear RGB, alpha = object mask) and a PNG beside it.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// The scene file the store was baked from.
    scene: InputPath,
    /// The preset the store was baked with (it may change `bounces`).
    #[arg(short, long)]
    preset: Option<String>,
    /// Check that this store was baked from this scene (scene hash and bounces).
    #[arg(long)]
    store: Option<InputPath>,
    /// Comma-separated: recon, mirror, recon-mirror, glossy, recon-glossy, pbr (the runtime's modes).
    #[arg(short, long, default_value = "recon,mirror,recon-mirror")]
    modes: String,
    /// Output prefix: writes PREFIX-MODE.exr and PREFIX-MODE.png.
    #[arg(short, long, default_value = "truth")]
    output: OutputPrefix,
    /// Samples per pixel (paths for recon and mirror, lobe samples for glossy).
    #[arg(long, default_value_t = 256)]
    spp: u32,
    #[arg(long, default_value_t = 655)]
    width: u32,
    #[arg(long, default_value_t = 460)]
    height: u32,
    /// Ashikhmin–Shirley specular reflectance R_s.
    #[arg(long, default_value_t = 1.0)]
    rs: f64,
    /// Ashikhmin–Shirley exponent along the tangent ∂x/∂u.
    #[arg(long, default_value_t = 100.0)]
    nu: f64,
    /// Ashikhmin–Shirley exponent along the bitangent.
    #[arg(long, default_value_t = 100.0)]
    nv: f64,
    /// glTF metallic factor of the pbr mode's material (base colour: the object's C_s, or a
    /// mesh object's base colour texture) [default: each object's own metallic-roughness
    /// material, its metallic-roughness texture included, else 1]. With this flag or
    /// --roughness, every object is drawn with the flags' factors (as `oslf render`).
    #[arg(long)]
    metallic: Option<f32>,
    /// glTF roughness of the pbr mode's material [default: the object's own, else 0.3].
    #[arg(long)]
    roughness: Option<f32>,
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Exposure of the PNG previews, 1e-6 to 1e6.
    #[arg(long, default_value_t = 1.0, value_parser = super::args::parse_exposure)]
    exposure: f32,
    /// What pixels off the object show: `none` (black, the default) or `scene` (the scene
    /// behind the object, path traced from the camera with --spp paths per pixel). Alpha stays
    /// the object mask either way, so `oslf compare` is unaffected.
    #[arg(long, value_enum, default_value_t = TruthBackground::None)]
    background: TruthBackground,
    /// Draw the mirror term as a noise-free cube map of N² texels a face, captured at each
    /// shaded point itself, would give it: the floor of any store with N² cube maps, however
    /// its points are placed (only with `-m mirror`; `oslf compare` it against the truth).
    #[arg(long, value_name = "N")]
    cube_floor: Option<u32>,
    /// How --cube-floor's cube is read: `bilinear` (the runtime's lookup) or `nearest`.
    #[arg(long, value_enum, default_value_t = CubeFloorLookup::Bilinear, requires = "cube_floor")]
    cube_floor_lookup: CubeFloorLookup,
    /// Worker threads [default: all cores]; the images are identical for any count.
    #[arg(short = 'j', long)]
    threads: Option<usize>,
    /// No progress bar.
    #[arg(short, long)]
    quiet: bool,
}

/// `--background`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
enum TruthBackground {
    None,
    Scene,
}

/// `--cube-floor-lookup`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
enum CubeFloorLookup {
    Bilinear,
    Nearest,
}

const MODES: [&str; 6] = [
    "recon",
    "mirror",
    "recon-mirror",
    "glossy",
    "recon-glossy",
    "pbr",
];

pub fn run(args: Args) -> anyhow::Result<()> {
    super::args::in_pool(args.threads, || render_all(&args))
}

fn render_all(args: &Args) -> anyhow::Result<()> {
    let modes = parse_modes(&args.modes)?;
    let cube_floor = parse_cube_floor(args, &modes)?;
    // The terms' materials, checked before any work.
    let lobe = AsLobe {
        rs: args.rs,
        nu: args.nu,
        nv: args.nv,
    };
    let defaults = oslf_runtime::PbrMaterial::default();
    let pbr_term = Term::Pbr {
        metallic: args.metallic.unwrap_or(defaults.metallic),
        roughness: args.roughness.unwrap_or(defaults.roughness),
        object_material: args.metallic.is_none() && args.roughness.is_none(),
    };
    let wants = |m: &str| modes.contains(&m);
    if wants("glossy") || wants("recon-glossy") {
        Term::Glossy(lobe).validate()?;
    }
    if wants("pbr") {
        pbr_term.validate()?;
    }
    let scene = Scene::load(&args.scene, args.preset.as_deref())?;
    door(args, &scene, &modes).check()?;
    if let Some(path) = &args.store {
        let store = oslf_format::Store::open(path)?;
        let bake = &store.meta().bake;
        if bake.scene_hash != scene.hash {
            bail!(
                "{} was not baked from {} (the scene file's hash differs)",
                path.display(),
                args.scene.display()
            );
        }
        if bake.bounces != scene.bake.bounces {
            bail!(
                "{} was baked with {} bounces, the scene (preset {:?}) has {}: pass the store's --preset",
                path.display(),
                bake.bounces,
                args.preset,
                scene.bake.bounces
            );
        }
    }
    let Some(camera) = scene.camera else {
        bail!(
            "{}: the scene has no [camera]; the ground truth is rendered from it",
            args.scene.display()
        );
    };
    let truth = GroundTruth::new(&scene, camera)?
        .with_progress(super::progress::bars(!args.quiet))
        .with_cube_floor(cube_floor)?;
    let settings = TruthSettings {
        width: args.width,
        height: args.height,
        spp: args.spp,
        seed: args.seed,
    };
    let recon = if wants("recon") || wants("recon-mirror") || wants("recon-glossy") {
        Some(timed("recon", || truth.render(Term::Recon, &settings))?)
    } else {
        None
    };
    let mirror = if wants("mirror") || wants("recon-mirror") {
        Some(timed("mirror", || truth.render(Term::Mirror, &settings))?)
    } else {
        None
    };
    let glossy = if wants("glossy") || wants("recon-glossy") {
        Some(timed("glossy", || {
            truth.render(Term::Glossy(lobe), &settings)
        })?)
    } else {
        None
    };
    let pbr = if wants("pbr") {
        Some(timed("pbr", || truth.render(pbr_term, &settings))?)
    } else {
        None
    };
    let background = match args.background {
        TruthBackground::None => None,
        TruthBackground::Scene => Some(timed("background", || truth.render_background(&settings))?),
    };
    for m in &modes {
        let image = match *m {
            "recon" => recon.clone(),
            "mirror" => mirror.clone(),
            "glossy" => glossy.clone(),
            "pbr" => pbr.clone(),
            "recon-mirror" => recon
                .as_ref()
                .zip(mirror.as_ref())
                .map(|(a, b)| compose(a, b))
                .transpose()?,
            "recon-glossy" => recon
                .as_ref()
                .zip(glossy.as_ref())
                .map(|(a, b)| compose(a, b))
                .transpose()?,
            _ => None,
        };
        let Some(mut image) = image else { continue };
        if let Some(bg) = &background {
            // Off the object (alpha 0) the term images are black and the background holds the
            // scene; on the object the background is zero.
            for (p, b) in image.pixels.iter_mut().zip(&bg.pixels) {
                if p[3] == 0.0 {
                    *p = *b;
                }
            }
        }
        let exr = output_path(&args.output, m, "exr");
        write(&exr, &image, args.exposure)?;
        println!("{m:<13} {}", exr.display());
    }
    Ok(())
}

/// `--cube-floor` and its lookup, checked: a resolution the bake takes, the mirror mode alone.
fn parse_cube_floor(args: &Args, modes: &[&str]) -> anyhow::Result<Option<CubeFloor>> {
    let Some(resolution) = args.cube_floor else {
        return Ok(None);
    };
    let floor = CubeFloor {
        resolution,
        lookup: match args.cube_floor_lookup {
            CubeFloorLookup::Bilinear => FloorLookup::Bilinear,
            CubeFloorLookup::Nearest => FloorLookup::Nearest,
        },
    };
    floor
        .validate()
        .map_err(|e| anyhow::anyhow!("--cube-floor: {e}"))?;
    if modes != ["mirror"] {
        bail!(
            "--cube-floor draws the mirror term only: pass -m mirror (--modes is {:?})",
            args.modes
        );
    }
    Ok(Some(floor))
}

/// `--modes`: each mode once, in the order first named; an unknown one is an error.
fn parse_modes(list: &str) -> anyhow::Result<Vec<&str>> {
    let mut modes: Vec<&str> = Vec::new();
    for m in list.split(',').map(str::trim) {
        if !MODES.contains(&m) {
            bail!(
                "--modes: unknown mode {m:?} (expected one of {})",
                MODES.join(", ")
            );
        }
        if !modes.contains(&m) {
            modes.push(m);
        }
    }
    Ok(modes)
}

/// Every file `oslf truth` reads and writes: the scene's, the store, each mode's EXR and PNG.
fn door(args: &Args, scene: &Scene, modes: &[&str]) -> Door {
    let mut door = Door::new();
    declare_scene(&mut door, "SCENE", scene);
    if let Some(path) = &args.store {
        door.input("--store", path);
    }
    for m in modes {
        let exr = output_path(&args.output, m, "exr");
        door.output(format!("the --output image of mode {m}"), &exr)
            .output(format!("the PNG of mode {m}"), &exr.with_extension("png"));
    }
    door
}

fn timed(
    name: &str,
    f: impl FnOnce() -> oslf_scene::Result<TruthImage>,
) -> anyhow::Result<TruthImage> {
    let image = f()?;
    let rays = image.rays.total() as f64;
    eprintln!(
        "{name:<13} {:.1} s, {:.1} M rays, {:.2} Mrays/s",
        image.seconds,
        rays / 1e6,
        rays / image.seconds.max(1e-9) / 1e6
    );
    Ok(image)
}

fn output_path(prefix: &Path, mode: &str, ext: &str) -> PathBuf {
    let mut name = prefix.as_os_str().to_os_string();
    name.push(format!("-{mode}.{ext}"));
    PathBuf::from(name)
}

fn write(exr: &Path, image: &TruthImage, exposure: f32) -> anyhow::Result<()> {
    image_file::write_exr_rgba(exr, image.width, image.height, &image.pixels)?;
    let rgb: Vec<Vec3> = image
        .pixels
        .iter()
        .map(|p| Vec3::new(p[0], p[1], p[2]))
        .collect();
    image_file::write_png(
        &exr.with_extension("png"),
        image.width,
        image.height,
        &rgb,
        exposure,
    )?;
    Ok(())
}
