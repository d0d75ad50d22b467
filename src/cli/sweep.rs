//! `oslf sweep`: the speed/accuracy sweep and the sensitivity analysis (see
//! `oslf_measure::sweep`).

use std::path::Path;

use anyhow::{bail, Context};
use oslf_measure::error::MeasureError;
use oslf_measure::judge::render_truth;
use oslf_measure::plot::plot_tradeoff;
use oslf_measure::sweep::{
    check_changes, parse_vary, run_sweep, SweepConfig, SweepRow, RUNTIME_KEYS,
};
use oslf_measure::sweep_report::{front_members, panels, rows_table, sensitivity_table, Fronts};
use oslf_runtime::{
    AshikhminShirley, Mode, MonteCarlo, Order, PbrMaterial, ShadingParams, ShadingParts,
};
use oslf_scene::scene::Scene;
use oslf_trace::ground_truth::{GroundTruth, TruthSettings};
use oslf_util::door::Door;
use oslf_util::image_file;

use super::paths::{declare_scene, InputPath, OutputDir};

/// Bake variants of a scene and render them with variants of the runtime settings, one setting
/// changed at a time from the defaults; judge every combination against the ray-traced ground
/// truth (RMSE of L*) and time it (frame times interleaved over all configurations; bake CPU
/// time). Writes sweep.csv, sweep.json, the sensitivity table (sensitivity.md) and the plot
/// (tradeoff.png, tradeoff.svg): error against frame time for the runtime settings on the
/// default bake, and against bake CPU time for the bake settings with the default runtime, each
/// with its Pareto front.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// The scene file; its settings (with --preset) are the defaults.
    scene: InputPath,
    #[arg(short, long)]
    preset: Option<String>,
    /// What captures the default store's cube maps (and every variation's but
    /// `--vary device=…`): auto, cpu or gpu [default: the scene's `[bake] device`].
    #[arg(long, value_parser = parse_device)]
    device: Option<oslf_scene::scene::DeviceChoice>,
    /// KEY=V1,V2,...: bake keys epsilon, sample_count, cube_resolution, phi_samplemap,
    /// samples_per_texel, sample_map_resolution, mantissa_bits, device; runtime keys phi_shader, blend (distance,
    /// angle, avg, rN, nN, envmap), m, order (per-point, per-direction, per-point-visible,
    /// per-point-searched). Repeatable.
    /// [default: cube_resolution=16,64 sample_count=150,600 epsilon=0.05,0.2 phi_samplemap=60
    /// phi_shader=45,85 blend=distance,angle,avg,r4,envmap]
    #[arg(long)]
    vary: Vec<String>,
    /// The runtime mode judged (its ground truth is rendered).
    #[arg(long, default_value = "recon-mirror")]
    mode: Mode,
    /// The default blend and power N (as --vary blend= takes it: distance, angle, avg, rN, nN).
    #[arg(long, default_value = "n4")]
    blend: String,
    /// Default φ_shader (degrees).
    #[arg(long, default_value_t = 65.0)]
    phi_shader: f32,
    /// Glossy and pbr modes: samples M, R_s, n_u, n_v, order.
    #[arg(short = 'M', long, default_value_t = 16)]
    m: u32,
    #[arg(long, default_value_t = 1.0)]
    rs: f32,
    #[arg(long, default_value_t = 100.0)]
    nu: f32,
    #[arg(long, default_value_t = 100.0)]
    nv: f32,
    #[arg(long, default_value = "per-point")]
    order: String,
    /// The pbr mode's glTF metallic factor and roughness [default: each object's own
    /// metallic-roughness material, else 1 and 0.3]; either flag sets them for every object.
    #[arg(long)]
    metallic: Option<f32>,
    #[arg(long)]
    roughness: Option<f32>,
    /// Samples per pixel of the ground truth.
    #[arg(long, default_value_t = 256)]
    spp: u32,
    #[arg(long, default_value_t = 655)]
    width: u32,
    #[arg(long, default_value_t = 460)]
    height: u32,
    /// Warm frames timed per configuration (median reported).
    #[arg(long, default_value_t = 5)]
    frames: u32,
    /// Output directory (the variant stores go to OUT/stores and are reused by later runs
    /// when their settings match).
    #[arg(short, long, default_value = "sweep")]
    out: OutputDir,
    /// No progress output.
    #[arg(short, long)]
    quiet: bool,
}

