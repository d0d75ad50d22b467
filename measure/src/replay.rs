//! Cache replay (thesis §6.6, Tables 6.3–6.7): renders a store along a camera path — a still
//! view, or an orbit around the object — and sums the cache's per-frame counters
//! ([`CacheStats`]) into rows per phase of the path: the cold start, the steady state, the
//! whole path. `oslf cache-stats` runs this for lists of modes, blends, granularities and
//! cache sizes, with a fresh [`Renderer`] (a cold cache) for every row group.
//!
//! **Units.** A *request* is one unit that a frame's shading needs, counted once per frame
//! however many pixels read it: a cube map with [`Granularity::Cube`], a face with
//! [`Granularity::Face`]; the pinned environment cube counts every frame (one cube, or six
//! faces) and always hits. A *hit* is a requested unit wholly resident on the GPU when the
//! frame is first shaded, a *miss* one that is not; with misses resolved (the default) the
//! renderer then loads and shades again, and what it loads counts in `loads`, never as more
//! requests. So a frame requests its working set once, unlike the thesis, whose software
//! renderer counted every texel lookup (a two-item cache could hit 75 % there; here a cache
//! smaller than a frame's working set misses the rest every frame). The GPU budget is in
//! cube-map slots for both granularities; with [`Granularity::Face`] a slot holds only the
//! faces read. When a needed face is not resident, reconstruction falls back to another
//! candidate and marks the face it reads as well (shade.wgsl), so under a budget short of the
//! working set a frame can request a few more units than with everything resident.
//!
//! **Phases.** `cold`: the first frame (an empty cache). `steady`: for a still view, every
//! frame after the first; for an orbit that reaches 360°, every frame at 360° or more (the
//! second revolution on, whose views the first showed); for a shorter orbit, the last
//! ⌊frames/2⌋ frames ([`CameraPath::steady_from`]). `all`: every frame (orbits only).
//!
//! Before a path, [`replay`] shades one frame looking away from the object (nothing is
//! requested but the pinned environment cube): that compiles the mode's pipeline and sizes
//! the render targets, so that the cold frame times the cache and not the shader compiler. It
//! is reported as [`Replay::setup_seconds`] and counted nowhere else.

use std::time::Instant;

use glam::{Quat, Vec3};
use oslf_geometry::Camera;
use serde::{Deserialize, Serialize};

use oslf_runtime::{Blend, CacheStats, Granularity, Mode, RenderOptions, Renderer, ShadingParams};

pub use crate::error::ReplayParam;
use crate::error::{MeasureError, Result};

/// The kind of camera path.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum PathKind {
    /// The same view every frame.
    Still,
    /// The camera turns about the up axis through its target.
    Orbit,
}

impl PathKind {
    /// Every kind, in CLI order.
    pub const ALL: [PathKind; 2] = [PathKind::Still, PathKind::Orbit];

    /// The CLI name.
    pub fn name(self) -> &'static str {
        match self {
            PathKind::Still => "still",
            PathKind::Orbit => "orbit",
        }
    }
}

impl std::str::FromStr for PathKind {
    type Err = MeasureError;
    fn from_str(s: &str) -> Result<Self> {
        Self::ALL
            .into_iter()
            .find(|k| k.name() == s)
            .ok_or_else(|| MeasureError::Invalid(format!("unknown path {s:?} (still or orbit)")))
    }
}

/// A part of a path whose frames are summed into one row.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Phase {
    /// The first frame, from an empty cache.
    Cold,
    /// The frames from [`CameraPath::steady_from`] on.
    Steady,
    /// Every frame.
    All,
}

impl Phase {
    /// The name in tables.
    pub fn name(self) -> &'static str {
        match self {
            Phase::Cold => "cold",
            Phase::Steady => "steady",
            Phase::All => "all",
        }
    }
}

/// The cameras of a replay, one per frame, and where its steady state begins.
#[derive(Clone, Debug)]
pub struct CameraPath {
    /// Still or orbit.
    pub kind: PathKind,
    /// One camera per frame.
    pub cameras: Vec<Camera>,
    /// Index of the first steady-state frame (`cameras.len()` when there is none).
    pub steady_from: usize,
    /// What the steady state is, in words (for reports).
    pub steady_note: String,
}

