//! What a frame's shading depends on besides the camera: [`ShadingParams`], one variant per
//! [`Mode`], each holding only the parameters its terms read, so that a combination no mode
//! accepts (a split-sum baseline of the OSLF, a proxy box without the parallax baseline, M for
//! reconstruction) cannot be written. Ranges are checked by [`ShadingParams::validate`].

use serde::{Deserialize, Serialize};

use crate::error::{Result, RuntimeError};
use crate::params::{Blend, GlossyFilter, Mode, Order, Source};

/// A box in world space, `[min, max]`.
pub type Box3 = [[f32; 3]; 2];

/// Everything a frame's shading depends on besides the camera: the mode and its parameters.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case", tag = "mode")]
pub enum ShadingParams {
    /// Surface reconstruction F_recon alone (3.11–3.12).
    Recon(Recon),
    /// The mirror term F_refl alone (4.6–4.7).
    Mirror(Mirror),
    /// P = F_recon + C_s · F_refl (4.12).
    ReconMirror(ReconMirror),
    /// Ashikhmin–Shirley by Monte Carlo (5.5–5.12).
    Glossy(Glossy),
    /// P = F_recon + C_s · (Ashikhmin–Shirley).
    ReconGlossy(ReconGlossy),
    /// glTF's metallic-roughness BRDF.
    Pbr(Pbr),
}

/// [`Mode::Recon`]: the nearest sample point within φ_shader of the shaded normal (§6.3).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct Recon {
    /// φ_shader in degrees: the nearest sample point within this angle of the shaded normal;
    /// 0..=180.
    pub phi_shader_deg: f32,
    /// Depth-corrected lookups (a store with a distance channel): the candidates that see the
    /// shaded point by their distances are averaged.
    pub depth: bool,
}

/// [`Mode::Mirror`]: F_refl alone, not scaled by C_s (thesis Figures 4.1–4.6).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct Mirror {
    /// Where reflected radiance comes from.
    pub lookup: Lookup,
    /// Depth-corrected lookups of the sample points' cubes ([`Lookup::Oslf`], a store with a
    /// distance channel): each goes towards where the ray from the *shaded point* meets the
    /// scene as that sample point's distances describe it (§6.3, RGBZ).
    pub depth: bool,
}

/// [`Mode::ReconMirror`]: P = F_recon + C_s · F_refl (4.12).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct ReconMirror {
    /// See [`Recon::phi_shader_deg`].
    pub phi_shader_deg: f32,
    /// See [`Mirror::lookup`].
    pub lookup: Lookup,
    /// Depth-corrected lookups, for reconstruction and reflection alike.
    pub depth: bool,
}

/// [`Mode::Glossy`]: the Ashikhmin–Shirley term alone by Monte Carlo, plus the diffuse term
/// 5.4 when R_d > 0.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct Glossy {
    /// See [`Mirror::lookup`].
    pub lookup: Lookup,
    /// See [`Mirror::depth`].
    pub depth: bool,
    /// The BRDF.
    pub lobe: AshikhminShirley,
    /// The Monte Carlo integration.
    pub integration: MonteCarlo,
}

/// [`Mode::ReconGlossy`]: P = F_recon + C_s · (Ashikhmin–Shirley).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct ReconGlossy {
    /// See [`Recon::phi_shader_deg`].
    pub phi_shader_deg: f32,
    /// See [`Mirror::lookup`].
    pub lookup: Lookup,
    /// Depth-corrected lookups, for reconstruction and the glossy term alike.
    pub depth: bool,
    /// The BRDF.
    pub lobe: AshikhminShirley,
    /// The Monte Carlo integration.
    pub integration: MonteCarlo,
}

/// [`Mode::Pbr`]: glTF's metallic-roughness BRDF with the object's base colour.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct Pbr {
    /// The factors.
    pub material: PbrMaterial,
    /// Monte Carlo over the light field, or the engines' split-sum baseline.
    pub integration: PbrIntegration,
}

