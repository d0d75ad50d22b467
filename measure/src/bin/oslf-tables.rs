//! `oslf-tables`: the thesis's Tables 6.1 and 6.2 and a new Ashikhmin–Shirley table, on a
//! user's scene, against ray-traced ground truth, with the frame time of each method measured in
//! the same run.

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::{bail, Context};
use clap::Parser;
use oslf_bake::ground_truth::{GroundTruth, TruthImage, TruthSettings};
use oslf_bake::image_file;
use oslf_bake::scene::Scene;
use oslf_format::Store;
use oslf_measure::judge::{judge, render_truth, Judgement};
use oslf_measure::sweep::blend_label;
use oslf_measure::table::Table;
use oslf_runtime::{Blend, CacheConfig, Gpu, Mode, Order, Renderer, ShadingParams, Source};

/// Reproduce the thesis's tables on a scene: Table 6.1 (reconstruction error) and Table 6.2
/// (mirror-reflection error of the environment map and of every OSLF blend) for each store
/// given (e.g. two cube-map resolutions), and the Ashikhmin–Shirley error for n_u = n_v ∈ {10,
/// 100, 1000} and an anisotropic lobe, M ∈ {4, 16, 64, 256}, both integration orders. Errors
/// are RMSE of L* (÷ 100, the thesis's scale) against the ground truth; frame times are medians
/// of warm frames in the same run. Writes tables.md, tables.csv, tables.json and the ground
/// truth images to the output directory.
#[derive(Parser, Debug)]
#[command(version, about)]
struct Args {
    /// The scene the stores were baked from.
    scene: PathBuf,
    /// Stores to compare (baked from SCENE), e.g. two cube-map resolutions. Repeatable.
    #[arg(long = "store", required = true)]
    stores: Vec<PathBuf>,
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
    /// Warm frames timed per method (median reported).
    #[arg(long, default_value_t = 5)]
    frames: u32,
    #[arg(short, long, default_value = "tables")]
    out: PathBuf,
    #[arg(short, long)]
    quiet: bool,
}

fn main() -> ExitCode {
    match run(Args::parse()) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
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
}

struct Bench<'a> {
    args: &'a Args,
    records: Vec<Record>,
}

impl Bench<'_> {
    fn measure(
        &mut self,
        table: &'static str,
        renderer: &mut Renderer,
        path: &Path,
        method: String,
        params: ShadingParams,
        truth: &TruthImage,
    ) -> anyhow::Result<Judgement> {
        let camera = renderer.default_view();
        let (j, _) = judge(renderer, &camera, &params, truth, self.args.frames)
            .with_context(|| format!("{table}: {method} on {}", path.display()))?;
        if !self.args.quiet {
            eprintln!(
                "{table:<10} {:<28} {:>4}²  L* {:7.3}  {:8.2} ms",
                method,
                renderer.store().cube_resolution(),
                j.metrics.rmse_lab[0],
                j.frame_ms
            );
        }
        self.records.push(Record {
            table,
            store: path.to_path_buf(),
            cube_resolution: renderer.store().cube_resolution(),
            method,
            params,
            judgement: j.clone(),
        });
        Ok(j)
    }
}

fn l100(j: &Judgement) -> String {
    format!("{:.4}", j.metrics.rmse_lab_normalized[0])
}

fn ms(j: &Judgement) -> String {
    format!("{:.1}", j.frame_ms)
}

