//! The speed/accuracy sweep and the sensitivity analysis (thesis §8.1.1).
//!
//! Starting from a scene's settings (the *defaults*), each variation `KEY=V1,V2,…` changes one
//! setting at a time. Bake keys give bake variants (each baked to its own store); runtime keys
//! give runtime variants. Every bake variant is judged with every runtime variant against one
//! ground truth of the unchanged scene ([`crate::judge`]), which records bake time, store size,
//! frame time and error. Rows where exactly one setting differs from the defaults are the
//! sensitivity analysis; all rows together give the Pareto front of error against frame time.

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Instant;

use oslf_bake::bake::{bake, BakeOptions, BakeReport};
use oslf_format::Store;
use oslf_runtime::{
    Blend, CacheConfig, Gpu, Lookup, Mode, Order, Probe, Renderer, ShadingParams, Source,
};
use oslf_scene::scene::{BakeSettings, SampleDensity, Scene};
use oslf_trace::ground_truth::TruthImage;
use oslf_trace::progress::Progress;
use serde::{Deserialize, Serialize};

use crate::error::{MeasureError, Result};
use crate::judge::{judge, time_interleaved, Judgement, TimedJob};

/// Bake settings the sweep can vary.
pub const BAKE_KEYS: [&str; 8] = [
    "epsilon",
    "sample_count",
    "cube_resolution",
    "phi_samplemap",
    "samples_per_texel",
    "sample_map_resolution",
    "mantissa_bits",
    "device",
];

/// Runtime settings the sweep can vary. `blend` takes `distance`, `angle`, `avg`, `rN`
/// (B^r with power N), `nN` (B^n), `envmap` (the environment-map baseline) or `parallax` (that
/// map parallax-corrected).
pub const RUNTIME_KEYS: [&str; 4] = ["phi_shader", "blend", "m", "order"];

/// One setting changed from the defaults: `key = value`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Change {
    pub key: String,
    pub value: String,
}

impl Change {
    /// [`MeasureError::Vary`] naming this change's setting and `problem`.
    fn problem(&self, problem: String) -> MeasureError {
        MeasureError::Vary {
            setting: Some(self.key.clone()),
            problem,
        }
    }
}

/// Parses `KEY=V1,V2,…` into one change per value, checking the key and every value.
pub fn parse_vary(spec: &str) -> Result<Vec<Change>> {
    let (key, values) = spec.split_once('=').ok_or_else(|| MeasureError::Vary {
        setting: Some(format!("{spec:?}")),
        problem: "expected KEY=V1,V2,...".into(),
    })?;
    let key = key.trim();
    if !BAKE_KEYS.contains(&key) && !RUNTIME_KEYS.contains(&key) {
        return Err(MeasureError::Vary {
            setting: None,
            problem: format!(
                "unknown key {key:?} (bake: {}; runtime: {})",
                BAKE_KEYS.join(", "),
                RUNTIME_KEYS.join(", ")
            ),
        });
    }
    let changes: Vec<Change> = values
        .split(',')
        .map(|v| Change {
            key: key.to_string(),
            value: v.trim().to_string(),
        })
        .collect();
    for c in &changes {
        if BAKE_KEYS.contains(&key) {
            apply_bake(&mut BakeSettings::clone(&default_settings()), c)?;
        } else {
            // The value's syntax, on a mode that has every runtime key.
            apply_runtime(&mut ShadingParams::of_mode(Mode::ReconGlossy), c)?;
        }
    }
    Ok(changes)
}

fn default_settings() -> BakeSettings {
    BakeSettings {
        epsilon: 0.1,
        sample_count: SampleDensity::Count(300),
        phi_samplemap_deg: 85.0,
        cube_resolution: 32,
        sample_map_resolution: 256,
        samples_per_texel: 4,
        target_noise: 0.0,
        denoise: false,
        placement: Default::default(),
        near_surface: Default::default(),
        bounces: 1,
        seed: 0,
        encoding: oslf_format::Encoding::Rgb9e5,
        zstd_level: 3,
        mantissa_bits: 9,
        distance_channel: false,
        env_cube: true,
        device: Default::default(),
    }
}

fn parse<T: std::str::FromStr>(c: &Change) -> Result<T> {
    c.value
        .parse::<T>()
        .map_err(|_| c.problem(format!("{:?} is not a valid value", c.value)))
}