/// Where reflected radiance comes from.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Lookup {
    /// The four sample points of the shaded texel, the OSLF, blended (chapter 4).
    Oslf {
        /// How the four are blended.
        blend: Blend,
        /// The lobe power N of B^r and B^n (0 gives B^avg); 0..=1e6.
        blend_n: f32,
    },
    /// One cube map at the object's centre: the baselines.
    Probe(Probe),
}

/// The baselines' one cube map, captured at the object's centre.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Probe {
    /// Indexed by direction alone (the thesis's environment-map baseline).
    EnvMap,
    /// Parallax-corrected against a proxy box (Lagarde & Zanuttini 2012), as engines do: the
    /// reflected ray is intersected with the box from the shaded point and the cube looked up
    /// towards that hit from the cube's centre.
    Parallax {
        /// The box in world space; `None` fits it to the cube's own distance channel
        /// (`Renderer::proxy_box`).
        proxy_box: Option<Box3>,
    },
}

/// The Ashikhmin–Shirley BRDF of chapter 5.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct AshikhminShirley {
    /// Specular reflectance at normal incidence R_s, in [0, 1].
    pub rs: f32,
    /// Diffuse reflectance R_d of the optional diffuse term 5.4, in [0, 1].
    pub rd: f32,
    /// Phong-like exponent n_u (along ∂x/∂u), in [0, 1e7].
    pub nu: f32,
    /// Exponent n_v, in [0, 1e7].
    pub nv: f32,
}

/// How the glossy and pbr terms integrate by Monte Carlo over the cube maps.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct MonteCarlo {
    /// Samples per integration (M); 1..=65536.
    pub m: u32,
    /// The integration order of §5.2.
    pub order: Order,
    /// Seed of the per-pixel random numbers.
    pub seed: u32,
    /// How each sample reads the cube maps.
    pub filter: SampleFilter,
    /// Where the diffuse part (the term 5.4, glTF's diffuse base) comes from.
    pub diffuse: DiffuseSource,
}

/// Where the glossy and pbr modes' diffuse part comes from.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum DiffuseSource {
    /// The irradiance each sample point stores (format 1.1: its cube's spherical harmonics,
    /// projected from every texel at bake time), convolved with the diffuse lobe at the normal
    /// and blended between the candidates: smooth, and no Monte Carlo samples. Stores without
    /// it (format 1.0) are sampled.
    Irradiance,
    /// M cosine-weighted Monte Carlo samples of the cube maps per integration, as the thesis.
    Samples,
}

impl DiffuseSource {
    /// Both, in CLI order.
    pub const ALL: [DiffuseSource; 2] = [DiffuseSource::Irradiance, DiffuseSource::Samples];

    /// The CLI name.
    pub fn name(self) -> &'static str {
        match self {
            DiffuseSource::Irradiance => "irradiance",
            DiffuseSource::Samples => "samples",
        }
    }
}

/// How each Monte Carlo sample reads the cube maps.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum SampleFilter {
    /// Filtered importance sampling (Křivánek & Colbert 2008): each sample reads the mip level
    /// whose texels subtend the sample's share of the lobe, 1 / (M p(l)) steradians, blended
    /// between the two nearest levels. Converges with far fewer samples.
    Mip,
    /// One bilinear read at full resolution per sample, as the thesis did.
    Point,
}

/// The pbr mode's factors.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct PbrMaterial {
    /// glTF's metallic factor, in [0, 1].
    pub metallic: f32,
    /// glTF's perceptual roughness (α = roughness²), in [0, 1].
    pub roughness: f32,
    /// Each object with a metallic-roughness material in the store is shaded with that
    /// material's factors (and textures); `metallic` and `roughness` then serve only the
    /// objects without one. `false`: `metallic` and `roughness` for every object.
    pub object_material: bool,
}

