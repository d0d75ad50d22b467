//! Drawing into a host application's frame (an engine, a viewer): the host's view and
//! projection matrices, its colour and depth targets and its command encoder. The object is
//! depth-tested against what the host drew and writes its own depth, so the host's meshes in
//! front hide it and it hides what lies behind it. The cache's feedback is read back
//! asynchronously: a frame never waits for the GPU, misses fall back (as in `oslf view`) and
//! are resident a few frames later.
//!
//! Per frame: [`Renderer::encode_into`] records the G-buffer, shading and composite passes into
//! the host's encoder; the host submits it; [`Renderer::after_submit`] then maps that frame's
//! feedback and books the feedback of earlier frames whose maps have arrived (loads, uploads).

use std::sync::{Arc, Mutex};

use glam::{Mat4, Vec3, Vec4};
use oslf_geometry::Camera;
use wgpu::util::DeviceExt;

use super::timer::{PassTimer, TimedPass};
use super::Renderer;
use crate::buffers::TIMESTAMP_BYTES;
use crate::cache::CacheStats;
use crate::error::{Result, RuntimeError};
use crate::params::Background;
use crate::pipelines::ShadeKey;
use crate::shading::ShadingParams;
use crate::uniform::ShadeUniform;

/// A host's view of the world: the matrices it draws its own meshes with.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HostView {
    /// World to view space: right-handed, the camera looking down −z (glam's
    /// `camera::rh::view::look_at_mat4`, Bevy's inverse camera transform).
    pub view: Mat4,
    /// View to clip space with depth in 0..1, as wgpu wants: a perspective projection, with
    /// depth increasing away from the camera or reversed (glam's
    /// `camera::rh::proj::directx::perspective_infinite_reverse`, Bevy's default), as
    /// [`HostTarget::depth_compare`] says.
    pub projection: Mat4,
    /// The scale of the radiance written: an engine's camera exposure (Bevy multiplies its
    /// meshes' lighting by the view's exposure, `ExtractedCamera::exposure`), 1 for none.
    pub exposure: f32,
    /// This frame's sub-pixel offset of the host's projection, in normalised device
    /// coordinates (clip x, y += jitter · w): the jitter of temporal anti-aliasing (Bevy's
    /// `TemporalJitter`), [0, 0] for none. The object is rasterised with it, as the host's
    /// meshes are; `projection` stays unjittered, and so do the shading and the motion
    /// vectors. Finite and within ±1.
    pub jitter: [f32; 2],
}

impl HostView {
    /// The camera of this view in world space (position, a target one unit ahead, up and the
    /// vertical field of view), as [`Renderer::render`] and the CPU reference take it.
    ///
    /// Errors when a matrix is not finite or not invertible, the projection is not a
    /// perspective one (the shading needs the eye point), or the exposure is negative or not
    /// finite.
    pub fn camera(&self) -> Result<Camera> {
        if !(self.exposure.is_finite() && self.exposure >= 0.0) {
            return Err(RuntimeError::Parameter(format!(
                "HostView::exposure {}: must be finite and ≥ 0",
                self.exposure
            )));
        }
        if !self.jitter.iter().all(|j| j.abs() <= 1.0) {
            return Err(RuntimeError::Parameter(format!(
                "HostView::jitter {:?}: must be finite and within ±1 (normalised device \
                 coordinates; a sub-pixel offset is 2 / width at most)",
                self.jitter
            )));
        }
        let finite = |m: &Mat4| m.to_cols_array().iter().all(|v| v.is_finite());
        if !finite(&self.view) || !finite(&self.projection) {
            return Err(RuntimeError::Parameter(
                "HostView: the view and projection matrices must be finite".into(),
            ));
        }
        let det = self.view.determinant();
        if det.abs() <= 1e-12 {
            return Err(RuntimeError::Parameter(format!(
                "HostView: the view matrix is not invertible (determinant {det})"
            )));
        }
        // A perspective projection makes clip w = −z_view: its last row is (0, 0, −1, 0).
        let last_row = self.projection.row(3);
        if (last_row - Vec4::new(0.0, 0.0, -1.0, 0.0))
            .abs()
            .max_element()
            > 1e-6
        {
            return Err(RuntimeError::Parameter(format!(
                "HostView: the projection's last row is {last_row:?}, not (0, 0, -1, 0): only \
                 right-handed perspective projections are supported (the shading needs the eye \
                 point; orthographic views have none)"
            )));
        }
        let inv = self.view.inverse();
        let position = inv.w_axis.truncate();
        let forward = (-inv.z_axis.truncate()).normalize_or(Vec3::NEG_Z);
        let up = inv.y_axis.truncate().normalize_or(Vec3::Y);
        let fy = self.projection.y_axis.y;
        if !(fy.is_finite() && fy > 0.0) {
            return Err(RuntimeError::Parameter(format!(
                "HostView: the projection's y scale {fy} must be positive"
            )));
        }
        Ok(Camera {
            position,
            target: position + forward,
            up,
            vfov_deg: (2.0 * (1.0 / fy).atan()).to_degrees(),
        })
    }
}

