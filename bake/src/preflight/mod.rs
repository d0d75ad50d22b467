//! Preflight: before any slow work, estimate what a bake will cost — peak memory,
//! store size, time — from the scene and its settings alone, and refuse a bake that cannot
//! fit the machine, naming the setting to change.
//!
//! [`estimate`] is a pure function of the scene and a thread count: it reads no file and
//! traces no ray (it tessellates nothing either: triangle counts come from
//! [`oslf_geometry::bezier::BezierPatch::tessellation_level`], patch areas from a 16 × 16 grid of evaluations).
//! [`check`] compares an [`Estimate`] with [`Limits`] — what the machine offers, read by
//! [`Limits::of_machine`] ([`machine::available_memory`], [`machine::free_space`]) or given by the caller (tests) —
//! and with hard limits that no machine lifts ([`hard_limits`]).
//!
//! Every constant below says where its figure comes from: the code it models (bake/stages.rs,
//! capture.rs, sample_map.rs, sample_points.rs, bvh/, oslf-format's writer) or a measurement
//! (docs/measurements.md, or the counting-allocator test in bake/tests/preflight.rs).
//!
//! What is only estimated: the number of sample points (placement removes some, §6.3 refinement
//! adds up to as many again), the compression of the cube maps (scene-dependent; the table's
//! figures are the gazebo's), and the speed (scene- and machine-dependent, hence a range).
//!
//! Submodules: `costs` (the cost model's constants, re-exported here) and `terms` (the counts
//! and the terms computed from them).

mod costs;
mod terms;

use std::fmt;
use std::path::{Path, PathBuf};

use oslf_util::machine;

pub use costs::*;
use oslf_scene::error::BakeError;
use oslf_scene::scene::Scene;
use terms::*;
pub use terms::{Term, TimeTerm};

/// What a bake will cost, from its settings alone ([`estimate`]).
#[derive(Clone, Debug, PartialEq)]
pub struct Estimate {
    /// The thread count the times are for.
    pub threads: usize,
    /// Sample points: (fewest, typical, most) — see [`POINTS_TYPICAL`].
    pub sample_points: (u64, u64, u64),
    /// Cube maps the store holds, typical (points + the environment cube).
    pub cubes: u64,
    /// Triangles of the BVH (environment meshes + the tessellated OSLF objects).
    pub triangles: u64,
    /// Sample-map texels over all patches.
    pub map_texels: u64,
    /// Path vertices of the capture: cubes × 6 × res² × spp × (bounces + 1), spp rounded up to
    /// a square as the capture does (typical cube count).
    pub path_vertices: u64,
    /// Rays the capture traces at most: `path_vertices` × (1 + delta lights + 1 if the
    /// environment is not black).
    pub capture_rays: u64,
    /// The largest memory in use at once, bytes: the largest of the stages' sums (see
    /// `memory`).
    pub peak_memory_bytes: u64,
    /// The terms of the stage that peaks, largest first.
    pub memory: Vec<Term>,
    /// Which stage peaks: "placement", "sample maps" or "capture".
    pub peak_stage: &'static str,
    /// Store size: typical, and (low, high) = typical × [`STORE_RANGE`].
    pub store_bytes: u64,
    pub store_range: (u64, u64),
    /// Terms of the store size, largest first.
    pub store: Vec<Term>,
    /// Wall seconds on `threads` threads, (optimistic, pessimistic).
    pub seconds: (f64, f64),
    /// Terms of the time, largest first.
    pub time: Vec<TimeTerm>,
    /// Things that will work but may not be what was meant (shown, never refused).
    pub warnings: Vec<String>,
    /// The capture device the cube maps' time is for ([`Estimate::on_device`]); `None`: the
    /// CPU.
    pub device: Option<String>,
    /// The device memory its capture holds, bytes, where the device says ([`for_device`]).
    pub device_memory_bytes: Option<u64>,
}

/// What the machine offers. `None`: unknown, not checked.
#[derive(Clone, Debug, PartialEq)]
pub struct Limits {
    /// Bytes of memory available (Linux: `MemAvailable`).
    pub available_memory: Option<u64>,
    /// Free bytes on the store's volume, and the directory it was measured for (named in the
    /// error).
    pub free_space: Option<(PathBuf, u64)>,
    /// Refuse a bake whose optimistic time exceeds this many seconds.
    pub max_seconds: Option<f64>,
}

impl Limits {
    /// This machine's limits for a store written at `output`: [`machine::available_memory`],
    /// [`machine::free_space`] of its directory, [`DEFAULT_MAX_SECONDS`].
    pub fn of_machine(output: &Path) -> Limits {
        let dir = match output.parent() {
            Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
            _ => PathBuf::from("."),
        };
        Limits {
            available_memory: machine::available_memory(),
            free_space: machine::free_space(&dir).map(|b| (dir, b)),
            max_seconds: Some(DEFAULT_MAX_SECONDS),
        }
    }

