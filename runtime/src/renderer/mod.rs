//! The wgpu renderer: a G-buffer pass over the tessellated patches (gbuffer.wgsl), a compute
//! pass that shades every pixel from the sample maps and the cached cube maps (shade.wgsl),
//! and the feedback loop that feeds the [`CubeCache`]. The pipelines are in `pipelines.rs`, the
//! cube-map pool in `pool.rs`, the store's buffers in `buffers.rs`; here, the render targets
//! (`targets`), the two passes' encoding (`passes`), their GPU timestamps (`timer`), reading a
//! frame back (`readback`) and the camera's projection (`camera`).

use std::sync::Arc;
use std::time::Instant;

use oslf_format::Store;
use oslf_geometry::Camera;

use crate::buffers::{upload_sample_maps, StoreBuffers};
use crate::cache::{CacheConfig, CacheStats, CubeCache};
use crate::error::{Param, Result, RuntimeError};
use crate::face::FaceLayout;
use crate::geometry::ObjectMesh;
use crate::params::{Background, Source};
use crate::pipelines::{GBufferPipeline, ShadeBindings, ShadeKey, ShadePipelines};
use crate::pool::{CubePool, PoolLayout};
use crate::prefilter::PrefilteredEnv;
use crate::shading::ShadingParams;
use crate::textures::ObjectTextureGroups;
use crate::uniform::{ShadeUniform, StoreConstants};
use crate::Gpu;

pub use crate::pool::DEFAULT_POOL_BYTES;

mod camera;
mod host;
mod passes;
mod prefiltered;
mod prepass;
mod readback;
mod targets;
mod timer;

pub(crate) use camera::store_view;
pub use camera::{default_camera, view_projection};
pub use host::{HostPassSeconds, HostTarget, HostView, DEPTH_SLACK, MAX_DEPTH_SLACK};
pub use prepass::{normal_from_local, HostPrepass, PrepassTarget, PrepassUniform};
pub use targets::FrameBytes;

use readback::map_read;
use targets::SizedTargets;
use timer::{PassTimer, TimedPass};

/// Frame options.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RenderOptions {
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// After shading, load what the frame missed and shade again (up to `max_passes` in
    /// all), so that a budget holding the working set gives the exact image in one call. A
    /// viewer streams instead (`false`): misses fall back this frame and are resident next.
    pub resolve_misses: bool,
    /// Most shading passes per frame when resolving misses.
    pub max_passes: u32,
    /// Read the image back to the CPU ([`Frame::pixels`]); off for timing the GPU alone.
    pub read_pixels: bool,
    /// What the pixels off the object show; their alpha stays 0 (the object mask) whatever
    /// is chosen. [`Background::Env`] needs a store with an environment cube.
    pub background: Background,
}

impl Default for RenderOptions {
    /// The thesis's 655×460, misses resolved, pixels read back, no background (transparent
    /// black: embedders compose their own scene).
    fn default() -> Self {
        Self {
            width: 655,
            height: 460,
            resolve_misses: true,
            max_passes: 3,
            read_pixels: true,
            background: Background::None,
        }
    }
}

/// A rendered frame.
#[derive(Clone, Debug)]
pub struct Frame {
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// Linear RGB and the object mask in alpha (1 on the object, 0 elsewhere, where the RGB
    /// is the [`RenderOptions::background`]), row-major, top row first; empty unless
    /// [`RenderOptions::read_pixels`].
    pub pixels: Vec<[f32; 4]>,
    /// Cache counters of the frame's first shading pass, with the loads of every pass.
    pub stats: CacheStats,
    /// Shading passes run.
    pub passes: u32,
    /// Needed units (cubes or faces, as [`CacheStats`] counts them) that the final shading
    /// pass did not have resident, so their sample points fell back (see [`crate::cache`]):
    /// a budget too small for the frame's working set, faces that failed to decode
    /// ([`crate::CubeCache::errors`]), or, when streaming, loads that arrive next frame. 0 means
    /// the image is exactly what the store holds.
    pub fallbacks: u64,
    /// GPU time of the frame's shading passes (timestamps at the start and end of each
    /// compute pass, summed), without the G-buffer pass, the feedback read-back and the cache:
    /// the part of a frame that the shading parameters (M, filtering, depth correction) set.
    /// `None` where the device has no `TIMESTAMP_QUERY` ([`Gpu::has_timestamps`]).
    pub shade_gpu_seconds: Option<f64>,
    /// GPU time of the frame's G-buffer pass (rasterizing the object), likewise; with
    /// `shade_gpu_seconds`, what the GPU spends on a frame.
    pub gbuffer_gpu_seconds: Option<f64>,
}