/// How the pbr mode integrates.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum PbrIntegration {
    /// By Monte Carlo over the light field: the GGX lobe by visible-normal sampling and, for
    /// metallic < 1, the diffuse base by cosine sampling, both read from the cube maps as the
    /// glossy mode reads them.
    MonteCarlo {
        /// Where reflected radiance comes from.
        lookup: Lookup,
        /// See [`Mirror::depth`].
        depth: bool,
        /// The integration.
        integration: MonteCarlo,
    },
    /// No Monte Carlo: the engines' baseline. The probe's cube prefiltered per roughness, read
    /// once towards the (parallax-corrected) reflection vector and scaled by GGX's directional
    /// albedo (the split-sum approximation, Karis 2013); the diffuse base from the cube's
    /// irradiance ([`crate::prefilter`]).
    SplitSum(Probe),
}

/// Every part a mode can have, for choosing parameters across modes (a command line's flags, a
/// viewer that switches modes): [`ShadingParts::params`] gives a mode its parts and leaves the
/// others.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShadingParts {
    /// See [`Recon::phi_shader_deg`].
    pub phi_shader_deg: f32,
    /// See [`Mirror::lookup`].
    pub lookup: Lookup,
    /// See [`Mirror::depth`].
    pub depth: bool,
    /// The glossy modes' BRDF.
    pub lobe: AshikhminShirley,
    /// The glossy and pbr modes' integration.
    pub integration: MonteCarlo,
    /// The pbr mode's factors.
    pub material: PbrMaterial,
    /// The pbr mode's split-sum baseline instead of Monte Carlo; needs a [`Lookup::Probe`].
    pub split_sum: bool,
}

impl Default for ShadingParts {
    /// Each part's default.
    fn default() -> Self {
        Self {
            phi_shader_deg: PHI_SHADER_DEG,
            lookup: Lookup::default(),
            depth: true,
            lobe: AshikhminShirley::default(),
            integration: MonteCarlo::default(),
            material: PbrMaterial::default(),
            split_sum: false,
        }
    }
}

impl ShadingParts {
    /// The parameters of `mode`, validated. Every part is checked, also those the mode does
    /// not read, so that no out-of-range choice passes unseen; `split_sum` outside the pbr mode
    /// or over the OSLF is an error.
    pub fn params(&self, mode: Mode) -> Result<ShadingParams> {
        if self.split_sum && (mode != Mode::Pbr || self.lookup.source() == Source::Oslf) {
            return Err(RuntimeError::Parameter(format!(
                "glossy filter split-sum is the engines' baseline of the pbr mode: it needs mode \
                 pbr and source env or parallax, not mode {} and source {}",
                mode.name(),
                self.lookup.source().name()
            )));
        }
        for every_part in [Mode::ReconGlossy, Mode::Pbr] {
            self.build(every_part).validate()?;
        }
        let params = self.build(mode);
        params.validate()?;
        Ok(params)
    }

    /// The parameters of `mode`, unchecked.
    fn build(&self, mode: Mode) -> ShadingParams {
        let Self {
            phi_shader_deg,
            lookup,
            depth,
            lobe,
            integration,
            material,
            split_sum,
        } = *self;
        match mode {
            Mode::Recon => ShadingParams::Recon(Recon {
                phi_shader_deg,
                depth,
            }),
            Mode::Mirror => ShadingParams::Mirror(Mirror { lookup, depth }),
            Mode::ReconMirror => ShadingParams::ReconMirror(ReconMirror {
                phi_shader_deg,
                lookup,
                depth,
            }),
            Mode::Glossy => ShadingParams::Glossy(Glossy {
                lookup,
                depth,
                lobe,
                integration,
            }),
            Mode::ReconGlossy => ShadingParams::ReconGlossy(ReconGlossy {
                phi_shader_deg,
                lookup,
                depth,
                lobe,
                integration,
            }),
            Mode::Pbr => ShadingParams::Pbr(Pbr {
                material,
                integration: match lookup {
                    Lookup::Probe(probe) if split_sum => PbrIntegration::SplitSum(probe),
                    _ => PbrIntegration::MonteCarlo {
                        lookup,
                        depth,
                        integration,
                    },
                },
            }),
        }
    }
}

/// The thesis's φ_shader.
const PHI_SHADER_DEG: f32 = 65.0;