fn run(args: Args) -> anyhow::Result<()> {
    let scene = Scene::load(&args.scene, args.preset.as_deref())?;
    let Some(camera) = scene.camera else {
        bail!(
            "{}: the scene has no [camera] to judge from",
            args.scene.display()
        );
    };
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
        stores.push((path.clone(), store));
    }
    stores.sort_by_key(|(_, s)| s.cube_resolution());
    let lobes: Vec<(f32, f32)> = args
        .lobes
        .iter()
        .map(|l| {
            let (a, b) = l.split_once(':').unwrap_or((l, l));
            match (a.trim().parse::<f32>(), b.trim().parse::<f32>()) {
                (Ok(a), Ok(b)) => Ok((a, b)),
                _ => bail!("--lobes {l:?}: expected NU:NV"),
            }
        })
        .collect::<anyhow::Result<_>>()?;
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("cannot create {}", args.out.display()))?;

    // Ground truth.
    let gt = GroundTruth::new(&scene, camera)?;
    let settings = TruthSettings {
        width: args.width,
        height: args.height,
        spp: args.spp,
        seed: 1,
        progress: !args.quiet,
    };
    let base = ShadingParams {
        rd: 0.0,
        ..ShadingParams::default()
    };
    let truth_of = |mode: Mode, nu: f32, nv: f32, name: &str| -> anyhow::Result<TruthImage> {
        let p = ShadingParams {
            mode,
            nu,
            nv,
            ..base
        };
        let t = render_truth(&gt, &p, &settings)?;
        let path = args.out.join(format!("truth-{name}.exr"));
        image_file::write_exr_rgba(&path, t.width, t.height, &t.pixels)?;
        if !args.quiet {
            eprintln!("truth      {:<28} {:.1} s", path.display(), t.seconds);
        }
        Ok(t)
    };
    let recon_truth = truth_of(Mode::Recon, 0.0, 0.0, "recon")?;
    let mirror_truth = truth_of(Mode::Mirror, 0.0, 0.0, "mirror")?;

    let mut bench = Bench {
        args: &args,
        records: Vec::new(),
    };
    let res_names: Vec<String> = stores
        .iter()
        .map(|(_, s)| format!("{}²", s.cube_resolution()))
        .collect();

    // Table 6.1 and 6.2, per store.
    let mut t61 = Table::new(
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
    let mut mirror_methods: Vec<(String, ShadingParams)> = vec![(
        "EnvMap".into(),
        ShadingParams {
            mode: Mode::Mirror,
            source: Source::EnvMap,
            ..base
        },
    )];
    for (name, blend, n) in [
        ("closest distance (4.3)", Blend::Distance, 0.0),
        ("closest angle (4.4)", Blend::Angle, 0.0),
        ("B^avg (4.9)", Blend::Average, 0.0),
    ] {
        mirror_methods.push((
            name.into(),
            ShadingParams {
                mode: Mode::Mirror,
                blend,
                blend_n: n,
                ..base
            },
        ));
    }
    for (name, blend) in [("B^r", Blend::Reflection), ("B^n", Blend::Normal)] {
        for n in [1.0, 4.0, 8.0, 16.0] {
            mirror_methods.push((
                format!("{name} N={n}"),
                ShadingParams {
                    mode: Mode::Mirror,
                    blend,
                    blend_n: n,
                    ..base
                },
            ));
        }
    }
    let mut headers = vec!["method".to_string()];
    for r in &res_names {
        headers.push(format!("L* {r}"));
        headers.push(format!("÷ EnvMap {r}"));
        headers.push(format!("ms {r}"));
    }
    let header_refs: Vec<&str> = headers.iter().map(String::as_str).collect();
    let mut t62 = Table::new(
        "Table 6.2: mirror-reflection error (RMSE of L* ÷ 100 against the ground truth), ratio to the environment map, frame time",
        &header_refs,
    );
    let mut cells: Vec<Vec<String>> = mirror_methods
        .iter()
        .map(|(n, _)| vec![n.clone()])
        .collect();
    let mut renderers = Vec::new();
    for (path, store) in stores {
        let points = store.sample_points().len();
        let res = store.cube_resolution();
        if store.env_cube_index().is_none() {
            bail!(
                "{} has no environment cube (bake with env_cube = true)",
                path.display()
            );
        }
        let mut r = Renderer::new(Gpu::headless()?, store, CacheConfig::default())?;
        let recon = ShadingParams {
            mode: Mode::Recon,
            ..base
        };
        let j = bench.measure("6.1", &mut r, &path, "recon".into(), recon, &recon_truth)?;
        let (lab, rgb) = (j.metrics.rmse_lab_normalized, j.metrics.rmse_rgb);
        t61.push(vec![
            format!("{res}²"),
            points.to_string(),
            format!("{:.4}", lab[0]),
            format!("{:.4}", lab[1]),
            format!("{:.4}", lab[2]),
            format!("{:.4}", rgb[0]),
            format!("{:.4}", rgb[1]),
            format!("{:.4}", rgb[2]),
            ms(&j),
        ]);
        let mut env_error = f64::NAN;
        for (k, (name, p)) in mirror_methods.iter().enumerate() {
            let j = bench.measure("6.2", &mut r, &path, name.clone(), *p, &mirror_truth)?;
            let e = j.metrics.rmse_lab[0];
            if k == 0 {
                env_error = e;
            }
            cells[k].push(l100(&j));
            cells[k].push(format!("{:.3}", e / env_error));
            cells[k].push(ms(&j));
        }
        renderers.push((path, r));
    }
    for row in cells {
        t62.push(row);
    }

    // The Ashikhmin–Shirley table on the finest store.
    let mut tas = Table::new(
        "Ashikhmin–Shirley (R_s = 1, R_d = 0, blend B^n N=4): RMSE of L* ÷ 100 against the ground truth, frame time",
        &[
            "n_u", "n_v", "M", "per point L*", "ms", "per direction L*", "ms", "EnvMap L*", "ms",
        ],
    );
    if !args.no_glossy {
        let Some((path, r)) = renderers.last_mut() else {
            bail!("no store");
        };
        for &(nu, nv) in &lobes {
            let truth = truth_of(Mode::Glossy, nu, nv, &format!("glossy-{nu}-{nv}"))?;
            for &m in &args.glossy_m {
                let mut row = vec![nu.to_string(), nv.to_string(), m.to_string()];
                for (order, source, label) in [
                    (Order::PerPoint, Source::Oslf, "per point"),
                    (Order::PerDirection, Source::Oslf, "per direction"),
                    (Order::PerPoint, Source::EnvMap, "EnvMap"),
                ] {
                    let p = ShadingParams {
                        mode: Mode::Glossy,
                        nu,
                        nv,
                        m,
                        order,
                        source,
                        ..base
                    };
                    let name = format!("AS {nu}:{nv} M={m} {label} ({})", blend_label(&p));
                    let j = bench.measure("AS", r, path, name, p, &truth)?;
                    row.push(l100(&j));
                    row.push(ms(&j));
                }
                tas.push(row);
            }
        }
    }

    let mut text = format!("{}\n{}\n", t61.to_text(), t62.to_text());
    let mut md = format!("{}\n{}\n", t61.to_markdown(), t62.to_markdown());
    if !args.no_glossy {
        text += &tas.to_text();
        md += &format!("\n{}", tas.to_markdown());
    }
    print!("{text}");
    let mut csv = String::from(
        "table,store,cube_resolution,method,mode,blend,n_u,n_v,m,order,pixels,rmse_l,rmse_a,rmse_b,rmse_r,rmse_g,rmse_b_rgb,psnr_db,frame_ms,cold_ms\n",
    );
    for r in &bench.records {
        let m = &r.judgement.metrics;
        csv +=
            &format!(
            "{},{},{},{},{},{},{},{},{},{},{},{:.5},{:.5},{:.5},{:.6},{:.6},{:.6},{},{:.3},{:.3}\n",
            r.table,
            oslf_measure::table::csv_cell(&r.store.display().to_string()),
            r.cube_resolution,
            oslf_measure::table::csv_cell(&r.method),
            r.params.mode.name(),
            blend_label(&r.params),
            r.params.nu,
            r.params.nv,
            r.params.m,
            if r.params.order == Order::PerPoint { "per-point" } else { "per-direction" },
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
    let write = |name: &str, s: &str| -> anyhow::Result<()> {
        let p = args.out.join(name);
        std::fs::write(&p, s).with_context(|| format!("cannot write {}", p.display()))
    };
    write("tables.md", &md)?;
    write("tables.csv", &csv)?;
    write(
        "tables.json",
        &serde_json::to_string_pretty(&bench.records)?,
    )?;
    println!(
        "wrote {}/tables.md, tables.csv, tables.json",
        args.out.display()
    );
    Ok(())
}
