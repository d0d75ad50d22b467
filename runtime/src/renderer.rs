//! The wgpu renderer: a G-buffer pass over the tessellated patches (gbuffer.wgsl), a compute
//! pass that shades every pixel from the sample maps and the cached cube maps (shade.wgsl),
//! and the feedback loop that feeds the [`CubeCache`]. The pipelines are in `pipelines.rs`, the
//! cube-map pool in `pool.rs`, the store's buffers in `buffers.rs`.

use std::sync::Arc;
use std::time::Instant;

use glam::{Mat4, Vec3};
use oslf_format::Store;
use oslf_geometry::Camera;

use crate::buffers::{upload_sample_maps, StoreBuffers, TIMESTAMP_BYTES};
use crate::cache::{CacheConfig, CacheStats, CubeCache};
use crate::error::{Param, Result, RuntimeError};
use crate::face::FaceLayout;
use crate::geometry::ObjectMesh;
use crate::gpu::Gpu;
use crate::params::{Background, ShadeUniform, ShadingParams, Source, StoreConstants};
use crate::pipelines::{
    GBufferPipeline, ShadeBindings, ShadeKey, ShadePipelines, DEPTH_CLEAR, DEPTH_FORMAT,
    GBUFFER_FORMAT, OUTPUT_FORMAT, WORKGROUP,
};
use crate::pool::{CubePool, PoolLayout};
use crate::reference::GTexel;

pub use crate::pool::DEFAULT_POOL_BYTES;

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

/// Timestamps at the start and end of the G-buffer pass (queries 0, 1) and of the shading pass
/// (2, 3), resolved into `resolve` (one pair per 256-byte resolve offset) and copied behind
/// the feedback masks (`StoreBuffers::feedback_readback`), so one map per pass reads them.
struct PassTimer {
    queries: wgpu::QuerySet,
    resolve: wgpu::Buffer,
    /// Nanoseconds per tick (`Queue::get_timestamp_period`).
    period_ns: f64,
}

/// A pass's pair of timestamps: G-buffer or shading.
#[derive(Clone, Copy)]
enum TimedPass {
    GBuffer = 0,
    Shade = 1,
}

impl TimedPass {
    /// Its two queries' indices.
    fn queries(self) -> std::ops::Range<u32> {
        2 * self as u32..2 * self as u32 + 2
    }

    /// Where its pair is resolved (resolve offsets are multiples of 256 bytes).
    fn resolve_offset(self) -> u64 {
        wgpu::QUERY_RESOLVE_BUFFER_ALIGNMENT * self as u64
    }

    /// Where its pair lies behind the feedback masks.
    fn readback_offset(self) -> u64 {
        TIMESTAMP_BYTES / 2 * self as u64
    }
}

impl PassTimer {
    fn new(gpu: &Gpu) -> Option<Self> {
        if !gpu.has_timestamps() {
            return None;
        }
        Some(Self {
            queries: gpu.device.create_query_set(&wgpu::QuerySetDescriptor {
                label: Some("pass timestamps"),
                ty: wgpu::QueryType::Timestamp,
                count: 4,
            }),
            resolve: gpu.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("pass timestamps"),
                size: 2 * wgpu::QUERY_RESOLVE_BUFFER_ALIGNMENT,
                usage: wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
                mapped_at_creation: false,
            }),
            period_ns: f64::from(gpu.queue.get_timestamp_period()),
        })
    }

    /// The timestamp writes of `pass` for its pass descriptor.
    fn writes(&self, pass: TimedPass) -> (&wgpu::QuerySet, Option<u32>, Option<u32>) {
        let q = pass.queries();
        (&self.queries, Some(q.start), Some(q.start + 1))
    }

    /// Encodes resolving `pass`'s pair and copying it behind the feedback masks at `stamps`.
    fn encode_copy(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        pass: TimedPass,
        readback: &wgpu::Buffer,
        stamps: u64,
    ) {
        encoder.resolve_query_set(
            &self.queries,
            pass.queries(),
            &self.resolve,
            pass.resolve_offset(),
        );
        encoder.copy_buffer_to_buffer(
            &self.resolve,
            pass.resolve_offset(),
            readback,
            stamps + pass.readback_offset(),
            Some(TIMESTAMP_BYTES / 2),
        );
    }

    /// Seconds between `pass`'s two timestamps in `bytes` (the read-back from `stamps` on;
    /// start, end as u64 ticks); `None` for an end before the start (a device whose counter
    /// wrapped or was reset between them).
    fn seconds(&self, bytes: &[u8], pass: TimedPass) -> Option<f64> {
        let at = pass.readback_offset() as usize;
        let start = u64::from_le_bytes(bytes.get(at..at + 8)?.try_into().ok()?);
        let end = u64::from_le_bytes(bytes.get(at + 8..at + 16)?.try_into().ok()?);
        let ticks = end.checked_sub(start)?;
        Some(ticks as f64 * self.period_ns * 1e-9)
    }
}

