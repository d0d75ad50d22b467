//! `oslf tables`: the thesis's Tables 6.1 and 6.2 and a new Ashikhmin–Shirley table, on a
//! user's scene, against ray-traced ground truth, with the frame time of each method measured in
//! the same run.

use std::path::PathBuf;

use anyhow::{bail, Context};
use oslf_format::Store;
use oslf_measure::judge::{judge, render_truth, time_interleaved, Judgement, TimedJob};
use oslf_measure::sweep::blend_label;
use oslf_measure::table::{csv_cell, Table};
use oslf_runtime::{
    Blend, CacheConfig, GlossyFilter, Gpu, Mode, Order, Renderer, ShadingParams, Source,
};
use oslf_scene::scene::Scene;
use oslf_trace::ground_truth::{GroundTruth, TruthImage, TruthSettings};
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

/// One measured cell, for CSV and JSON.
#[derive(serde::Serialize)]
struct Record {
    table: &'static str,
    store: PathBuf,
    cube_resolution: u32,
    method: String,
    params: ShadingParams,
    judgement: Judgement,
    #[serde(skip)]
    renderer: usize,
}

/// Every measurement of the run; errors first, frame times at the end, interleaved.
struct Bench<'a> {
    args: &'a Args,
    renderers: Vec<(PathBuf, Renderer)>,
    records: Vec<Record>,
}

impl Bench<'_> {
    /// Renders `params` on renderer `r` and records its error against `truth`.
    fn measure(
        &mut self,
        table: &'static str,
        r: usize,
        method: &str,
        params: ShadingParams,
        truth: &TruthImage,
    ) -> anyhow::Result<()> {
        let (path, renderer) = &mut self.renderers[r];
        let camera = renderer.default_view();
        let (j, _) = judge(renderer, &camera, &params, truth, 0)
            .with_context(|| format!("{table}: {method} on {}", path.display()))?;
        let res = renderer.store().cube_resolution();
        if !self.args.quiet {
            eprintln!(
                "{table:<4} {method:<40} {res:>4}²  L* {:7.3}",
                j.metrics.rmse_lab[0]
            );
        }
        self.records.push(Record {
            table,
            store: path.clone(),
            cube_resolution: res,
            method: method.to_string(),
            params,
            judgement: j,
            renderer: r,
        });
        Ok(())
    }

    /// Times every record's frame, `--frames` rounds interleaved over all of them.
    fn time(&mut self) -> anyhow::Result<()> {
        let jobs: Vec<TimedJob> = self
            .records
            .iter()
            .map(|rec| TimedJob {
                renderer: rec.renderer,
                camera: self.renderers[rec.renderer].1.default_view(),
                params: rec.params,
            })
            .collect();
        let mut renderers: Vec<Renderer> = self.renderers.drain(..).map(|(_, r)| r).collect();
        let times = time_interleaved(
            &mut renderers,
            &jobs,
            self.args.width,
            self.args.height,
            self.args.frames,
        )?;
        for (rec, t) in self.records.iter_mut().zip(times) {
            rec.judgement.frame_ms = t;
            rec.judgement.warm_frames = self.args.frames;
        }
        Ok(())
    }

    fn find(&self, table: &str, r: usize, method: &str) -> Option<&Judgement> {
        self.records
            .iter()
            .find(|x| x.table == table && x.renderer == r && x.method == method)
            .map(|x| &x.judgement)
    }
}

fn l100(j: Option<&Judgement>) -> String {
    j.map_or("–".into(), |j| {
        format!("{:.4}", j.metrics.rmse_lab_normalized[0])
    })
}

fn ms(j: Option<&Judgement>) -> String {
    j.map_or("–".into(), |j| format!("{:.1}", j.frame_ms))
}

