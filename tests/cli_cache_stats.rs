//! `oslf cache-stats`: the table agrees with its CSV and JSON, and bad input is a clear error.

use crate::common;

use std::collections::HashMap;

use common::{oslf, runtime_fixture};
use oslf_measure::replay::Row;

fn cache_stats(args: &[&str]) -> std::process::Output {
    oslf("cache-stats").args(args).output().unwrap()
}

#[test]
fn the_command_prints_a_table_that_agrees_with_its_csv_and_json() {
    let store = runtime_fixture::store_path();
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
    let store = runtime_fixture::store_path();
    let store = store.to_str().unwrap();
    let tmp = tempfile::tempdir().unwrap();
    let missing = tmp.path().join("nope.oslf");
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
