//! What the sweep's rows show (`oslf sweep`): their Pareto fronts of error against frame time
//! and against bake time, the table of every row, the sensitivity table around the defaults
//! (thesis §8.1.1) and the panels of the trade-off plot.

use oslf_runtime::ShadingParams;

use crate::pareto::pareto_front;
use crate::plot::{Panel, PlotPoint, PlotText};
use crate::sweep::{blend_label, SweepRow};
use crate::table::Table;

/// Each row's place on the two Pareto fronts: `Some(on)` for the rows a front is over, `None`
/// for those it leaves out.
pub struct Fronts {
    /// Error against frame time, over the default bake's rows (what the runtime settings
    /// trade).
    pub frame: Vec<Option<bool>>,
    /// Error against bake cost ([`bake_cost`]), over the default runtime settings' rows (what
    /// the bake settings trade).
    pub bake: Vec<Option<bool>>,
}

impl Fronts {
    /// The fronts of `rows`.
    pub fn of(rows: &[SweepRow]) -> Self {
        Fronts {
            frame: front_of(rows, |r| r.bake_change.is_none(), |r| r.judgement.frame_ms),
            bake: front_of(rows, |r| r.runtime_change.is_none(), bake_cost),
        }
    }
}

/// Pareto membership (error against `cost`) among the rows `member` selects; `None` for the
/// rows it leaves out.
pub fn front_of(
    rows: &[SweepRow],
    member: impl Fn(&SweepRow) -> bool,
    cost: impl Fn(&SweepRow) -> f64,
) -> Vec<Option<bool>> {
    let members: Vec<usize> = (0..rows.len()).filter(|&i| member(&rows[i])).collect();
    let points: Vec<(f64, f64)> = members
        .iter()
        .map(|&i| (cost(&rows[i]), rows[i].judgement.metrics.rmse_lab[0]))
        .collect();
    let mut out = vec![None; rows.len()];
    for (&i, on) in members.iter().zip(pareto_front(&points)) {
        out[i] = Some(on);
    }
    out
}

/// The bake's CPU seconds (all threads), or its wall seconds where CPU time is not known or
/// the cube maps were captured on a GPU (whose time the CPU's does not count).
pub fn bake_cost(r: &SweepRow) -> f64 {
    if r.capture_device.starts_with("GPU") {
        return r.bake_seconds;
    }
    r.bake_cpu_seconds.unwrap_or(r.bake_seconds)
}

/// The bake panel's x axis: what [`bake_cost`] measures for these rows.
pub fn bake_cost_label(rows: &[SweepRow]) -> &'static str {
    let gpu = rows
        .iter()
        .filter(|r| r.capture_device.starts_with("GPU"))
        .count();
    match gpu {
        0 => "bake, CPU seconds",
        n if n == rows.len() => "bake, seconds (wall, cube maps captured on a GPU)",
        _ => "bake, CPU seconds (wall seconds for GPU bakes)",
    }
}

/// Every row with its times, errors and whether it is on each Pareto front; `defaults` names
/// the defaults in the title (the scene), `size` the image.
pub fn rows_table(
    params: &ShadingParams,
    defaults: &str,
    size: (u32, u32),
    rows: &[SweepRow],
    fronts: &Fronts,
) -> Table {
    let (frame_front, bake_front) = (&fronts.frame, &fronts.bake);
    let mut all = Table::new(
        &format!(
            "Sweep: mode {}, defaults {} (blend {}, φ_shader {}), {}x{}",
            params.mode().name(),
            defaults,
            blend_label(params),
            params
                .phi_shader_deg()
                .map_or_else(|| "-".into(), |d| format!("{d}°")),
            size.0,
            size.1
        ),
        &[
            "configuration",
            "sample points",
            "bake s",
            "bake CPU-s",
            "capture on",
            "store MB",
            "frame ms",
            "RMSE L*",
            "RMSE a*",
            "RMSE b*",
            "RMSE R",
            "RMSE G",
            "RMSE B",
            "PSNR dB",
            "pixels",
            "front: frame",
            "front: bake",
        ],
    );
    for ((r, on), on_bake) in rows.iter().zip(frame_front).zip(bake_front) {
        let m = &r.judgement.metrics;
        all.push(vec![
            r.label(),
            r.sample_points.to_string(),
            format!("{:.1}", r.bake_seconds),
            r.bake_cpu_seconds.map_or("–".into(), |c| format!("{c:.1}")),
            r.capture_device.clone(),
            format!("{:.2}", r.store_bytes as f64 / 1e6),
            format!("{:.1}", r.judgement.frame_ms),
            format!("{:.3}", m.rmse_lab[0]),
            format!("{:.3}", m.rmse_lab[1]),
            format!("{:.3}", m.rmse_lab[2]),
            format!("{:.4}", m.rmse_rgb[0]),
            format!("{:.4}", m.rmse_rgb[1]),
            format!("{:.4}", m.rmse_rgb[2]),
            m.psnr_db.map_or("–".into(), |p| format!("{p:.2}")),
            m.pixels.to_string(),
            yes_no(*on),
            yes_no(*on_bake),
        ]);
    }
    all
}