/// Renders one store. See the crate docs for the frame's steps.
pub struct Renderer {
    gpu: Gpu,
    store: Arc<Store>,
    mesh: ObjectMesh,
    cache: CubeCache,
    constants: StoreConstants,
    buffers: StoreBuffers,
    sample_maps: wgpu::TextureView,
    pool: CubePool,
    gbuffer: GBufferPipeline,
    /// The textured objects' texture groups (`None` when no object has textures).
    textures: Option<ObjectTextureGroups>,
    shade: ShadePipelines,
    /// The shading pipeline of the current frame.
    current: ShadeKey,
    /// The background of the last frame (for [`Renderer::reference_image`]).
    background: Background,
    targets: Option<SizedTargets>,
    cube_count: u32,
    timer: Option<PassTimer>,
    /// The prefiltered environment of the split-sum baseline, once a frame has asked for it
    /// ([`Renderer::ensure_prefiltered`]), and its texture (one black texel before).
    prefiltered: Option<PrefilteredEnv>,
    prefiltered_view: wgpu::TextureView,
    /// Frames recorded into a host's encoder ([`Renderer::encode_into`]).
    host_frames: u64,
    /// Where host frames' feedback is copied and mapped, asynchronously.
    feedback_slots: Vec<host::FeedbackSlot>,
    /// The latest booked host frame's pass times ([`Renderer::host_pass_seconds`]).
    host_pass_seconds: Option<HostPassSeconds>,
    /// The indirection table as last written to the GPU (`write_slots`).
    slots_written: Vec<u32>,
    /// The composite pipelines of the host targets seen.
    composites: host::Composites,
    /// The prepass pipelines of the host prepasses seen.
    prepasses: prepass::Prepasses,
    /// The prepass recorded for the view whose frame comes next, if any.
    prepassed: Option<prepass::Prepassed>,
}

/// Errors with [`RuntimeError::Limits`] when the device's 2D textures cannot hold `store`'s
/// cube faces or sample maps, or its array layers one sample-map layer per map (Bézier patch
/// or atlas page).
fn check_textures_fit(limits: &wgpu::Limits, store: &Store) -> Result<()> {
    let res = store.header().cube_resolution;
    let map_res = store.header().sample_map_resolution;
    let patch_count = store.meta().map_count() as u32;
    if res > limits.max_texture_dimension_2d || map_res > limits.max_texture_dimension_2d {
        return Err(RuntimeError::Limits(format!(
            "cube faces of {res}² and sample maps of {map_res}² need 2D textures of that \
             size; the device allows {}",
            limits.max_texture_dimension_2d
        )));
    }
    let textured = store.meta().objects.iter().any(|o| o.textures.is_some());
    let material_bytes = 2 * 16 + 16;
    if textured && limits.max_color_attachment_bytes_per_sample < material_bytes {
        return Err(RuntimeError::Limits(format!(
            "the store's textured objects need a G-buffer of {material_bytes} bytes per sample \
             (three Rgba32 targets); the device allows {} (request the adapter's limits)",
            limits.max_color_attachment_bytes_per_sample
        )));
    }
    if patch_count == 0 || patch_count > limits.max_texture_array_layers {
        return Err(RuntimeError::Limits(format!(
            "{patch_count} sample maps (patches and atlas pages) need as many layers; the device allows {}",
            limits.max_texture_array_layers
        )));
    }
    Ok(())
}

