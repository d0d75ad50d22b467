//! The names of the shading choices (mode, blend, source, filter, order) and the background:
//! the vocabulary of [`crate::ShadingParams`], with the names the CLI takes.

use serde::{Deserialize, Serialize};

use crate::error::{Result, RuntimeError};

/// What a frame shows. Each term can be rendered alone, as the thesis's figures do.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Mode {
    /// Surface reconstruction F_recon alone (3.11–3.12): the baked, diffuse object.
    Recon,
    /// The mirror term F_refl alone (4.6–4.7), not scaled by C_s (thesis Figures 4.1–4.6).
    Mirror,
    /// P = F_recon + C_s · F_refl (4.12).
    ReconMirror,
    /// The Ashikhmin–Shirley term alone by Monte Carlo (5.5–5.12), plus the diffuse term 5.4
    /// when R_d > 0.
    Glossy,
    /// P = F_recon + C_s · (Ashikhmin–Shirley) (4.12 with the BRDF of chapter 5).
    ReconGlossy,
    /// glTF's metallic-roughness BRDF with the object's base colour C_s, by Monte Carlo over
    /// the light field: its GGX specular lobe (visible normals) and, for `metallic` < 1, its
    /// diffuse base (cosine-weighted), both from the cube maps as the glossy mode reads them.
    Pbr,
}

impl Mode {
    /// Every mode, in CLI order.
    pub const ALL: [Mode; 6] = [
        Mode::Recon,
        Mode::Mirror,
        Mode::ReconMirror,
        Mode::Glossy,
        Mode::ReconGlossy,
        Mode::Pbr,
    ];

    /// The CLI name.
    pub fn name(self) -> &'static str {
        match self {
            Mode::Recon => "recon",
            Mode::Mirror => "mirror",
            Mode::ReconMirror => "recon-mirror",
            Mode::Glossy => "glossy",
            Mode::ReconGlossy => "recon-glossy",
            Mode::Pbr => "pbr",
        }
    }

    /// The mode a store is drawn in unless one is asked for: `pbr` when any of its objects
    /// carries a metallic-roughness material, else `recon-mirror`.
    pub fn default_for(meta: &oslf_format::StoreMeta) -> Mode {
        if meta
            .objects
            .iter()
            .any(|o| o.material.is_metallic_roughness())
        {
            Mode::Pbr
        } else {
            Mode::ReconMirror
        }
    }

    /// The shader's term flags: 1 recon, 2 mirror, 4 glossy, 8 scale by C_s, 16 the glossy
    /// term is glTF's metallic-roughness BRDF (else Ashikhmin–Shirley).
    pub fn terms(self) -> u32 {
        match self {
            Mode::Recon => 1,
            Mode::Mirror => 2,
            Mode::ReconMirror => 1 | 2 | 8,
            Mode::Glossy => 4,
            Mode::ReconGlossy => 1 | 4 | 8,
            Mode::Pbr => 4 | 16,
        }
    }
}

/// How the four sample points' radiance is blended (chapter 4).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Blend {
    /// The sample point closest to the shaded point (4.3).
    Distance,
    /// The sample point whose direction is closest to the lookup direction (4.4–4.5).
    Angle,
    /// B^avg = 1/4 (4.9).
    Average,
    /// B^r: cosine lobe of power N around the reflection vector (4.10).
    Reflection,
    /// B^n: cosine lobe of power N around the normal (4.11).
    Normal,
}

impl Blend {
    /// Every blend, in CLI order.
    pub const ALL: [Blend; 5] = [
        Blend::Distance,
        Blend::Angle,
        Blend::Average,
        Blend::Reflection,
        Blend::Normal,
    ];

    /// The CLI name.
    pub fn name(self) -> &'static str {
        match self {
            Blend::Distance => "distance",
            Blend::Angle => "angle",
            Blend::Average => "avg",
            Blend::Reflection => "r",
            Blend::Normal => "n",
        }
    }

    pub(crate) fn tag(self) -> u32 {
        match self {
            Blend::Distance => 0,
            Blend::Angle => 1,
            Blend::Average => 2,
            Blend::Reflection => 3,
            Blend::Normal => 4,
        }
    }
}

