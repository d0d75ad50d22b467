//! The GPU capture: the scene uploaded once, cubes captured in batches by shader/capture.wgsl
//! ([`GpuCapture::capture_cubes`]), and the closest-hit queries the tests compare with the
//! CPU BVH ([`GpuCapture::trace`]).

use bytemuck::{Pod, Zeroable};
use glam::Vec3;
use oslf_bake::device::{CaptureDevice, CapturedCube, CubeJob};
use oslf_format::CubeImage;
use oslf_gpu::Gpu;
use oslf_scene::scene::Scene;
use oslf_trace::capture::{pilot_samples, sampling_plan, CaptureSettings};
use oslf_trace::denoise::{denoise_cube, TexelVariance};
use oslf_trace::integrator::RayStats;
use oslf_trace::noise::{variance_of_mean, NoiseStats};
use rayon::prelude::*;
use wgpu::util::DeviceExt;

use crate::error::{GpuBakeError, Result};
use crate::features::SceneFeatures;
pub use crate::layouts::{Job, Params, TexelOut, TraceHit, TraceRay};
use crate::scene::GpuScene;
use crate::shader;

/// Invocations per workgroup on a hardware GPU (the default of the override `WORKGROUP` in
/// shader/capture.wgsl): two warps of 32, one wavefront of 64.
pub const WORKGROUP: u32 = 64;
/// Invocations per workgroup on a CPU adapter (lavapipe runs a workgroup on one thread, 8
/// invocations per 256-bit vector): smaller groups traced 1.2–1.3× the rays per second of 64
/// (docs/measurements.md, "The compressed wide BVH on the GPU").
pub const CPU_WORKGROUP: u32 = 16;

/// The workgroup size the capture's pipelines are compiled with on `gpu`.
pub fn workgroup_size(gpu: &Gpu) -> u32 {
    if gpu.shares_system_memory {
        CPU_WORKGROUP
    } else {
        WORKGROUP
    }
}
/// Workgroups per dispatch row: a dispatch is `ROW_GROUPS × rows` workgroups.
const ROW_GROUPS: u32 = 4096;
/// Most paths (texels × samples) per dispatch unless that is fewer than
/// [`MIN_INVOCATIONS_PER_DISPATCH`] invocations: each dispatch stays short (well under a
/// second on a desktop GPU, whose driver may reset a device that runs one for seconds).
const PATHS_PER_DISPATCH: u64 = 1 << 22;
/// Fewest invocations per dispatch, whatever the samples per texel: a large GPU holds about
/// 2¹⁸ threads at once (132 multiprocessors × 2 048 threads), and a dispatch of fewer leaves
/// most of it idle while the slowest paths finish (at 256 samples per texel, 2²² paths are
/// only 2¹⁴ texels).
const MIN_INVOCATIONS_PER_DISPATCH: u64 = 1 << 18;
/// Texels a batch aims for, so that the GPU has enough work in flight.
const BATCH_TEXELS: u64 = 1 << 20;
/// Most bytes of one batch's per-texel results.
const BATCH_BYTES: u64 = 64 << 20;
/// Most cubes per batch.
const MAX_BATCH_CUBES: u64 = 256;

/// `FLAG_DISTANCE` of shader/capture.wgsl.
pub const FLAG_DISTANCE: u32 = 1;

/// A ray of [`GpuCapture::trace`]: origin, unit direction, `t_max`, whether the OSLF objects
/// take part, and whether any hit answers it (a shadow ray's query, which stops at the first
/// triangle hit) rather than the closest.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct QueryRay {
    pub origin: Vec3,
    pub dir: Vec3,
    pub t_max: f32,
    pub objects: bool,
    pub any_hit: bool,
}

/// What [`GpuCapture::trace`] found for a ray: `(t, global triangle index)` of its hit (the
/// closest, or for an any-hit query the first found), `None` where it escapes; and the BVH
/// nodes and triangles its traversal tested.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct QueryHit {
    pub hit: Option<(f32, u32)>,
    pub nodes: u32,
    pub triangles: u32,
}

