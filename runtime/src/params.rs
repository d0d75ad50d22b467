//! Shading parameters: which terms to render, how to blend the four sample points, and the
//! Ashikhmin–Shirley settings. Shared by the GPU shader (as [`ShadeUniform`]) and the CPU
//! reference.

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

    fn tag(self) -> u32 {
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
    /// [`ShadingParams::proxy_box`] gives the box; by default it is fitted to the cube's own
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
    fn tag(self) -> u32 {
        match self {
            Source::Oslf => 0,
            Source::EnvMap => 1,
            Source::Parallax => 2,
        }
    }
}

/// How the glossy term reads the cube maps for each Monte Carlo sample.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum GlossyFilter {
    /// Filtered importance sampling (Křivánek & Colbert 2008): each sample reads the mip level
    /// whose texels subtend the sample's share of the lobe, 1 / (M p(l)) steradians, blended
    /// between the two nearest levels. Converges with far fewer samples.
    Mip,
    /// One bilinear read at full resolution per sample, as the thesis did.
    Point,
    /// No Monte Carlo: the engines' baseline of [`Mode::Pbr`] with [`Source::EnvMap`] or
    /// [`Source::Parallax`]. The environment cube prefiltered per roughness, read once towards
    /// the (parallax-corrected) reflection vector and scaled by GGX's directional albedo (the
    /// split-sum approximation, Karis 2013); the diffuse base from the cube's irradiance
    /// ([`crate::prefilter`]).
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

/// The two Monte Carlo integration orders of §5.2.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Order {
    /// Integrate at each sample point with its own M random vectors, then blend (the thesis's
    /// choice).
    PerPoint,
    /// For each of M random vectors blend the four sample points, then integrate.
    PerDirection,
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

/// Most steps of the linear search of a depth-corrected lookup (`depth_search` in shade.wgsl):
/// about one per texel of the arc the ray sweeps in the sample point's cube, at most this many.
pub const DEPTH_STEPS: u32 = 16;
/// How far behind the surface a sample point sees the refined hit may lie, in texel angles times
/// the distance, before the ray counts as passing behind an occluder's silhouette (a hit that
/// sample point cannot see).
pub const DEPTH_THICKNESS_TEXELS: f32 = 4.0;

/// Everything a frame's shading depends on besides the camera.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct ShadingParams {
    /// Which terms.
    pub mode: Mode,
    /// The blend of the four sample points.
    pub blend: Blend,
    /// The lobe power N of B^r and B^n (0 gives B^avg); 0..=1e6.
    pub blend_n: f32,
    /// OSLF or the environment-map baseline.
    pub source: Source,
    /// φ_shader in degrees (§6.3): reconstruction uses the nearest sample point within this
    /// angle of the shaded normal; 0..=180.
    pub phi_shader_deg: f32,
    /// Monte Carlo samples per integration (M); 1..=65536.
    pub m: u32,
    /// The integration order of §5.2.
    pub order: Order,
    /// Specular reflectance at normal incidence R_s, in [0, 1].
    pub rs: f32,
    /// Diffuse reflectance R_d of the optional diffuse term 5.4, in [0, 1].
    pub rd: f32,
    /// Phong-like exponents n_u (along ∂x/∂u) and n_v, in [0, 1e7].
    pub nu: f32,
    /// See `nu`.
    pub nv: f32,
    /// `metallic` of [`Mode::Pbr`] (glTF's metallic factor), in [0, 1].
    #[serde(default = "default_metallic")]
    pub metallic: f32,
    /// `roughness` of [`Mode::Pbr`] (glTF's perceptual roughness; α = roughness²), in [0, 1].
    #[serde(default = "default_roughness")]
    pub roughness: f32,
    /// [`Mode::Pbr`] shades each object with a metallic-roughness material in the store
    /// with that material's factors; `metallic` and `roughness` then serve
    /// only the objects without one. `false`: `metallic` and `roughness` for every object.
    #[serde(default = "default_object_material")]
    pub object_material: bool,
    /// Seed of the per-pixel random numbers.
    pub seed: u32,
    /// Depth-corrected lookups (needs a store with a distance channel): each sample point's
    /// reflection and glossy lookups go towards where the ray from the *shaded point* meets
    /// the scene as that sample point's distances describe it, instead of along the ray's
    /// direction from the sample point (§6.3, RGBZ; see shade.wgsl `depth_search` for
    /// reflections and per-direction glossy, `depth_iterate` for per-point glossy samples).
    pub depth: bool,
    /// How the glossy term reads the cube maps.
    pub glossy_filter: GlossyFilter,
    /// The proxy box of [`Source::Parallax`] in world space, `[min, max]`; `None` fits it to the
    /// environment cube's distances.
    pub proxy_box: Option<[[f32; 3]; 2]>,
}