/// Where reflected radiance comes from.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Source {
    /// The four sample points of the shaded texel: the OSLF.
    Oslf,
    /// The baseline the thesis compares against: one cube map captured at the object's centre,
    /// indexed by direction alone.
    EnvMap,
    /// The baseline engines use today: the same cube map, parallax-corrected against a proxy box
    /// (Lagarde & Zanuttini 2012): the reflected ray is intersected with the box from the
    /// shaded point and the cube looked up towards that hit from the cube's centre.
    /// [`crate::Probe::Parallax`] gives the box; by default it is fitted to the cube's own
    /// distance channel (see `Renderer::proxy_box`).
    Parallax,
}

impl Source {
    /// Every source, in CLI order.
    pub const ALL: [Source; 3] = [Source::Oslf, Source::EnvMap, Source::Parallax];

    /// The CLI name.
    pub fn name(self) -> &'static str {
        match self {
            Source::Oslf => "oslf",
            Source::EnvMap => "env",
            Source::Parallax => "parallax",
        }
    }

    /// The shader's tag.
    pub(crate) fn tag(self) -> u32 {
        match self {
            Source::Oslf => 0,
            Source::EnvMap => 1,
            Source::Parallax => 2,
        }
    }
}

/// How the glossy term reads the cube maps: the name of a [`SampleFilter`](crate::SampleFilter), or the split-sum
/// baseline ([`crate::PbrIntegration::SplitSum`]); [`ShadingParams::glossy_filter`](crate::ShadingParams::glossy_filter).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum GlossyFilter {
    /// Filtered importance sampling (Křivánek & Colbert 2008): each sample reads the mip level
    /// whose texels subtend the sample's share of the lobe, 1 / (M p(l)) steradians, blended
    /// between the two nearest levels. Converges with far fewer samples.
    Mip,
    /// One bilinear read at full resolution per sample, as the thesis did.
    Point,
    /// No Monte Carlo: the engines' baseline of [`Mode::Pbr`] ([`crate::PbrIntegration`]).
    SplitSum,
}

impl GlossyFilter {
    /// Every filter, in CLI order.
    pub const ALL: [GlossyFilter; 3] = [
        GlossyFilter::Mip,
        GlossyFilter::Point,
        GlossyFilter::SplitSum,
    ];

    /// The CLI name.
    pub fn name(self) -> &'static str {
        match self {
            GlossyFilter::Mip => "mip",
            GlossyFilter::Point => "point",
            GlossyFilter::SplitSum => "split-sum",
        }
    }
}

/// The Monte Carlo integration orders: the two of §5.2, and per point with hidden samples
/// read elsewhere (two ways).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Order {
    /// Integrate at each sample point with its own M random vectors, then blend (the thesis's
    /// choice).
    PerPoint,
    /// For each of M random vectors blend the four sample points, then integrate.
    PerDirection,
    /// Per point, but a sample whose ray its sample point cannot see (depth-corrected lookups
    /// only: the point at x's own distance along the ray lies behind the surface the point
    /// sees) reads the cube of the candidate of largest blend weight that can. The cost of per
    /// point plus one distance read per sample, and a few more where a sample is hidden.
    PerPointVisible,
    /// Per point, but each sample read where its sample point sees the ray meet the scene by
    /// the mirror's search (depth-corrected lookups only), and a sample whose ray that point
    /// cannot see where the candidate of largest blend weight that can sees it; a hit that
    /// lies lower above the surface than a quarter of the point's distance from it (the
    /// object's own surface seen at a grazing angle) is read as per point reads it. About two
    /// thirds of per direction's cost: a full search per sample and candidate.
    PerPointSearched,
}

impl Order {
    /// Every order, in CLI order.
    pub const ALL: [Order; 4] = [
        Order::PerPoint,
        Order::PerDirection,
        Order::PerPointVisible,
        Order::PerPointSearched,
    ];

    /// The CLI name.
    pub fn name(self) -> &'static str {
        match self {
            Order::PerPoint => "per-point",
            Order::PerDirection => "per-direction",
            Order::PerPointVisible => "per-point-visible",
            Order::PerPointSearched => "per-point-searched",
        }
    }

    /// Whether it reads the distance channel (per point visible, per point searched): without
    /// depth-corrected lookups ([`crate::ShadingParams::validate`]) or on a store baked without
    /// distances (the renderer) it is refused.
    pub fn reads_distances(self) -> bool {
        matches!(self, Order::PerPointVisible | Order::PerPointSearched)
    }

    /// The shader's tag (`ORDER`): 0 per point, 1 per direction, 2 per point visible, 3 per
    /// point searched.
    pub fn tag(self) -> u32 {
        match self {
            Order::PerPoint => 0,
            Order::PerDirection => 1,
            Order::PerPointVisible => 2,
            Order::PerPointSearched => 3,
        }
    }
}

