//! The shader's uniform block [`ShadeUniform`] (`Params` in shade.wgsl and gbuffer.wgsl): a
//! frame's [`ShadingParams`], camera, store constants and background packed for the GPU shader
//! and the CPU reference alike.

use crate::params::{Background, GlossyFilter};
use crate::shading::{DiffuseSource, Lookup, Recon, ShadingParams};

/// Most steps of the linear search of a depth-corrected lookup (`depth_search` in shade.wgsl):
/// about one per texel of the arc the ray sweeps in the sample point's cube, at most this many.
pub const DEPTH_STEPS: u32 = 16;
/// How far behind the surface a sample point sees the refined hit may lie, in texel angles times
/// the distance, before the ray counts as passing behind an occluder's silhouette (a hit that
/// sample point cannot see).
pub const DEPTH_THICKNESS_TEXELS: f32 = 4.0;

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
        /// [`crate::PbrMaterial::metallic`].
        pub metallic: f32,
        /// GGX α = roughness², at least [`oslf_shading::ggx::MIN_ALPHA`].
        pub alpha: f32,
        /// 1: the pbr mode takes an object's metallic and α from its material in the store where
        /// it has one ([`crate::PbrMaterial::object_material`] and a store with such objects).
        pub object_material: u32,
        /// The smallest metallic factor any pixel can have (`metallic`, and the store's
        /// materials' with `object_material`): below 1 the pbr mode has a diffuse part.
        pub min_metallic: f32,
        /// 1: [`GlossyFilter::SplitSum`].
        pub split_sum: u32,
        /// Where the diffuse part is read from the store's irradiance section
        /// ([`crate::DiffuseSource::Irradiance`] and a store that has one): the index in
        /// `samples` of cube 0's first spherical-harmonic coefficient; else `u32::MAX` (the
        /// diffuse part is sampled from the cube maps).
        pub irradiance: u32,
        /// How far the G-buffer's triangles may lie from the patches they tessellate (the
        /// mesh's [`crate::geometry::ObjectMesh::max_error`]): the shading pass refines each
        /// pixel's point onto its patch within [`oslf_geometry::bezier::REFINE_REACH`] of it.
        pub surface_error: f32,
        /// Pad the block to WGSL's 16-byte struct alignment.
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
    /// Where `samples` holds the store's irradiance section (format 1.1), `None` if it has none.
    pub irradiance_base: Option<u32>,
    /// The G-buffer tessellation's tolerance ([`crate::geometry::ObjectMesh::max_error`]).
    pub surface_error: f32,
}

impl ShadeUniform {
    /// The glossy term has a diffuse part (override DIFFUSE): R_d > 0, or in the pbr mode a
    /// material that is not wholly metallic.
    pub(crate) fn has_diffuse(&self) -> bool {
        if self.terms & 16 != 0 {
            self.min_metallic < 1.0
        } else {
            self.rd > 0.0
        }
    }

    /// The diffuse part is read from the store's irradiance section (override IRRADIANCE).
    pub(crate) fn reads_irradiance(&self) -> bool {
        self.has_diffuse() && self.irradiance != u32::MAX
    }

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
        // Parts the mode does not have keep their defaults: the shader does not read them.
        let (blend, blend_n) = p.blend().unwrap_or(Lookup::DEFAULT_BLEND);
        let mc = p.monte_carlo().unwrap_or_default();
        let lobe = p.lobe().unwrap_or_default();
        let material = p.material().unwrap_or_default();
        let object_material = material.object_material && p.material().is_some();
        Self {
            view_proj: view_proj.to_cols_array_2d(),
            camera_pos: camera.position.extend(1.0).to_array(),
            size,
            terms: p.mode().terms(),
            blend: blend.tag(),
            blend_n,
            source: p.source().tag(),
            m: mc.m,
            order: mc.order.tag(),
            rs: lobe.rs,
            rd: lobe.rd,
            nu: lobe.nu,
            nv: lobe.nv,
            cos_phi_shader: p
                .phi_shader_deg()
                .unwrap_or(Recon::default().phi_shader_deg)
                .to_radians()
                .cos(),
            seed: mc.seed,
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
            mip_levels: match p.glossy_filter() {
                Some(GlossyFilter::Point | GlossyFilter::SplitSum) => 1,
                Some(GlossyFilter::Mip) | None => k.mip_levels,
            },
            depth_steps: if p.depth() && k.has_depth {
                DEPTH_STEPS
            } else {
                0
            },
            depth_thickness: DEPTH_THICKNESS_TEXELS * std::f32::consts::FRAC_PI_2
                / k.cube_res.max(1) as f32,
            probe_pos: [0.0; 4],
            box_min: [0.0; 4],
            box_max: [0.0; 4],
            metallic: material.metallic,
            alpha: oslf_shading::ggx::alpha(material.roughness),
            object_material: u32::from(object_material && k.min_object_metallic.is_some()),
            min_metallic: match k.min_object_metallic {
                Some(m) if object_material => m.min(material.metallic),
                _ => material.metallic,
            },
            split_sum: u32::from(p.split_sum()),
            irradiance: match (mc.diffuse, k.irradiance_base) {
                (DiffuseSource::Irradiance, Some(base)) => base,
                _ => u32::MAX,
            },
            surface_error: k.surface_error,
            pad2: 0,
        }
        .with_proxy_box(p.proxy_box().or(k.fitted_box), k.origin)
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