fn default_metallic() -> f32 {
    1.0
}

fn default_roughness() -> f32 {
    0.3
}

fn default_object_material() -> bool {
    true
}

impl Default for ShadingParams {
    /// The thesis's settings: reconstruction plus mirror reflection blended with B^n, N = 4;
    /// φ_shader = 65°; Ashikhmin–Shirley R_s = 1, R_d = 0, n_u = n_v = 100, M = 16. Beyond the
    /// thesis: depth-corrected lookups and filtered importance sampling on.
    fn default() -> Self {
        Self {
            mode: Mode::ReconMirror,
            blend: Blend::Normal,
            blend_n: 4.0,
            source: Source::Oslf,
            phi_shader_deg: 65.0,
            m: 16,
            order: Order::PerPoint,
            rs: 1.0,
            rd: 0.0,
            nu: 100.0,
            nv: 100.0,
            metallic: default_metallic(),
            roughness: default_roughness(),
            object_material: default_object_material(),
            seed: 0,
            depth: true,
            glossy_filter: GlossyFilter::Mip,
            proxy_box: None,
        }
    }
}

impl ShadingParams {
    /// Errors naming the first parameter outside its range (NaN included).
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
        check("N", self.blend_n, 0.0, 1e6)?;
        check("phi_shader", self.phi_shader_deg, 0.0, 180.0)?;
        check("R_s", self.rs, 0.0, 1.0)?;
        check("R_d", self.rd, 0.0, 1.0)?;
        check("n_u", self.nu, 0.0, 1e7)?;
        check("n_v", self.nv, 0.0, 1e7)?;
        check("metallic", self.metallic, 0.0, 1.0)?;
        check("roughness", self.roughness, 0.0, 1.0)?;
        if let Some([lo, hi]) = self.proxy_box {
            let ok = (0..3).all(|k| lo[k].is_finite() && hi[k].is_finite() && lo[k] < hi[k]);
            if !ok {
                return Err(RuntimeError::Parameter(format!(
                    "proxy box {lo:?}..{hi:?} must be finite with min < max on every axis"
                )));
            }
        }
        if self.glossy_filter == GlossyFilter::SplitSum
            && (self.mode != Mode::Pbr || self.source == Source::Oslf)
        {
            return Err(RuntimeError::Parameter(format!(
                "glossy filter split-sum is the engines' baseline of the pbr mode: it needs mode \
                 pbr and source env or parallax, not mode {} and source {}",
                self.mode.name(),
                self.source.name()
            )));
        }
        if !(1..=65536).contains(&self.m) {
            return Err(RuntimeError::Parameter(format!(
                "M = {} must be in [1, 65536]",
                self.m
            )));
        }
        Ok(())
    }
}

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

/// A camera ray's frame as the shader rebuilds it (`camera_ray` in shade.wgsl): the basis of
/// [`oslf_geometry::Camera::basis`] and tan(vfov/2) clamped as
/// [`oslf_geometry::Camera::direction`] clamps it.
fn ray_frame(camera: &oslf_geometry::Camera) -> ([f32; 4], [f32; 4], [f32; 4]) {
    let (right, up, forward) = camera.basis();
    let vfov = if camera.vfov_deg.is_finite() {
        camera.vfov_deg.clamp(1e-3, 179.0)
    } else {
        60.0
    };
    let tan_half = (0.5 * vfov.to_radians()).tan();
    (
        right.extend(tan_half).to_array(),
        up.extend(0.0).to_array(),
        forward.extend(0.0).to_array(),
    )
}

