//! The tests' way of writing shading parameters: every knob of every mode in one flat struct
//! with the defaults, as the tests sweep them one at a time (`Knobs { m: 8, ..base }`), turned
//! into the mode's [`ShadingParams`] by [`Knobs::params`] through [`ShadingParts`].

use oslf_runtime::{
    AshikhminShirley, Blend, Box3, DiffuseSource, GlossyFilter, Lookup, Mode, MonteCarlo, Order,
    PbrMaterial, SampleFilter, ShadingParams, ShadingParts, Source,
};

/// Every knob; see the fields of the parts of [`ShadingParams`].
#[derive(Clone, Copy, Debug)]
pub struct Knobs {
    pub mode: Mode,
    pub blend: Blend,
    pub blend_n: f32,
    pub source: Source,
    pub phi_shader_deg: f32,
    pub m: u32,
    pub order: Order,
    pub rs: f32,
    pub rd: f32,
    pub nu: f32,
    pub nv: f32,
    pub metallic: f32,
    pub roughness: f32,
    pub object_material: bool,
    pub seed: u32,
    pub depth: bool,
    pub glossy_filter: GlossyFilter,
    pub proxy_box: Option<Box3>,
    pub diffuse: DiffuseSource,
}

impl Default for Knobs {
    /// The defaults of [`ShadingParts`], in the default mode (recon + C_s mirror).
    fn default() -> Self {
        let parts = ShadingParts::default();
        let (blend, blend_n) = Lookup::DEFAULT_BLEND;
        let (mc, lobe, material) = (parts.integration, parts.lobe, parts.material);
        Self {
            mode: ShadingParams::default().mode(),
            blend,
            blend_n,
            source: Source::Oslf,
            phi_shader_deg: parts.phi_shader_deg,
            m: mc.m,
            order: mc.order,
            rs: lobe.rs,
            rd: lobe.rd,
            nu: lobe.nu,
            nv: lobe.nv,
            metallic: material.metallic,
            roughness: material.roughness,
            object_material: material.object_material,
            seed: mc.seed,
            depth: parts.depth,
            glossy_filter: GlossyFilter::Mip,
            proxy_box: None,
            diffuse: mc.diffuse,
        }
    }
}

impl Knobs {
    /// The parameters of `self.mode` ([`ShadingParts::params`]); panics where the knobs are
    /// out of range or a combination no mode has (split-sum outside the pbr mode's
    /// baselines), as a test wants.
    pub fn params(&self) -> ShadingParams {
        ShadingParts {
            phi_shader_deg: self.phi_shader_deg,
            lookup: Lookup::of_source(self.source, self.blend, self.blend_n, self.proxy_box),
            depth: self.depth,
            lobe: AshikhminShirley {
                rs: self.rs,
                rd: self.rd,
                nu: self.nu,
                nv: self.nv,
            },
            integration: MonteCarlo {
                m: self.m,
                order: self.order,
                seed: self.seed,
                filter: match self.glossy_filter {
                    GlossyFilter::Point => SampleFilter::Point,
                    GlossyFilter::Mip | GlossyFilter::SplitSum => SampleFilter::Mip,
                },
                diffuse: self.diffuse,
            },
            material: PbrMaterial {
                metallic: self.metallic,
                roughness: self.roughness,
                object_material: self.object_material,
            },
            split_sum: self.glossy_filter == GlossyFilter::SplitSum,
        }
        .params(self.mode)
        .unwrap_or_else(|e| panic!("{self:?}: {e}"))
    }
}