    /// No limit at all (only [`hard_limits`] apply).
    pub fn none() -> Limits {
        Limits {
            available_memory: None,
            free_space: None,
            max_seconds: None,
        }
    }
}

/// Why a bake was refused before it started.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum PreflightError {
    #[error(
        "the bake needs about {} of memory ({} {}: {}) but {} are available; {}",
        bytes(*.needed), .term.name, bytes(.term.bytes), .term.detail, bytes(*.available), .term.remedy
    )]
    Memory {
        needed: u64,
        available: u64,
        term: Term,
    },
    #[error(
        "the store needs about {} ({} {}: {}) but {} has {} free; {}",
        bytes(*.needed), .term.name, bytes(.term.bytes), .term.detail, .dir.display(), bytes(*.free), .term.remedy
    )]
    Disk {
        needed: u64,
        dir: PathBuf,
        free: u64,
        term: Term,
    },
    #[error(
        "the bake would take {}–{} on {threads} threads ({}: {}), more than the time limit of {}; {}",
        duration(.seconds.0), duration(.seconds.1), .term.name, .term.detail, duration(*.limit), .term.remedy
    )]
    Time {
        seconds: (f64, f64),
        threads: usize,
        limit: f64,
        term: TimeTerm,
    },
    /// A limit no machine lifts.
    #[error("{0}")]
    Impossible(String),
}

impl From<PreflightError> for BakeError {
    fn from(e: PreflightError) -> Self {
        BakeError::Invalid(e.to_string())
    }
}

/// Estimates what baking `scene` costs on `threads` threads. Pure: reads no file.
pub fn estimate(scene: &Scene, threads: usize) -> Estimate {
    let s = &scene.bake;
    let c = Counts::of(scene, threads);
    let (peak_stage, memory, peak_memory_bytes) = memory_terms(s, &c);
    let (store, store_bytes, store_range) = store_terms(s, &c);
    let (time, seconds) = time_terms(scene, &c);
    Estimate {
        threads: c.threads,
        sample_points: c.points,
        cubes: c.cubes,
        triangles: c.triangles,
        map_texels: c.map_texels,
        path_vertices: c.path_vertices,
        capture_rays: c.capture_rays,
        peak_memory_bytes,
        memory,
        peak_stage,
        store_bytes,
        store_range,
        store,
        seconds,
        time,
        warnings: warnings(s),
        device: None,
        device_memory_bytes: None,
    }
}

/// Refuses what no machine can bake: more sample points (plus the environment cube) than the
/// `u32` sample index and cube count allow.
pub fn hard_limits(e: &Estimate) -> Result<(), PreflightError> {
    if e.sample_points.2 + 1 > MAX_SAMPLE_POINTS {
        return Err(PreflightError::Impossible(format!(
            "up to {} sample points do not fit the store's u32 sample indices (at most {MAX_SAMPLE_POINTS}); lower sample_count",
            e.sample_points.2
        )));
    }
    Ok(())
}

impl Estimate {
    /// The share of one shard of `count` (`oslf bake --shard I/N`): the cube maps, their store
    /// bytes and their capture time divided by `count` (shards differ by at most one cube);
    /// the sample points, sample maps, BVH and memory stay whole, as every shard computes them.
    pub fn for_shard(mut self, count: u32) -> Self {
        let n = u64::from(count.max(1));
        let share = |b: u64| b.div_ceil(n);
        self.cubes = share(self.cubes);
        self.path_vertices = share(self.path_vertices);
        self.capture_rays = share(self.capture_rays);
        let mut store_delta = 0;
        for t in self.store.iter_mut().filter(|t| t.name == "cube maps") {
            let kept = share(t.bytes);
            store_delta += t.bytes - kept;
            t.bytes = kept;
            t.detail = format!("{} (1/{n} of it in this shard)", t.detail);
        }
        self.store.sort_by_key(|t| std::cmp::Reverse(t.bytes));
        self.store_bytes -= store_delta;
        self.store_range = (
            (self.store_bytes as f64 * STORE_RANGE.0) as u64,
            (self.store_bytes as f64 * STORE_RANGE.1) as u64,
        );
        for t in self.time.iter_mut().filter(|t| t.name == "cube maps") {
            t.seconds = (t.seconds.0 / n as f64, t.seconds.1 / n as f64);
            t.detail = format!("{} (1/{n} of it in this shard)", t.detail);
        }
        self.resum_time();
        self
    }
}