/// Where a host wants the object drawn: its colour and depth targets, as its own meshes were
/// drawn into them.
#[derive(Clone, Copy, Debug)]
pub struct HostTarget<'a> {
    /// The colour target; the object's linear radiance is written where it is visible
    /// (tonemapping is the host's, as for its other meshes).
    pub color: &'a wgpu::TextureView,
    /// Its format (any renderable colour format; an `…Srgb` one encodes on write).
    pub color_format: wgpu::TextureFormat,
    /// The depth target holding the host's meshes' depth; the object's depth is written into
    /// it where the object is visible.
    pub depth: &'a wgpu::TextureView,
    /// Its format (a depth format: `Depth32Float`, `Depth24Plus`, …).
    pub depth_format: wgpu::TextureFormat,
    /// The host's depth test: `Less` or `LessEqual` for depth growing away from the camera,
    /// `Greater` or `GreaterEqual` for reversed depth (Bevy).
    pub depth_compare: wgpu::CompareFunction,
    /// Samples per pixel of both targets: 1, or 2, 4, 8 for multisampled targets (MSAA). The
    /// object is shaded once per pixel and written to every sample its pixel covers, each
    /// depth-tested against the host's samples; resolving the colour target stays the host's.
    pub sample_count: u32,
    /// Size of both targets in pixels.
    pub width: u32,
    pub height: u32,
    /// How much nearer than its own the object's depth is written and tested, in the depth
    /// buffer's units (0 to [`MAX_DEPTH_SLACK`]): 0, unless the host's depth already holds
    /// the object's surface (a proxy of it drawn for the host's shadows and depth prepass,
    /// whose depth the host computed with its own rounding), where the object must still win
    /// over its proxy. [`DEPTH_SLACK`] suits a 32-bit float depth.
    pub depth_slack: f32,
}

/// The largest [`HostTarget::depth_slack`].
pub const MAX_DEPTH_SLACK: f32 = 1e-3;

/// A [`HostTarget::depth_slack`] for a host whose depth holds a proxy of the object: 2⁻²⁰, a
/// few ulps of a 32-bit float depth near 1 (where the G-buffer's depth lies before it is
/// turned back for a reversed host).
pub const DEPTH_SLACK: f32 = 1.0 / (1u32 << 20) as f32;

/// Checks a host's depth target as `host` (the struct named in errors) describes it: its
/// samples per pixel, its format and its depth test; returns whether its depth is reversed
/// (1 near, 0 far), from the test.
pub(super) fn check_host_depth(
    host: &str,
    sample_count: u32,
    depth_format: wgpu::TextureFormat,
    depth_compare: wgpu::CompareFunction,
) -> Result<bool> {
    use wgpu::CompareFunction as C;
    if !matches!(sample_count, 1 | 2 | 4 | 8) {
        return Err(RuntimeError::Parameter(format!(
            "{host}::sample_count {sample_count}: must be 1, 2, 4 or 8 (the samples per pixel \
             of the host's targets)"
        )));
    }
    if !depth_format.has_depth_aspect() {
        return Err(RuntimeError::Parameter(format!(
            "{host}::depth_format {depth_format:?} has no depth aspect"
        )));
    }
    match depth_compare {
        C::Less | C::LessEqual => Ok(false),
        C::Greater | C::GreaterEqual => Ok(true),
        other => Err(RuntimeError::Parameter(format!(
            "{host}::depth_compare {other:?}: must be Less, LessEqual, Greater or \
             GreaterEqual (the test the host draws its meshes with)"
        ))),
    }
}