macro_rules! from_str_by_name {
    ($t:ty, $what:literal) => {
        impl std::str::FromStr for $t {
            type Err = RuntimeError;
            fn from_str(s: &str) -> Result<Self> {
                Self::ALL
                    .into_iter()
                    .find(|v| v.name() == s)
                    .ok_or_else(|| {
                        let names: Vec<_> = Self::ALL.iter().map(|v| v.name()).collect();
                        RuntimeError::Parameter(format!(
                            concat!("unknown ", $what, " {:?} (one of {})"),
                            s,
                            names.join(", ")
                        ))
                    })
            }
        }
    };
}
from_str_by_name!(Mode, "mode");
from_str_by_name!(Blend, "blend");
from_str_by_name!(Source, "source");
from_str_by_name!(GlossyFilter, "glossy filter");
from_str_by_name!(Order, "order");

/// What the pixels the object does not cover show. Their alpha stays 0 whatever is chosen:
/// alpha is the object mask, which the metrics use.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub enum Background {
    /// Transparent black, `[0, 0, 0, 0]`: the embedder composes its own scene (the default).
    #[default]
    None,
    /// The store's environment cube (the environment-map baseline's cube, pinned resident by
    /// the cache), looked up along each pixel's camera ray with the same bilinear filtering.
    /// The store must have one ([`Background::validate`]).
    Env,
    /// A constant linear RGB colour (finite, non-negative).
    Color([f32; 3]),
}

impl Background {
    /// The shader's tag: 0 none, 1 environment cube, 2 colour.
    pub fn tag(self) -> u32 {
        match self {
            Background::None => 0,
            Background::Env => 1,
            Background::Color(_) => 2,
        }
    }

    /// Errors when the colour is negative or not finite, or when [`Background::Env`] is asked
    /// for and the store has no environment cube (`has_env_cube` false).
    pub fn validate(&self, has_env_cube: bool) -> Result<()> {
        match self {
            Background::None => Ok(()),
            Background::Env if has_env_cube => Ok(()),
            Background::Env => Err(RuntimeError::Parameter(
                "background env: the store has no environment cube (bake with env_cube = true)"
                    .into(),
            )),
            Background::Color(c) if c.iter().all(|v| v.is_finite() && *v >= 0.0) => Ok(()),
            Background::Color(c) => Err(RuntimeError::Parameter(format!(
                "background colour {c:?} must be three finite, non-negative linear RGB values"
            ))),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn backgrounds_are_checked() {
        assert!(Background::None.validate(false).is_ok());
        assert!(Background::Env.validate(true).is_ok());
        let e = Background::Env.validate(false).unwrap_err();
        assert!(matches!(e, RuntimeError::Parameter(_)), "{e:?}");
        assert!(e.to_string().contains("no environment cube"), "{e}");
        assert!(Background::Color([0.0, 0.5, 2.0]).validate(false).is_ok());
        for bad in [
            [-0.1, 0.0, 0.0],
            [0.0, f32::NAN, 0.0],
            [0.0, 0.0, f32::INFINITY],
        ] {
            let e = Background::Color(bad).validate(true).unwrap_err();
            assert!(e.to_string().contains("background colour"), "{e}");
        }
    }

    #[test]
    fn names_round_trip_and_bad_values_are_named() {
        for m in Mode::ALL {
            assert_eq!(m.name().parse::<Mode>().unwrap(), m);
        }
        for b in Blend::ALL {
            assert_eq!(b.name().parse::<Blend>().unwrap(), b);
        }
        let e = "shiny".parse::<Mode>().unwrap_err().to_string();
        assert!(e.contains("shiny") && e.contains("recon-mirror"), "{e}");
        let p = crate::ShadingParams::Glossy(crate::Glossy {
            lobe: crate::AshikhminShirley {
                nu: f32::NAN,
                ..Default::default()
            },
            ..Default::default()
        });
        assert!(p.validate().unwrap_err().to_string().contains("n_u"));
        let p = crate::ShadingParams::Glossy(crate::Glossy {
            integration: crate::MonteCarlo {
                m: 0,
                ..Default::default()
            },
            ..Default::default()
        });
        assert!(p.validate().unwrap_err().to_string().contains("M = 0"));
    }
}