oslf_gpu::gpu_struct! {
    /// The shader's uniform block, `Params` in shade.wgsl and gbuffer.wgsl: its WGSL
    /// declaration is generated from these fields ([`ShadeUniform::wgsl`]), and the
    /// shader_layout tests check that WGSL places each at the Rust offset.
    #[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
    pub struct ShadeUniform as "Params" {
        pub view_proj: [[f32; 4]; 4],
        pub camera_pos: [f32; 4],
        pub size: [u32; 2],
        /// [`Mode::terms`]: 1 F_recon, 2 the mirror F_refl, 4 the glossy term, 8 scale the
        /// reflection by C_s (Eq. 4.12), 16 the glossy term is glTF's BRDF.
        pub terms: u32,
        /// 0 closest distance (4.3), 1 closest angle (4.4), 2 B^avg (4.9), 3 B^r (4.10), 4 B^n
        /// (4.11).
        pub blend: u32,
        pub blend_n: f32,
        /// 0 the OSLF's sample points, 1 the environment cube, 2 that cube parallax-corrected.
        pub source: u32,
        pub m: u32,
        /// 0 integrate per sample point, then blend; 1 blend per direction, then integrate (§5.2).
        pub order: u32,
        pub rs: f32,
        pub rd: f32,
        pub nu: f32,
        pub nv: f32,
        pub cos_phi_shader: f32,
        pub seed: u32,
        pub sample_count: u32,
        pub env_cube: u32,
        pub map_res: u32,
        pub index16: u32,
        pub cube_res: u32,
        pub slots_per_texture: u32,
        /// The camera's right vector; `w` = tan(vfov/2). With `cam_up` and `cam_forward`, the ray
        /// through each background pixel ([`Background::Env`]).
        pub cam_right: [f32; 4],
        /// The camera's up vector (`w` unused).
        pub cam_up: [f32; 4],
        /// The camera's viewing direction (`w` unused).
        pub cam_forward: [f32; 4],
        /// The colour of [`Background::Color`] (`w` unused).
        pub bg_color: [f32; 4],
        /// [`Background::tag`].
        pub background: u32,
        /// Mip levels the glossy term filters over; 1 = point sampling.
        pub mip_levels: u32,
        /// Most linear-search steps of a depth-corrected lookup; 0 = plain lookups.
        pub depth_steps: u32,
        /// [`DEPTH_THICKNESS_TEXELS`] as a fraction of the distance.
        pub depth_thickness: f32,
        /// The environment cube's centre, in the shader's coordinates (`w` unused).
        pub probe_pos: [f32; 4],
        /// The parallax proxy box, in the shader's coordinates (`w` unused).
        pub box_min: [f32; 4],
        /// See `box_min`.
        pub box_max: [f32; 4],
        /// [`ShadingParams::metallic`].
        pub metallic: f32,
        /// GGX α = roughness², at least [`oslf_shading::ggx::MIN_ALPHA`].
        pub alpha: f32,
        /// 1: the pbr mode takes an object's metallic and α from its material in the store where
        /// it has one ([`ShadingParams::object_material`] and a store with such objects).
        pub object_material: u32,
        /// The smallest metallic factor any pixel can have (`metallic`, and the store's
        /// materials' with `object_material`): below 1 the pbr mode has a diffuse part.
        pub min_metallic: f32,
        /// 1: [`GlossyFilter::SplitSum`].
        pub split_sum: u32,
        /// Pad the block to WGSL's 16-byte struct alignment.
        pub pad0: u32,
        pub pad1: u32,
        pub pad2: u32,
    }
}