impl CameraPath {
    /// `frames` frames of `camera`; the steady state is every frame after the first.
    pub fn still(camera: Camera, frames: u32) -> Result<Self> {
        check_frames(frames, ReplayParam::StillFrames)?;
        let n = frames as usize;
        Ok(Self {
            kind: PathKind::Still,
            cameras: vec![camera; n],
            steady_from: 1,
            steady_note: if n > 1 {
                format!("frames 2–{n}")
            } else {
                "none (one frame)".into()
            },
        })
    }

    /// `frames` frames turning `degrees` in all about the axis through `start.target` along
    /// `start.up`, at equal steps from `start` (frame i at i·degrees/frames, so a whole number
    /// of revolutions does not show the first view twice in a row at the seam).
    ///
    /// The steady state is every frame at an angle of 360° or more when there is one (the
    /// second revolution onwards); otherwise the last ⌊frames/2⌋ frames. When a revolution
    /// takes a whole number of frames (`360 · frames / degrees`), the second revolution shows
    /// exactly the first's cameras, so a budget holding every cube misses nothing there.
    pub fn orbit(start: Camera, frames: u32, degrees: f32) -> Result<Self> {
        check_frames(frames, ReplayParam::OrbitFrames)?;
        check_degrees(degrees)?;
        let axis = start.up.try_normalize().unwrap_or(Vec3::Z);
        let offset = start.position - start.target;
        let n = frames as usize;
        let step = f64::from(degrees) / n as f64;
        let cameras = (0..n)
            .map(|i| {
                // Reduced to one turn first, so that a later revolution's frame is the same
                // camera, bit for bit, as the first revolution's at the same angle.
                let angle = (step * i as f64).rem_euclid(360.0).to_radians() as f32;
                Camera {
                    position: start.target + Quat::from_axis_angle(axis, angle) * offset,
                    ..start
                }
            })
            .collect();
        // First frame at 360° or more: i·|step| ≥ 360, with a tolerance for rounding.
        let revolution = if step != 0.0 {
            (360.0 / step.abs() - 1e-6).ceil().max(0.0) as usize
        } else {
            usize::MAX
        };
        let (steady_from, steady_note) = if revolution < n {
            (
                revolution,
                format!(
                    "frames {}–{n} (at 360° and beyond: the second revolution on)",
                    revolution + 1
                ),
            )
        } else if n / 2 > 0 {
            (
                n - n / 2,
                format!(
                    "frames {}–{n} (the last half: the orbit does not come round)",
                    n - n / 2 + 1
                ),
            )
        } else {
            (n, "none (one frame)".into())
        };
        Ok(Self {
            kind: PathKind::Orbit,
            cameras,
            steady_from,
            steady_note,
        })
    }

    /// The frame range of `phase` (empty when the path has no such frames).
    pub fn range(&self, phase: Phase) -> std::ops::Range<usize> {
        let n = self.cameras.len();
        match phase {
            Phase::Cold => 0..n.min(1),
            Phase::Steady => self.steady_from.min(n)..n,
            Phase::All => 0..n,
        }
    }
}

/// Errors when a path asks for no frames (`param` names which).
pub fn check_frames(frames: u32, param: ReplayParam) -> Result<()> {
    if frames == 0 {
        return Err(MeasureError::InvalidParam {
            param,
            problem: "0: a path needs at least one frame".into(),
        });
    }
    Ok(())
}

/// Errors when the orbit's angle is not a finite number.
pub fn check_degrees(degrees: f32) -> Result<()> {
    if !degrees.is_finite() {
        return Err(MeasureError::InvalidParam {
            param: ReplayParam::OrbitDegrees,
            problem: format!("{degrees} must be a finite number"),
        });
    }
    Ok(())
}

/// A GPU cache size as the command takes it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum CacheSize {
    /// This many slots (cube maps).
    Slots(u32),
    /// This share of the store's cube maps (environment cube included), rounded up.
    Percent(f64),
    /// As many whole cube maps as fit in this many MB (10⁶ bytes) of texels.
    Megabytes(f64),
    /// Every cube of the store (the renderer's default budget, up to 1 GiB of texels).
    All,
}