/// `compare` passing equal depths too (`Less` ↦ `LessEqual`, `Greater` ↦ `GreaterEqual`).
fn inclusive(compare: wgpu::CompareFunction) -> wgpu::CompareFunction {
    use wgpu::CompareFunction as C;
    match compare {
        C::Less => C::LessEqual,
        C::Greater => C::GreaterEqual,
        other => other,
    }
}

/// Errors unless `format` (of `host`'s `field`) is a colour format.
pub(super) fn check_color_format(
    host: &str,
    field: &str,
    format: wgpu::TextureFormat,
) -> Result<()> {
    if format.has_depth_aspect() || format.has_stencil_aspect() {
        return Err(RuntimeError::Parameter(format!(
            "{host}::{field} {format:?} is not a colour format"
        )));
    }
    Ok(())
}

impl HostTarget<'_> {
    /// Checks the target; returns whether its depth is reversed ([`check_host_depth`]).
    fn validate(&self) -> Result<bool> {
        let reversed = check_host_depth(
            "HostTarget",
            self.sample_count,
            self.depth_format,
            self.depth_compare,
        )?;
        if !(0.0..=MAX_DEPTH_SLACK).contains(&self.depth_slack) {
            return Err(RuntimeError::Parameter(format!(
                "HostTarget::depth_slack {}: must be within 0..={MAX_DEPTH_SLACK}",
                self.depth_slack
            )));
        }
        check_color_format("HostTarget", "color_format", self.color_format)?;
        Ok(reversed)
    }
}

/// The composite pipelines, one per host target kind, their bind-group layout and the
/// uniform they read (composite.wgsl's `exposure`).
pub(super) struct Composites {
    pipelines: std::collections::HashMap<CompositeKey, wgpu::RenderPipeline>,
    layout: wgpu::BindGroupLayout,
    /// The exposure and depth slack, copied from each view's staging buffer in the encoder.
    uniform: wgpu::Buffer,
}

/// Bytes of the composite's uniform: exposure, depth slack, two unused.
const COMPOSITE_UNIFORM_BYTES: u64 = 16;

impl Composites {
    pub(super) fn new(device: &wgpu::Device) -> Self {
        Self {
            pipelines: Default::default(),
            layout: composite_layout(device),
            uniform: device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("composite exposure"),
                size: COMPOSITE_UNIFORM_BYTES,
                usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            }),
        }
    }
}

/// What a composite pipeline depends on: the host targets' sample count and formats, its
/// depth test, and whether its depth is reversed.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
struct CompositeKey {
    samples: u32,
    color: wgpu::TextureFormat,
    depth: wgpu::TextureFormat,
    compare: wgpu::CompareFunction,
    reversed: bool,
}

/// Where a frame's feedback is copied and mapped; a slot is reused once read.
pub(super) struct FeedbackSlot {
    /// The feedback masks, then the frame's pass timestamps where it was timed.
    buffer: wgpu::Buffer,
    state: SlotState,
    /// The slot's own timestamp queries (where the device has them), so that several views
    /// recorded into one encoder never share one; every frame copied into it is timed.
    pub(super) timer: Option<PassTimer>,
    /// Whether the frame copied into it had a prepass (whose pass it then timed too).
    prepassed: bool,
}

/// The GPU time of a host frame's passes ([`Renderer::host_pass_seconds`]), seconds; `None`
/// for a pass whose timestamps the device did not give.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct HostPassSeconds {
    /// The object's G-buffer pass.
    pub gbuffer: Option<f64>,
    /// Its shading pass.
    pub shade: Option<f64>,
    /// The composite pass into the host's targets.
    pub composite: Option<f64>,
    /// The prepass into the host's depth prepass ([`Renderer::encode_prepass_into`]); `None`
    /// also for a frame without one.
    pub prepass: Option<f64>,
}

