//! Cache replay (`oslf_runtime::replay`) and the `oslf-cache-stats` command: the counters add
//! up, an unlimited cache stops missing once the orbit comes round, a smaller cache misses
//! more, whole cubes decode at least what faces do, and the table, CSV and JSON agree.

mod common;

use std::collections::HashMap;
use std::process::Command;

use oslf_runtime::replay::{self, CameraPath, Phase, Row, RowKey};
use oslf_runtime::{CacheConfig, Gpu, Granularity, Mode, RenderOptions, Renderer, ShadingParams};

fn options(resolve_misses: bool) -> RenderOptions {
    RenderOptions {
        width: 80,
        height: 60,
        resolve_misses,
        ..Default::default()
    }
}

fn renderer(slots: Option<u32>, granularity: Granularity) -> Renderer {
    let config = CacheConfig {
        gpu_slots: slots,
        ram_bytes: 64 << 20,
        granularity,
        slots_per_texture: None,
    };
    Renderer::new(Gpu::headless().unwrap(), common::open_store(), config).unwrap()
}

/// Replays `path` with a fresh renderer and returns its rows.
fn run(
    slots: Option<u32>,
    granularity: Granularity,
    mode: Mode,
    path: &CameraPath,
    resolve: bool,
) -> Vec<Row> {
    let mut r = renderer(slots, granularity);
    let params = ShadingParams {
        mode,
        m: 4,
        ..Default::default()
    };
    let replay = replay::replay(&mut r, path, &params, &options(resolve)).unwrap();
    assert_eq!(replay.frames.len(), path.cameras.len());
    let key = RowKey {
        mode,
        blend: Some(params.blend),
        granularity,
        size: slots.map_or("all".into(), |s| s.to_string()),
        slots: r.cache().slots(),
    };
    let rows = replay::rows(&key, path, &replay);
    for row in &rows {
        assert_eq!(row.hits + row.misses, row.requests, "{row:?}");
        assert!(row.requests > 0, "{row:?}");
    }
    rows
}

fn phase(rows: &[Row], phase: Phase) -> &Row {
    rows.iter().find(|r| r.phase == phase.name()).unwrap()
}

fn orbit(frames: u32, degrees: f32) -> CameraPath {
    let camera = renderer(Some(1), Granularity::Cube).default_view();
    CameraPath::orbit(camera, frames, degrees).unwrap()
}

#[test]
fn an_unlimited_cache_stops_missing_once_the_orbit_comes_round_and_a_small_one_keeps_missing() {
    let path = orbit(12, 720.0);
    assert_eq!(path.range(Phase::Steady), 6..12);
    for granularity in [Granularity::Cube, Granularity::Face] {
        for mode in [Mode::ReconMirror, Mode::Glossy] {
            let all = run(None, granularity, mode, &path, true);
            let (cold, steady, whole) = (
                phase(&all, Phase::Cold),
                phase(&all, Phase::Steady),
                phase(&all, Phase::All),
            );
            assert!(cold.misses > 10, "{cold:?}");
            assert_eq!(
                cold.hits,
                if granularity == Granularity::Cube {
                    1
                } else {
                    6
                }
            );
            // The first revolution shows new views (misses after the cold frame too)...
            assert!(whole.misses > cold.misses, "{whole:?}");
            // ...the second only views already seen: every cube the orbit needs is resident.
            assert_eq!(
                (steady.misses, steady.loads, steady.over_budget),
                (0, 0, 0),
                "{steady:?}"
            );
            assert_eq!(steady.bytes_decoded, 0);
            assert_eq!(steady.frames, 6);

            // Four slots hold less than a frame's working set: it misses every frame, more in
            // every phase than the unlimited cache.
            let small = run(Some(4), granularity, mode, &path, true);
            for p in [Phase::Cold, Phase::Steady, Phase::All] {
                let (s, a) = (phase(&small, p), phase(&all, p));
                // The same path needs the same units; reconstruction's fallback (another
                // candidate when the nearest is not resident) marks what it reads as well, so
                // a short budget can only add requests.
                assert!(s.requests >= a.requests, "{p:?}: {s:?} vs {a:?}");
                if mode == Mode::Glossy {
                    assert_eq!(s.requests, a.requests, "{p:?}: {s:?} vs {a:?}");
                }
                if p != Phase::Cold {
                    assert!(s.misses > a.misses, "{p:?}: {s:?} vs {a:?}");
                }
                assert!(s.over_budget > 0, "{s:?}");
            }
            let s = phase(&small, Phase::Steady);
            assert!(s.miss_rate > 0.5, "{s:?}");
        }
    }
}