impl std::str::FromStr for CacheSize {
    type Err = MeasureError;
    /// `N` slots, `P%` of the store's cubes, `all`.
    fn from_str(s: &str) -> Result<Self> {
        let bad = |why: &str| {
            MeasureError::Invalid(format!(
                "cache size {s:?}: {why} (a number of slots, a percentage such as 25%, or all)"
            ))
        };
        if s == "all" {
            return Ok(Self::All);
        }
        if let Some(p) = s.strip_suffix('%') {
            let p: f64 = p.trim().parse().map_err(|_| bad("not a percentage"))?;
            if !(p > 0.0 && p <= 100.0) {
                return Err(bad("a percentage must be in (0, 100]"));
            }
            return Ok(Self::Percent(p));
        }
        match s.trim().parse::<u32>() {
            Ok(0) => Err(bad("the GPU cache needs at least one slot")),
            Ok(n) => Ok(Self::Slots(n)),
            Err(_) => Err(bad("not a whole number")),
        }
    }
}

impl CacheSize {
    /// The label in tables: as given (`64`, `25%`, `4MB`, `all`).
    pub fn label(&self) -> String {
        match self {
            Self::Slots(n) => n.to_string(),
            Self::Percent(p) => format!("{p}%"),
            Self::Megabytes(mb) => format!("{mb}MB"),
            Self::All => "all".into(),
        }
    }

    /// The [`oslf_runtime::CacheConfig::gpu_slots`] for `store` (`None` = all) on an adapter
    /// with (`adapter_has_bc`, [`oslf_runtime::Gpu::has_bc`]) or without BC texture compression, which
    /// decides how many cube maps a megabyte buys.
    pub fn gpu_slots(
        &self,
        store: &oslf_format::Store,
        adapter_has_bc: bool,
    ) -> Result<Option<u32>> {
        Ok(match *self {
            Self::Slots(n) => Some(n),
            Self::Percent(p) => {
                Some(((p / 100.0 * f64::from(store.cube_count())).ceil() as u32).max(1))
            }
            Self::Megabytes(mb) => Some(oslf_runtime::cache::slots_for_megabytes(
                store,
                mb,
                adapter_has_bc,
            )?),
            Self::All => None,
        })
    }
}

/// One rendered frame of a replay.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct FrameRecord {
    /// The frame's cache counters ([`oslf_runtime::Frame::stats`]).
    pub stats: CacheStats,
    /// Wall time of [`Renderer::render`], to GPU completion (image not read back).
    pub seconds: f64,
    /// Shading passes.
    pub passes: u32,
}

/// A path rendered with one renderer.
#[derive(Clone, Debug)]
pub struct Replay {
    /// Per frame.
    pub frames: Vec<FrameRecord>,
    /// The priming frame's wall time (pipeline compile, render targets), not counted in
    /// `frames`.
    pub setup_seconds: f64,
}

/// Renders `path` with `renderer` (which should be fresh: its cache cold), after one priming
/// frame looking away from the object. `options.read_pixels` is ignored (off).
pub fn replay(
    renderer: &mut Renderer,
    path: &CameraPath,
    params: &ShadingParams,
    options: &RenderOptions,
) -> Result<Replay> {
    let options = RenderOptions {
        read_pixels: false,
        ..*options
    };
    let first = path
        .cameras
        .first()
        .ok_or_else(|| MeasureError::Invalid("a path needs at least one frame".into()))?;
    // The same camera turned round: the object is behind it, so nothing is rasterized.
    let away = Camera {
        target: first.position + (first.position - first.target),
        ..*first
    };
    let start = Instant::now();
    let primed = renderer.render(&away, params, &options)?;
    let setup_seconds = start.elapsed().as_secs_f64();
    let pinned = u64::from(renderer.store().env_cube_index().is_some())
        * match renderer.cache().granularity() {
            Granularity::Cube => 1,
            Granularity::Face => 6,
        };
    if primed.stats.requests > pinned {
        return Err(MeasureError::Invalid(format!(
            "the priming frame, looking away from the object, requested {} units",
            primed.stats.requests
        )));
    }
    let mut frames = Vec::with_capacity(path.cameras.len());
    for camera in &path.cameras {
        let start = Instant::now();
        let frame = renderer.render(camera, params, &options)?;
        frames.push(FrameRecord {
            stats: frame.stats,
            seconds: start.elapsed().as_secs_f64(),
            passes: frame.passes,
        });
    }
    Ok(Replay {
        frames,
        setup_seconds,
    })
}