enum SlotState {
    Free,
    /// Copied into by the frame of this sequence number, not yet submitted.
    Encoded(u64),
    /// Being mapped; the callback's result lands in the mutex.
    Mapping(u64, Arc<Mutex<Option<bool>>>),
}

/// Feedback buffers in flight at most: a frame whose every slot is busy skips its feedback
/// (the next one reports the same needs).
const FEEDBACK_SLOTS: usize = 3;

impl Renderer {
    /// Records this frame of the object into the host's `encoder`, seen through `view`, drawn
    /// into `target`: the G-buffer pass (at the target's size, the host's matrices), the
    /// shading pass, the feedback copy and the composite pass, which writes the shaded
    /// object's colour and depth into the host's targets where it passes the host's depth
    /// test. Nothing is submitted and nothing waits: submit the encoder, then call
    /// [`Renderer::after_submit`].
    ///
    /// Several calls may go into one encoder (several views): each records its own uniform.
    /// Errors for an invalid view or target ([`HostView::camera`], sample counts, formats) or
    /// parameters, before anything is recorded.
    ///
    /// After [`Renderer::encode_prepass_into`] for the same view, parameters and size, the
    /// frame shades the G-buffer that pass rasterised instead of rasterising the object again.
    pub fn encode_into(
        &mut self,
        encoder: &mut wgpu::CommandEncoder,
        view: &HostView,
        target: &HostTarget<'_>,
        params: &ShadingParams,
    ) -> Result<()> {
        let reversed = target.validate()?;
        let camera = view.camera()?;
        self.check_frame(params, Background::None)?;
        let gpu = self.gpu.clone();
        // What can fail on the device (targets, pipelines) first: a failure records nothing.
        let (u, composite) =
            gpu.scoped(|| self.prepare_host_frame(view, &camera, target, params, reversed))?;
        gpu.scoped(|| self.record_host_frame(encoder, target, &u, &composite, view.exposure))
    }

    /// The uniform of a host view of `size` pixels, with the targets of that size and the
    /// shading pipeline it needs made ready.
    pub(super) fn prepare_host_view(
        &mut self,
        view: &HostView,
        camera: &Camera,
        params: &ShadingParams,
        size: [u32; 2],
        reversed: bool,
    ) -> Result<ShadeUniform> {
        if params.split_sum() {
            self.ensure_prefiltered()?;
        }
        self.ensure_targets(size[0], size[1])?;
        let u = self.host_uniform(view, camera, params, size, reversed);
        self.current = ShadeKey::of(&u);
        self.background = Background::None;
        self.shade.prepare(&self.gpu.device, self.current);
        Ok(u)
    }

    /// The host frame's uniform and composite pipeline, with the targets and the shading
    /// pipeline it needs made ready.
    fn prepare_host_frame(
        &mut self,
        view: &HostView,
        camera: &Camera,
        target: &HostTarget<'_>,
        params: &ShadingParams,
        reversed: bool,
    ) -> Result<(ShadeUniform, wgpu::RenderPipeline)> {
        let size = [target.width, target.height];
        let u = self.prepare_host_view(view, camera, params, size, reversed)?;
        self.ensure_composite_group()?;
        // After this view's prepass the host's depth holds the object's own depth, which the
        // composite writes again bit for bit: its test then passes equal depths too.
        let compare = if self.prepassed.as_ref().is_some_and(|p| p.shades(&u)) {
            inclusive(target.depth_compare)
        } else {
            target.depth_compare
        };
        let key = CompositeKey {
            samples: target.sample_count,
            color: target.color_format,
            depth: target.depth_format,
            compare,
            reversed,
        };
        if let Some(pipeline) = self.composites.pipelines.get(&key) {
            return Ok((u, pipeline.clone()));
        }
        let (device, layout) = (&self.gpu.device, &self.composites.layout);
        // Kept only once the device took it (a colour format it cannot render to fails here).
        let pipeline = self
            .gpu
            .scoped(|| Ok::<_, RuntimeError>(composite_pipeline(device, layout, key)))?;
        self.composites.pipelines.insert(key, pipeline.clone());
        Ok((u, pipeline))
    }