/// The smallest metallic any pixel of a metallic-roughness object can have: its factor, or
/// the smallest its metallic-roughness texture holds (`None` without such objects).
fn min_object_metallic(meta: &oslf_format::StoreMeta) -> Option<f32> {
    let kind = oslf_format::TextureKind::MetallicRoughness;
    meta.objects
        .iter()
        .filter(|o| o.material.is_metallic_roughness())
        .map(|o| match o.textures.as_ref().and_then(|t| t.image(kind)) {
            Some(image) => image
                .texels
                .iter()
                .map(|t| t[2])
                .min()
                .map_or(0.0, |b| f32::from(b) / 255.0),
            None => o.material.metallic,
        })
        .reduce(f32::min)
}

/// What the shader sees of `store` (drawn as `mesh`) with its faces in the pool `layout`.
pub(crate) fn store_constants(
    store: &Store,
    mesh: &ObjectMesh,
    layout: &PoolLayout,
) -> StoreConstants {
    StoreConstants {
        sample_count: store.sample_points().len() as u32,
        env_cube: store.env_cube_index().unwrap_or(u32::MAX),
        map_res: store.header().sample_map_resolution,
        index16: store.index_width() == oslf_format::IndexWidth::U16,
        cube_res: layout.cube_res,
        slots_per_texture: layout.slots_per_texture,
        mip_levels: layout.face.levels,
        has_depth: layout.face.depth,
        origin: mesh.origin.to_array(),
        // A damaged environment cube leaves no fitted box; the cache reports the damage
        // when it loads the cube, and parallax then asks for a given box.
        fitted_box: crate::probe::fit_proxy_box(store, mesh.origin).unwrap_or(None),
        min_object_metallic: min_object_metallic(store.meta()),
        irradiance_base: crate::buffers::irradiance_base(store),
        surface_error: mesh.max_error,
    }
}

/// The cube cache for `store` with the pool's slots, the environment cube pinned.
fn open_cache(store: &Store, layout: &PoolLayout, config: &CacheConfig) -> CubeCache {
    let mut cache = CubeCache::new(
        store.cube_count(),
        layout.slots,
        config.granularity,
        config.ram_bytes,
        layout.face,
    );
    if let Some(env_cube) = store.env_cube_index() {
        cache.pin(env_cube);
    }
    cache
}

impl Renderer {
    /// Opens `store` on `gpu`: tessellates the patches, uploads the sample maps and sample
    /// points, creates the cube-map pool and pins the environment cube.
    ///
    /// Errors with [`RuntimeError::Limits`] when the device cannot hold the store's sample
    /// maps, or the requested number of GPU slots.
    pub fn new(gpu: Gpu, store: Store, config: CacheConfig) -> Result<Self> {
        gpu.clone().scoped(|| Self::open(gpu, store, config))
    }

    /// [`Renderer::new`]'s work, its device errors caught by the caller.
    fn open(gpu: Gpu, store: Store, config: CacheConfig) -> Result<Self> {
        let limits = gpu.limits();
        check_textures_fit(&limits, &store)?;
        let cube_count = store.cube_count();
        // BC6H stores go up as their blocks where the device has BC texture compression.
        let face = FaceLayout::for_store(&store, gpu.has_bc());
        let layout = PoolLayout::plan(&limits, face, cube_count, &config)?;
        let mesh = ObjectMesh::of_store(&store);
        let cache = open_cache(&store, &layout, &config);
        let buffers = StoreBuffers::new(&gpu.device, &store, &mesh, cube_count);
        let sample_maps = upload_sample_maps(&gpu, &store)?;
        let pool = CubePool::new(&gpu.device, layout);
        let textures = ObjectTextureGroups::new(&gpu.device, &gpu.queue, store.meta());
        let gbuffer = GBufferPipeline::new(
            &gpu.device,
            &buffers.uniform,
            &buffers.vertices,
            textures.as_ref().map(|t| &t.layout),
        );
        let shade = ShadePipelines::new(
            &gpu.device,
            layout.textures_in_use(),
            layout.face_shift,
            textures.is_some(),
        );
        let constants = store_constants(&store, &mesh, &layout);
        let prefiltered_view = prefiltered::upload(&gpu, &PrefilteredEnv::black());
        let composites = host::Composites::new(&gpu.device);
        let prepasses = prepass::Prepasses::new(&gpu.device);
        let mut renderer = Self {
            gpu,
            store: Arc::new(store),
            mesh,
            cache,
            constants,
            buffers,
            sample_maps,
            pool,
            gbuffer,
            textures,
            shade,
            current: ShadeKey::default(),
            background: Background::None,
            targets: None,
            cube_count,
            timer: None,
            prefiltered: None,
            prefiltered_view,
            host_frames: 0,
            feedback_slots: Vec::new(),
            host_pass_seconds: None,
            composites,
            prepasses,
            prepassed: None,
            slots_written: Vec::new(),
        };
        renderer.timer = PassTimer::new(&renderer.gpu);
        renderer.load_env_cube();
        renderer.write_slots();
        renderer.gpu.take_errors()?;
        Ok(renderer)
    }

