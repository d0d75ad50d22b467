//! Progress bars on stderr for the library's long stages ([`Progress`]): sample-map rows,
//! cube maps, ground-truth rows.

use std::sync::{Arc, Mutex};
use std::time::Duration;

use indicatif::{ProgressBar, ProgressStyle};
use oslf_trace::progress::Progress;

/// A bar with ETA for each stage in turn, counting the stage's units.
#[derive(Default)]
struct Bars {
    current: Mutex<Option<ProgressBar>>,
}

impl Progress for Bars {
    fn start(&self, what: &str, total: u64, done: u64) {
        let bar = ProgressBar::new(total);
        bar.set_style(
            ProgressStyle::with_template(&format!(
                "{{spinner}} {what} {{bar:40}} {{pos}}/{{len}} [{{elapsed_precise}} < ETA {{eta_precise}}] {{per_sec}}"
            ))
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
        );
        bar.enable_steady_tick(Duration::from_millis(200));
        bar.set_position(done);
        if let Some(old) = self.lock().replace(bar) {
            old.finish_and_clear();
        }
    }

    fn advance(&self, n: u64) {
        if let Some(bar) = self.lock().as_ref() {
            bar.inc(n);
        }
    }

    fn finish(&self) {
        if let Some(bar) = self.lock().take() {
            bar.finish_and_clear();
        }
    }
}

impl Bars {
    fn lock(&self) -> std::sync::MutexGuard<'_, Option<ProgressBar>> {
        self.current.lock().unwrap_or_else(|e| e.into_inner())
    }
}

/// Bars on stderr when `enabled` (not `--quiet`), else no reporter.
pub fn bars(enabled: bool) -> Option<Arc<dyn Progress>> {
    enabled.then(|| Arc::new(Bars::default()) as Arc<dyn Progress>)
}