impl Default for Lookup {
    /// The OSLF blended with [`Lookup::DEFAULT_BLEND`].
    fn default() -> Self {
        let (blend, blend_n) = Lookup::DEFAULT_BLEND;
        Lookup::Oslf { blend, blend_n }
    }
}

impl Default for Recon {
    fn default() -> Self {
        Self {
            phi_shader_deg: PHI_SHADER_DEG,
            depth: true,
        }
    }
}

impl Default for Mirror {
    fn default() -> Self {
        Self {
            lookup: Lookup::default(),
            depth: true,
        }
    }
}

impl Default for ReconMirror {
    fn default() -> Self {
        Self {
            phi_shader_deg: PHI_SHADER_DEG,
            lookup: Lookup::default(),
            depth: true,
        }
    }
}

impl Default for Glossy {
    fn default() -> Self {
        Self {
            lookup: Lookup::default(),
            depth: true,
            lobe: AshikhminShirley::default(),
            integration: MonteCarlo::default(),
        }
    }
}

impl Default for ReconGlossy {
    fn default() -> Self {
        Self {
            phi_shader_deg: PHI_SHADER_DEG,
            lookup: Lookup::default(),
            depth: true,
            lobe: AshikhminShirley::default(),
            integration: MonteCarlo::default(),
        }
    }
}

impl Default for AshikhminShirley {
    /// The thesis's: R_s = 1, R_d = 0, n_u = n_v = 100.
    fn default() -> Self {
        Self {
            rs: 1.0,
            rd: 0.0,
            nu: 100.0,
            nv: 100.0,
        }
    }
}

impl Default for MonteCarlo {
    /// M = 16 per point (the thesis's), seed 0, filtered importance sampling.
    fn default() -> Self {
        Self {
            m: 16,
            order: Order::PerPoint,
            seed: 0,
            filter: SampleFilter::Mip,
            diffuse: DiffuseSource::Irradiance,
        }
    }
}

impl Default for PbrMaterial {
    /// The store's materials; metallic 1 and roughness 0.3 for objects without one.
    fn default() -> Self {
        Self {
            metallic: 1.0,
            roughness: 0.3,
            object_material: true,
        }
    }
}

impl Default for PbrIntegration {
    fn default() -> Self {
        PbrIntegration::MonteCarlo {
            lookup: Lookup::default(),
            depth: true,
            integration: MonteCarlo::default(),
        }
    }
}

impl Default for ShadingParams {
    /// The thesis's settings: reconstruction plus mirror reflection blended with B^n;
    /// φ_shader = 65°. Beyond the thesis: depth-corrected lookups on, and with them the blend's
    /// power N = 2 instead of 4 ([`Lookup::DEFAULT_BLEND`]).
    fn default() -> Self {
        ShadingParams::ReconMirror(ReconMirror::default())
    }
}

impl Probe {
    /// The source it is.
    pub fn source(self) -> Source {
        match self {
            Probe::EnvMap => Source::EnvMap,
            Probe::Parallax { .. } => Source::Parallax,
        }
    }
}

impl Lookup {
    /// The default blend and power N: B^n (Eq. 4.11) with N = 2. The thesis chose N = 4 by
    /// eye, for plain lookups; with depth-corrected lookups (the default) the four candidates
    /// agree on where a reflection lies, and the wider blend averages their cube maps' noise.
    /// N = 2 measured lower error than 4 in every mode on every scene tried but one (within
    /// 1.2 %); N = 1, lower still on wide lobes, lost 5–7 % on the sharpest glossy lobe
    /// (docs/measurements.md, "The blend's power with depth-corrected lookups").
    pub const DEFAULT_BLEND: (Blend, f32) = (Blend::Normal, 2.0);

    /// The thesis's power N of B^n (§4, chosen there for plain lookups), which plain lookups
    /// still measure best with (Table 6.2: 0.1411 against N = 1's 0.1484 at 64²).
    pub const THESIS_BLEND_N: f32 = 4.0;

    /// The default power N for lookups with (`depth`) or without depth correction.
    pub fn default_blend_n(depth: bool) -> f32 {
        if depth {
            Lookup::DEFAULT_BLEND.1
        } else {
            Lookup::THESIS_BLEND_N
        }
    }