    /// Loads the pinned environment cube, if the store has one, into the pool now.
    fn load_env_cube(&mut self) {
        let Some(env_cube) = self.store.env_cube_index() else {
            return;
        };
        let mut needed = vec![0u32; self.cube_count as usize];
        needed[env_cube as usize] = 63;
        let (uploads, _) = self.cache.plan(&needed, &self.store, true);
        let _ = self.pool.upload(&self.gpu.queue, &uploads);
    }

    /// The GPU this renderer draws on.
    pub fn gpu(&self) -> &Gpu {
        &self.gpu
    }

    /// The store.
    pub fn store(&self) -> &Store {
        &self.store
    }

    /// The tessellated object.
    pub fn mesh(&self) -> &ObjectMesh {
        &self.mesh
    }

    /// What each cube face holds in the GPU pool (encoding, mip levels, distance plane): build
    /// the CPU reference with the same ([`crate::reference::StoreCubes::decode_as`]).
    pub fn face_layout(&self) -> FaceLayout {
        self.cache.face_layout()
    }

    /// The cache (its cumulative statistics, decode errors, slot count).
    pub fn cache(&self) -> &CubeCache {
        &self.cache
    }

    /// The cache, to reset its statistics between measurements.
    pub fn cache_mut(&mut self) -> &mut CubeCache {
        &mut self.cache
    }

    /// The proxy box [`Source::Parallax`] uses with `params` (world space): the given one, else
    /// the one fitted to the environment cube's distances ([`crate::probe::fit_proxy_box`]).
    pub fn proxy_box(&self, params: &ShadingParams) -> Option<[[f32; 3]; 2]> {
        params.proxy_box().or(self.constants.fitted_box)
    }

    /// The store constants the shader sees.
    pub fn constants(&self) -> StoreConstants {
        self.constants
    }

    /// The shaded image of the last frame (an `Rgba32Float` texture), for viewers that draw
    /// it themselves.
    pub fn output_texture(&self) -> Option<&wgpu::Texture> {
        self.targets.as_ref().map(|t| &t.output)
    }

    /// The uniform block for a frame of `width` × `height` pixels with `background`.
    pub fn uniform(
        &self,
        camera: &Camera,
        params: &ShadingParams,
        width: u32,
        height: u32,
        background: Background,
    ) -> ShadeUniform {
        // Object-relative coordinates (see `ObjectMesh`): the G-buffer, the sample points and
        // the camera all have `mesh.origin` subtracted.
        let relative = Camera {
            position: camera.position - self.mesh.origin,
            target: camera.target - self.mesh.origin,
            ..*camera
        };
        ShadeUniform::new(
            params,
            view_projection(&relative, width, height),
            &relative,
            [width, height],
            &self.constants,
            background,
        )
    }