/// The scene's buffers on the GPU.
pub(crate) struct SceneBuffers {
    pub(crate) nodes: wgpu::Buffer,
    pub(crate) tris: wgpu::Buffer,
    pub(crate) attrs: wgpu::Buffer,
    pub(crate) materials: wgpu::Buffer,
    pub(crate) texels: wgpu::Buffer,
    pub(crate) lights: wgpu::Buffer,
    pub(crate) env_tables: wgpu::Buffer,
}

impl SceneBuffers {
    /// Their bytes on the device.
    fn bytes(&self) -> u64 {
        [
            &self.nodes,
            &self.tris,
            &self.attrs,
            &self.materials,
            &self.texels,
            &self.lights,
            &self.env_tables,
        ]
        .iter()
        .map(|b| b.size())
        .sum()
    }
}

/// The bake's cube-map capture on a GPU, for one scene.
pub struct GpuCapture {
    pub(crate) gpu: Gpu,
    pub(crate) buffers: SceneBuffers,
    capture: wgpu::ComputePipeline,
    trace: wgpu::ComputePipeline,
    pub(crate) preview: wgpu::ComputePipeline,
    /// `Params` without the per-capture fields.
    pub(crate) base: Params,
    triangles: usize,
    /// Capture rays per second measured on this scene ([`GpuCapture::calibrate`]).
    rate: Option<f64>,
    /// Invocations per workgroup of its pipelines ([`workgroup_size`]).
    workgroup: u32,
}

impl std::fmt::Debug for GpuCapture {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("GpuCapture")
            .field("adapter", &self.gpu.adapter_name)
            .field("triangles", &self.triangles)
            .finish()
    }
}

/// A storage buffer holding `data` (one zeroed `T` when `data` is empty: a binding cannot be
/// empty; the shader never reads it then).
pub(crate) fn storage<T: Pod>(gpu: &Gpu, label: &str, data: &[T]) -> wgpu::Buffer {
    let zero = [T::zeroed()];
    let contents: &[T] = if data.is_empty() { &zero } else { data };
    gpu.device
        .create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some(label),
            contents: bytemuck::cast_slice(contents),
            usage: wgpu::BufferUsages::STORAGE,
        })
}

impl GpuCapture {
    /// The capture of `scene` on `gpu`: the same triangles as the CPU bake's geometry (the
    /// objects tessellated within ε × `TESSELLATION_ERROR`), its materials, lights,
    /// environment and bounces.
    pub fn for_scene(gpu: Gpu, scene: &Scene) -> Result<Self> {
        let max_error = scene.bake.epsilon * oslf_scene::tolerance::TESSELLATION_ERROR;
        let geometry = oslf_trace::bvh::TriangleScene::build(oslf_trace::bvh::scene_instances(
            scene, true, max_error,
        ))?;
        let packed = GpuScene::new(
            &geometry.triangles(),
            &scene.materials,
            &scene.lights,
            &scene.environment,
        )?;
        let mut capture = Self::new(gpu, &packed, scene.bake.bounces)?;
        let settings = CaptureSettings::from_bake(&scene.bake);
        capture.rate = Some(capture.calibrate(oslf_bake::bake::object_centre(scene), &settings)?);
        Ok(capture)
    }

    /// Capture rays per second of this device on this scene: a batch of cubes of 16² texels
    /// (at most the bake's resolution) at `origin`, with the bake's samples per texel and
    /// bounces, timed after a warm-up capture (drivers compile at the first dispatch). A
    /// hardware GPU gets 64 cubes (enough to fill it, else the rate would be
    /// that of an idle GPU), a CPU adapter one.
    pub fn calibrate(&self, origin: Vec3, settings: &CaptureSettings) -> Result<f64> {
        let settings = CaptureSettings {
            resolution: settings.resolution.min(16),
            samples_per_texel: settings.samples_per_texel.min(16),
            target_noise: 0.0,
            denoise: false,
            distance_channel: false,
            ..*settings
        };
        // A first tiny capture: drivers compile the pipeline at its first dispatch.
        let warm_up = CaptureSettings {
            resolution: 1,
            samples_per_texel: 1,
            target_noise: 0.0,
            denoise: false,
            ..settings
        };
        let first = CubeJob {
            origin,
            index: 0,
            sees_objects: true,
        };
        self.capture_cubes(&[first], &warm_up)?;
        let cubes = if self.gpu.shares_system_memory { 1 } else { 64 };
        let jobs: Vec<CubeJob> = (0..cubes)
            .map(|index| CubeJob {
                origin,
                index,
                sees_objects: true,
            })
            .collect();
        let start = std::time::Instant::now();
        let captured = self.capture_cubes(&jobs, &settings)?;
        let seconds = start.elapsed().as_secs_f64().max(1e-6);
        let rays: u64 = captured.iter().map(|c| c.1.total()).sum();
        Ok(rays as f64 / seconds)
    }

