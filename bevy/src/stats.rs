//! The cache's statistics in the main world: a resource summed over every OSLF object's
//! renderer, and Bevy diagnostics (misses and loads per frame, miss rate, the GPU time of the
//! plugin's G-buffer, prepass, shading and composite passes, the objects extracted) for the usual
//! diagnostic tools.

use std::collections::HashMap;
use std::sync::{Arc, Mutex};

use bevy::app::App;
use bevy::asset::AssetId;
use bevy::diagnostic::{Diagnostic, DiagnosticPath, Diagnostics, RegisterDiagnostic};
use bevy::ecs::prelude::*;
use oslf_runtime::{CacheStats, HostPassSeconds};

use crate::asset::OslfStore;

/// Units (cubes or faces) the frames booked last needed that were not resident: they fell
/// back, and load in the background.
pub const CACHE_MISSES: DiagnosticPath = DiagnosticPath::const_new("oslf/cache_misses");
/// Units made resident by the feedback booked last.
pub const CACHE_LOADS: DiagnosticPath = DiagnosticPath::const_new("oslf/cache_loads");
/// `misses / requests` of the feedback booked last.
pub const CACHE_MISS_RATE: DiagnosticPath = DiagnosticPath::const_new("oslf/cache_miss_rate");
/// GPU milliseconds of the objects' G-buffer passes in the latest frame booked (summed over
/// the stores drawn; where the device has timestamp queries).
pub const GBUFFER_GPU_MS: DiagnosticPath = DiagnosticPath::const_new("oslf/gbuffer_gpu_ms");
/// GPU milliseconds of the objects' shading passes, as [`GBUFFER_GPU_MS`].
pub const SHADE_GPU_MS: DiagnosticPath = DiagnosticPath::const_new("oslf/shade_gpu_ms");
/// GPU milliseconds of the objects' composite passes (into the camera's colour and depth), as
/// [`GBUFFER_GPU_MS`].
pub const COMPOSITE_GPU_MS: DiagnosticPath = DiagnosticPath::const_new("oslf/composite_gpu_ms");
/// GPU milliseconds of the objects' prepass passes (their depth, normals and motion vectors
/// into the prepass of a camera that has one), as [`GBUFFER_GPU_MS`].
pub const PREPASS_GPU_MS: DiagnosticPath = DiagnosticPath::const_new("oslf/prepass_gpu_ms");

/// OSLF objects extracted to the render world since the previous main-world update: every
/// object in a frame where one of them (its component, transform or visibility) or a store
/// changed, none in a frame where nothing did.
pub const EXTRACTED_OBJECTS: DiagnosticPath = DiagnosticPath::const_new("oslf/extracted_objects");

/// The cache counters of every OSLF object, as the render world booked them (feedback arrives
/// a few frames after it was drawn: the GPU is never waited for).
#[derive(Resource, Clone, Debug, Default)]
pub struct OslfCacheStats {
    /// Summed over every frame booked so far.
    pub total: CacheStats,
    /// The frames booked since the previous main-world update (`frames` = 0 when none).
    pub latest: CacheStats,
}

/// What the render world booked since the main world last looked: cache counters, and each
/// store's latest pass times.
#[derive(Default)]
pub(crate) struct Booked {
    cache: CacheStats,
    passes: HashMap<AssetId<OslfStore>, HostPassSeconds>,
    extracted: u64,
}

/// The render world's side of [`OslfCacheStats`] and the diagnostics.
#[derive(Resource, Clone, Default)]
pub(crate) struct StatsSink(Arc<Mutex<Booked>>);

impl StatsSink {
    pub fn add(&self, stats: &CacheStats) {
        if let Ok(mut s) = self.0.lock() {
            s.cache.add(stats);
        }
    }

    pub fn passes(&self, store: AssetId<OslfStore>, seconds: HostPassSeconds) {
        if let Ok(mut s) = self.0.lock() {
            s.passes.insert(store, seconds);
        }
    }

    pub fn extracted(&self, objects: u64) {
        if let Ok(mut s) = self.0.lock() {
            s.extracted += objects;
        }
    }

    fn take(&self) -> Booked {
        self.0
            .lock()
            .map(|mut s| std::mem::take(&mut *s))
            .unwrap_or_default()
    }
}

pub(crate) fn register(app: &mut App) {
    app.init_resource::<OslfCacheStats>()
        .register_diagnostic(Diagnostic::new(CACHE_MISSES))
        .register_diagnostic(Diagnostic::new(CACHE_LOADS))
        .register_diagnostic(Diagnostic::new(CACHE_MISS_RATE))
        .register_diagnostic(Diagnostic::new(GBUFFER_GPU_MS).with_suffix("ms"))
        .register_diagnostic(Diagnostic::new(SHADE_GPU_MS).with_suffix("ms"))
        .register_diagnostic(Diagnostic::new(COMPOSITE_GPU_MS).with_suffix("ms"))
        .register_diagnostic(Diagnostic::new(PREPASS_GPU_MS).with_suffix("ms"))
        .register_diagnostic(Diagnostic::new(EXTRACTED_OBJECTS));
}

/// Moves what the render world booked into [`OslfCacheStats`] and the diagnostics.
pub(crate) fn publish_stats(
    sink: Res<StatsSink>,
    mut stats: ResMut<OslfCacheStats>,
    mut diagnostics: Diagnostics,
) {
    let booked = sink.take();
    let sum = |pass: fn(&HostPassSeconds) -> Option<f64>| {
        let times: Vec<f64> = booked.passes.values().filter_map(pass).collect();
        (!times.is_empty()).then(|| times.iter().sum::<f64>() * 1e3)
    };
    if let Some(ms) = sum(|p| p.gbuffer) {
        diagnostics.add_measurement(&GBUFFER_GPU_MS, || ms);
    }
    if let Some(ms) = sum(|p| p.shade) {
        diagnostics.add_measurement(&SHADE_GPU_MS, || ms);
    }
    if let Some(ms) = sum(|p| p.composite) {
        diagnostics.add_measurement(&COMPOSITE_GPU_MS, || ms);
    }
    if let Some(ms) = sum(|p| p.prepass) {
        diagnostics.add_measurement(&PREPASS_GPU_MS, || ms);
    }
    diagnostics.add_measurement(&EXTRACTED_OBJECTS, || booked.extracted as f64);
    let latest = booked.cache;
    if latest.frames > 0 {
        stats.total.add(&latest);
        diagnostics.add_measurement(&CACHE_MISSES, || latest.misses as f64);
        diagnostics.add_measurement(&CACHE_LOADS, || latest.loads as f64);
        diagnostics.add_measurement(&CACHE_MISS_RATE, || latest.miss_rate);
    }
    stats.latest = latest;
}