fn check(c: &Change, ok: bool, range: &str) -> Result<()> {
    if ok {
        Ok(())
    } else {
        Err(c.problem(format!("{} is outside {range}", c.value)))
    }
}

/// Applies a bake change to `s` (the ranges are the scene file's).
pub fn apply_bake(s: &mut BakeSettings, c: &Change) -> Result<()> {
    match c.key.as_str() {
        "epsilon" => {
            let v: f32 = parse(c)?;
            check(c, v.is_finite() && v > 0.0, "(0, ∞)")?;
            s.epsilon = v;
        }
        "sample_count" => {
            let v: u32 = parse(c)?;
            check(c, v >= 1, "[1, ∞)")?;
            s.sample_count = SampleDensity::Count(v);
        }
        "cube_resolution" => {
            let v: u32 = parse(c)?;
            check(c, (1..=16384).contains(&v), "[1, 16384]")?;
            s.cube_resolution = v;
        }
        "phi_samplemap" => {
            let v: f32 = parse(c)?;
            check(c, v > 0.0 && v < 90.0, "(0, 90)")?;
            s.phi_samplemap_deg = v;
        }
        "device" => s.device = parse(c)?,
        "samples_per_texel" => {
            let v: u32 = parse(c)?;
            check(c, v >= 1, "[1, ∞)")?;
            s.samples_per_texel = v;
        }
        "sample_map_resolution" => {
            let v: u32 = parse(c)?;
            check(c, (1..=16384).contains(&v), "[1, 16384]")?;
            s.sample_map_resolution = v;
        }
        "mantissa_bits" => {
            let v: u32 = parse(c)?;
            check(c, (1..=9).contains(&v), "[1, 9]")?;
            oslf_format::meta::check_mantissa_bits(s.encoding, v)
                .map_err(|e| c.problem(e.to_string()))?;
            s.mantissa_bits = v;
        }
        k => return Err(MeasureError::Invalid(format!("{k} is not a bake setting"))),
    }
    Ok(())
}

/// Applies a runtime change to `p`; a setting the mode does not have is an error naming both.
pub fn apply_runtime(p: &mut ShadingParams, c: &Change) -> Result<()> {
    match c.key.as_str() {
        "phi_shader" => p.set_phi_shader_deg(parse(c)?)?,
        "m" => p.monte_carlo_mut()?.m = parse(c)?,
        "order" => {
            p.monte_carlo_mut()?.order = match c.value.parse::<Order>() {
                Ok(order) => order,
                Err(_) => {
                    let names: Vec<_> = Order::ALL.iter().map(|o| o.name()).collect();
                    return check(c, false, &format!("{{{}}}", names.join(", ")));
                }
            }
        }
        "blend" => {
            let v = c.value.as_str();
            let blend_n = p.blend().map_or(Lookup::DEFAULT_BLEND.1, |(_, n)| n);
            let lookup = match v {
                "distance" => Lookup::oslf(Blend::Distance, blend_n),
                "angle" => Lookup::oslf(Blend::Angle, blend_n),
                "avg" => Lookup::oslf(Blend::Average, blend_n),
                "envmap" => Lookup::Probe(Probe::EnvMap),
                "parallax" => Lookup::Probe(Probe::Parallax { proxy_box: None }),
                _ if v.len() > 1 && (v.starts_with('r') || v.starts_with('n')) => {
                    let blend = if v.starts_with('r') {
                        Blend::Reflection
                    } else {
                        Blend::Normal
                    };
                    let n = v[1..]
                        .parse()
                        .map_err(|_| c.problem(format!("{v:?}: expected rN or nN")))?;
                    Lookup::oslf(blend, n)
                }
                _ => {
                    return check(c, false, "{distance, angle, avg, rN, nN, envmap, parallax}");
                }
            };
            p.set_lookup(lookup)?;
        }
        k => {
            return Err(MeasureError::Invalid(format!(
                "{k} is not a runtime setting"
            )))
        }
    }
    p.validate()?;
    Ok(())
}