/// The textures of one image size and the shading bind group that binds them.
struct SizedTargets {
    width: u32,
    height: u32,
    gb_position: wgpu::Texture,
    gb_normal: wgpu::Texture,
    depth: wgpu::Texture,
    output: wgpu::Texture,
    shade_group: wgpu::BindGroup,
}

impl SizedTargets {
    /// Creates the G-buffer, depth and output textures for `width` × `height` and the shading
    /// bind group `bind` makes of the views of position, normal, output and depth.
    fn new(
        device: &wgpu::Device,
        width: u32,
        height: u32,
        bind: impl FnOnce(
            &wgpu::TextureView,
            &wgpu::TextureView,
            &wgpu::TextureView,
            &wgpu::TextureView,
        ) -> wgpu::BindGroup,
    ) -> Self {
        let size = wgpu::Extent3d {
            width,
            height,
            depth_or_array_layers: 1,
        };
        let make = |label, format, usage| {
            device.create_texture(&wgpu::TextureDescriptor {
                label: Some(label),
                size,
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format,
                usage,
                view_formats: &[],
            })
        };
        let rt = wgpu::TextureUsages::RENDER_ATTACHMENT
            | wgpu::TextureUsages::TEXTURE_BINDING
            | wgpu::TextureUsages::COPY_SRC;
        let gb_position = make("gbuffer position", GBUFFER_FORMAT, rt);
        let gb_normal = make("gbuffer normal", GBUFFER_FORMAT, rt);
        let depth = make(
            "depth",
            DEPTH_FORMAT,
            wgpu::TextureUsages::RENDER_ATTACHMENT
                | wgpu::TextureUsages::TEXTURE_BINDING
                | wgpu::TextureUsages::COPY_SRC,
        );
        let output = make(
            "output",
            OUTPUT_FORMAT,
            wgpu::TextureUsages::STORAGE_BINDING
                | wgpu::TextureUsages::COPY_SRC
                | wgpu::TextureUsages::TEXTURE_BINDING,
        );
        let view = |t: &wgpu::Texture| t.create_view(&Default::default());
        let shade_group = bind(
            &view(&gb_position),
            &view(&gb_normal),
            &view(&output),
            &view(&depth),
        );
        Self {
            width,
            height,
            gb_position,
            gb_normal,
            depth,
            output,
            shade_group,
        }
    }
}

/// What one frame of a given size needs besides the store and its cube-map pool.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct FrameBytes {
    /// The render targets on the GPU: two G-buffer textures, depth and the output.
    pub gpu: u64,
    /// With [`RenderOptions::read_pixels`]: the read-back buffer and [`Frame::pixels`].
    pub readback: u64,
}