#[test]
fn more_slots_miss_less_along_the_orbit() {
    let path = orbit(12, 720.0);
    let misses: Vec<u64> = [4, 16, 48]
        .into_iter()
        .map(|s| {
            let rows = run(Some(s), Granularity::Cube, Mode::ReconMirror, &path, true);
            phase(&rows, Phase::All).misses
        })
        .collect();
    assert!(
        misses[0] > misses[1] && misses[1] > misses[2],
        "misses by size 4, 16, 48: {misses:?}"
    );
}

#[test]
fn whole_cubes_decode_at_least_the_bytes_of_single_faces() {
    let path = orbit(8, 720.0);
    for mode in [Mode::Recon, Mode::Mirror, Mode::Glossy] {
        for slots in [None, Some(8)] {
            let cube = run(slots, Granularity::Cube, mode, &path, true);
            let face = run(slots, Granularity::Face, mode, &path, true);
            let (c, f) = (phase(&cube, Phase::All), phase(&face, Phase::All));
            assert!(
                c.bytes_decoded >= f.bytes_decoded,
                "{mode:?}: {c:?} vs {f:?}"
            );
            // A cube request is a face request's cube: six times the units at most.
            assert!(f.requests > c.requests && f.requests <= 6 * c.requests);
            // A cold view does not read every face of every cube it needs.
            let (c, f) = (phase(&cube, Phase::Cold), phase(&face, Phase::Cold));
            assert!(
                c.bytes_decoded > f.bytes_decoded,
                "{mode:?}: {c:?} vs {f:?}"
            );
        }
    }
}

#[test]
fn streaming_falls_back_in_the_cold_frame_and_decodes_in_the_background() {
    let camera = renderer(Some(1), Granularity::Cube).default_view();
    let path = CameraPath::still(camera, 2).unwrap();
    let rows = run(None, Granularity::Face, Mode::ReconMirror, &path, false);
    let cold = phase(&rows, Phase::Cold);
    assert_eq!(
        (cold.loads, cold.passes, cold.bytes_decoded),
        (0, 1, 0),
        "{cold:?}"
    );
    assert!(cold.misses > 0);
    // Resolved, the same frame loads what it missed and shades again.
    let rows = run(None, Granularity::Face, Mode::ReconMirror, &path, true);
    let cold = phase(&rows, Phase::Cold);
    assert_eq!(cold.loads, cold.misses, "{cold:?}");
    assert_eq!(cold.passes, 2);
}

fn cache_stats(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_oslf-cache-stats"))
        .args(args)
        .output()
        .unwrap()
}