/// What a row group was rendered with.
#[derive(Clone, Debug)]
pub struct RowKey {
    pub mode: Mode,
    /// `None` for modes that do not blend (recon).
    pub blend: Option<Blend>,
    pub granularity: Granularity,
    /// The cache size as asked for (`64`, `25%`, `4MB`, `all`).
    pub size: String,
    /// GPU slots the renderer has.
    pub slots: u32,
}

impl RowKey {
    /// `cube` or `face`.
    pub fn granularity_name(&self) -> &'static str {
        match self.granularity {
            Granularity::Cube => "cube",
            Granularity::Face => "face",
        }
    }
}

/// One line of the statistics: a phase of a path under one configuration. Counts and times
/// are sums over the phase's frames except `frame_ms` (the mean). Requests, hits, misses and
/// miss rate are in the granularity's units (see the module docs).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Row {
    pub mode: String,
    /// The blend, `-` for recon.
    pub blend: String,
    pub granularity: String,
    /// The cache size as asked for.
    pub size: String,
    /// GPU slots (cube maps) it gave.
    pub slots: u32,
    pub path: String,
    pub phase: String,
    /// First and last frame of the phase, 1-based.
    pub first_frame: usize,
    pub last_frame: usize,
    pub frames: usize,
    pub requests: u64,
    pub hits: u64,
    pub misses: u64,
    /// `misses / requests`.
    pub miss_rate: f64,
    /// Units made resident on the GPU.
    pub loads: u64,
    /// Cubes evicted from GPU slots.
    pub evictions: u64,
    /// Needed units the GPU budget could not hold (after the frame's last pass).
    pub over_budget: u64,
    /// Faces taken from the RAM level instead of decoding.
    pub ram_hits: u64,
    /// Faces decoded from the store.
    pub faces_decoded: u64,
    /// Bytes of texels decoded.
    pub bytes_decoded: u64,
    /// Bytes uploaded to the GPU.
    pub bytes_uploaded: u64,
    /// Wall time decoding (milliseconds).
    pub decode_ms: f64,
    /// Wall time handing uploads to the queue.
    pub upload_ms: f64,
    /// Wall time of the cache's CPU work (feedback, plan, decode, upload, indirection).
    pub cache_ms: f64,
    /// Mean wall time of a frame (all its passes, to GPU completion).
    pub frame_ms: f64,
    /// Shading passes run.
    pub passes: u64,
}

