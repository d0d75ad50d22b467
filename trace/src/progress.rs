//! Progress of the long stages (sample-map rows, cube maps, ground-truth rows), reported to
//! whoever runs them. The library draws nothing; a tool implements [`Progress`] (the `oslf`
//! command line draws a bar on stderr).

use std::sync::Arc;

/// Receives the progress of the long stages, which run one after another: [`start`], any
/// number of [`advance`] (from any thread), [`finish`].
///
/// [`start`]: Progress::start
/// [`advance`]: Progress::advance
/// [`finish`]: Progress::finish
pub trait Progress: Send + Sync {
    /// A stage starts: `total` units of `what` (e.g. `"cube maps"`), `done` of them already
    /// done (a resumed bake).
    fn start(&self, what: &str, total: u64, done: u64);
    /// `n` more units are done.
    fn advance(&self, n: u64);
    /// The stage has ended.
    fn finish(&self);
}

impl std::fmt::Debug for dyn Progress {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("dyn Progress")
    }
}

/// Reports nothing.
#[derive(Clone, Copy, Debug, Default)]
pub struct Silent;

impl Progress for Silent {
    fn start(&self, _what: &str, _total: u64, _done: u64) {}
    fn advance(&self, _n: u64) {}
    fn finish(&self) {}
}

/// The reporter `progress` names, or [`Silent`].
pub fn or_silent(progress: &Option<Arc<dyn Progress>>) -> &dyn Progress {
    match progress {
        Some(p) => p.as_ref(),
        None => &Silent,
    }
}