/// What the uniform needs from the store and the cache besides the parameters.
#[derive(Clone, Copy, Debug)]
pub struct StoreConstants {
    pub sample_count: u32,
    /// The environment cube's index, or `u32::MAX`.
    pub env_cube: u32,
    pub map_res: u32,
    pub index16: bool,
    pub cube_res: u32,
    pub slots_per_texture: u32,
    /// Mip levels of the pool's faces.
    pub mip_levels: u32,
    /// Whether the pool has distance planes.
    pub has_depth: bool,
    /// World position of the shader's coordinate origin (the object's centre, where the
    /// environment cube was captured).
    pub origin: [f32; 3],
    /// The proxy box fitted to the environment cube's distances (world space), if it has them.
    pub fitted_box: Option<[[f32; 3]; 2]>,
    /// The smallest metallic factor of the store's metallic-roughness objects (format version
    /// 7), `None` if it has none.
    pub min_object_metallic: Option<f32>,
}

impl ShadeUniform {
    /// Packs parameters, camera (in the coordinates the shader works in), image size, store
    /// constants and background for the shader.
    pub fn new(
        p: &ShadingParams,
        view_proj: glam::Mat4,
        camera: &oslf_geometry::Camera,
        size: [u32; 2],
        k: &StoreConstants,
        background: Background,
    ) -> Self {
        let (cam_right, cam_up, cam_forward) = ray_frame(camera);
        let bg_color = match background {
            Background::Color([r, g, b]) => [r, g, b, 0.0],
            Background::None | Background::Env => [0.0; 4],
        };
        Self {
            view_proj: view_proj.to_cols_array_2d(),
            camera_pos: camera.position.extend(1.0).to_array(),
            size,
            terms: p.mode.terms(),
            blend: p.blend.tag(),
            blend_n: p.blend_n,
            source: p.source.tag(),
            m: p.m,
            order: match p.order {
                Order::PerPoint => 0,
                Order::PerDirection => 1,
            },
            rs: p.rs,
            rd: p.rd,
            nu: p.nu,
            nv: p.nv,
            cos_phi_shader: p.phi_shader_deg.to_radians().cos(),
            seed: p.seed,
            sample_count: k.sample_count,
            env_cube: k.env_cube,
            map_res: k.map_res,
            index16: u32::from(k.index16),
            cube_res: k.cube_res,
            slots_per_texture: k.slots_per_texture,
            cam_right,
            cam_up,
            cam_forward,
            bg_color,
            background: background.tag(),
            mip_levels: if p.glossy_filter == GlossyFilter::Mip {
                k.mip_levels
            } else {
                1
            },
            depth_steps: if p.depth && k.has_depth {
                DEPTH_STEPS
            } else {
                0
            },
            depth_thickness: DEPTH_THICKNESS_TEXELS * std::f32::consts::FRAC_PI_2
                / k.cube_res.max(1) as f32,
            probe_pos: [0.0; 4],
            box_min: [0.0; 4],
            box_max: [0.0; 4],
            metallic: p.metallic,
            alpha: oslf_shading::ggx::alpha(p.roughness),
            object_material: u32::from(p.object_material && k.min_object_metallic.is_some()),
            min_metallic: match k.min_object_metallic {
                Some(m) if p.object_material => m.min(p.metallic),
                _ => p.metallic,
            },
            split_sum: u32::from(p.glossy_filter == GlossyFilter::SplitSum),
            pad0: 0,
            pad1: 0,
            pad2: 0,
        }
        .with_proxy_box(p.proxy_box.or(k.fitted_box), k.origin)
    }

    /// Sets the proxy box (world space) in the shader's coordinates; none gives an empty box
    /// (every lookup then keeps its direction).
    fn with_proxy_box(mut self, b: Option<[[f32; 3]; 2]>, origin: [f32; 3]) -> Self {
        if let Some([lo, hi]) = b {
            for k in 0..3 {
                self.box_min[k] = lo[k] - origin[k];
                self.box_max[k] = hi[k] - origin[k];
            }
        }
        self
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
        let p = ShadingParams {
            nu: f32::NAN,
            ..Default::default()
        };
        assert!(p.validate().unwrap_err().to_string().contains("n_u"));
        let p = ShadingParams {
            m: 0,
            ..Default::default()
        };
        assert!(p.validate().unwrap_err().to_string().contains("M = 0"));
    }
}