/// The labels of the rows on `front`, and whether the defaults are among them.
pub fn front_members(rows: &[SweepRow], front: &[Option<bool>]) -> (Vec<String>, bool) {
    let labels = rows
        .iter()
        .zip(front)
        .filter(|(_, f)| **f == Some(true))
        .map(|(r, _)| r.label())
        .collect();
    let default_on = rows
        .iter()
        .zip(front)
        .any(|(r, f)| r.is_default() && *f == Some(true));
    (labels, default_on)
}

/// The trade-off plot's two panels: error against frame time (runtime settings, default bake)
/// and against bake cost (bake settings, default runtime).
pub fn panels(params: &ShadingParams, rows: &[SweepRow], fronts: &Fronts) -> [Panel; 2] {
    let panel =
        |front: &[Option<bool>], time: &dyn Fn(&SweepRow) -> f64, x: &str, what: &str| Panel {
            points: rows
                .iter()
                .zip(front)
                .filter_map(|(r, f)| {
                    f.map(|on| PlotPoint {
                        label: r.label(),
                        time_ms: time(r),
                        error: r.judgement.metrics.rmse_lab[0],
                        on_front: on,
                        is_default: r.is_default(),
                    })
                })
                .collect(),
            text: PlotText {
                caption: format!("{}: {what}", params.mode().name()),
                x: x.into(),
                y: "RMSE of L* against the ground truth".into(),
            },
        };
    [
        panel(
            &fronts.frame,
            &|r| r.judgement.frame_ms,
            "frame time, ms",
            "runtime settings, default bake",
        ),
        panel(
            &fronts.bake,
            &bake_cost,
            bake_cost_label(rows),
            "bake settings, default runtime",
        ),
    ]
}

/// Rows with at most one change, grouped by the changed key: how the error moves around the
/// defaults (thesis §8.1.1).
pub fn sensitivity_table(rows: &[SweepRow]) -> Table {
    let mut t = Table::new(
        "Sensitivity: one setting changed from the defaults",
        &[
            "setting",
            "value",
            "RMSE L*",
            "Δ L*",
            "frame ms",
            "bake CPU-s",
            "store MB",
        ],
    );
    let Some(base) = rows.iter().find(|r| r.is_default()) else {
        return t;
    };
    let e0 = base.judgement.metrics.rmse_lab[0];
    let mut push = |key: &str, value: &str, r: &SweepRow| {
        let e = r.judgement.metrics.rmse_lab[0];
        t.push(vec![
            key.into(),
            value.into(),
            format!("{e:.3}"),
            format!("{:+.3}", e - e0),
            format!("{:.1}", r.judgement.frame_ms),
            format!("{:.1}", bake_cost(r)),
            format!("{:.2}", r.store_bytes as f64 / 1e6),
        ]);
    };
    push("(defaults)", "", base);
    for r in rows {
        let change = match (&r.bake_change, &r.runtime_change) {
            (Some(c), None) | (None, Some(c)) => c,
            _ => continue,
        };
        push(&change.key, &change.value, r);
    }
    t
}

fn yes_no(on: Option<bool>) -> String {
    match on {
        Some(true) => "yes".into(),
        Some(false) => "no".into(),
        None => "–".into(),
    }
}