const DEFAULT_VARY: [&str; 6] = [
    "cube_resolution=16,64",
    "sample_count=150,600",
    "epsilon=0.05,0.2",
    "phi_samplemap=60",
    "phi_shader=45,85",
    "blend=distance,angle,avg,r4,envmap",
];

/// The files of the sweep's results, in --out.
const OUTPUTS: [&str; 5] = [
    "sweep.csv",
    "sensitivity.md",
    "sweep.json",
    "tradeoff.png",
    "tradeoff.svg",
];

/// The runtime settings the variations start from: the mode's, with the flags it has (the
/// others are checked, not read).
fn default_params(args: &Args) -> anyhow::Result<ShadingParams> {
    let defaults = ShadingParts::default();
    let mut params = ShadingParts {
        phi_shader_deg: args.phi_shader,
        lobe: AshikhminShirley {
            rs: args.rs,
            nu: args.nu,
            nv: args.nv,
            ..defaults.lobe
        },
        integration: MonteCarlo {
            m: args.m,
            order: args
                .order
                .parse::<Order>()
                .map_err(|e| anyhow::anyhow!("--order: {e}"))?,
            ..defaults.integration
        },
        material: PbrMaterial {
            metallic: args.metallic.unwrap_or(defaults.material.metallic),
            roughness: args.roughness.unwrap_or(defaults.material.roughness),
            object_material: args.metallic.is_none() && args.roughness.is_none(),
        },
        ..defaults
    }
    .params(args.mode)?;
    if params.lookup().is_some() {
        oslf_measure::sweep::apply_runtime(
            &mut params,
            &oslf_measure::sweep::Change {
                key: "blend".into(),
                value: args.blend.clone(),
            },
        )
        .map_err(|e| match e {
            MeasureError::Vary { problem, .. } => anyhow::anyhow!("--blend: {problem}"),
            e => e.into(),
        })?;
    }
    Ok(params)
}

pub fn run(args: Args) -> anyhow::Result<()> {
    let mut scene = Scene::load(&args.scene, args.preset.as_deref())?;
    if let Some(d) = args.device {
        scene.bake.device = d;
    }
    let Some(camera) = scene.camera else {
        bail!(
            "{}: the scene has no [camera] to judge from",
            args.scene.display()
        );
    };
    let params = default_params(&args)?;
    let specs: Vec<String> = if args.vary.is_empty() {
        DEFAULT_VARY.iter().map(|s| s.to_string()).collect()
    } else {
        args.vary.clone()
    };
    let mut changes = Vec::new();
    for s in &specs {
        for c in parse_vary(s).map_err(vary_flag)? {
            // A runtime key the mode does not have: refused when asked for, left out of the
            // default variations.
            let is_runtime = RUNTIME_KEYS.contains(&c.key.as_str());
            if is_runtime {
                if let Err(e) = oslf_measure::sweep::apply_runtime(&mut params.clone(), &c) {
                    if args.vary.is_empty() {
                        continue;
                    }
                    bail!("--vary {s}: {e}");
                }
            }
            changes.push(c);
        }
    }
    check_changes(&scene, &changes).map_err(vary_flag)?;
    let truth_path = args.out.join(format!("truth-{}.exr", params.mode().name()));
    let mut door = Door::new();
    declare_scene(&mut door, "SCENE", &scene);
    door.output_dir("--out", &args.out)
        .output("the truth image in --out", &truth_path);
    for name in OUTPUTS {
        door.output(format!("{name} in --out"), &args.out.join(name));
    }
    door.check()?;
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("cannot create {}", args.out.display()))?;

    let truth_settings = TruthSettings {
        width: args.width,
        height: args.height,
        spp: args.spp,
        seed: 1,
    };
    let gt = GroundTruth::new(&scene, camera)?.with_progress(super::progress::bars(!args.quiet));
    let truth = render_truth(&gt, &params, &truth_settings)?;
    image_file::write_exr_rgba(&truth_path, truth.width, truth.height, &truth.pixels)?;
    if !args.quiet {
        eprintln!(
            "ground truth {} ({:.1} s)",
            truth_path.display(),
            truth.seconds
        );
    }

    let config = SweepConfig {
        scene: &scene,
        params,
        changes,
        store_dir: args.out.join("stores"),
        warm_frames: args.frames,
        progress: super::progress::bars(!args.quiet),
        door: &door,
    };
    let quiet = args.quiet;
    let rows = run_sweep(&config, &truth, |r| {
        if !quiet {
            eprintln!(
                "{:<40} L* {:7.3}",
                r.label(),
                r.judgement.metrics.rmse_lab[0]
            );
        }
    })
    .map_err(vary_flag)?;
    let fronts = Fronts::of(&rows);
    Outputs {
        args: &args,
        params: &params,
        rows: &rows,
        fronts: &fronts,
    }
    .write()
}