/// The glossy table's methods: (integration order, source, filter, depth correction, label).
/// The first is the thesis's (point sampling, plain lookups); the rest use filtered importance
/// sampling.
const GLOSSY_METHODS: [(Order, Source, GlossyFilter, bool, &str); 6] = [
    (
        Order::PerPoint,
        Source::Oslf,
        GlossyFilter::Point,
        false,
        "thesis",
    ),
    (
        Order::PerPoint,
        Source::Oslf,
        GlossyFilter::Mip,
        false,
        "FIS",
    ),
    (
        Order::PerPoint,
        Source::Oslf,
        GlossyFilter::Mip,
        true,
        "FIS + depth",
    ),
    (
        Order::PerDirection,
        Source::Oslf,
        GlossyFilter::Mip,
        true,
        "per direction",
    ),
    (
        Order::PerPoint,
        Source::EnvMap,
        GlossyFilter::Mip,
        false,
        "EnvMap",
    ),
    (
        Order::PerPoint,
        Source::Parallax,
        GlossyFilter::Mip,
        false,
        "Parallax",
    ),
];

/// The record name of one glossy measurement.
fn as_name(nu: f32, nv: f32, m: u32, label: &str) -> String {
    format!("AS {nu}:{nv} M={m} {label}")
}

/// The shading every table starts from: no diffuse term, so errors are the specular term's.
fn base_params() -> ShadingParams {
    ShadingParams {
        rd: 0.0,
        ..ShadingParams::default()
    }
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

    // Ground truth.
    let gt = GroundTruth::new(&scene, camera)?.with_progress(super::progress::bars(!args.quiet));
    let settings = TruthSettings {
        width: args.width,
        height: args.height,
        spp: args.spp,
        seed: 1,
    };
    let truth_of = |mode: Mode, nu: f32, nv: f32, name: &str| -> anyhow::Result<TruthImage> {
        let p = ShadingParams {
            mode,
            nu,
            nv,
            ..base_params()
        };
        let t = render_truth(&gt, &p, &settings)?;
        let path = args.out.join(format!("truth-{name}.exr"));
        door.check_output_in_dir("a truth image in --out", &path)?;
        image_file::write_exr_rgba(&path, t.width, t.height, &t.pixels)?;
        if !args.quiet {
            eprintln!("truth {:<40} {:.1} s", path.display(), t.seconds);
        }
        Ok(t)
    };
    let recon_truth = truth_of(Mode::Recon, 0.0, 0.0, "recon")?;
    let mirror_truth = truth_of(Mode::Mirror, 0.0, 0.0, "mirror")?;

    let mut bench = Bench {
        args: &args,
        renderers: Vec::new(),
        records: Vec::new(),
    };
    let mut points = Vec::new();
    for (path, store) in stores {
        points.push(store.sample_points().len());
        let r = Renderer::new(Gpu::headless()?, store, CacheConfig::default())?;
        bench.renderers.push((path, r));
    }
    let n_stores = bench.renderers.len();
    let resolutions: Vec<u32> = bench
        .renderers
        .iter()
        .map(|(_, r)| r.store().cube_resolution())
        .collect();

    // Table 6.1 and 6.2: every store.
    let mirror = mirror_methods();
    for r in 0..n_stores {
        let recon = ShadingParams {
            mode: Mode::Recon,
            ..base_params()
        };
        bench.measure("6.1", r, "recon", recon, &recon_truth)?;
        for (name, p) in &mirror {
            bench.measure("6.2", r, name, *p, &mirror_truth)?;
        }
    }

    // The Ashikhmin–Shirley table: the finest store.
    let finest = n_stores - 1;
    if !args.no_glossy {
        for &(nu, nv) in &lobes {
            let truth = truth_of(Mode::Glossy, nu, nv, &format!("glossy-{nu}-{nv}"))?;
            for &m in &args.glossy_m {
                for (order, source, glossy_filter, depth, label) in GLOSSY_METHODS {
                    let p = ShadingParams {
                        mode: Mode::Glossy,
                        nu,
                        nv,
                        m,
                        order,
                        source,
                        glossy_filter,
                        depth,
                        ..base_params()
                    };
                    bench.measure("AS", finest, &as_name(nu, nv, m, label), p, &truth)?;
                }
            }
        }
    }
    if !args.quiet {
        eprintln!(
            "timing {} configurations, {} interleaved rounds",
            bench.records.len(),
            args.frames
        );
    }
    bench.time()?;

    let mut tables = vec![
        table_6_1(&bench, &resolutions, &points),
        table_6_2(&bench, &resolutions, &mirror),
    ];
    if !args.no_glossy {
        tables.push(glossy_table(
            &bench,
            finest,
            resolutions[finest],
            &lobes,
            &args.glossy_m,
        ));
    }
    write_outputs(&args, &tables, &bench.records)
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

/// Table 6.2's rows: the two baselines (the environment map, and that map parallax-corrected),
/// then every blend of §4 (B^r and B^n at N = 1, 4, 8, 16). Each OSLF row is measured twice:
/// with plain lookups as the thesis did, and depth-corrected (records named "… depth").
fn mirror_methods() -> Vec<(String, ShadingParams)> {
    let mirror = |blend: Blend, blend_n: f32, source: Source, depth: bool| ShadingParams {
        mode: Mode::Mirror,
        blend,
        blend_n,
        source,
        depth,
        ..base_params()
    };
    let default_n = base_params().blend_n;
    let mut methods = vec![
        (
            "EnvMap".to_string(),
            mirror(Blend::Normal, default_n, Source::EnvMap, false),
        ),
        (
            "Parallax".to_string(),
            mirror(Blend::Normal, default_n, Source::Parallax, false),
        ),
    ];
    let mut blends: Vec<(String, Blend, f32)> = vec![
        ("closest distance (4.3)".into(), Blend::Distance, default_n),
        ("closest angle (4.4)".into(), Blend::Angle, default_n),
        ("B^avg (4.9)".into(), Blend::Average, default_n),
    ];
    for (name, blend) in [("B^r", Blend::Reflection), ("B^n", Blend::Normal)] {
        for n in [1.0, 4.0, 8.0, 16.0] {
            blends.push((format!("{name} N={n}"), blend, n));
        }
    }
    for (name, blend, n) in blends {
        methods.push((name.clone(), mirror(blend, n, Source::Oslf, false)));
        methods.push((
            format!("{name} depth"),
            mirror(blend, n, Source::Oslf, true),
        ));
    }
    methods
}

/// Table 6.1: reconstruction error per store.
fn table_6_1(bench: &Bench, resolutions: &[u32], points: &[usize]) -> Table {
    let mut t = Table::new(
        "Table 6.1: reconstruction error (RMSE against the ground truth; L*, a*, b* ÷ 100)",
        &[
            "cube maps",
            "sample points",
            "L*",
            "a*",
            "b*",
            "R",
            "G",
            "B",
            "frame ms",
        ],
    );
    for (r, (res, n)) in resolutions.iter().zip(points).enumerate() {
        let j = bench.find("6.1", r, "recon");
        let (lab, rgb) = j.map_or(([f64::NAN; 3], [f64::NAN; 3]), |j| {
            (j.metrics.rmse_lab_normalized, j.metrics.rmse_rgb)
        });
        let mut row = vec![format!("{res}²"), n.to_string()];
        row.extend(lab.iter().chain(&rgb).map(|v| format!("{v:.4}")));
        row.push(ms(j));
        t.push(row);
    }
    t
}

/// Table 6.2: mirror-reflection error with plain (thesis) and depth-corrected lookups, the
/// ratios to both baselines, frame times; a column group per store.
fn table_6_2(bench: &Bench, resolutions: &[u32], methods: &[(String, ShadingParams)]) -> Table {
    let mut headers = vec!["method".to_string()];
    for res in resolutions {
        for h in [
            "L*",
            "L* depth",
            "÷ EnvMap",
            "÷ EnvMap depth",
            "÷ Parallax depth",
            "ms",
            "ms depth",
        ] {
            headers.push(format!("{h} {res}²"));
        }
    }
    let header_refs: Vec<&str> = headers.iter().map(String::as_str).collect();
    let mut t = Table::new(
        "Table 6.2: mirror-reflection error (RMSE of L* ÷ 100 against the ground truth) with plain (thesis) and depth-corrected lookups, ratios to the environment map and to the parallax-corrected map, frame time",
        &header_refs,
    );
    let ratio = |j: Option<&Judgement>, base: Option<&Judgement>| {
        j.zip(base).map_or("–".into(), |(j, e)| {
            format!("{:.3}", j.metrics.rmse_lab[0] / e.metrics.rmse_lab[0])
        })
    };
    for (name, _) in methods.iter().filter(|(n, _)| !n.ends_with(" depth")) {
        let mut row = vec![name.clone()];
        for r in 0..resolutions.len() {
            let j = bench.find("6.2", r, name);
            let d = bench.find("6.2", r, &format!("{name} depth"));
            let env = bench.find("6.2", r, "EnvMap");
            let parallax = bench.find("6.2", r, "Parallax");
            row.extend([
                l100(j),
                l100(d),
                ratio(j, env),
                ratio(d, env),
                ratio(d, parallax),
                ms(j),
                ms(d),
            ]);
        }
        t.push(row);
    }
    t
}

/// The Ashikhmin–Shirley table on the finest store: a row per lobe and M.
fn glossy_table(
    bench: &Bench,
    finest: usize,
    resolution: u32,
    lobes: &[(f32, f32)],
    sample_counts: &[u32],
) -> Table {
    let mut t = Table::new(
        &format!(
            "Ashikhmin–Shirley (R_s = 1, R_d = 0, blend B^n N=4, {resolution}² cube maps): RMSE of L* ÷ 100 against the ground truth, frame time. thesis: point sampling, plain lookups, per point; FIS: filtered importance sampling; depth: depth-corrected lookups; EnvMap and Parallax with FIS",
        ),
        &[
            "n_u",
            "n_v",
            "M",
            "thesis L*",
            "ms",
            "FIS L*",
            "ms",
            "FIS + depth L*",
            "ms",
            "per direction L*",
            "ms",
            "EnvMap L*",
            "ms",
            "Parallax L*",
            "ms",
        ],
    );
    for &(nu, nv) in lobes {
        for &m in sample_counts {
            let mut row = vec![nu.to_string(), nv.to_string(), m.to_string()];
            for (_, _, _, _, label) in GLOSSY_METHODS {
                let j = bench.find("AS", finest, &as_name(nu, nv, m, label));
                row.push(l100(j));
                row.push(ms(j));
            }
            t.push(row);
        }
    }
    t
}

/// One CSV line per record.
fn records_csv(records: &[Record]) -> String {
    let mut csv = String::from(
        "table,store,cube_resolution,method,mode,blend,depth,glossy_filter,n_u,n_v,m,order,pixels,rmse_l,rmse_a,rmse_b,rmse_r,rmse_g,rmse_b_rgb,psnr_db,frame_ms,cold_ms\n",
    );
    for r in records {
        let m = &r.judgement.metrics;
        csv += &format!(
            "{},{},{},{},{},{},{},{},{},{},{},{},{},{:.5},{:.5},{:.5},{:.6},{:.6},{:.6},{},{:.3},{:.3}\n",
            r.table,
            csv_cell(&r.store.display().to_string()),
            r.cube_resolution,
            csv_cell(&r.method),
            r.params.mode.name(),
            blend_label(&r.params),
            r.params.depth,
            r.params.glossy_filter.name(),
            r.params.nu,
            r.params.nv,
            r.params.m,
            if r.params.order == Order::PerPoint {
                "per-point"
            } else {
                "per-direction"
            },
            m.pixels,
            m.rmse_lab[0],
            m.rmse_lab[1],
            m.rmse_lab[2],
            m.rmse_rgb[0],
            m.rmse_rgb[1],
            m.rmse_rgb[2],
            m.psnr_db.map_or(String::new(), |p| format!("{p:.3}")),
            r.judgement.frame_ms,
            r.judgement.cold_ms,
        );
    }
    csv
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