impl FrameBytes {
    /// The bytes of a `width` × `height` frame, from the formats the renderer uses.
    pub fn of(width: u32, height: u32) -> Self {
        let pixels = u64::from(width) * u64::from(height);
        let texel = |f: wgpu::TextureFormat| {
            u64::from(
                f.block_copy_size(None)
                    .or(f.block_copy_size(Some(wgpu::TextureAspect::DepthOnly)))
                    .unwrap_or(16),
            )
        };
        let gpu = pixels * (2 * texel(GBUFFER_FORMAT) + texel(DEPTH_FORMAT) + texel(OUTPUT_FORMAT));
        // The read-back buffer (rows padded to 256 bytes) and the pixel vector, both RGBA f32.
        let row = u64::from(padded_row(width, texel(OUTPUT_FORMAT) as u32));
        let readback = row * u64::from(height) + pixels * 16;
        Self { gpu, readback }
    }
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
    shade: ShadePipelines,
    /// The shading pipeline of the current frame.
    current: ShadeKey,
    /// The background of the last frame (for [`Renderer::reference_image`]).
    background: Background,
    targets: Option<SizedTargets>,
    cube_count: u32,
    timer: Option<PassTimer>,
}

/// Bytes of one row of `width` texels of `bytes_per_texel`, padded for buffer copies.
fn padded_row(width: u32, bytes_per_texel: u32) -> u32 {
    let row = width * bytes_per_texel;
    row.div_ceil(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT) * wgpu::COPY_BYTES_PER_ROW_ALIGNMENT
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
    if patch_count == 0 || patch_count > limits.max_texture_array_layers {
        return Err(RuntimeError::Limits(format!(
            "{patch_count} sample maps (patches and atlas pages) need as many layers; the device allows {}",
            limits.max_texture_array_layers
        )));
    }
    Ok(())
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
        let limits = gpu.limits();
        check_textures_fit(&limits, &store)?;
        let cube_count = store.cube_count();
        // BC6H stores go up as their blocks where the device has BC texture compression.
        let face = FaceLayout::for_store(&store, gpu.has_bc());
        let layout = PoolLayout::plan(&limits, face, cube_count, &config)?;
        let mesh = ObjectMesh::from_store(&store, store.meta().bake.epsilon / 20.0);
        let cache = open_cache(&store, &layout, &config);
        let buffers = StoreBuffers::new(&gpu.device, &store, &mesh, cube_count);
        let sample_maps = upload_sample_maps(&gpu, &store)?;
        let pool = CubePool::new(&gpu.device, layout);
        let gbuffer = GBufferPipeline::new(&gpu.device, &buffers.uniform, &buffers.vertices);
        let shade = ShadePipelines::new(&gpu.device, layout.textures_in_use(), layout.face_shift);
        let constants = StoreConstants {
            sample_count: store.sample_points().len() as u32,
            env_cube: store.env_cube_index().unwrap_or(u32::MAX),
            map_res: store.header().sample_map_resolution,
            index16: store.index_width() == oslf_format::IndexWidth::U16,
            cube_res: layout.cube_res,
            slots_per_texture: layout.slots_per_texture,
            mip_levels: face.levels,
            has_depth: face.depth,
            origin: mesh.origin.to_array(),
            // A damaged environment cube leaves no fitted box; the cache reports the damage
            // when it loads the cube (below), and parallax then asks for a given box.
            fitted_box: crate::probe::fit_proxy_box(&store, mesh.origin).unwrap_or(None),
        };
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
            shade,
            current: ShadeKey::default(),
            background: Background::None,
            targets: None,
            cube_count,
            timer: None,
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
        params.proxy_box.or(self.constants.fitted_box)
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

    /// Writes the cache's indirection table to the GPU.
    fn write_slots(&self) {
        let mut table = self.cache.indirection();
        if table.is_empty() {
            table.push(0);
        }
        self.gpu
            .queue
            .write_buffer(&self.buffers.slots, 0, bytemuck::cast_slice(&table));
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
        let targets = SizedTargets::new(&self.gpu.device, width, height, |gp, gn, out, dv| {
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
                },
            )
        });
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
        params.validate()?;
        if params.source == Source::Parallax && self.proxy_box(params).is_none() {
            return Err(RuntimeError::InvalidParam {
                param: Param::ProxyBox,
                problem: "missing: source parallax needs one, and this store has no environment \
                          cube with a readable distance channel to fit one to (give the box)"
                    .into(),
            });
        }
        opts.background
            .validate(self.constants.env_cube != u32::MAX)?;
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
            self.write_slots();
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

    /// Runs the G-buffer pass (if `geometry`) and the shading pass, and returns the feedback
    /// masks, the seconds spent copying them out of the mapped buffer and the G-buffer and
    /// shading passes' GPU seconds (with timestamps; the G-buffer's 0 when not `geometry`).
    fn shade_pass(&mut self, geometry: bool) -> Result<(Vec<u32>, f64, [Option<f64>; 2])> {
        let targets = self
            .targets
            .as_ref()
            .ok_or_else(|| RuntimeError::Gpu("render targets missing".into()))?;
        let device = &self.gpu.device;
        let mut encoder = device.create_command_encoder(&Default::default());
        encoder.clear_buffer(&self.buffers.feedback, 0, None);
        if geometry {
            self.encode_gbuffer(&mut encoder, targets);
        }
        self.encode_shading(&mut encoder, targets)?;
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

    /// Encodes the G-buffer pass: clears depth and rasterizes the mesh into the targets. The
    /// colour targets are not cleared: the shading pass and `read_gbuffer` take a pixel as
    /// covered where its depth is below [`DEPTH_CLEAR`] and ignore the colour elsewhere (an
    /// NVIDIA H200 spent most of the pass clearing the two Rgba32Float targets:
    /// docs/measurements.md).
    fn encode_gbuffer(&self, encoder: &mut wgpu::CommandEncoder, targets: &SizedTargets) {
        let gp = targets.gb_position.create_view(&Default::default());
        let gn = targets.gb_normal.create_view(&Default::default());
        let dv = targets.depth.create_view(&Default::default());
        let keep = wgpu::Operations {
            load: wgpu::LoadOp::Load,
            store: wgpu::StoreOp::Store,
        };
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("gbuffer"),
            color_attachments: &[
                Some(wgpu::RenderPassColorAttachment {
                    view: &gp,
                    depth_slice: None,
                    resolve_target: None,
                    ops: keep,
                }),
                Some(wgpu::RenderPassColorAttachment {
                    view: &gn,
                    depth_slice: None,
                    resolve_target: None,
                    ops: keep,
                }),
            ],
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: &dv,
                depth_ops: Some(wgpu::Operations {
                    load: wgpu::LoadOp::Clear(DEPTH_CLEAR),
                    store: wgpu::StoreOp::Store,
                }),
                stencil_ops: None,
            }),
            timestamp_writes: self.timer.as_ref().map(|t| {
                let (query_set, begin, end) = t.writes(TimedPass::GBuffer);
                wgpu::RenderPassTimestampWrites {
                    query_set,
                    beginning_of_pass_write_index: begin,
                    end_of_pass_write_index: end,
                }
            }),
            occlusion_query_set: None,
            multiview_mask: None,
        });
        pass.set_pipeline(&self.gbuffer.pipeline);
        pass.set_bind_group(0, &self.gbuffer.group, &[]);
        pass.set_index_buffer(self.buffers.indices.slice(..), wgpu::IndexFormat::Uint32);
        pass.draw_indexed(0..self.buffers.index_count, 0, 0..1);
    }

    /// Encodes the shading pass of the current frame's pipeline over every pixel.
    fn encode_shading(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        targets: &SizedTargets,
    ) -> Result<()> {
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("shade"),
            timestamp_writes: self.timer.as_ref().map(|t| {
                let (query_set, begin, end) = t.writes(TimedPass::Shade);
                wgpu::ComputePassTimestampWrites {
                    query_set,
                    beginning_of_pass_write_index: begin,
                    end_of_pass_write_index: end,
                }
            }),
        });
        let pipeline = self
            .shade
            .get(&self.current)
            .ok_or_else(|| RuntimeError::Gpu("no shading pipeline for this mode".into()))?;
        pass.set_pipeline(pipeline);
        pass.set_bind_group(0, &targets.shade_group, &[]);
        pass.dispatch_workgroups(
            targets.width.div_ceil(WORKGROUP),
            targets.height.div_ceil(WORKGROUP),
            1,
        );
        Ok(())
    }

    /// Reads one of the targets (an `Rgba32Float` texture) back to the CPU, row-major.
    fn read_texture_rgba32f(
        &self,
        pick: impl Fn(&SizedTargets) -> &wgpu::Texture,
    ) -> Result<Vec<[f32; 4]>> {
        self.read_texture(pick, wgpu::TextureAspect::All)
    }

    /// Reads aspect `aspect` of a render target back, texel type `T`, row-major.
    fn read_texture<T: bytemuck::Pod>(
        &self,
        pick: impl Fn(&SizedTargets) -> &wgpu::Texture,
        aspect: wgpu::TextureAspect,
    ) -> Result<Vec<T>> {
        let texel = std::mem::size_of::<T>();
        let targets = self
            .targets
            .as_ref()
            .ok_or_else(|| RuntimeError::Gpu("render targets missing".into()))?;
        let (w, h) = (targets.width, targets.height);
        let row = padded_row(w, texel as u32);
        let buffer = self.gpu.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("readback"),
            size: u64::from(row) * u64::from(h),
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let mut encoder = self.gpu.device.create_command_encoder(&Default::default());
        encoder.copy_texture_to_buffer(
            wgpu::TexelCopyTextureInfo {
                texture: pick(targets),
                mip_level: 0,
                origin: wgpu::Origin3d::ZERO,
                aspect,
            },
            wgpu::TexelCopyBufferInfo {
                buffer: &buffer,
                layout: wgpu::TexelCopyBufferLayout {
                    offset: 0,
                    bytes_per_row: Some(row),
                    rows_per_image: Some(h),
                },
            },
            wgpu::Extent3d {
                width: w,
                height: h,
                depth_or_array_layers: 1,
            },
        );
        self.gpu.queue.submit([encoder.finish()]);
        let bytes = map_read(&self.gpu, &buffer)?;
        let mut out = Vec::with_capacity((w * h) as usize);
        for y in 0..h as usize {
            let start = y * row as usize;
            let line: &[T] = bytemuck::cast_slice(&bytes[start..start + w as usize * texel]);
            out.extend_from_slice(line);
        }
        Ok(out)
    }

    /// The G-buffer of the last frame, for the CPU reference: zero where depth says no
    /// triangle covers the pixel (the colour targets are not cleared: `encode_gbuffer`).
    pub fn read_gbuffer(&self) -> Result<Vec<GTexel>> {
        let p = self.read_texture_rgba32f(|t| &t.gb_position)?;
        let n = self.read_texture_rgba32f(|t| &t.gb_normal)?;
        let z: Vec<f32> = self.read_texture(|t| &t.depth, wgpu::TextureAspect::DepthOnly)?;
        Ok(p.into_iter()
            .zip(n)
            .zip(z)
            .map(|((position_patch, normal_uv), z)| {
                if z < DEPTH_CLEAR {
                    GTexel {
                        position_patch,
                        normal_uv,
                    }
                } else {
                    GTexel::default()
                }
            })
            .collect())
    }
}