/// A short name of a blend setting, as a `blend=` variation takes it ("-" for the modes
/// without a lookup).
pub fn blend_label(p: &ShadingParams) -> String {
    match p.lookup() {
        None => "-".into(),
        Some(Lookup::Probe(Probe::EnvMap)) => "envmap".into(),
        Some(Lookup::Probe(Probe::Parallax { .. })) => "parallax".into(),
        Some(Lookup::Oslf { blend, blend_n }) => match blend {
            Blend::Distance => "distance".into(),
            Blend::Angle => "angle".into(),
            Blend::Average => "avg".into(),
            Blend::Reflection => format!("r{blend_n}"),
            Blend::Normal => format!("n{blend_n}"),
        },
    }
}

/// How to run a sweep.
pub struct SweepConfig<'a> {
    /// The scene with its default settings.
    pub scene: &'a Scene,
    /// The default runtime settings.
    pub params: ShadingParams,
    /// Bake and runtime changes, each applied alone.
    pub changes: Vec<Change>,
    /// Where the variant stores go (`<dir>/<label>.oslf`, reused when their recorded settings
    /// match).
    pub store_dir: PathBuf,
    pub warm_frames: u32,
    /// Where the bakes report their progress; `Some` also prints a line per store.
    pub progress: Option<Arc<dyn Progress>>,
    /// The command's inputs and outputs: each variant store and its record is checked against
    /// them before it is baked or reused.
    pub door: &'a oslf_util::door::Door,
}

/// One judged configuration.
#[derive(Clone, Debug, Serialize)]
pub struct SweepRow {
    /// The bake change (`None`: the defaults).
    pub bake_change: Option<Change>,
    /// The runtime change (`None`: the defaults).
    pub runtime_change: Option<Change>,
    pub store: PathBuf,
    pub bake_seconds: f64,
    /// CPU time of the bake, all threads: less sensitive than `bake_seconds` to what else
    /// runs on the machine.
    pub bake_cpu_seconds: Option<f64>,
    /// What captured the store's cube maps: `CPU (N threads)` or `GPU <adapter>`.
    pub capture_device: String,
    pub store_bytes: u64,
    pub sample_points: usize,
    pub judgement: Judgement,
}

impl SweepRow {
    /// `defaults`, or the changes, as `key=value[, key=value]`.
    pub fn label(&self) -> String {
        let parts: Vec<String> = [&self.bake_change, &self.runtime_change]
            .into_iter()
            .flatten()
            .map(|c| format!("{}={}", c.key, c.value))
            .collect();
        if parts.is_empty() {
            "defaults".into()
        } else {
            parts.join(", ")
        }
    }

    pub fn is_default(&self) -> bool {
        self.bake_change.is_none() && self.runtime_change.is_none()
    }
}

/// What the sweep records beside each store, to reuse it in a later run.
#[derive(Serialize, Deserialize)]
struct StoreRecord {
    settings: String,
    scene_hash: String,
    bake_seconds: f64,
    #[serde(default)]
    bake_cpu_seconds: Option<f64>,
    store_bytes: u64,
    sample_points: usize,
    /// What captured the cube maps ([`BakeReport::capture_device`]).
    #[serde(default)]
    capture_device: String,
}

fn record_path(store: &Path) -> PathBuf {
    let mut s = store.as_os_str().to_os_string();
    s.push(".sweep.json");
    PathBuf::from(s)
}

fn hex(bytes: &[u8]) -> String {
    bytes.iter().map(|b| format!("{b:02x}")).collect()
}

/// Bakes `scene` to `path` unless a store baked with the same settings is already there.
fn bake_or_reuse(
    scene: &Scene,
    path: &Path,
    progress: Option<Arc<dyn Progress>>,
) -> Result<StoreRecord> {
    let settings = format!("{:?}", scene.bake);
    let hash = hex(&scene.hash);
    let record = record_path(path);
    if path.exists() {
        let limit = oslf_util::input_file::Limit::new(1 << 20, "the 1 MiB allowed for a record");
        if let Ok(Ok(text)) = oslf_util::input_file::read(&record, &limit).map(String::from_utf8) {
            if let Ok(r) = serde_json::from_str::<StoreRecord>(&text) {
                if r.settings == settings && r.scene_hash == hash {
                    return Ok(r);
                }
            }
        }
    }
    let (gpu, _) = oslf_bake_gpu::choice::capture_device(scene, scene.bake.device, "device")?;
    let report: BakeReport = bake(
        scene,
        &BakeOptions {
            output: path.to_path_buf(),
            resume: false,
            progress,
            cube_limit: None,
            refuse_empty_texels: false,
            device: gpu.map(|g| g as Arc<dyn oslf_bake::device::CaptureDevice>),
        },
    )?;
    let r = StoreRecord {
        settings,
        scene_hash: hash,
        bake_seconds: report.total_seconds,
        bake_cpu_seconds: report.cpu_seconds,
        store_bytes: report.store_bytes,
        sample_points: report.sample_points,
        capture_device: report.capture_device.clone(),
    };
    let json =
        serde_json::to_string_pretty(&r).map_err(|e| MeasureError::Invalid(e.to_string()))?;
    oslf_util::output_file::write_bytes(&record, json.as_bytes())?;
    Ok(r)
}