    /// The capture of a packed scene, gathering `max_bounces` bounces.
    pub fn new(gpu: Gpu, scene: &GpuScene, max_bounces: u32) -> Result<Self> {
        let limits = gpu.limits();
        let largest = [
            std::mem::size_of_val(scene.tris.as_slice()),
            std::mem::size_of_val(scene.attrs.as_slice()),
            std::mem::size_of_val(scene.nodes.as_slice()),
            std::mem::size_of_val(scene.texels.as_slice()),
        ]
        .into_iter()
        .max()
        .unwrap_or(0) as u64;
        if largest > limits.max_storage_buffer_binding_size {
            return Err(GpuBakeError::Scene(format!(
                "the scene needs a {largest}-byte buffer; {} binds at most {} bytes (bake on the CPU: --device cpu)",
                gpu.adapter_name, limits.max_storage_buffer_binding_size
            )));
        }
        if limits.max_storage_buffers_per_shader_stage < 10 {
            return Err(GpuBakeError::Scene(format!(
                "{} allows {} storage buffers per shader stage; the GPU capture needs 10 (bake on the CPU: --device cpu)",
                gpu.adapter_name, limits.max_storage_buffers_per_shader_stage
            )));
        }
        let buffers = SceneBuffers {
            nodes: storage(&gpu, "bvh nodes", &scene.nodes),
            tris: storage(&gpu, "triangles", &scene.tris),
            attrs: storage(&gpu, "triangle attributes", &scene.attrs),
            materials: storage(&gpu, "materials", &scene.materials),
            texels: storage(&gpu, "texels", &scene.texels),
            lights: storage(&gpu, "lights", &scene.lights),
            env_tables: storage(&gpu, "environment tables", &scene.env_tables),
        };
        let module = gpu
            .device
            .create_shader_module(wgpu::ShaderModuleDescriptor {
                label: Some("capture"),
                source: wgpu::ShaderSource::Wgsl(shader::source().into()),
            });
        let workgroup = workgroup_size(&gpu);
        let mut constants = vec![("WORKGROUP", f64::from(workgroup))];
        constants.extend(SceneFeatures::of(scene)?.constants());
        let pipeline = |entry: &str| {
            gpu.device
                .create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                    label: Some(entry),
                    layout: None,
                    module: &module,
                    entry_point: Some(entry),
                    compilation_options: wgpu::PipelineCompilationOptions {
                        constants: &constants,
                        ..Default::default()
                    },
                    cache: None,
                })
        };
        let capture = pipeline("capture");
        let trace = pipeline("trace");
        let preview = pipeline("preview");
        let e = &scene.environment;
        let base = Params {
            max_bounces,
            env_size: e.size,
            env_tables: e.tables,
            env_rotation: e.rotation,
            env_constant: e.constant,
            perez_y: e.perez[0],
            perez_x: e.perez[1],
            perez_yc: e.perez[2],
            perez_e: e.perez[3],
            norm: e.norm,
            model_sun: e.model_sun,
            ground: e.ground,
            ..Params::zeroed()
        };
        let capture_gpu = GpuCapture {
            gpu,
            buffers,
            capture,
            trace,
            preview,
            base,
            triangles: scene.tris.len(),
            rate: None,
            workgroup,
        };
        capture_gpu.check("building the capture pipelines")?;
        Ok(capture_gpu)
    }

    /// The adapter this runs on.
    pub fn gpu(&self) -> &Gpu {
        &self.gpu
    }

    pub(crate) fn check(&self, what: &str) -> Result<()> {
        self.gpu.take_errors().map_err(|e| GpuBakeError::Gpu {
            adapter: self.gpu.adapter_name.clone(),
            message: format!("{what}: {e}"),
        })
    }

    pub(crate) fn read(&self, buffer: &wgpu::Buffer) -> Result<Vec<u8>> {
        self.gpu.read_buffer(buffer).map_err(|e| GpuBakeError::Gpu {
            adapter: self.gpu.adapter_name.clone(),
            message: e.to_string(),
        })
    }

    /// The device memory a capture of `settings` holds, bytes: the scene's buffers, uploaded
    /// once, and one batch's jobs, texels and read-back copy of them.
    pub fn memory_bytes(&self, settings: &CaptureSettings) -> u64 {
        let cubes = self.cubes_per_batch(settings) as u64;
        let texels = cubes * 6 * u64::from(settings.resolution).pow(2);
        let batch = 2 * texels * std::mem::size_of::<TexelOut>() as u64
            + cubes * std::mem::size_of::<Job>() as u64;
        self.buffers.bytes() + batch
    }

    /// Cubes per batch for `settings` (see [`CaptureDevice::batch_cubes`]).
    pub fn cubes_per_batch(&self, settings: &CaptureSettings) -> usize {
        let texels = 6 * u64::from(settings.resolution.max(1)).pow(2);
        let bytes = texels * std::mem::size_of::<TexelOut>() as u64;
        let limit = self
            .gpu
            .limits()
            .max_storage_buffer_binding_size
            .min(BATCH_BYTES);
        let by_memory = (limit / bytes).max(1);
        BATCH_TEXELS
            .div_ceil(texels)
            .min(by_memory)
            .clamp(1, MAX_BATCH_CUBES) as usize
    }

    /// Captures the cubes of `jobs` (each as `oslf_trace::capture::capture_cube_with_noise`
    /// does; no noise for the environment-map baseline's cube), in order.
    pub fn capture_cubes(
        &self,
        jobs: &[CubeJob],
        settings: &CaptureSettings,
    ) -> Result<Vec<CapturedCube>> {
        if jobs.is_empty() {
            return Ok(Vec::new());
        }
        let res = settings.resolution;
        let (k, rounds) = sampling_plan(settings.samples_per_texel, settings.target_noise);
        let per_cube = 6 * u64::from(res) * u64::from(res);
        let total = per_cube * jobs.len() as u64;
        let out_bytes = total * std::mem::size_of::<TexelOut>() as u64;
        if total > u64::from(u32::MAX)
            || out_bytes > self.gpu.limits().max_storage_buffer_binding_size
        {
            return Err(GpuBakeError::Scene(format!(
                "{} cubes of {res}² texels do not fit one GPU batch ({out_bytes} bytes)",
                jobs.len()
            )));
        }
        let gpu_jobs: Vec<Job> = jobs
            .iter()
            .map(|j| Job {
                origin: j.origin.to_array(),
                index: j.index,
                sees_objects: u32::from(j.sees_objects),
                _pad: [0; 3],
            })
            .collect();
        let jobs_buffer = storage(&self.gpu, "jobs", &gpu_jobs);
        let (out, staging) = self.output_buffers("texels", out_bytes);
        let uniform = self.params_buffer("capture params");
        let mut entries = self.scene_entries(&uniform);
        entries.extend([(8, &jobs_buffer), (9, &out)]);
        let bind_group = self.bind_group(&self.capture, &entries);
        let seed = settings.seed;
        let mut params = Params {
            resolution: res,
            strata: k,
            rounds,
            target_noise: settings.target_noise,
            seed: [seed as u32, (seed >> 32) as u32],
            texels: total as u32,
            row_invocations: ROW_GROUPS * self.workgroup,
            ..self.base
        };
        if settings.distance_channel {
            params.flags |= FLAG_DISTANCE;
        }
        self.dispatch(
            &self.capture,
            &bind_group,
            &uniform,
            params,
            total,
            u64::from(k * k * rounds),
        );
        let mut encoder = self.gpu.device.create_command_encoder(&Default::default());
        encoder.copy_buffer_to_buffer(&out, 0, &staging, 0, out_bytes);
        self.gpu.queue.submit([encoder.finish()]);
        let bytes = self.read(&staging)?;
        self.check("capturing cubes")?;
        let texels: &[TexelOut] = bytemuck::cast_slice(&bytes);
        let pilot = pilot_samples(settings);
        Ok(jobs
            .par_iter()
            .zip(texels.par_chunks_exact(per_cube as usize))
            .map(|(job, cube)| unpack_cube(cube, settings, pilot, job.sees_objects))
            .collect())
    }

    /// The uniform buffer a pass writes its [`Params`] to (per dispatch, [`Self::dispatch`]).
    pub(crate) fn params_buffer(&self, label: &str) -> wgpu::Buffer {
        self.gpu.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some(label),
            size: std::mem::size_of::<Params>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        })
    }

    /// Bindings 0 to 7, which the capture and the preview share: `uniform` and the scene.
    pub(crate) fn scene_entries<'a>(
        &'a self,
        uniform: &'a wgpu::Buffer,
    ) -> Vec<(u32, &'a wgpu::Buffer)> {
        let b = &self.buffers;
        vec![
            (0, uniform),
            (1, &b.nodes),
            (2, &b.tris),
            (3, &b.attrs),
            (4, &b.materials),
            (5, &b.texels),
            (6, &b.lights),
            (7, &b.env_tables),
        ]
    }

    /// A storage buffer of `bytes` the shader writes, and the buffer it is copied to for
    /// reading back.
    pub(crate) fn output_buffers(&self, label: &str, bytes: u64) -> (wgpu::Buffer, wgpu::Buffer) {
        let buffer = |usage, suffix: &str| {
            self.gpu.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(&format!("{label} {suffix}")),
                size: bytes,
                usage,
                mapped_at_creation: false,
            })
        };
        (
            buffer(
                wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
                "out",
            ),
            buffer(
                wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
                "readback",
            ),
        )
    }

    /// Runs `pipeline` over `items` invocations (texels, pixels) of `samples` paths each, in
    /// dispatches of at most [`PATHS_PER_DISPATCH`] paths, each told its first item through
    /// `params.first` in `uniform`.
    pub(crate) fn dispatch(
        &self,
        pipeline: &wgpu::ComputePipeline,
        bind_group: &wgpu::BindGroup,
        uniform: &wgpu::Buffer,
        mut params: Params,
        items: u64,
        samples: u64,
    ) {
        params.row_invocations = ROW_GROUPS * self.workgroup;
        let per_dispatch = (PATHS_PER_DISPATCH / samples.max(1))
            .max(MIN_INVOCATIONS_PER_DISPATCH)
            .next_multiple_of(u64::from(self.workgroup));
        let mut first = 0u64;
        while first < items {
            let count = per_dispatch.min(items - first);
            params.first = first as u32;
            self.gpu
                .queue
                .write_buffer(uniform, 0, bytemuck::bytes_of(&params));
            let groups = count.div_ceil(u64::from(self.workgroup)) as u32;
            let mut encoder = self.gpu.device.create_command_encoder(&Default::default());
            {
                let mut pass = encoder.begin_compute_pass(&Default::default());
                pass.set_pipeline(pipeline);
                pass.set_bind_group(0, bind_group, &[]);
                pass.dispatch_workgroups(groups.min(ROW_GROUPS), groups.div_ceil(ROW_GROUPS), 1);
            }
            self.gpu.queue.submit([encoder.finish()]);
            first += count;
        }
    }

    pub(crate) fn bind_group(
        &self,
        pipeline: &wgpu::ComputePipeline,
        entries: &[(u32, &wgpu::Buffer)],
    ) -> wgpu::BindGroup {
        let entries: Vec<wgpu::BindGroupEntry> = entries
            .iter()
            .map(|(binding, buffer)| wgpu::BindGroupEntry {
                binding: *binding,
                resource: buffer.as_entire_binding(),
            })
            .collect();
        self.gpu
            .device
            .create_bind_group(&wgpu::BindGroupDescriptor {
                label: None,
                layout: &pipeline.get_bind_group_layout(0),
                entries: &entries,
            })
    }

    /// Each ray's hit on the GPU, by the bake's own traversal.
    pub fn trace(&self, rays: &[QueryRay]) -> Result<Vec<QueryHit>> {
        if rays.is_empty() {
            return Ok(Vec::new());
        }
        let gpu_rays: Vec<TraceRay> = rays
            .iter()
            .map(|r| TraceRay {
                origin: r.origin.to_array(),
                t_max: r.t_max,
                dir: r.dir.to_array(),
                flags: u32::from(r.objects) | (u32::from(r.any_hit) << 1),
            })
            .collect();
        let rays_buffer = storage(&self.gpu, "trace rays", &gpu_rays);
        let bytes = (rays.len() * std::mem::size_of::<TraceHit>()) as u64;
        let (hits, staging) = self.output_buffers("trace hits", bytes);
        let b = &self.buffers;
        let bind_group = self.bind_group(
            &self.trace,
            &[
                (1, &b.nodes),
                (2, &b.tris),
                (3, &b.attrs),
                (10, &rays_buffer),
                (11, &hits),
            ],
        );
        let mut encoder = self.gpu.device.create_command_encoder(&Default::default());
        {
            let mut pass = encoder.begin_compute_pass(&Default::default());
            pass.set_pipeline(&self.trace);
            pass.set_bind_group(0, &bind_group, &[]);
            pass.dispatch_workgroups((rays.len() as u32).div_ceil(self.workgroup), 1, 1);
        }
        encoder.copy_buffer_to_buffer(&hits, 0, &staging, 0, bytes);
        self.gpu.queue.submit([encoder.finish()]);
        let out = self.read(&staging)?;
        self.check("tracing rays")?;
        Ok(bytemuck::cast_slice::<u8, TraceHit>(&out)
            .iter()
            .map(|h| QueryHit {
                hit: (h.triangle != u32::MAX).then_some((h.t, h.triangle)),
                nodes: h.nodes,
                triangles: h.tris,
            })
            .collect())
    }
}