/// The rows of one replay: one per phase that has frames (`cold`, `steady`, `all`; a still
/// path's `all` is left out as it adds only the cold frame to `steady`).
pub fn rows(key: &RowKey, path: &CameraPath, replay: &Replay) -> Vec<Row> {
    let phases: &[Phase] = match path.kind {
        PathKind::Still => &[Phase::Cold, Phase::Steady],
        PathKind::Orbit => &[Phase::Cold, Phase::Steady, Phase::All],
    };
    phases
        .iter()
        .filter_map(|&phase| {
            let range = path.range(phase);
            let frames = replay.frames.get(range.clone())?;
            if frames.is_empty() {
                return None;
            }
            let mut s = CacheStats::default();
            let (mut seconds, mut passes) = (0.0, 0u64);
            for f in frames {
                s.add(&f.stats);
                seconds += f.seconds;
                passes += u64::from(f.passes);
            }
            Some(Row {
                mode: key.mode.name().into(),
                blend: key.blend.map_or("-", Blend::name).into(),
                granularity: key.granularity_name().into(),
                size: key.size.clone(),
                slots: key.slots,
                path: path.kind.name().into(),
                phase: phase.name().into(),
                first_frame: range.start + 1,
                last_frame: range.end,
                frames: frames.len(),
                requests: s.requests,
                hits: s.hits,
                misses: s.misses,
                miss_rate: s.miss_rate,
                loads: s.loads,
                evictions: s.evictions,
                // Frame counters keep the last pass's shortfall; summed over frames here.
                over_budget: frames.iter().map(|f| f.stats.unresolved).sum(),
                ram_hits: s.ram_hits,
                faces_decoded: s.ram_misses,
                bytes_decoded: s.bytes_decoded,
                bytes_uploaded: s.bytes_uploaded,
                decode_ms: s.decode_seconds * 1e3,
                upload_ms: s.upload_seconds * 1e3,
                cache_ms: s.cache_seconds * 1e3,
                frame_ms: seconds * 1e3 / frames.len() as f64,
                passes,
            })
        })
        .collect()
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    fn camera() -> Camera {
        Camera {
            position: Vec3::new(3.0, 0.0, 1.0),
            target: Vec3::new(0.0, 0.0, 1.0),
            up: Vec3::Z,
            vfov_deg: 40.0,
        }
    }

    #[test]
    fn an_orbit_turns_about_the_up_axis_and_its_steady_state_is_the_second_revolution() {
        let p = CameraPath::orbit(camera(), 8, 720.0).unwrap();
        assert_eq!(p.cameras.len(), 8);
        assert_eq!(p.steady_from, 4);
        for (i, c) in p.cameras.iter().enumerate() {
            assert!((c.position - c.target).length() - 3.0 < 1e-5);
            assert!((c.position.z - 1.0).abs() < 1e-5);
            // The second revolution repeats the first's views exactly.
            if i >= 4 {
                assert_eq!(c.position, p.cameras[i - 4].position);
            }
        }
        assert!((p.cameras[1].position - Vec3::new(0.0, 3.0, 1.0)).length() < 1e-4);
        assert_eq!(p.range(Phase::Cold), 0..1);
        assert_eq!(p.range(Phase::Steady), 4..8);
        assert_eq!(p.range(Phase::All), 0..8);
        // One revolution never comes round: the last half.
        let p = CameraPath::orbit(camera(), 9, 360.0).unwrap();
        assert_eq!(p.range(Phase::Steady), 5..9);
        let p = CameraPath::orbit(camera(), 1, 720.0).unwrap();
        assert!(p.range(Phase::Steady).is_empty());
        assert!(CameraPath::orbit(camera(), 0, 360.0).is_err());
        assert!(CameraPath::orbit(camera(), 4, f32::NAN).is_err());
        let s = CameraPath::still(camera(), 3).unwrap();
        assert_eq!(s.range(Phase::Steady), 1..3);
        assert!(CameraPath::still(camera(), 0)
            .unwrap_err()
            .to_string()
            .contains("at least one frame"));
    }

    /// Four frames of an orbit and their cache counters (misses 9, 4, 0, 0), and a row key:
    /// the rows' tests here and in [`crate::cache_stats`].
    pub(crate) fn four_frame_orbit() -> (CameraPath, Replay, RowKey) {
        let path = CameraPath::orbit(camera(), 4, 720.0).unwrap();
        let frame = |requests: u64, misses: u64| FrameRecord {
            stats: CacheStats {
                frames: 1,
                requests,
                hits: requests - misses,
                misses,
                loads: misses,
                bytes_decoded: misses * 1000,
                unresolved: 1,
                ..Default::default()
            },
            seconds: 0.01,
            passes: 2,
        };
        let replay = Replay {
            frames: vec![frame(10, 9), frame(12, 4), frame(10, 0), frame(12, 0)],
            setup_seconds: 0.0,
        };
        let key = RowKey {
            mode: Mode::Mirror,
            blend: Some(Blend::Normal),
            granularity: Granularity::Face,
            size: "25%".into(),
            slots: 30,
        };
        (path, replay, key)
    }

    #[test]
    fn rows_sum_their_phase() {
        let (path, replay, key) = four_frame_orbit();
        let rows = rows(&key, &path, &replay);
        assert_eq!(rows.len(), 3);
        let all = &rows[2];
        assert_eq!((all.requests, all.hits, all.misses), (44, 31, 13));
        assert_eq!(all.over_budget, 4);
        assert!((all.miss_rate - 13.0 / 44.0).abs() < 1e-12);
        assert_eq!((rows[1].first_frame, rows[1].last_frame), (3, 4));
        assert_eq!(rows[1].misses, 0);
    }
}

