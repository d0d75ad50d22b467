//! Cache replay (`oslf_measure::replay`): the counters add up, an unlimited cache stops missing once the orbit comes round, a smaller cache misses
//! more, and whole cubes decode at least what faces do. The `oslf cache-stats` command is tested in
//! the top-level `tests/cli_cache_stats.rs`.

#[path = "../../runtime/tests/common/mod.rs"]
mod common;

use oslf_measure::replay::{self, CameraPath, Phase, Row, RowKey};
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
    let mut params = ShadingParams::of_mode(mode);
    if let Ok(mc) = params.monte_carlo_mut() {
        mc.m = 4;
    }
    let replay = replay::replay(&mut r, path, &params, &options(resolve)).unwrap();
    assert_eq!(replay.frames.len(), path.cameras.len());
    let key = RowKey {
        mode,
        blend: params.blend().map(|(b, _)| b),
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
                // candidate when the nearest is not resident) marks what it reads as well, and a
                // depth-corrected lookup that meets a face not resident marks its whole cube,
                // so a short budget can only add requests.
                assert!(s.requests >= a.requests, "{p:?}: {s:?} vs {a:?}");
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
            // A cold view does not read every face of every cube it needs, except that a
            // depth-corrected reflection meeting a face not resident requests its whole cube
            // (its search could go on to any face).
            let (c, f) = (phase(&cube, Phase::Cold), phase(&face, Phase::Cold));
            assert!(
                c.bytes_decoded > f.bytes_decoded
                    || (mode != Mode::Recon && c.bytes_decoded == f.bytes_decoded),
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