    /// The OSLF blended with `blend` and power `blend_n`.
    pub fn oslf(blend: Blend, blend_n: f32) -> Self {
        Lookup::Oslf { blend, blend_n }
    }

    /// The lookup of `source`: the OSLF with `blend` and `blend_n`, or the baseline probe
    /// (the parallax one with `proxy_box`).
    pub fn of_source(source: Source, blend: Blend, blend_n: f32, proxy_box: Option<Box3>) -> Self {
        match source {
            Source::Oslf => Lookup::Oslf { blend, blend_n },
            Source::EnvMap => Lookup::Probe(Probe::EnvMap),
            Source::Parallax => Lookup::Probe(Probe::Parallax { proxy_box }),
        }
    }

    /// The source it is.
    pub fn source(self) -> Source {
        match self {
            Lookup::Oslf { .. } => Source::Oslf,
            Lookup::Probe(p) => p.source(),
        }
    }
}

impl ShadingParams {
    /// The mode's defaults (the thesis's settings where it has them; see each part's
    /// `Default`).
    pub fn of_mode(mode: Mode) -> Self {
        match mode {
            Mode::Recon => ShadingParams::Recon(Recon::default()),
            Mode::Mirror => ShadingParams::Mirror(Mirror::default()),
            Mode::ReconMirror => ShadingParams::ReconMirror(ReconMirror::default()),
            Mode::Glossy => ShadingParams::Glossy(Glossy::default()),
            Mode::ReconGlossy => ShadingParams::ReconGlossy(ReconGlossy::default()),
            Mode::Pbr => ShadingParams::Pbr(Pbr::default()),
        }
    }

    /// The mode.
    pub fn mode(&self) -> Mode {
        match self {
            ShadingParams::Recon(_) => Mode::Recon,
            ShadingParams::Mirror(_) => Mode::Mirror,
            ShadingParams::ReconMirror(_) => Mode::ReconMirror,
            ShadingParams::Glossy(_) => Mode::Glossy,
            ShadingParams::ReconGlossy(_) => Mode::ReconGlossy,
            ShadingParams::Pbr(_) => Mode::Pbr,
        }
    }

    /// φ_shader in degrees, for the modes with reconstruction.
    pub fn phi_shader_deg(&self) -> Option<f32> {
        match self {
            ShadingParams::Recon(p) => Some(p.phi_shader_deg),
            ShadingParams::ReconMirror(p) => Some(p.phi_shader_deg),
            ShadingParams::ReconGlossy(p) => Some(p.phi_shader_deg),
            _ => None,
        }
    }

    /// Where reflected radiance comes from, for the modes that look it up (the split-sum
    /// baseline reads its probe once: [`ShadingParams::probe`]).
    pub fn lookup(&self) -> Option<Lookup> {
        match self {
            ShadingParams::Recon(_) => None,
            ShadingParams::Mirror(p) => Some(p.lookup),
            ShadingParams::ReconMirror(p) => Some(p.lookup),
            ShadingParams::Glossy(p) => Some(p.lookup),
            ShadingParams::ReconGlossy(p) => Some(p.lookup),
            ShadingParams::Pbr(p) => match p.integration {
                PbrIntegration::MonteCarlo { lookup, .. } => Some(lookup),
                PbrIntegration::SplitSum(_) => None,
            },
        }
    }

    /// The baseline's probe, when the frame reads one (a probe lookup or the split-sum
    /// baseline).
    pub fn probe(&self) -> Option<Probe> {
        if let ShadingParams::Pbr(Pbr {
            integration: PbrIntegration::SplitSum(p),
            ..
        }) = self
        {
            return Some(*p);
        }
        match self.lookup() {
            Some(Lookup::Probe(p)) => Some(p),
            _ => None,
        }
    }

    /// Where reflected radiance comes from: the OSLF (reconstruction included) or a baseline.
    pub fn source(&self) -> Source {
        self.probe().map_or(Source::Oslf, Probe::source)
    }

