//! The `[bake]` settings of a scene file: the table, with a preset's keys over it, checked
//! and given their defaults.

use std::ops::Range;

use toml::Spanned;

use super::context::Ctx;
use super::raw::{RawBake, RawScene};
use crate::bake_defaults::Unset;
use crate::error::{BakeError, Result};
use crate::scene::{BakeSettings, SampleDensity};

/// Whether a bake denoises its cube maps where `[bake] denoise` is not given.
pub const DENOISE_DEFAULT: bool = true;

impl Ctx<'_> {
    /// The bake settings, where `epsilon` was given (if it was), and which of the settings the
    /// scene chooses ([`crate::bake_defaults`]) the file leaves unset (those hold the former
    /// constant defaults until [`crate::bake_defaults::choose`] sets them).
    /// `target_noise`: in (0, 1], 0 where unset (no adaptive sampling).
    fn target_noise(&self, merged: &RawBake) -> Result<f32> {
        match &merged.target_noise {
            Some(t) if !(t.get_ref().is_finite() && *t.get_ref() > 0.0 && *t.get_ref() <= 1.0) => {
                Err(self.error_at(
                    t.span(),
                    "target_noise must be in (0, 1]: the relative standard error each cube texel samples down to (0.05 is 5 %)",
                ))
            }
            Some(t) => Ok(*t.get_ref() as f32),
            None => Ok(0.0),
        }
    }

    /// `[bake]` with preset `preset`'s keys over it.
    fn merged_bake(&self, raw: &RawScene, preset: Option<&str>) -> Result<RawBake> {
        Ok(match preset {
            None => raw.bake.clone(),
            Some(name) => match raw.presets.get(name) {
                Some(p) => raw.bake.overridden_by(p),
                None => {
                    let known: Vec<&str> = raw.presets.keys().map(String::as_str).collect();
                    return Err(BakeError::Invalid(format!(
                        "{}: no preset named {name:?} (the scene defines: {})",
                        self.path.display(),
                        if known.is_empty() {
                            "none".to_string()
                        } else {
                            known.join(", ")
                        }
                    )));
                }
            },
        })
    }

    pub(super) fn bake_settings(
        &self,
        raw: &RawScene,
        preset: Option<&str>,
    ) -> Result<(BakeSettings, Option<Range<usize>>, Unset)> {
        let merged = self.merged_bake(raw, preset)?;
        let sample_count = match (&merged.sample_count, &merged.sample_spacing) {
            (Some(c), Some(_)) => {
                return Err(self.error_at(
                    c.span(),
                    "give either sample_count or sample_spacing, not both",
                ))
            }
            (Some(c), None) => {
                if *c.get_ref() == 0 || *c.get_ref() > 16_000_000 {
                    return Err(self.error_at(c.span(), "sample_count must be in 1..=16000000"));
                }
                SampleDensity::Count(*c.get_ref())
            }
            (None, Some(s)) => SampleDensity::Spacing(s.0),
            (None, None) => SampleDensity::Count(300),
        };
        let phi = match &merged.phi_samplemap {
            Some(p) if p.get_ref().0 <= 0.0 || p.get_ref().0 >= 90.0 => {
                return Err(self.error_at(
                    p.span(),
                    "phi_samplemap must be in (0, 90) degrees (Eq. 3.10)",
                ))
            }
            Some(p) => p.get_ref().0,
            None => 85.0,
        };
        let spp = match &merged.samples_per_texel {
            Some(s) if *s.get_ref() == 0 || *s.get_ref() > 1 << 16 => {
                return Err(self.error_at(s.span(), "samples_per_texel must be in 1..=65536"))
            }
            Some(s) => *s.get_ref(),
            None => 4,
        };
        let target_noise = self.target_noise(&merged)?;
        let bounces = match &merged.bounces {
            Some(b) if *b.get_ref() > 64 => {
                return Err(self.error_at(b.span(), "bounces must be at most 64"))
            }
            Some(b) => *b.get_ref(),
            None => 1,
        };
        let zstd_level = match &merged.zstd_level {
            Some(z) if !(1..=22).contains(z.get_ref()) => {
                return Err(self.error_at(z.span(), "zstd_level must be in 1..=22"))
            }
            Some(z) => *z.get_ref(),
            None => 3,
        };
        let encoding = merged
            .encoding
            .map_or(oslf_format::Encoding::Rgb9e5, |e| e.0);
        let mantissa_bits = match &merged.mantissa_bits {
            Some(m) => {
                let bits = u32::try_from(*m.get_ref()).unwrap_or(0);
                oslf_format::meta::check_mantissa_bits(encoding, bits).map_err(|_| {
                    let problem = if (1..=9).contains(m.get_ref()) {
                        format!(
                            "mantissa_bits = {} needs encoding = \"rgb9e5\" (the encoding is {encoding}, {})",
                            m.get_ref(),
                            if encoding.is_block_compressed() {
                                "whose precision its 4×4 blocks set"
                            } else {
                                "which keeps every bit"
                            }
                        )
                    } else {
                        format!("mantissa_bits {} must be in 1..=9", m.get_ref())
                    };
                    self.error_at(m.span(), problem)
                })?;
                bits
            }
            None => oslf_format::encoding::RGB9E5_FULL_MANTISSA_BITS,
        };
        let epsilon_span = merged.epsilon.as_ref().map(Spanned::span);
        let unset = unset(&merged);
        let settings = BakeSettings {
            epsilon: merged.epsilon.as_ref().map_or(0.1, |e| e.get_ref().0),
            sample_count,
            placement: merged.placement.map_or_else(Default::default, |p| p.0),
            near_surface: merged.near_surface.map_or_else(Default::default, |n| n.0),
            phi_samplemap_deg: phi,
            cube_resolution: merged.cube_resolution.map_or(32, |r| r.0),
            sample_map_resolution: merged.sample_map_resolution.map_or(256, |r| r.0),
            samples_per_texel: spp,
            target_noise,
            denoise: merged.denoise.unwrap_or(DENOISE_DEFAULT),
            bounces,
            seed: merged.seed.unwrap_or(0),
            encoding,
            zstd_level,
            mantissa_bits,
            distance_channel: merged.distance_channel.unwrap_or(true),
            env_cube: merged.env_cube.unwrap_or(true),
            device: merged.device.map_or_else(Default::default, |d| d.0),
        };
        Ok((settings, epsilon_span, unset))
    }
}

/// Which of the settings the scene chooses `merged` leaves unset.
fn unset(merged: &RawBake) -> Unset {
    Unset {
        epsilon: merged.epsilon.is_none(),
        density: merged.sample_count.is_none() && merged.sample_spacing.is_none(),
        placement: merged.placement.is_none(),
        near_surface: merged.near_surface.is_none(),
        cube_resolution: merged.cube_resolution.is_none(),
        samples_per_texel: merged.samples_per_texel.is_none(),
        store_budget: merged.store_budget_mb.map(|b| f64::from(b.0) * 1e6),
    }
}
