//! The thesis's Tables 6.1 and 6.2 and a new Ashikhmin–Shirley table, on a user's scene,
//! against ray-traced ground truth, with the frame time of each method measured in the same run
//! (`oslf tables`): Table 6.1 the reconstruction error per store, Table 6.2 the
//! mirror-reflection error of the environment map, its parallax-corrected form and every OSLF
//! blend, with plain (thesis) and depth-corrected lookups; the Ashikhmin–Shirley table the
//! glossy error per lobe and M for the thesis's integration and its successors.

use std::path::PathBuf;

use oslf_format::Store;
use oslf_runtime::{
    AshikhminShirley, Blend, CacheConfig, Glossy, GlossyFilter, Gpu, Lookup, Mirror, Mode,
    MonteCarlo, Order, Renderer, RuntimeError, SampleFilter, ShadingParams, Source,
};
use oslf_trace::ground_truth::TruthImage;

use crate::error::{MeasureError, Result};
use crate::judge::{judge, time_interleaved, Judgement, TimedJob};
use crate::sweep::blend_label;
use crate::table::{csv_cell, Table};

/// What to measure besides the stores and the truth.
#[derive(Clone, Debug)]
pub struct TablesConfig {
    /// Image size of every render (the truth's).
    pub width: u32,
    pub height: u32,
    /// Warm frames timed per method (median reported), in interleaved rounds.
    pub frames: u32,
    /// Monte Carlo sample counts M of the Ashikhmin–Shirley table.
    pub glossy_m: Vec<u32>,
    /// Lobes (n_u, n_v) of the Ashikhmin–Shirley table; empty skips the table.
    pub lobes: Vec<(f32, f32)>,
    /// No progress lines on stderr.
    pub quiet: bool,
}

/// The tables and every measurement they were made from.
pub struct TablesReport {
    pub tables: Vec<Table>,
    pub records: Vec<Record>,
}

/// The truth `truth` renders for `mode` with the lobe (`nu`, `nv`), named `name`.
fn truth_of(
    truth: &mut dyn FnMut(&ShadingParams, &str) -> Result<TruthImage>,
    mode: Mode,
    nu: f32,
    nv: f32,
    name: &str,
) -> Result<TruthImage> {
    let mut p = ShadingParams::of_mode(mode);
    if let Ok(lobe) = p.lobe_mut() {
        (lobe.nu, lobe.nv) = (nu, nv);
    }
    truth(&p, name)
}

/// Measures every table on `stores` (sorted by cube-map resolution, each with an environment
/// cube), judged against the images `truth` renders for a shading (named for its file). The
/// Ashikhmin–Shirley table uses the finest store.
pub fn measure_tables(
    stores: Vec<(PathBuf, Store)>,
    config: &TablesConfig,
    mut truth: impl FnMut(&ShadingParams, &str) -> Result<TruthImage>,
) -> Result<TablesReport> {
    if stores.is_empty() {
        return Err(MeasureError::Invalid(
            "the tables need at least one store".into(),
        ));
    }
    let recon_truth = truth_of(&mut truth, Mode::Recon, 0.0, 0.0, "recon")?;
    let mirror_truth = truth_of(&mut truth, Mode::Mirror, 0.0, 0.0, "mirror")?;
    let mut bench = Bench {
        config,
        renderers: Vec::new(),
        records: Vec::new(),
    };
    let mut points = Vec::new();
    for (path, store) in stores {
        points.push(store.sample_points().len());
        let gpu = Gpu::headless().map_err(RuntimeError::from)?;
        let r = Renderer::new(gpu, store, CacheConfig::default())?;
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
        let recon = ShadingParams::of_mode(Mode::Recon);
        bench.measure("6.1", r, "recon", recon, &recon_truth)?;
        for (name, p) in &mirror {
            bench.measure("6.2", r, name, *p, &mirror_truth)?;
        }
    }

    // The Ashikhmin–Shirley table: the finest store.
    let finest = n_stores - 1;
    // The thesis's blend (B^n, N = 4), which its table used, whatever the runtime's default.
    let (default_blend, default_n) = (Blend::Normal, Lookup::THESIS_BLEND_N);
    for &(nu, nv) in &config.lobes {
        let name = format!("glossy-{nu}-{nv}");
        let glossy_truth = truth_of(&mut truth, Mode::Glossy, nu, nv, &name)?;
        for &m in &config.glossy_m {
            for (order, source, filter, depth, label) in GLOSSY_METHODS {
                let p = ShadingParams::Glossy(Glossy {
                    lookup: Lookup::of_source(source, default_blend, default_n, None),
                    depth,
                    lobe: AshikhminShirley {
                        nu,
                        nv,
                        ..Default::default()
                    },
                    integration: MonteCarlo {
                        m,
                        order,
                        filter,
                        ..Default::default()
                    },
                });
                let method = as_name(nu, nv, m, label);
                bench.measure("AS", finest, &method, p, &glossy_truth)?;
            }
        }
    }
    if !config.quiet {
        eprintln!(
            "timing {} configurations, {} interleaved rounds",
            bench.records.len(),
            config.frames
        );
    }
    bench.time()?;

    let mut tables = vec![
        table_6_1(&bench, &resolutions, &points),
        table_6_2(&bench, &resolutions, &mirror),
    ];
    if !config.lobes.is_empty() {
        tables.push(glossy_table(
            &bench,
            finest,
            resolutions[finest],
            &config.lobes,
            &config.glossy_m,
        ));
    }
    Ok(TablesReport {
        tables,
        records: bench.records,
    })
}