/// Maps a MAP_READ buffer, waits, and copies its bytes out.
fn map_read(gpu: &Gpu, buffer: &wgpu::Buffer) -> Result<Vec<u8>> {
    let (tx, rx) = std::sync::mpsc::channel();
    buffer.map_async(wgpu::MapMode::Read, .., move |r| {
        let _ = tx.send(r);
    });
    gpu.wait()?;
    rx.recv()
        .map_err(|_| RuntimeError::Gpu("buffer mapping was dropped".into()))?
        .map_err(|e| RuntimeError::Gpu(format!("cannot map a buffer: {e}")))?;
    let bytes = {
        let view = buffer
            .get_mapped_range(..)
            .map_err(|e| RuntimeError::Gpu(format!("cannot read a mapped buffer: {e}")))?;
        view.to_vec()
    };
    buffer.unmap();
    Ok(bytes)
}

/// The camera's view-projection matrix (right-handed, depth 0..1 as wgpu wants), with near and
/// far planes from the distance to the target.
pub fn view_projection(camera: &Camera, width: u32, height: u32) -> Mat4 {
    use glam::Vec4;
    let (r, u, f) = camera.basis();
    let p = camera.position;
    let view = Mat4::from_cols(
        Vec4::new(r.x, u.x, -f.x, 0.0),
        Vec4::new(r.y, u.y, -f.y, 0.0),
        Vec4::new(r.z, u.z, -f.z, 0.0),
        Vec4::new(-r.dot(p), -u.dot(p), f.dot(p), 1.0),
    );
    let dist = (camera.target - p).length().max(1e-6);
    let (near, far) = (dist * 1e-3, dist * 1e3);
    let aspect = width.max(1) as f32 / height.max(1) as f32;
    let h = 1.0 / (0.5 * camera.vfov_deg.to_radians()).tan();
    let depth = far / (near - far);
    let proj = Mat4::from_cols(
        Vec4::new(h / aspect, 0.0, 0.0, 0.0),
        Vec4::new(0.0, h, 0.0, 0.0),
        Vec4::new(0.0, 0.0, depth, -1.0),
        Vec4::new(0.0, 0.0, depth * near, 0.0),
    );
    proj * view
}

