//! `oslf tables`: the thesis's Tables 6.1 and 6.2 and a new Ashikhmin–Shirley table, on a
//! user's scene, against ray-traced ground truth, with the frame time of each method measured in
//! the same run. The measuring is `oslf_measure::thesis_tables`'s; this parses, renders the
//! truth into --out, and prints and writes the tables.

use std::path::PathBuf;

use anyhow::{bail, Context};
use oslf_format::Store;
use oslf_measure::judge::render_truth;
use oslf_measure::table::Table;
use oslf_measure::thesis_tables::{measure_tables, records_csv, Record, TablesConfig};
use oslf_scene::scene::Scene;
use oslf_trace::ground_truth::{GroundTruth, TruthSettings};
use oslf_util::door::Door;
use oslf_util::image_file;

use super::paths::{declare_scene, InputPath, OutputDir};

/// Reproduce the thesis's tables on a scene: Table 6.1 (reconstruction error) and Table 6.2
/// (mirror-reflection error of the environment map and of every OSLF blend) for each store
/// given (e.g. two cube-map resolutions), and the Ashikhmin–Shirley error for n_u = n_v ∈ {10,
/// 100, 1000} and an anisotropic lobe, M ∈ {4, 16, 64, 256}, both integration orders. Errors
/// are RMSE of L* (÷ 100, the thesis's scale) against the ground truth; frame times are medians
/// of warm frames in the same run, interleaved over every method so that the load of a shared
/// machine falls on all alike. Writes tables.md, tables.csv, tables.json and the ground
/// truth images to the output directory.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// The scene the stores were baked from.
    scene: InputPath,
    /// Stores to compare (baked from SCENE), e.g. two cube-map resolutions. Repeatable.
    #[arg(long = "store", required = true)]
    stores: Vec<InputPath>,
    /// The preset the stores were baked with.
    #[arg(short, long)]
    preset: Option<String>,
    /// Samples per pixel of the ground truth.
    #[arg(long, default_value_t = 256)]
    spp: u32,
    /// Monte Carlo sample counts M of the Ashikhmin–Shirley table.
    #[arg(long, value_delimiter = ',', default_value = "4,16,64,256")]
    glossy_m: Vec<u32>,
    /// Lobes n_u:n_v of the Ashikhmin–Shirley table.
    #[arg(
        long,
        value_delimiter = ',',
        default_value = "10:10,100:100,1000:1000,10:1000"
    )]
    lobes: Vec<String>,
    /// Skip the Ashikhmin–Shirley table.
    #[arg(long)]
    no_glossy: bool,
    #[arg(long, default_value_t = 655)]
    width: u32,
    #[arg(long, default_value_t = 460)]
    height: u32,
    /// Warm frames timed per method (median reported), in interleaved rounds.
    #[arg(long, default_value_t = 5)]
    frames: u32,
    #[arg(short, long, default_value = "tables")]
    out: OutputDir,
    #[arg(short, long)]
    quiet: bool,
}

/// The files of the tables themselves, in --out.
const OUTPUTS: [&str; 3] = ["tables.md", "tables.csv", "tables.json"];