/// What `oslf sweep` writes: the rows with their places on the two Pareto fronts.
#[derive(Clone, Copy)]
struct Outputs<'a> {
    args: &'a Args,
    params: &'a ShadingParams,
    rows: &'a [SweepRow],
    fronts: &'a Fronts,
}

impl Outputs<'_> {
    fn write(&self) -> anyhow::Result<()> {
        let Outputs {
            args,
            params,
            rows,
            fronts,
        } = *self;
        let all = rows_table(
            params,
            &args.scene.display().to_string(),
            (args.width, args.height),
            rows,
            fronts,
        );
        let sensitivity = sensitivity_table(rows);
        print!("{}\n{}", all.to_text(), sensitivity.to_text());
        self.print_fronts();
        write(&args.out.join("sweep.csv"), &all.to_csv())?;
        write(
            &args.out.join("sensitivity.md"),
            &format!("{}\n{}", sensitivity.to_markdown(), all.to_markdown()),
        )?;
        let json = serde_json::json!({
            "mode": params.mode().name(),
            "scene": args.scene.0,
            "width": args.width,
            "height": args.height,
            "truth_spp": args.spp,
            "rows": rows.iter().zip(&fronts.frame).zip(&fronts.bake).map(|((r, f), b)| serde_json::json!({
                "label": r.label(), "front_frame_time": f, "front_bake_time": b, "row": r,
            })).collect::<Vec<_>>(),
        });
        write(
            &args.out.join("sweep.json"),
            &serde_json::to_string_pretty(&json)?,
        )?;
        self.plot_fronts()?;
        println!(
            "wrote {}/sweep.csv, sweep.json, sensitivity.md, tradeoff.png, tradeoff.svg",
            args.out.display()
        );
        Ok(())
    }

    /// The two Pareto fronts, and whether the defaults are on them.
    fn print_fronts(&self) {
        for (name, front) in [
            (
                "frame time (runtime settings, default bake)",
                &self.fronts.frame,
            ),
            (
                "bake CPU time (bake settings, default runtime)",
                &self.fronts.bake,
            ),
        ] {
            let (labels, default_on) = front_members(self.rows, front);
            println!(
                "\nPareto front of RMSE L* against {name}: {}\nthe defaults are {}on it",
                labels.join("; "),
                if default_on { "" } else { "NOT " }
            );
        }
    }

    /// tradeoff.png and tradeoff.svg: error against frame time and against bake time.
    fn plot_fronts(&self) -> anyhow::Result<()> {
        plot_tradeoff(
            &panels(self.params, self.rows, self.fronts),
            &self.args.out.join("tradeoff.png"),
            &self.args.out.join("tradeoff.svg"),
            (1500, 640),
        )?;
        Ok(())
    }
}

fn write(path: &Path, text: &str) -> anyhow::Result<()> {
    Ok(oslf_util::output_file::write_bytes(path, text.as_bytes())?)
}

/// `e`, where a variation cannot be applied, naming the `--vary` flag that gave it.
fn vary_flag(e: MeasureError) -> anyhow::Error {
    match e {
        MeasureError::Vary {
            setting: Some(setting),
            problem,
        } => anyhow::anyhow!("--vary {setting}: {problem}"),
        MeasureError::Vary {
            setting: None,
            problem,
        } => anyhow::anyhow!("--vary: {problem}"),
        e => e.into(),
    }
}

fn parse_device(s: &str) -> Result<oslf_scene::scene::DeviceChoice, String> {
    s.parse()
}