    /// Records copying `u` and then `pass` (the uniform of the pass that follows) from a
    /// staging buffer of their own into the shading uniform and `to`. The uniforms travel in
    /// the encoder, so that each view recorded into it has its own.
    pub(super) fn record_host_uniforms(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        u: &ShadeUniform,
        pass: &[u8],
        to: &wgpu::Buffer,
    ) {
        let shade_bytes = std::mem::size_of::<ShadeUniform>() as u64;
        let mut contents = bytemuck::bytes_of(u).to_vec();
        contents.extend_from_slice(pass);
        let staging = self
            .gpu
            .device
            .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("host uniforms"),
                contents: &contents,
                usage: wgpu::BufferUsages::COPY_SRC,
            });
        encoder.copy_buffer_to_buffer(&staging, 0, &self.buffers.uniform, 0, Some(shade_bytes));
        encoder.copy_buffer_to_buffer(&staging, shade_bytes, to, 0, Some(pass.len() as u64));
    }

    /// Records the start of a host frame whose uniforms are recorded: clearing the feedback
    /// and the G-buffer pass, timed into the frame's feedback slot (if one is free), which it
    /// returns.
    pub(super) fn record_host_gbuffer(
        &mut self,
        encoder: &mut wgpu::CommandEncoder,
    ) -> Result<Option<usize>> {
        encoder.clear_buffer(&self.buffers.feedback, 0, None);
        let table_bytes = self.buffers.timestamps_offset;
        let slot = self.feedback_slot(table_bytes + TIMESTAMP_BYTES);
        let (targets, timer) = self.host_passes(slot)?;
        self.encode_gbuffer(encoder, targets, timer);
        Ok(slot)
    }

    /// The targets a host frame's passes draw into, and the timer of its feedback `slot` (if
    /// it has one and the device has timestamps).
    pub(super) fn host_passes(
        &self,
        slot: Option<usize>,
    ) -> Result<(&super::targets::SizedTargets, Option<&PassTimer>)> {
        let targets = self
            .targets
            .as_ref()
            .ok_or_else(|| RuntimeError::gpu("render targets missing"))?;
        let timer = slot.and_then(|i| self.feedback_slots[i].timer.as_ref());
        Ok((targets, timer))
    }

    /// Records the host frame's passes into `encoder`: its uniforms, the G-buffer (unless the
    /// view's prepass recorded it), the shading, the feedback copy (when a slot is free), the
    /// composite and its timestamps.
    fn record_host_frame(
        &mut self,
        encoder: &mut wgpu::CommandEncoder,
        target: &HostTarget<'_>,
        u: &ShadeUniform,
        composite: &wgpu::RenderPipeline,
        exposure: f32,
    ) -> Result<()> {
        let composite_uniform = [exposure, target.depth_slack, 0.0, 0.0];
        let pass = bytemuck::bytes_of(&composite_uniform);
        self.record_host_uniforms(encoder, u, pass, &self.composites.uniform);
        // The prepass of this very view (same uniform: matrices, size, parameters) left its
        // G-buffer; any other frame rasterises its own.
        let (slot, prepassed) = match self.prepassed.take() {
            Some(p) if p.shades(u) => (p.slot, true),
            _ => (self.record_host_gbuffer(encoder)?, false),
        };
        let table_bytes = self.buffers.timestamps_offset;
        let (targets, timer) = self.host_passes(slot)?;
        self.encode_shading(encoder, targets, timer)?;
        if let Some(i) = slot {
            encoder.copy_buffer_to_buffer(
                &self.buffers.feedback,
                0,
                &self.feedback_slots[i].buffer,
                0,
                Some(table_bytes),
            );
        }
        encode_composite(encoder, target, composite, targets, timer);
        self.host_frames += 1;
        if let Some(i) = slot {
            let s = &self.feedback_slots[i];
            if let Some(t) = &s.timer {
                let passes = [TimedPass::GBuffer, TimedPass::Shade, TimedPass::Composite];
                let prepass = prepassed.then_some(TimedPass::Prepass);
                for pass in passes.into_iter().chain(prepass) {
                    t.encode_copy(encoder, pass, &s.buffer, table_bytes);
                }
            }
            self.feedback_slots[i].state = SlotState::Encoded(self.host_frames);
            self.feedback_slots[i].prepassed = prepassed;
        }
        Ok(())
    }

    /// Makes the composite's bind group for the current targets, unless they have one.
    fn ensure_composite_group(&mut self) -> Result<()> {
        let targets = self
            .targets
            .as_mut()
            .ok_or_else(|| RuntimeError::gpu("render targets missing"))?;
        if targets.composite_group.is_some() {
            return Ok(());
        }
        let shaded = targets.output.create_view(&Default::default());
        let depth = targets.depth.create_view(&Default::default());
        let group = self
            .gpu
            .device
            .create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("composite"),
                layout: &self.composites.layout,
                entries: &[
                    wgpu::BindGroupEntry {
                        binding: 0,
                        resource: wgpu::BindingResource::TextureView(&shaded),
                    },
                    wgpu::BindGroupEntry {
                        binding: 1,
                        resource: wgpu::BindingResource::TextureView(&depth),
                    },
                    wgpu::BindGroupEntry {
                        binding: 2,
                        resource: self.composites.uniform.as_entire_binding(),
                    },
                ],
            });
        targets.composite_group = Some(group);
        Ok(())
    }

    /// Call once the encoder of [`Renderer::encode_into`] is submitted: maps the feedback it
    /// recorded, and books the feedback of earlier frames whose maps have arrived, oldest
    /// first: the cube maps they missed are loaded (decoded in the background) and uploaded.
    /// Never waits for the GPU. Returns the cache counters of the feedback booked now, if any
    /// arrived (`misses` > 0: some sample points fell back in that frame).
    pub fn after_submit(&mut self) -> Result<Option<CacheStats>> {
        let gpu = self.gpu.clone();
        gpu.scoped(|| self.book_feedback())
    }

    /// The GPU time of the G-buffer and shading passes of the latest host frame whose
    /// feedback [`Renderer::after_submit`] booked (a frame or more after it was drawn), where
    /// the device has timestamp queries; `None` before.
    pub fn host_pass_seconds(&self) -> Option<HostPassSeconds> {
        self.host_pass_seconds
    }

    /// [`Renderer::after_submit`]'s work, its device errors caught by the caller.
    fn book_feedback(&mut self) -> Result<Option<CacheStats>> {
        for slot in &mut self.feedback_slots {
            if let SlotState::Encoded(frame) = slot.state {
                let done = Arc::new(Mutex::new(None));
                let sink = Arc::clone(&done);
                slot.buffer.map_async(wgpu::MapMode::Read, .., move |r| {
                    if let Ok(mut d) = sink.lock() {
                        *d = Some(r.is_ok());
                    }
                });
                slot.state = SlotState::Mapping(frame, done);
            }
        }
        self.gpu
            .device
            .poll(wgpu::PollType::Poll)
            .map_err(|e| RuntimeError::gpu(format!("polling the device: {e}")))?;
        let mut booked: Option<CacheStats> = None;
        let table_bytes = self.buffers.timestamps_offset as usize;
        while let Some(slot) = self.oldest_mapped() {
            let masks = {
                let s = &self.feedback_slots[slot];
                let bytes = s
                    .buffer
                    .get_mapped_range(..)
                    .map_err(|e| RuntimeError::gpu(format!("reading the feedback: {e}")))?
                    .to_vec();
                s.buffer.unmap();
                if let Some(t) = &s.timer {
                    let stamps = bytes.get(table_bytes..).unwrap_or_default();
                    self.host_pass_seconds = Some(HostPassSeconds {
                        gbuffer: t.seconds(stamps, TimedPass::GBuffer),
                        shade: t.seconds(stamps, TimedPass::Shade),
                        composite: t.seconds(stamps, TimedPass::Composite),
                        prepass: s
                            .prepassed
                            .then(|| t.seconds(stamps, TimedPass::Prepass))
                            .flatten(),
                    });
                }
                let mut masks: Vec<u32> =
                    bytemuck::pod_collect_to_vec(&bytes[..table_bytes.min(bytes.len())]);
                masks.truncate(self.cube_count as usize);
                masks
            };
            self.feedback_slots[slot].state = SlotState::Free;
            let (uploads, mut stats) = self.cache.plan(&masks, &self.store, false);
            stats.upload_seconds = self.pool.upload(&self.gpu.queue, &uploads);
            stats.table_writes = self.write_slots();
            self.cache.cumulative.add(&stats);
            match &mut booked {
                None => booked = Some(stats),
                Some(b) => b.add_loading(&stats),
            }
        }
        Ok(booked)
    }

    /// The slot whose map arrived for the oldest frame, if any; a failed map frees its slot.
    fn oldest_mapped(&mut self) -> Option<usize> {
        let mut best: Option<(u64, usize)> = None;
        for (i, slot) in self.feedback_slots.iter_mut().enumerate() {
            if let SlotState::Mapping(frame, done) = &slot.state {
                let result = done.lock().ok().and_then(|d| *d);
                match result {
                    Some(true) if best.is_none_or(|(f, _)| *frame < f) => best = Some((*frame, i)),
                    Some(false) => slot.state = SlotState::Free,
                    _ => {}
                }
            }
        }
        best.map(|(_, i)| i)
    }

    /// A free feedback slot of `bytes`, created on first use; `None` when all are busy.
    fn feedback_slot(&mut self, bytes: u64) -> Option<usize> {
        if let Some(i) = self
            .feedback_slots
            .iter()
            .position(|s| matches!(s.state, SlotState::Free))
        {
            return Some(i);
        }
        if self.feedback_slots.len() >= FEEDBACK_SLOTS {
            return None;
        }
        let buffer = self.gpu.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("host feedback"),
            size: bytes,
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        self.feedback_slots.push(FeedbackSlot {
            buffer,
            state: SlotState::Free,
            timer: PassTimer::new(&self.gpu),
            prepassed: false,
        });
        Some(self.feedback_slots.len() - 1)
    }

    /// The uniform of a host frame: the host's matrices in the object-relative coordinates the
    /// G-buffer works in; reversed depth is turned around (z ↦ w − z), so that the G-buffer's
    /// own test and clear stay as they are, and the composite turns it back.
    fn host_uniform(
        &self,
        view: &HostView,
        camera: &Camera,
        params: &ShadingParams,
        size: [u32; 2],
        reversed: bool,
    ) -> ShadeUniform {
        let origin = self.mesh.origin;
        let flip = if reversed {
            Mat4::from_cols(
                Vec4::X,
                Vec4::Y,
                Vec4::new(0.0, 0.0, -1.0, 0.0),
                Vec4::new(0.0, 0.0, 1.0, 1.0),
            )
        } else {
            Mat4::IDENTITY
        };
        // TAA's jitter: clip x, y moved by jitter · w.
        let [jx, jy] = view.jitter;
        let jitter = Mat4::from_cols(Vec4::X, Vec4::Y, Vec4::Z, Vec4::new(jx, jy, 0.0, 1.0));
        let view_proj =
            flip * jitter * view.projection * view.view * Mat4::from_translation(origin);
        let relative = Camera {
            position: camera.position - origin,
            target: camera.target - origin,
            ..*camera
        };
        ShadeUniform::new(
            params,
            view_proj,
            &relative,
            size,
            &self.constants,
            Background::None,
        )
    }
}