    /// The blend of the sample points and its power N, where the OSLF is looked up.
    pub fn blend(&self) -> Option<(Blend, f32)> {
        match self.lookup() {
            Some(Lookup::Oslf { blend, blend_n }) => Some((blend, blend_n)),
            _ => None,
        }
    }

    /// The parallax baseline's proxy box as given (`None` also where it is fitted).
    pub fn proxy_box(&self) -> Option<Box3> {
        match self.probe() {
            Some(Probe::Parallax { proxy_box }) => proxy_box,
            _ => None,
        }
    }

    /// Whether lookups are depth-corrected (where the store has a distance channel).
    pub fn depth(&self) -> bool {
        match self {
            ShadingParams::Recon(p) => p.depth,
            ShadingParams::Mirror(p) => p.depth,
            ShadingParams::ReconMirror(p) => p.depth,
            ShadingParams::Glossy(p) => p.depth,
            ShadingParams::ReconGlossy(p) => p.depth,
            ShadingParams::Pbr(p) => match p.integration {
                PbrIntegration::MonteCarlo { depth, .. } => depth,
                PbrIntegration::SplitSum(_) => false,
            },
        }
    }

    /// The Monte Carlo integration, for the glossy modes and the pbr mode's own.
    pub fn monte_carlo(&self) -> Option<MonteCarlo> {
        match self {
            ShadingParams::Glossy(p) => Some(p.integration),
            ShadingParams::ReconGlossy(p) => Some(p.integration),
            ShadingParams::Pbr(Pbr {
                integration: PbrIntegration::MonteCarlo { integration, .. },
                ..
            }) => Some(*integration),
            _ => None,
        }
    }

    /// The Ashikhmin–Shirley BRDF of the glossy modes.
    pub fn lobe(&self) -> Option<AshikhminShirley> {
        match self {
            ShadingParams::Glossy(p) => Some(p.lobe),
            ShadingParams::ReconGlossy(p) => Some(p.lobe),
            _ => None,
        }
    }

    /// The pbr mode's factors.
    pub fn material(&self) -> Option<PbrMaterial> {
        match self {
            ShadingParams::Pbr(p) => Some(p.material),
            _ => None,
        }
    }

    /// How the glossy or pbr term reads the cube maps; `None` for the modes without one.
    pub fn glossy_filter(&self) -> Option<GlossyFilter> {
        if self.split_sum() {
            return Some(GlossyFilter::SplitSum);
        }
        self.monte_carlo().map(|mc| match mc.filter {
            SampleFilter::Mip => GlossyFilter::Mip,
            SampleFilter::Point => GlossyFilter::Point,
        })
    }

    /// Whether this is the pbr mode's split-sum baseline.
    pub fn split_sum(&self) -> bool {
        matches!(
            self,
            ShadingParams::Pbr(Pbr {
                integration: PbrIntegration::SplitSum(_),
                ..
            })
        )
    }

    /// Sets where reflected radiance comes from, where the mode looks it up; errors naming
    /// the mode otherwise.
    pub fn set_lookup(&mut self, lookup: Lookup) -> Result<()> {
        let slot = match self {
            ShadingParams::Mirror(p) => &mut p.lookup,
            ShadingParams::ReconMirror(p) => &mut p.lookup,
            ShadingParams::Glossy(p) => &mut p.lookup,
            ShadingParams::ReconGlossy(p) => &mut p.lookup,
            ShadingParams::Pbr(Pbr {
                integration: PbrIntegration::MonteCarlo { lookup, .. },
                ..
            }) => lookup,
            _ => return Err(self.not_for("a lookup (source and blend)")),
        };
        *slot = lookup;
        Ok(())
    }

    /// Sets φ_shader where the mode reconstructs; errors naming the mode otherwise.
    pub fn set_phi_shader_deg(&mut self, deg: f32) -> Result<()> {
        match self {
            ShadingParams::Recon(p) => p.phi_shader_deg = deg,
            ShadingParams::ReconMirror(p) => p.phi_shader_deg = deg,
            ShadingParams::ReconGlossy(p) => p.phi_shader_deg = deg,
            _ => return Err(self.not_for("phi_shader (it has no reconstruction)")),
        }
        Ok(())
    }

