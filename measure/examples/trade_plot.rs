//! Plots error against bake time for several `oslf sweep` runs over one bake setting
//! (samples per texel, say), one line per run: how devices (or scenes) trade time for
//! accuracy. Reads each run's `sweep.json`.
//!
//! ```sh
//! cargo run --release -p oslf-measure --example trade_plot -- OUT.png "CAPTION" \
//!     [--default-label 4] SERIES...
//! ```
//!
//! Each SERIES is `[dashed:][cN:]NAME=SWEEP.json[@TIMES.json]`: the rows of SWEEP.json with a
//! bake change (and the defaults, labelled by `--default-label`), x their bake wall seconds,
//! y their RMSE of L*. With `@TIMES.json` the seconds come from that run's rows of the same
//! label instead (the same stores judged in another mode); `cN` picks palette colour N. The
//! SVG is written beside the PNG.

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use oslf_measure::plot::PlotText;
use oslf_measure::series_plot::{plot_series, Series};

fn main() {
    if let Err(e) = run() {
        eprintln!("error: {e}");
        std::process::exit(1);
    }
}

/// (label, bake seconds, RMSE L*) of each row of a sweep.json.
fn rows(path: &Path, default_label: &str) -> Result<Vec<(String, f64, f64)>, String> {
    let text = std::fs::read_to_string(path).map_err(|e| format!("{}: {e}", path.display()))?;
    let json: serde_json::Value =
        serde_json::from_str(&text).map_err(|e| format!("{}: {e}", path.display()))?;
    let rows = json["rows"]
        .as_array()
        .ok_or_else(|| format!("{}: no \"rows\" array", path.display()))?;
    rows.iter()
        .enumerate()
        .filter(|(_, r)| r["row"]["runtime_change"].is_null())
        .map(|(i, r)| {
            let label = match r["row"]["bake_change"]["value"].as_str() {
                Some(v) => v.to_string(),
                None => default_label.to_string(),
            };
            let seconds = r["row"]["bake_seconds"].as_f64();
            let error = r["row"]["judgement"]["metrics"]["rmse_lab"][0].as_f64();
            match (seconds, error) {
                (Some(s), Some(e)) => Ok((label, s, e)),
                _ => Err(format!(
                    "{}: row {i} lacks bake_seconds or judgement.metrics.rmse_lab",
                    path.display()
                )),
            }
        })
        .collect()
}

fn series(spec: &str, default_label: &str) -> Result<Series, String> {
    let mut rest = spec;
    let dashed = rest.starts_with("dashed:");
    if dashed {
        rest = &rest["dashed:".len()..];
    }
    let mut colour = 0;
    if let Some((c, tail)) = rest.split_once(':') {
        if let Some(n) = c.strip_prefix('c').and_then(|n| n.parse().ok()) {
            colour = n;
            rest = tail;
        }
    }
    let (name, files) = rest
        .split_once('=')
        .ok_or_else(|| format!("series {spec:?}: expected NAME=SWEEP.json[@TIMES.json]"))?;
    let (errors, times) = match files.split_once('@') {
        Some((e, t)) => (PathBuf::from(e), Some(PathBuf::from(t))),
        None => (PathBuf::from(files), None),
    };
    let mut points = rows(&errors, default_label)?;
    if let Some(times) = times {
        let seconds: HashMap<String, f64> = rows(&times, default_label)?
            .into_iter()
            .map(|(l, s, _)| (l, s))
            .collect();
        for p in &mut points {
            p.1 = *seconds
                .get(&p.0)
                .ok_or_else(|| format!("{}: no row labelled {:?}", times.display(), p.0))?;
        }
    }
    Ok(Series {
        name: name.to_string(),
        points: points.into_iter().map(|(l, s, e)| (s, e, l)).collect(),
        dashed,
        colour,
    })
}

fn run() -> Result<(), String> {
    let mut args: Vec<String> = std::env::args().skip(1).collect();
    let mut default_label = "defaults".to_string();
    if let Some(i) = args.iter().position(|a| a == "--default-label") {
        if i + 1 >= args.len() {
            return Err("--default-label needs a value".into());
        }
        default_label = args.remove(i + 1);
        args.remove(i);
    }
    if args.len() < 3 {
        return Err("usage: trade_plot OUT.png CAPTION [--default-label L] SERIES...".into());
    }
    let png = PathBuf::from(&args[0]);
    let text = PlotText {
        caption: args[1].clone(),
        x: "bake, wall seconds (log scale)".into(),
        y: "RMSE of L* against the ground truth".into(),
    };
    let all = args[2..]
        .iter()
        .map(|s| series(s, &default_label))
        .collect::<Result<Vec<_>, _>>()?;
    plot_series(&all, &text, &png, &png.with_extension("svg"), (900, 560))
        .map_err(|e| e.to_string())?;
    println!(
        "wrote {} and {}",
        png.display(),
        png.with_extension("svg").display()
    );
    Ok(())
}