/// Checks `e` against [`hard_limits`] and `limits`: memory (the peak against the available
/// memory), disk (the typical store size against the free space), time (the optimistic time
/// against `max_seconds`), in that order. The error names the largest term and its setting.
pub fn check(e: &Estimate, limits: &Limits) -> Result<(), PreflightError> {
    hard_limits(e)?;
    if let Some(available) = limits.available_memory {
        if e.peak_memory_bytes > available {
            return Err(PreflightError::Memory {
                needed: e.peak_memory_bytes,
                available,
                term: e.memory[0].clone(),
            });
        }
    }
    if let Some((dir, free)) = &limits.free_space {
        if e.store_bytes > *free {
            return Err(PreflightError::Disk {
                needed: e.store_bytes,
                dir: dir.clone(),
                free: *free,
                term: e.store[0].clone(),
            });
        }
    }
    if let Some(limit) = limits.max_seconds {
        if e.seconds.0 > limit {
            return Err(PreflightError::Time {
                seconds: e.seconds,
                threads: e.threads,
                limit,
                term: e.time[0].clone(),
            });
        }
    }
    Ok(())
}

/// `bytes` in SI units with three significant digits: `37.5 MB`, `1.65 TB`.
pub fn bytes(b: u64) -> String {
    const UNITS: [&str; 6] = ["B", "kB", "MB", "GB", "TB", "PB"];
    let mut v = b as f64;
    let mut u = 0;
    while v >= 1000.0 && u + 1 < UNITS.len() {
        v /= 1000.0;
        u += 1;
    }
    if u == 0 {
        format!("{b} B")
    } else if v >= 100.0 {
        format!("{v:.0} {}", UNITS[u])
    } else {
        format!("{v:.1} {}", UNITS[u])
    }
}

/// Seconds as `40 s`, `12 min`, `3.5 h`, `14 days`.
pub fn duration(s: f64) -> String {
    if s < 1.0 {
        "<1 s".into()
    } else if s < 90.0 {
        format!("{s:.0} s")
    } else if s < 90.0 * 60.0 {
        format!("{:.0} min", s / 60.0)
    } else if s < 48.0 * 3600.0 {
        format!("{:.1} h", s / 3600.0)
    } else if s < 2.0 * 365.0 * 86400.0 {
        format!("{:.0} days", s / 86400.0)
    } else {
        format!("{:.0} years", s / (365.0 * 86400.0))
    }
}

/// `estimate` for `device`'s capture of `capture` where the device was measured
/// ([`Estimate::on_device`]), with the device memory it holds where the device says; else as it
/// is.
pub fn for_device(
    estimate: Estimate,
    device: Option<&dyn crate::device::CaptureDevice>,
    capture: &oslf_trace::capture::CaptureSettings,
) -> Estimate {
    let Some(device) = device else {
        return estimate;
    };
    let mut estimate = match device.rays_per_second() {
        Some(rate) => estimate.on_device(rate, &device.describe()),
        None => estimate,
    };
    estimate.device_memory_bytes = device.memory_bytes(capture);
    estimate
}

impl Estimate {
    /// This estimate for a capture on a device measured at `rays_per_second` (`device`
    /// names it): the cube maps' time is the capture's rays at that rate (optimistic: half of
    /// them, as on the CPU, whose paths often end early).
    pub fn on_device(mut self, rays_per_second: f64, device: &str) -> Self {
        let rays = self.capture_rays as f64;
        if let Some(t) = self.time.iter_mut().find(|t| t.name == "cube maps") {
            t.seconds = (
                rays * 0.5 / rays_per_second.max(1.0),
                rays / rays_per_second.max(1.0),
            );
            t.detail = format!(
                "{} at {:.1} Mrays/s on {device} (measured)",
                t.detail,
                rays_per_second / 1e6
            );
        }
        self.resum_time();
        self.device = Some(device.to_string());
        self
    }

    /// Sorts the time terms, largest first, and sums them again.
    fn resum_time(&mut self) {
        self.time
            .sort_by(|a, b| b.seconds.1.total_cmp(&a.seconds.1));
        self.seconds = self
            .time
            .iter()
            .fold((0.0, 0.0), |a, t| (a.0 + t.seconds.0, a.1 + t.seconds.1));
    }
}

impl fmt::Display for Estimate {
    /// One line: `estimate: peak memory ~38 MB, store ~14 MB, time ~9 s–1 min on 2 threads`.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "estimate: peak memory ~{}, store ~{}, time ~{}–{} on {} thread{}",
            bytes(self.peak_memory_bytes),
            bytes(self.store_bytes),
            duration(self.seconds.0),
            duration(self.seconds.1),
            self.threads,
            if self.threads == 1 { "" } else { "s" }
        )?;
        if let Some(d) = &self.device {
            write!(f, " with the cube maps on {d}")?;
        }
        match self.device_memory_bytes {
            Some(b) => write!(f, " (GPU memory ~{})", bytes(b)),
            None => Ok(()),
        }
    }
}