    /// Sets depth correction where the mode has lookups to correct; errors naming the mode
    /// otherwise.
    pub fn set_depth(&mut self, on: bool) -> Result<()> {
        match self {
            ShadingParams::Recon(p) => p.depth = on,
            ShadingParams::Mirror(p) => p.depth = on,
            ShadingParams::ReconMirror(p) => p.depth = on,
            ShadingParams::Glossy(p) => p.depth = on,
            ShadingParams::ReconGlossy(p) => p.depth = on,
            ShadingParams::Pbr(Pbr {
                integration: PbrIntegration::MonteCarlo { depth, .. },
                ..
            }) => *depth = on,
            _ => return Err(self.not_for("depth correction (the split-sum baseline)")),
        }
        Ok(())
    }

    /// The Monte Carlo integration to change, for the modes that have one; errors naming the
    /// mode otherwise.
    pub fn monte_carlo_mut(&mut self) -> Result<&mut MonteCarlo> {
        match self {
            ShadingParams::Glossy(p) => Ok(&mut p.integration),
            ShadingParams::ReconGlossy(p) => Ok(&mut p.integration),
            ShadingParams::Pbr(Pbr {
                integration: PbrIntegration::MonteCarlo { integration, .. },
                ..
            }) => Ok(integration),
            _ => Err(self.not_for("Monte Carlo integration (M, order, seed, filter)")),
        }
    }

    /// The Ashikhmin–Shirley BRDF to change, for the glossy modes; errors naming the mode
    /// otherwise.
    pub fn lobe_mut(&mut self) -> Result<&mut AshikhminShirley> {
        match self {
            ShadingParams::Glossy(p) => Ok(&mut p.lobe),
            ShadingParams::ReconGlossy(p) => Ok(&mut p.lobe),
            _ => Err(self.not_for("the Ashikhmin–Shirley BRDF (R_s, R_d, n_u, n_v)")),
        }
    }

    /// The pbr factors to change; errors naming the mode otherwise.
    pub fn material_mut(&mut self) -> Result<&mut PbrMaterial> {
        match self {
            ShadingParams::Pbr(p) => Ok(&mut p.material),
            _ => Err(self.not_for("metallic-roughness factors")),
        }
    }

    fn not_for(&self, what: &str) -> RuntimeError {
        RuntimeError::Parameter(format!("mode {} has no {what}", self.mode().name()))
    }