/// Records the composite pass: the shaded object, scaled by the exposure, into the host's
/// colour target where its depth passes the host's depth test, its depth written; timed where
/// `timer`.
fn encode_composite(
    encoder: &mut wgpu::CommandEncoder,
    target: &HostTarget<'_>,
    pipeline: &wgpu::RenderPipeline,
    targets: &super::targets::SizedTargets,
    timer: Option<&PassTimer>,
) {
    fn keep<V>() -> wgpu::Operations<V> {
        wgpu::Operations {
            load: wgpu::LoadOp::Load,
            store: wgpu::StoreOp::Store,
        }
    }
    let timestamp_writes = timer.map(|t| {
        let (query_set, begin, end) = t.writes(TimedPass::Composite);
        wgpu::RenderPassTimestampWrites {
            query_set,
            beginning_of_pass_write_index: begin,
            end_of_pass_write_index: end,
        }
    });
    let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
        label: Some("composite"),
        color_attachments: &[Some(wgpu::RenderPassColorAttachment {
            view: target.color,
            depth_slice: None,
            resolve_target: None,
            ops: keep(),
        })],
        depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
            view: target.depth,
            depth_ops: Some(keep()),
            stencil_ops: target.depth_format.has_stencil_aspect().then(keep),
        }),
        timestamp_writes,
        occlusion_query_set: None,
        multiview_mask: None,
    });
    pass.set_pipeline(pipeline);
    pass.set_bind_group(0, targets.composite_group.as_ref(), &[]);
    pass.draw(0..3, 0..1);
}