/// A camera that frames the whole object from the front-left, above (for stores without one).
pub fn default_camera(mesh: &ObjectMesh) -> Camera {
    let (lo, hi) = mesh.bounds();
    let centre = (lo + hi) * 0.5;
    let radius = ((hi - lo).length() * 0.5).max(1e-6);
    let dir = Vec3::new(0.55, -0.75, 0.45).normalize();
    Camera {
        position: centre + dir * radius * 3.2,
        target: centre,
        up: Vec3::Z,
        vfov_deg: 40.0,
    }
}

impl Renderer {
    /// The store's camera, or [`default_camera`] when it has none.
    pub fn default_view(&self) -> Camera {
        match &self.store.meta().camera {
            Some(c) => Camera {
                position: Vec3::from_array(c.position),
                target: Vec3::from_array(c.target),
                up: Vec3::from_array(c.up),
                vfov_deg: c.vfov_deg,
            },
            None => default_camera(&self.mesh),
        }
    }

    /// Shades the last frame's G-buffer on the CPU with the reference implementation, reading
    /// cube maps from `cubes`, with the last frame's size and [`RenderOptions::background`].
    /// Returns the image and the feedback masks it produced.
    pub fn reference_image<C: crate::reference::CubeTexels>(
        &self,
        camera: &Camera,
        params: &ShadingParams,
        cubes: &C,
    ) -> Result<(Vec<[f32; 4]>, Vec<u32>)> {
        use rayon::prelude::*;
        use std::sync::atomic::{AtomicU32, Ordering};
        let targets = self
            .targets
            .as_ref()
            .ok_or_else(|| RuntimeError::Parameter("render a frame first".into()))?;
        let (w, h) = (targets.width, targets.height);
        let gbuffer = self.read_gbuffer()?;
        let samples: Vec<Vec3> = self
            .store
            .sample_points()
            .iter()
            .map(|s| Vec3::from_array(s.position) - self.mesh.origin)
            .collect();
        let maps = (0..self.store.meta().map_count() as u32)
            .map(|p| self.store.sample_map(p))
            .collect::<Result<Vec<_>, _>>()
            .map_err(|source| RuntimeError::Store {
                path: "sample maps".into(),
                source,
            })?;
        let feedback: Vec<AtomicU32> = (0..self.cube_count).map(|_| AtomicU32::new(0)).collect();
        let shader = crate::reference::Shader {
            uniform: self.uniform(camera, params, w, h, self.background),
            samples: &samples,
            patches: &self.mesh.patches,
            colors: &self.mesh.colors,
            maps: &maps,
            cubes,
            feedback: &feedback,
        };
        let pixels = gbuffer
            .par_iter()
            .enumerate()
            .map(|(i, g)| shader.shade(i as u32 % w, i as u32 / w, g))
            .collect();
        let masks = feedback.iter().map(|a| a.load(Ordering::Relaxed)).collect();
        Ok((pixels, masks))
    }
}
