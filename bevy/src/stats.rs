//! The cache's statistics in the main world: a resource summed over every OSLF object's
//! renderer, and Bevy diagnostics (misses and loads per frame, miss rate) for the usual
//! diagnostic tools.

use std::sync::{Arc, Mutex};

use bevy::app::App;
use bevy::diagnostic::{Diagnostic, DiagnosticPath, Diagnostics, RegisterDiagnostic};
use bevy::ecs::prelude::*;
use oslf_runtime::CacheStats;

/// Units (cubes or faces) the frames booked last needed that were not resident: they fell
/// back, and load in the background.
pub const CACHE_MISSES: DiagnosticPath = DiagnosticPath::const_new("oslf/cache_misses");
/// Units made resident by the feedback booked last.
pub const CACHE_LOADS: DiagnosticPath = DiagnosticPath::const_new("oslf/cache_loads");
/// `misses / requests` of the feedback booked last.
pub const CACHE_MISS_RATE: DiagnosticPath = DiagnosticPath::const_new("oslf/cache_miss_rate");

/// The cache counters of every OSLF object, as the render world booked them (feedback arrives
/// a few frames after it was drawn: the GPU is never waited for).
#[derive(Resource, Clone, Debug, Default)]
pub struct OslfCacheStats {
    /// Summed over every frame booked so far.
    pub total: CacheStats,
    /// The frames booked since the previous main-world update (`frames` = 0 when none).
    pub latest: CacheStats,
}

/// The render world's side: what it booked since the main world last looked.
#[derive(Resource, Clone, Default)]
pub(crate) struct StatsSink(pub Arc<Mutex<CacheStats>>);

impl StatsSink {
    pub fn add(&self, stats: &CacheStats) {
        if let Ok(mut s) = self.0.lock() {
            s.add(stats);
        }
    }

    fn take(&self) -> CacheStats {
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
        .register_diagnostic(Diagnostic::new(CACHE_MISS_RATE));
}

/// Moves what the render world booked into [`OslfCacheStats`] and the diagnostics.
pub(crate) fn publish_stats(
    sink: Res<StatsSink>,
    mut stats: ResMut<OslfCacheStats>,
    mut diagnostics: Diagnostics,
) {
    let latest = sink.take();
    if latest.frames > 0 {
        stats.total.add(&latest);
        diagnostics.add_measurement(&CACHE_MISSES, || latest.misses as f64);
        diagnostics.add_measurement(&CACHE_LOADS, || latest.loads as f64);
        diagnostics.add_measurement(&CACHE_MISS_RATE, || latest.miss_rate);
    }
    stats.latest = latest;
}
