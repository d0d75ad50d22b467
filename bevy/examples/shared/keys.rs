//! The viewer examples' shading keys, as in `oslf view`: 1–6 the mode, `e` the OSLF or the
//! environment-map baseline, `d` depth-corrected lookups, `b` the blend, `[` `]` halve or
//! double M. A key for what the mode does not have changes nothing (the setters refuse it).
//! The tests compile this file too (`bevy/tests/headless.rs`), so that it follows the
//! library's API.

use oslf_bevy::{Blend, Lookup, Mode, Probe, ShadingParams, Source};

/// What a key asks of an object's shading.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ShadingKey {
    /// The mode, with its defaults.
    Mode(Mode),
    /// The OSLF, or the environment-map baseline.
    Source,
    /// Depth-corrected lookups on or off.
    Depth,
    /// The next blend of the four points.
    Blend,
    /// Twice the Monte Carlo samples M (at most 65 536).
    MoreSamples,
    /// Half of them (at least 1).
    FewerSamples,
}

/// Applies `key` to `p`.
pub fn apply(p: &mut ShadingParams, key: ShadingKey) {
    match key {
        ShadingKey::Mode(mode) => *p = ShadingParams::of_mode(mode),
        ShadingKey::Source => {
            let lookup = match p.source() {
                Source::Oslf => Lookup::Probe(Probe::EnvMap),
                Source::EnvMap | Source::Parallax => {
                    let (blend, n) = p.blend().unwrap_or(Lookup::DEFAULT_BLEND);
                    Lookup::oslf(blend, n)
                }
            };
            let _ = p.set_lookup(lookup);
        }
        ShadingKey::Depth => {
            let _ = p.set_depth(!p.depth());
        }
        ShadingKey::Blend => {
            if let Some((blend, n)) = p.blend() {
                let i = Blend::ALL.iter().position(|b| *b == blend).unwrap_or(0);
                let _ = p.set_lookup(Lookup::oslf(Blend::ALL[(i + 1) % Blend::ALL.len()], n));
            }
        }
        ShadingKey::MoreSamples | ShadingKey::FewerSamples => {
            if let Ok(mc) = p.monte_carlo_mut() {
                mc.m = if key == ShadingKey::MoreSamples {
                    (mc.m * 2).min(65536)
                } else {
                    (mc.m / 2).max(1)
                };
            }
        }
    }
}

/// One line of `p`'s settings: mode, source, depth correction, blend and M (where it has them).
pub fn describe(p: &ShadingParams) -> String {
    format!(
        "{:?} {:?} depth {} blend {:?} M {:?}",
        p.mode(),
        p.source(),
        p.depth(),
        p.blend(),
        p.monte_carlo().map(|mc| mc.m)
    )
}