pub fn run(args: Args) -> anyhow::Result<()> {
    let scene = Scene::load(&args.scene, args.preset.as_deref())?;
    let Some(camera) = scene.camera else {
        bail!(
            "{}: the scene has no [camera] to judge from",
            args.scene.display()
        );
    };
    let door = door(&args, &scene);
    door.check()?;
    let stores = open_stores(&args, &scene)?;
    let lobes = parse_lobes(&args.lobes)?;
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("cannot create {}", args.out.display()))?;

    // The ground truth of each shading, written into --out as it is rendered.
    let gt = GroundTruth::new(&scene, camera)?.with_progress(super::progress::bars(!args.quiet));
    let settings = TruthSettings {
        width: args.width,
        height: args.height,
        spp: args.spp,
        seed: 1,
    };
    let truth = |p: &oslf_runtime::ShadingParams, name: &str| {
        let t = render_truth(&gt, p, &settings)?;
        let path = args.out.join(format!("truth-{name}.exr"));
        door.check_output_in_dir("a truth image in --out", &path)?;
        image_file::write_exr_rgba(&path, t.width, t.height, &t.pixels)?;
        if !args.quiet {
            eprintln!("truth {:<40} {:.1} s", path.display(), t.seconds);
        }
        Ok(t)
    };
    let config = TablesConfig {
        width: args.width,
        height: args.height,
        frames: args.frames,
        glossy_m: args.glossy_m.clone(),
        lobes: if args.no_glossy { Vec::new() } else { lobes },
        quiet: args.quiet,
    };
    let report = measure_tables(stores, &config, truth)?;
    write_outputs(&args, &report.tables, &report.records)
}

/// Every file `oslf tables` reads, and those it writes into --out that it can name up front
/// (the truth images are checked as they are named).
fn door(args: &Args, scene: &Scene) -> Door {
    let mut door = Door::new();
    declare_scene(&mut door, "SCENE", scene);
    for store in &args.stores {
        door.input("--store", store);
    }
    door.output_dir("--out", &args.out);
    for name in OUTPUTS {
        door.output(format!("{name} in --out"), &args.out.join(name));
    }
    door
}

/// Opens the stores, checks each was baked from `scene` and has an environment cube, and sorts
/// them by cube-map resolution.
fn open_stores(args: &Args, scene: &Scene) -> anyhow::Result<Vec<(PathBuf, Store)>> {
    let mut stores = Vec::new();
    for path in &args.stores {
        let store =
            Store::open(path).with_context(|| format!("cannot open store {}", path.display()))?;
        let b = &store.meta().bake;
        if b.scene_hash != scene.hash || b.bounces != scene.bake.bounces {
            bail!(
                "{} was not baked from {} with these settings (scene hash or bounces differ; pass the store's --preset)",
                path.display(),
                args.scene.display()
            );
        }
        if store.env_cube_index().is_none() {
            bail!(
                "{} has no environment cube (bake with env_cube = true)",
                path.display()
            );
        }
        stores.push((path.0.clone(), store));
    }
    stores.sort_by_key(|(_, s)| s.cube_resolution());
    Ok(stores)
}

/// `--lobes`: `NU:NV` pairs, or one number for an isotropic lobe.
fn parse_lobes(lobes: &[String]) -> anyhow::Result<Vec<(f32, f32)>> {
    lobes
        .iter()
        .map(|l| {
            let (a, b) = l.split_once(':').unwrap_or((l, l));
            match (a.trim().parse::<f32>(), b.trim().parse::<f32>()) {
                (Ok(a), Ok(b)) => Ok((a, b)),
                _ => bail!("--lobes {l:?}: expected NU:NV"),
            }
        })
        .collect()
}

/// Prints the tables and writes tables.md, tables.csv and tables.json.
fn write_outputs(args: &Args, tables: &[Table], records: &[Record]) -> anyhow::Result<()> {
    let text: Vec<String> = tables.iter().map(Table::to_text).collect();
    let md: Vec<String> = tables.iter().map(Table::to_markdown).collect();
    println!("{}", text.join("\n"));
    let write = |name: &str, s: &str| -> anyhow::Result<()> {
        Ok(oslf_util::output_file::write_bytes(
            &args.out.join(name),
            s.as_bytes(),
        )?)
    };
    let [md_name, csv_name, json_name] = OUTPUTS;
    write(md_name, &format!("{}\n", md.join("\n")))?;
    write(csv_name, &records_csv(records))?;
    write(json_name, &serde_json::to_string_pretty(records)?)?;
    println!(
        "wrote {}/tables.md, tables.csv, tables.json",
        args.out.display()
    );
    Ok(())
}