/// One measured cell, for CSV and JSON.
#[derive(serde::Serialize)]
pub struct Record {
    pub table: &'static str,
    pub store: PathBuf,
    pub cube_resolution: u32,
    pub method: String,
    pub params: ShadingParams,
    pub judgement: Judgement,
    #[serde(skip)]
    renderer: usize,
}

/// Every measurement of the run; errors first, frame times at the end, interleaved.
struct Bench<'a> {
    config: &'a TablesConfig,
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
    ) -> Result<()> {
        let (path, renderer) = &mut self.renderers[r];
        let camera = renderer.default_view();
        let (j, _) = judge(renderer, &camera, &params, truth, 0).map_err(|e| {
            MeasureError::Invalid(format!("{table}: {method} on {}: {e}", path.display()))
        })?;
        let res = renderer.store().cube_resolution();
        if !self.config.quiet {
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

    /// Times every record's frame, `frames` rounds interleaved over all of them.
    fn time(&mut self) -> Result<()> {
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
            self.config.width,
            self.config.height,
            self.config.frames,
        )?;
        for (rec, t) in self.records.iter_mut().zip(times) {
            rec.judgement.frame_ms = t;
            rec.judgement.warm_frames = self.config.frames;
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
const GLOSSY_METHODS: [(Order, Source, SampleFilter, bool, &str); 6] = [
    (
        Order::PerPoint,
        Source::Oslf,
        SampleFilter::Point,
        false,
        "thesis",
    ),
    (
        Order::PerPoint,
        Source::Oslf,
        SampleFilter::Mip,
        false,
        "FIS",
    ),
    (
        Order::PerPoint,
        Source::Oslf,
        SampleFilter::Mip,
        true,
        "FIS + depth",
    ),
    (
        Order::PerDirection,
        Source::Oslf,
        SampleFilter::Mip,
        true,
        "per direction",
    ),
    (
        Order::PerPoint,
        Source::EnvMap,
        SampleFilter::Mip,
        false,
        "EnvMap",
    ),
    (
        Order::PerPoint,
        Source::Parallax,
        SampleFilter::Mip,
        false,
        "Parallax",
    ),
];

/// The record name of one glossy measurement.
fn as_name(nu: f32, nv: f32, m: u32, label: &str) -> String {
    format!("AS {nu}:{nv} M={m} {label}")
}

/// Table 6.2's rows: the two baselines (the environment map, and that map parallax-corrected),
/// then every blend of §4 (B^r and B^n at N = 1, 4, 8, 16). Each OSLF row is measured twice:
/// with plain lookups as the thesis did, and depth-corrected (records named "… depth").
fn mirror_methods() -> Vec<(String, ShadingParams)> {
    let mirror = |blend: Blend, blend_n: f32, source: Source, depth: bool| {
        ShadingParams::Mirror(Mirror {
            lookup: Lookup::of_source(source, blend, blend_n, None),
            depth,
        })
    };
    let (_, default_n) = Lookup::DEFAULT_BLEND;
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
pub fn records_csv(records: &[Record]) -> String {
    let mut csv = String::from(
        "table,store,cube_resolution,method,mode,blend,depth,glossy_filter,n_u,n_v,m,order,pixels,rmse_l,rmse_a,rmse_b,rmse_r,rmse_g,rmse_b_rgb,psnr_db,frame_ms,cold_ms\n",
    );
    for r in records {
        let m = &r.judgement.metrics;
        let (lobe, mc) = (r.params.lobe(), r.params.monte_carlo());
        csv += &format!(
            "{},{},{},{},{},{},{},{},{},{},{},{},{},{:.5},{:.5},{:.5},{:.6},{:.6},{:.6},{},{:.3},{:.3}\n",
            r.table,
            csv_cell(&r.store.display().to_string()),
            r.cube_resolution,
            csv_cell(&r.method),
            r.params.mode().name(),
            blend_label(&r.params),
            r.params.depth(),
            r.params.glossy_filter().map_or("", GlossyFilter::name),
            lobe.map_or(String::new(), |l| l.nu.to_string()),
            lobe.map_or(String::new(), |l| l.nv.to_string()),
            mc.map_or(String::new(), |mc| mc.m.to_string()),
            mc.map_or("", |mc| mc.order.name()),
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