#[test]
fn the_command_prints_a_table_that_agrees_with_its_csv_and_json() {
    let store = common::store_path();
    let dir = store.parent().unwrap().join("cache-stats");
    std::fs::create_dir_all(&dir).unwrap();
    let (csv, json) = (dir.join("rows.csv"), dir.join("rows.json"));
    let out = cache_stats(&[
        store.to_str().unwrap(),
        "--modes",
        "recon,mirror",
        "--blend",
        "n,distance",
        "--slots",
        "4,25%,all",
        "--granularity",
        "cube,face",
        "--frames",
        "6",
        "--still-frames",
        "2",
        "--width",
        "64",
        "--height",
        "48",
        "--csv",
        csv.to_str().unwrap(),
        "--json",
        json.to_str().unwrap(),
    ]);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{stdout}\n{}",
        String::from_utf8_lossy(&out.stderr)
    );

    // JSON rows.
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    let rows: Vec<Row> = serde_json::from_value(json["rows"].clone()).unwrap();
    // (recon + mirror × 2 blends) × 2 granularities × 3 sizes × (still 2 phases + orbit 3).
    assert_eq!(rows.len(), 3 * 2 * 3 * 5);
    assert_eq!(json["replays"].as_array().unwrap().len(), 3 * 2 * 3 * 2);
    for r in &rows {
        assert_eq!(r.hits + r.misses, r.requests, "{r:?}");
        assert!(r.requests > 0 && r.frames > 0, "{r:?}");
    }
    let cubes = json["cube_maps"].as_u64().unwrap();
    assert!(rows
        .iter()
        .any(|r| r.size == "25%" && u64::from(r.slots) == cubes.div_ceil(4)));
    assert!(rows
        .iter()
        .any(|r| r.size == "all" && u64::from(r.slots) == cubes));

    // CSV: same rows, same numbers.
    let text = std::fs::read_to_string(&csv).unwrap();
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let csv_rows: Vec<HashMap<&str, &str>> = lines
        .map(|l| header.iter().copied().zip(l.split(',')).collect())
        .collect();
    assert_eq!(csv_rows.len(), rows.len());
    let json_rows = json["rows"].as_array().unwrap();
    for (c, j) in csv_rows.iter().zip(json_rows) {
        assert_eq!(c.len(), header.len());
        for (&k, &v) in c {
            match &j[k] {
                serde_json::Value::String(s) => assert_eq!(s, v, "{k}"),
                serde_json::Value::Number(n) => {
                    // Both hold the shortest round-trip decimal; serde_json's default parser
                    // may land one ulp off it.
                    let (a, b) = (n.as_f64().unwrap(), v.parse::<f64>().unwrap());
                    assert!((a - b).abs() <= 1e-14 * a.abs().max(1.0), "{k}: {a} vs {v}")
                }
                other => panic!("{k}: {other:?}"),
            }
        }
    }

    // The table: one line per row, its numbers the CSV's (rounded as the table says).
    // (mode, blend, unit, slots, path, phase) → the numbers.
    type Key = (String, String, String, String, String, String);
    let mut table: HashMap<Key, Vec<String>> = HashMap::new();
    for line in stdout.lines() {
        let t: Vec<&str> = line.split_whitespace().collect();
        if t.len() < 17 || !["recon", "mirror"].contains(&t[0]) {
            continue;
        }
        let (text, numbers) = t.split_at(t.len() - 11);
        let key = (
            text[0].to_string(),
            text[1].to_string(),
            text[2].to_string(),
            text[3].to_string(), // slots
            text[text.len() - 2].to_string(),
            text[text.len() - 1].to_string(),
        );
        let old = table.insert(key, numbers.iter().map(|s| s.to_string()).collect());
        assert!(old.is_none(), "two table lines for {line}");
    }
    assert_eq!(table.len(), rows.len(), "{stdout}");
    for r in &rows {
        let key = (
            r.mode.clone(),
            r.blend.clone(),
            r.granularity.clone(),
            r.slots.to_string(),
            r.path.clone(),
            r.phase.clone(),
        );
        let t = table
            .get(&key)
            .unwrap_or_else(|| panic!("no line for {key:?}"));
        let expect = [
            r.frames.to_string(),
            r.requests.to_string(),
            r.hits.to_string(),
            r.misses.to_string(),
            format!("{:.2}", 100.0 * r.misses as f64 / r.requests as f64),
            r.loads.to_string(),
            r.evictions.to_string(),
            r.over_budget.to_string(),
            format!("{:.3}", r.bytes_decoded as f64 / 1e6),
            format!("{:.1}", r.decode_ms),
            format!("{:.1}", r.frame_ms),
        ];
        assert_eq!(t.as_slice(), expect.as_slice(), "{key:?}");
    }
    // Recon does not blend: it runs once, with blend "-".
    assert!(rows
        .iter()
        .filter(|r| r.mode == "recon")
        .all(|r| r.blend == "-"));
    assert!(rows
        .iter()
        .any(|r| r.mode == "mirror" && r.blend == "distance"));
    assert!(stdout.contains("second revolution"), "{stdout}");
}

#[test]
fn bad_inputs_give_clear_errors_and_a_failing_exit() {
    let store = common::store_path();
    let store = store.to_str().unwrap();
    let missing = std::env::temp_dir().join(format!("oslf-cache-stats-{}", std::process::id()));
    let missing = missing.join("nope.oslf");
    for (args, says) in [
        (vec![missing.to_str().unwrap()], "nope.oslf"),
        (vec![store, "--modes", "recon,shiny"], "shiny"),
        (vec![store, "--frames", "0"], "--frames 0"),
        (vec![store, "--still-frames", "0"], "--still-frames 0"),
        (vec![store, "--slots", "0"], "at least one slot"),
        (vec![store, "--slots", "150%"], "(0, 100]"),
        (vec![store, "--slots", "many"], "many"),
        (vec![store, "--granularity", "texel"], "texel"),
        (vec![store, "--paths", "spiral"], "spiral"),
        (vec![store, "--orbit-degrees", "inf"], "--orbit-degrees"),
        (vec![store, "--cache-mb", "0.000001"], "holds no cube map"),
        (vec![store, "-M", "0"], "M = 0"),
    ] {
        let out = cache_stats(&args);
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success(), "{args:?} succeeded");
        assert!(err.contains(says), "{args:?}: {err}");
        assert!(out.stdout.is_empty(), "{args:?} printed a table");
    }
}