/// composite.wgsl's bindings: the shaded image, the G-buffer's depth and the exposure.
fn composite_layout(device: &wgpu::Device) -> wgpu::BindGroupLayout {
    device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some("composite"),
        entries: &[
            fragment_texture(0, wgpu::TextureSampleType::Float { filterable: false }),
            fragment_texture(1, wgpu::TextureSampleType::Depth),
            fragment_uniform(2),
        ],
    })
}

/// A 2D texture composite.wgsl's fragment stage loads from, at `binding`.
pub(super) fn fragment_texture(
    binding: u32,
    sample_type: wgpu::TextureSampleType,
) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::FRAGMENT,
        ty: wgpu::BindingType::Texture {
            sample_type,
            view_dimension: wgpu::TextureViewDimension::D2,
            multisampled: false,
        },
        count: None,
    }
}

/// A uniform buffer composite.wgsl's fragment stage reads, at `binding`.
pub(super) fn fragment_uniform(binding: u32) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::FRAGMENT,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Uniform,
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    }
}

/// A full-screen triangle writing the host's colour format and testing its depth as it does.
fn composite_pipeline(
    device: &wgpu::Device,
    layout: &wgpu::BindGroupLayout,
    key: CompositeKey,
) -> wgpu::RenderPipeline {
    let pass = FullScreenPass {
        label: "composite",
        entry_point: "fs_main",
        depth: key.depth,
        compare: key.compare,
        samples: key.samples,
        reversed: key.reversed,
    };
    pass.pipeline(device, layout, &[Some(key.color.into())])
}