    /// Errors naming the first parameter outside its range (NaN included), or an integration
    /// order that reads distances without depth-corrected lookups.
    pub fn validate(&self) -> Result<()> {
        let check = |name: &str, v: f32, lo: f32, hi: f32| {
            if v.is_finite() && v >= lo && v <= hi {
                Ok(())
            } else {
                Err(RuntimeError::Parameter(format!(
                    "{name} = {v} must be in [{lo}, {hi}]"
                )))
            }
        };
        if let Some((_, n)) = self.blend() {
            check("N", n, 0.0, 1e6)?;
        }
        if let Some(phi) = self.phi_shader_deg() {
            check("phi_shader", phi, 0.0, 180.0)?;
        }
        if let Some(l) = self.lobe() {
            check("R_s", l.rs, 0.0, 1.0)?;
            check("R_d", l.rd, 0.0, 1.0)?;
            check("n_u", l.nu, 0.0, 1e7)?;
            check("n_v", l.nv, 0.0, 1e7)?;
        }
        if let Some(m) = self.material() {
            check("metallic", m.metallic, 0.0, 1.0)?;
            check("roughness", m.roughness, 0.0, 1.0)?;
        }
        if let Some([lo, hi]) = self.proxy_box() {
            let ok = (0..3).all(|k| lo[k].is_finite() && hi[k].is_finite() && lo[k] < hi[k]);
            if !ok {
                return Err(RuntimeError::Parameter(format!(
                    "proxy box {lo:?}..{hi:?} must be finite with min < max on every axis"
                )));
            }
        }
        if let Some(mc) = self.monte_carlo() {
            if mc.order.reads_distances() && !self.depth() {
                return Err(RuntimeError::Parameter(format!(
                    "order {} reads the distance channel and so needs depth-corrected lookups \
                     (depth = true): without them it would integrate per point",
                    mc.order.name()
                )));
            }
            if !(1..=65536).contains(&mc.m) {
                return Err(RuntimeError::Parameter(format!(
                    "M = {} must be in [1, 65536]",
                    mc.m
                )));
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Each mode's parameters hold what its terms read and nothing else; a setter for a part
    /// the mode lacks is refused, naming the mode.
    #[test]
    fn each_mode_has_its_own_parts() {
        for mode in Mode::ALL {
            let p = ShadingParams::of_mode(mode);
            assert_eq!(p.mode(), mode);
            assert!(p.validate().is_ok(), "{mode:?}");
            let recon = matches!(mode, Mode::Recon | Mode::ReconMirror | Mode::ReconGlossy);
            assert_eq!(p.phi_shader_deg().is_some(), recon, "{mode:?}");
            assert_eq!(p.lookup().is_none(), mode == Mode::Recon, "{mode:?}");
            let mc = matches!(mode, Mode::Glossy | Mode::ReconGlossy | Mode::Pbr);
            assert_eq!(p.monte_carlo().is_some(), mc, "{mode:?}");
            assert_eq!(p.material().is_some(), mode == Mode::Pbr, "{mode:?}");
        }
        let mut recon = ShadingParams::of_mode(Mode::Recon);
        let e = recon.monte_carlo_mut().unwrap_err().to_string();
        assert!(e.contains("mode recon") && e.contains("Monte Carlo"), "{e}");
        assert!(recon.set_lookup(Lookup::default()).is_err());
        assert!(ShadingParams::of_mode(Mode::Mirror)
            .set_phi_shader_deg(10.0)
            .is_err());
        // The split-sum baseline reads its probe once: no lookup, depth or Monte Carlo.
        let split = ShadingParams::Pbr(Pbr {
            integration: PbrIntegration::SplitSum(Probe::Parallax { proxy_box: None }),
            ..Default::default()
        });
        assert_eq!(split.source(), Source::Parallax);
        assert!(split.split_sum() && split.lookup().is_none() && !split.depth());
        assert_eq!(split.glossy_filter(), Some(GlossyFilter::SplitSum));
    }

    /// Ranges are checked where the mode has the part (NaN included).
    #[test]
    fn ranges_are_checked() {
        let mut p = ShadingParams::of_mode(Mode::ReconGlossy);
        p.lobe_mut().unwrap().rs = f32::NAN;
        assert!(p.validate().unwrap_err().to_string().contains("R_s"));
        let p = ShadingParams::Mirror(Mirror {
            lookup: Lookup::Probe(Probe::Parallax {
                proxy_box: Some([[0.0; 3], [0.0, 1.0, 1.0]]),
            }),
            depth: true,
        });
        assert!(p.validate().unwrap_err().to_string().contains("min < max"));
        let p = ShadingParams::Recon(Recon {
            phi_shader_deg: 181.0,
            depth: true,
        });
        assert!(p.validate().unwrap_err().to_string().contains("phi_shader"));
    }

    /// The orders that read the distance channel are refused without depth-corrected lookups
    /// (they would integrate per point under their own name); the others are not.
    #[test]
    fn orders_that_read_distances_need_depth() {
        for mode in [Mode::Glossy, Mode::ReconGlossy, Mode::Pbr] {
            for order in Order::ALL {
                for depth in [true, false] {
                    let mut p = ShadingParams::of_mode(mode);
                    p.set_depth(depth).unwrap();
                    p.monte_carlo_mut().unwrap().order = order;
                    let r = p.validate();
                    if order.reads_distances() && !depth {
                        let e = r.unwrap_err().to_string();
                        assert!(e.contains(order.name()) && e.contains("depth"), "{e}");
                    } else {
                        assert!(r.is_ok(), "{mode:?} {order:?} {depth}: {r:?}");
                    }
                }
            }
        }
    }
}