/// `scene` with a bake change applied, checked against the limits the scene file's parser
/// enforces (ε for each object).
pub fn bake_variant(scene: &Scene, change: &Change) -> Result<Scene> {
    let mut variant = scene.clone();
    apply_bake(&mut variant.bake, change)?;
    if matches!(change.key.as_str(), "sample_count" | "sample_spacing") {
        // Spacings chosen per object where the file sets no density give way to the change.
        variant.set_sample_density(variant.bake.sample_count);
    }
    variant
        .check_epsilon()
        .map_err(|e| change.problem(e.to_string()))?;
    Ok(variant)
}

/// Checks every bake change against `scene` (before anything slow runs).
pub fn check_changes(scene: &Scene, changes: &[Change]) -> Result<()> {
    for c in changes
        .iter()
        .filter(|c| BAKE_KEYS.contains(&c.key.as_str()))
    {
        bake_variant(scene, c)?;
    }
    Ok(())
}

/// Runs the sweep against `truth` (the ground truth of `config.params.mode` for the scene's
/// camera). Calls `on_row` as each row's error is measured; frame times are measured at the
/// end, `warm_frames` rounds interleaved over every row.
pub fn run_sweep(
    config: &SweepConfig,
    truth: &TruthImage,
    mut on_row: impl FnMut(&SweepRow),
) -> Result<Vec<SweepRow>> {
    let bake_changes: Vec<Option<&Change>> = std::iter::once(None)
        .chain(
            config
                .changes
                .iter()
                .filter(|c| BAKE_KEYS.contains(&c.key.as_str()))
                .map(Some),
        )
        .collect();
    let runtime_changes: Vec<Option<&Change>> = std::iter::once(None)
        .chain(
            config
                .changes
                .iter()
                .filter(|c| RUNTIME_KEYS.contains(&c.key.as_str()))
                .map(Some),
        )
        .collect();
    std::fs::create_dir_all(&config.store_dir).map_err(|e| MeasureError::Output {
        path: config.store_dir.clone(),
        message: e.to_string(),
    })?;
    // Every variant is checked before the first is baked.
    let mut variants = Vec::with_capacity(bake_changes.len());
    for bc in &bake_changes {
        let (scene, name) = match bc {
            Some(c) => (
                bake_variant(config.scene, c)?,
                format!("{}-{}", c.key, c.value),
            ),
            None => (config.scene.clone(), "defaults".to_string()),
        };
        variants.push((bc, scene, name));
    }
    let mut rows = Vec::new();
    let mut renderers = Vec::new();
    let mut jobs = Vec::new();
    for (bc, scene, name) in variants {
        let path = config.store_dir.join(format!("{name}.oslf"));
        config.door.check_output_in_dir("a variant store", &path)?;
        config.door.check_output_in_dir(
            "a variant store's partial file",
            &oslf_format::writer::partial_path(&path),
        )?;
        config
            .door
            .check_output_in_dir("a variant store's record", &record_path(&path))?;
        let t = Instant::now();
        let record = bake_or_reuse(&scene, &path, config.progress.clone())?;
        if config.progress.is_some() {
            eprintln!(
                "store {} ({:.1} s{})",
                path.display(),
                t.elapsed().as_secs_f64(),
                if t.elapsed().as_secs_f64() < 1.0 {
                    ", reused"
                } else {
                    ""
                }
            );
        }
        let store = Store::open(&path)?;
        let mut renderer = Renderer::new(
            Gpu::headless().map_err(oslf_runtime::RuntimeError::from)?,
            store,
            CacheConfig::default(),
        )?;
        let camera = renderer.default_view();
        for rc in &runtime_changes {
            let mut params = config.params;
            if let Some(c) = rc {
                apply_runtime(&mut params, c)?;
            }
            if params.source() == Source::EnvMap && renderer.store().env_cube_index().is_none() {
                return Err(MeasureError::Invalid(format!(
                    "{} has no environment cube for blend=envmap (env_cube = true)",
                    path.display()
                )));
            }
            let (judgement, _) = judge(&mut renderer, &camera, &params, truth, 0)?;
            let row = SweepRow {
                bake_change: bc.cloned(),
                runtime_change: rc.cloned(),
                store: path.clone(),
                bake_seconds: record.bake_seconds,
                bake_cpu_seconds: record.bake_cpu_seconds,
                capture_device: record.capture_device.clone(),
                store_bytes: record.store_bytes,
                sample_points: record.sample_points,
                judgement,
            };
            on_row(&row);
            rows.push(row);
            jobs.push(TimedJob {
                renderer: renderers.len(),
                camera,
                params,
            });
        }
        renderers.push(renderer);
    }
    // Frame times last, interleaved over every configuration (see `time_interleaved`).
    let times = time_interleaved(
        &mut renderers,
        &jobs,
        truth.width,
        truth.height,
        config.warm_frames,
    )?;
    for (row, ms) in rows.iter_mut().zip(times) {
        row.judgement.frame_ms = ms;
        row.judgement.warm_frames = config.warm_frames;
    }
    Ok(rows)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn vary_specs_are_checked() {
        let c = parse_vary("cube_resolution=16,64").unwrap();
        assert_eq!(c.len(), 2);
        assert_eq!(
            (c[1].key.as_str(), c[1].value.as_str()),
            ("cube_resolution", "64")
        );
        assert!(parse_vary("blend=distance,n16,r4,envmap,avg").is_ok());
        for bad in [
            "cube_resolution",
            "colour=1",
            "epsilon=-1",
            "blend=x4",
            "blend=nq",
            "m=0",
            "phi_shader=200",
            "mantissa_bits=0",
            "mantissa_bits=10",
            "mantissa_bits=5.5",
        ] {
            assert!(parse_vary(bad).is_err(), "{bad}");
        }
        // The error names the setting (or the variation without one) and the problem.
        assert!(matches!(
            parse_vary("colour=1"),
            Err(MeasureError::Vary { setting: None, problem }) if problem.starts_with("unknown key \"colour\" (bake: epsilon, ")
        ));
        assert!(matches!(
            parse_vary("epsilon=-1"),
            Err(MeasureError::Vary { setting: Some(s), problem }) if s == "epsilon" && problem == "-1 is outside (0, ∞)"
        ));
        assert!(matches!(
            parse_vary("cube_resolution"),
            Err(MeasureError::Vary { setting: Some(s), problem }) if s == "\"cube_resolution\"" && problem == "expected KEY=V1,V2,..."
        ));
        let c = parse_vary("mantissa_bits=4,5,6,7").unwrap();
        let mut s = default_settings();
        apply_bake(&mut s, &c[1]).unwrap();
        assert_eq!(s.mantissa_bits, 5);
        // Only RGB9E5 can be quantized.
        let mut s = default_settings();
        s.encoding = oslf_format::Encoding::Rgba16f;
        assert!(apply_bake(&mut s, &c[0]).is_err());
        let mut p = ShadingParams::default();
        apply_runtime(
            &mut p,
            &Change {
                key: "blend".into(),
                value: "r8".into(),
            },
        )
        .unwrap();
        assert_eq!(
            (p.blend(), blend_label(&p)),
            (Some((Blend::Reflection, 8.0)), "r8".to_string())
        );
        // A setting the mode does not have is refused, naming it.
        let e = apply_runtime(
            &mut p,
            &Change {
                key: "m".into(),
                value: "4".into(),
            },
        )
        .unwrap_err()
        .to_string();
        assert!(
            e.contains("recon-mirror") && e.contains("Monte Carlo"),
            "{e}"
        );
    }
}