    /// Writes the cache's indirection table to the GPU unless the GPU has it already.
    /// Returns 1 when it wrote it, 0 when not (a [`CacheStats::table_writes`] count).
    fn write_slots(&mut self) -> u64 {
        let mut table = self.cache.indirection();
        if table.is_empty() {
            table.push(0);
        }
        if table == self.slots_written {
            return 0;
        }
        self.gpu
            .queue
            .write_buffer(&self.buffers.slots, 0, bytemuck::cast_slice(&table));
        self.slots_written = table;
        1
    }

    /// Creates the G-buffer, depth and output textures and the shading bind group for images
    /// of `width` × `height`, unless the last frame had that size.
    fn ensure_targets(&mut self, width: u32, height: u32) -> Result<()> {
        if let Some(t) = &self.targets {
            if t.width == width && t.height == height {
                return Ok(());
            }
        }
        let limits = self.gpu.limits();
        if width == 0
            || height == 0
            || width > limits.max_texture_dimension_2d
            || height > limits.max_texture_dimension_2d
        {
            return Err(RuntimeError::Parameter(format!(
                "image size {width}x{height} must be 1..={} on each side",
                limits.max_texture_dimension_2d
            )));
        }
        let textured = self.textures.is_some();
        let targets = SizedTargets::new(
            &self.gpu.device,
            width,
            height,
            textured,
            |gp, gn, out, dv, gm| {
                self.shade.bind_group(
                    &self.gpu.device,
                    &ShadeBindings {
                        uniform: &self.buffers.uniform,
                        gb_position: gp,
                        gb_normal: gn,
                        sample_maps: &self.sample_maps,
                        samples: &self.buffers.samples,
                        patches: &self.buffers.patches,
                        slots: &self.buffers.slots,
                        feedback: &self.buffers.feedback,
                        pool: self.pool.views(),
                        depth_pool: self.pool.depth_views(),
                        output: out,
                        gb_depth: dv,
                        prefiltered: &self.prefiltered_view,
                        gb_material: gm,
                    },
                )
            },
        );
        self.targets = Some(targets);
        Ok(())
    }

    /// Renders a frame: G-buffer, shading, feedback to the cache; with
    /// [`RenderOptions::resolve_misses`], loads and shades again until nothing the frame
    /// needs is missing (or the budget is full, or `max_passes` is reached).
    pub fn render(
        &mut self,
        camera: &Camera,
        params: &ShadingParams,
        opts: &RenderOptions,
    ) -> Result<Frame> {
        self.check_frame(params, opts.background)?;
        if params.split_sum() {
            self.ensure_prefiltered()?;
        }
        self.ensure_targets(opts.width, opts.height)?;
        let u = self.uniform(camera, params, opts.width, opts.height, opts.background);
        self.current = ShadeKey::of(&u);
        self.background = opts.background;
        self.shade.prepare(&self.gpu.device, self.current);
        self.gpu
            .queue
            .write_buffer(&self.buffers.uniform, 0, bytemuck::bytes_of(&u));
        let mut stats: Option<CacheStats> = None;
        let mut shade_gpu_seconds = self.timer.as_ref().map(|_| 0.0);
        let mut gbuffer_gpu_seconds = shade_gpu_seconds;
        let mut passes = 0;
        let mut fallbacks;
        let max_passes = opts.max_passes.max(1);
        loop {
            passes += 1;
            let (needed, readback, [gbuffer, shade]) = self.shade_pass(passes == 1)?;
            let add = |sum: Option<f64>, t: Option<f64>| sum.zip(t).map(|(a, b)| a + b);
            shade_gpu_seconds = add(shade_gpu_seconds, shade);
            gbuffer_gpu_seconds = add(gbuffer_gpu_seconds, gbuffer);
            let start = Instant::now();
            let (uploads, mut frame_stats) =
                self.cache.plan(&needed, &self.store, opts.resolve_misses);
            frame_stats.upload_seconds = self.pool.upload(&self.gpu.queue, &uploads);
            frame_stats.table_writes = self.write_slots();
            frame_stats.cache_seconds = readback + start.elapsed().as_secs_f64();
            let missed = frame_stats.misses > 0 && !uploads.is_empty();
            // This pass shaded without what it missed; the last pass's count is the image's.
            fallbacks = frame_stats.misses;
            match &mut stats {
                None => stats = Some(frame_stats),
                Some(s) => s.add_loading(&frame_stats),
            }
            if !(opts.resolve_misses && missed && passes < max_passes) {
                break;
            }
        }
        let pixels = if opts.read_pixels {
            self.read_texture_rgba32f(|t| &t.output)?
        } else {
            self.gpu.wait()?;
            Vec::new()
        };
        self.gpu.take_errors()?;
        let stats = stats.unwrap_or_default();
        self.cache.cumulative.add(&stats);
        Ok(Frame {
            width: opts.width,
            height: opts.height,
            pixels,
            stats,
            passes,
            fallbacks,
            shade_gpu_seconds,
            gbuffer_gpu_seconds,
        })
    }