/// One (mode, blend) to replay, with its parameters; recon does not blend (`None`).
pub type Shading = (Mode, Option<Blend>, ShadingParams);

/// One renderer's worth of work, with what it cost to set up.
#[derive(Clone, Debug, Serialize)]
pub struct ReplayInfo {
    pub mode: String,
    pub blend: String,
    pub granularity: String,
    pub size: String,
    pub slots: u32,
    pub path: String,
    /// `Renderer::new`: tessellation, uploads, the pool.
    pub renderer_ms: f64,
    /// The priming frame (pipeline compile).
    pub setup_ms: f64,
}

/// What [`replay_all`] replays: every shading × granularity × GPU budget × path.
pub struct ReplayPlan<'a> {
    pub shadings: &'a [Shading],
    pub granularities: &'a [Granularity],
    /// GPU cache budgets as (label, slots; `None` for every cube).
    pub budgets: &'a [(String, Option<u32>)],
    pub paths: &'a [CameraPath],
    pub options: RenderOptions,
    /// The RAM level's budget in bytes.
    pub ram_bytes: u64,
}

/// A replay of [`replay_all`] that has ended.
pub struct ReplayDone<'a> {
    /// Its number, from 1, and how many there are.
    pub index: usize,
    pub total: usize,
    pub info: &'a ReplayInfo,
    pub rows: &'a [Row],
    pub frames: usize,
    /// Wall time, renderer set-up included.
    pub seconds: f64,
    /// Cube maps that failed to decode (their sample points fell back).
    pub failures: Vec<String>,
}

/// Replays every combination of `plan`, each with a fresh renderer (a cold cache) on `gpu`'s
/// device and the store as `open` opens it; `done` hears of each replay as it ends. Returns the
/// rows of every replay and what each cost to set up.
pub fn replay_all(
    gpu: &oslf_runtime::Gpu,
    open: impl Fn() -> Result<oslf_format::Store>,
    plan: &ReplayPlan,
    mut done: impl FnMut(ReplayDone<'_>),
) -> Result<(Vec<Row>, Vec<ReplayInfo>)> {
    let total =
        plan.shadings.len() * plan.granularities.len() * plan.budgets.len() * plan.paths.len();
    let (mut rows, mut infos) = (Vec::new(), Vec::new());
    for (mode, blend, params) in plan.shadings {
        for &granularity in plan.granularities {
            for (label, gpu_slots) in plan.budgets {
                for path in plan.paths {
                    let t = Instant::now();
                    let config = oslf_runtime::CacheConfig {
                        gpu_slots: *gpu_slots,
                        ram_bytes: plan.ram_bytes,
                        granularity,
                        slots_per_texture: None,
                    };
                    let device = oslf_runtime::Gpu::from_device(
                        gpu.device.clone(),
                        gpu.queue.clone(),
                        gpu.adapter_name.clone(),
                    );
                    let mut renderer = Renderer::new(device, open()?, config)
                        .map_err(|e| MeasureError::Invalid(format!("cache size {label}: {e}")))?;
                    let renderer_ms = t.elapsed().as_secs_f64() * 1e3;
                    let result = replay(&mut renderer, path, params, &plan.options)?;
                    let key = RowKey {
                        mode: *mode,
                        blend: *blend,
                        granularity,
                        size: label.clone(),
                        slots: renderer.cache().slots(),
                    };
                    let new_rows = self::rows(&key, path, &result);
                    let info = ReplayInfo {
                        mode: mode.name().into(),
                        blend: blend.map_or("-", Blend::name).into(),
                        granularity: key.granularity_name().into(),
                        size: label.clone(),
                        slots: key.slots,
                        path: path.kind.name().into(),
                        renderer_ms,
                        setup_ms: result.setup_seconds * 1e3,
                    };
                    done(ReplayDone {
                        index: infos.len() + 1,
                        total,
                        info: &info,
                        rows: &new_rows,
                        frames: result.frames.len(),
                        seconds: t.elapsed().as_secs_f64(),
                        failures: renderer
                            .cache()
                            .errors
                            .iter()
                            .map(|e| e.to_string())
                            .collect(),
                    });
                    infos.push(info);
                    rows.extend(new_rows);
                }
            }
        }
    }
    Ok((rows, infos))
}
