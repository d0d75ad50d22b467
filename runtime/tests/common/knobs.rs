//! The tests' way of writing shading parameters: every knob of every mode in one flat struct
//! with the thesis's defaults, as the tests sweep them one at a time, turned into the mode's
//! [`ShadingParams`] by [`Knobs::params`] (which drops the knobs the mode does not have).

use oslf_runtime::{
    AshikhminShirley, Blend, Box3, Glossy, GlossyFilter, Lookup, Mirror, Mode, MonteCarlo, Order,
    Pbr, PbrIntegration, PbrMaterial, Recon, ReconGlossy, ReconMirror, SampleFilter, ShadingParams,
    Source,
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
}

impl Default for Knobs {
    /// The defaults of [`ShadingParams`]' parts, in the default mode (recon + C_s mirror).
    fn default() -> Self {
        let (blend, blend_n) = match Lookup::default() {
            Lookup::Oslf { blend, blend_n } => (blend, blend_n),
            Lookup::Probe(_) => unreachable!("the default lookup is the OSLF's"),
        };
        let mc = MonteCarlo::default();
        let lobe = AshikhminShirley::default();
        let material = PbrMaterial::default();
        Self {
            mode: ShadingParams::default().mode(),
            blend,
            blend_n,
            source: Source::Oslf,
            phi_shader_deg: Recon::default().phi_shader_deg,
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
            depth: true,
            glossy_filter: GlossyFilter::Mip,
            proxy_box: None,
        }
    }
}

impl Knobs {
    /// The parameters of `self.mode`; panics on a combination no mode has (split-sum outside
    /// the pbr mode's baselines), as a test wants.
    pub fn params(&self) -> ShadingParams {
        let lookup = Lookup::of_source(self.source, self.blend, self.blend_n, self.proxy_box);
        let filter = match self.glossy_filter {
            GlossyFilter::Mip => SampleFilter::Mip,
            GlossyFilter::Point => SampleFilter::Point,
            GlossyFilter::SplitSum => SampleFilter::Mip,
        };
        let integration = MonteCarlo {
            m: self.m,
            order: self.order,
            seed: self.seed,
            filter,
        };
        let lobe = AshikhminShirley {
            rs: self.rs,
            rd: self.rd,
            nu: self.nu,
            nv: self.nv,
        };
        let (phi_shader_deg, depth) = (self.phi_shader_deg, self.depth);
        let split_sum = self.glossy_filter == GlossyFilter::SplitSum;
        assert!(
            !split_sum || self.mode == Mode::Pbr,
            "split-sum is a baseline of the pbr mode"
        );
        match self.mode {
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
                material: PbrMaterial {
                    metallic: self.metallic,
                    roughness: self.roughness,
                    object_material: self.object_material,
                },
                integration: match lookup {
                    Lookup::Probe(probe) if split_sum => PbrIntegration::SplitSum(probe),
                    Lookup::Oslf { .. } if split_sum => {
                        panic!("split-sum is a baseline: it needs source env or parallax")
                    }
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