    /// Errors for parameters this store cannot shade: invalid values, an order that reads
    /// distances on a store without them, the parallax baseline without a proxy box, an
    /// environment background without an environment cube.
    fn check_frame(&self, params: &ShadingParams, background: Background) -> Result<()> {
        params.validate()?;
        if let Some(mc) = params.monte_carlo() {
            if mc.order.reads_distances() && !self.constants.has_depth {
                return Err(RuntimeError::Parameter(format!(
                    "order {} reads the distance channel, and this store has none (bake it \
                     with distance_channel = true, the default)",
                    mc.order.name()
                )));
            }
        }
        if params.source() == Source::Parallax && self.proxy_box(params).is_none() {
            return Err(RuntimeError::InvalidParam {
                param: Param::ProxyBox,
                problem: "missing: source parallax needs one, and this store has no environment \
                          cube with a readable distance channel to fit one to (give the box)"
                    .into(),
            });
        }
        background.validate(self.constants.env_cube != u32::MAX)
    }

    /// Runs the G-buffer pass (if `geometry`) and the shading pass, and returns the feedback
    /// masks, the seconds spent copying them out of the mapped buffer and the G-buffer and
    /// shading passes' GPU seconds (with timestamps; the G-buffer's 0 when not `geometry`).
    fn shade_pass(&mut self, geometry: bool) -> Result<(Vec<u32>, f64, [Option<f64>; 2])> {
        let targets = self
            .targets
            .as_ref()
            .ok_or_else(|| RuntimeError::gpu("render targets missing"))?;
        let device = &self.gpu.device;
        let mut encoder = device.create_command_encoder(&Default::default());
        encoder.clear_buffer(&self.buffers.feedback, 0, None);
        if geometry {
            self.encode_gbuffer(&mut encoder, targets, self.timer.as_ref());
        }
        self.encode_shading(&mut encoder, targets, self.timer.as_ref())?;
        encoder.copy_buffer_to_buffer(
            &self.buffers.feedback,
            0,
            &self.buffers.feedback_readback,
            0,
            Some(self.buffers.timestamps_offset),
        );
        let stamps = self.buffers.timestamps_offset;
        if let Some(timer) = &self.timer {
            let readback = &self.buffers.feedback_readback;
            if geometry {
                timer.encode_copy(&mut encoder, TimedPass::GBuffer, readback, stamps);
            }
            timer.encode_copy(&mut encoder, TimedPass::Shade, readback, stamps);
        }
        self.gpu.queue.submit([encoder.finish()]);
        self.gpu.wait()?;
        let start = Instant::now();
        let bytes = map_read(&self.gpu, &self.buffers.feedback_readback)?;
        let mut masks: Vec<u32> = bytemuck::pod_collect_to_vec(&bytes[..stamps as usize]);
        masks.truncate(self.cube_count as usize);
        let seconds = |pass| {
            let t = self.timer.as_ref()?;
            match (pass, geometry) {
                (TimedPass::GBuffer, false) => Some(0.0),
                _ => t.seconds(&bytes[stamps as usize..], pass),
            }
        };
        let gpu = [seconds(TimedPass::GBuffer), seconds(TimedPass::Shade)];
        Ok((masks, start.elapsed().as_secs_f64(), gpu))
    }
}