/// One cube's texels read back: the image, its rays, and the noise of its texels (none for
/// the environment-map baseline's cube).
/// `pilot`: the samples of each texel's pilot, spent but not in its value or its `samples`.
/// Denoised, as the CPU's capture is, where `settings` asks.
fn unpack_cube(
    texels: &[TexelOut],
    settings: &CaptureSettings,
    pilot: u32,
    noise: bool,
) -> CapturedCube {
    let (res, distance) = (settings.resolution, settings.distance_channel);
    let per_face = (res * res) as usize;
    let mut stats = RayStats::default();
    let mut noise_stats = NoiseStats::default();
    let mut faces: [Vec<[f32; 3]>; 6] = Default::default();
    let mut planes: [Vec<f32>; 6] = Default::default();
    let mut variance: TexelVariance = Default::default();
    for (face, chunk) in texels.chunks_exact(per_face).enumerate() {
        faces[face] = chunk.iter().map(|t| t.radiance).collect();
        if settings.denoise {
            variance[face] = chunk
                .iter()
                .map(|t| variance_of_mean(f64::from(t.lum_sum), f64::from(t.lum_sq), t.samples))
                .collect();
        }
        if distance {
            planes[face] = chunk.iter().map(|t| t.distance).collect();
        }
        for t in chunk {
            stats.closest += u64::from(t.closest);
            stats.shadow += u64::from(t.shadow_hit >> 1);
            stats.nodes += u64::from(t.nodes);
            stats.triangles += u64::from(t.tris);
            if noise {
                noise_stats.add_texel(
                    f64::from(t.lum_sum),
                    f64::from(t.lum_sq),
                    t.samples,
                    t.shadow_hit & 1 == 1,
                );
                noise_stats.count_samples(t.samples + pilot);
            }
        }
    }
    let mut cube = CubeImage {
        resolution: res,
        faces,
        distance: distance.then_some(planes),
    };
    if settings.denoise {
        denoise_cube(&mut cube, &variance);
    }
    (cube, stats, noise_stats)
}

impl CaptureDevice for GpuCapture {
    fn describe(&self) -> String {
        format!("GPU {}", self.gpu.adapter_name)
    }

    fn rays_per_second(&self) -> Option<f64> {
        self.rate
    }

    fn batch_cubes(&self, settings: &CaptureSettings) -> usize {
        self.cubes_per_batch(settings)
    }

    fn memory_bytes(&self, settings: &CaptureSettings) -> Option<u64> {
        Some(self.memory_bytes(settings))
    }

    fn capture(
        &self,
        jobs: &[CubeJob],
        settings: &CaptureSettings,
    ) -> oslf_scene::Result<Vec<CapturedCube>> {
        self.capture_cubes(jobs, settings)
            .map_err(|e| oslf_scene::BakeError::Device {
                device: self.describe(),
                message: e.to_string(),
            })
    }
}