/// A full-screen pass of composite.wgsl into a host's targets: its fragment entry point, and
/// the host's depth format, depth test, samples per pixel and depth direction.
pub(super) struct FullScreenPass {
    pub(super) label: &'static str,
    pub(super) entry_point: &'static str,
    pub(super) depth: wgpu::TextureFormat,
    pub(super) compare: wgpu::CompareFunction,
    pub(super) samples: u32,
    pub(super) reversed: bool,
}

impl FullScreenPass {
    /// Its pipeline over `layout`, writing the colour `targets` and the depth it tests.
    pub(super) fn pipeline(
        &self,
        device: &wgpu::Device,
        layout: &wgpu::BindGroupLayout,
        targets: &[Option<wgpu::ColorTargetState>],
    ) -> wgpu::RenderPipeline {
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("composite.wgsl"),
            source: wgpu::ShaderSource::Wgsl(crate::pipelines::composite_wgsl().into()),
        });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some(self.label),
            bind_group_layouts: &[Some(layout)],
            immediate_size: 0,
        });
        let constants = [("REVERSED", if self.reversed { 1.0 } else { 0.0 })];
        device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some(self.label),
            layout: Some(&pipeline_layout),
            vertex: wgpu::VertexState {
                module: &module,
                entry_point: Some("vs_main"),
                compilation_options: Default::default(),
                buffers: &[],
            },
            primitive: Default::default(),
            depth_stencil: Some(wgpu::DepthStencilState {
                format: self.depth,
                depth_write_enabled: Some(true),
                depth_compare: Some(self.compare),
                stencil: Default::default(),
                bias: Default::default(),
            }),
            multisample: wgpu::MultisampleState {
                count: self.samples,
                ..Default::default()
            },
            fragment: Some(wgpu::FragmentState {
                module: &module,
                entry_point: Some(self.entry_point),
                compilation_options: wgpu::PipelineCompilationOptions {
                    constants: &constants,
                    ..Default::default()
                },
                targets,
            }),
            multiview_mask: None,
            cache: None,
        })
    }
}
