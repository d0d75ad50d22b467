//! A host's depth prepass (an engine's: Bevy's `DepthPrepass`, `NormalPrepass`,
//! `MotionVectorPrepass`): the object is rasterised into its G-buffer once, before the host
//! draws its main pass, and written from that G-buffer into the prepass's targets (depth,
//! world normals, motion vectors: what screen-space effects such as SSAO and TAA read). The
//! frame's [`Renderer::encode_into`] for the same view then shades that G-buffer, so the object
//! is rasterised once per view, and the host's main pass already tests its meshes against the
//! object's depth.

use glam::Mat4;

use super::host::{
    check_color_format, check_host_depth, fragment_texture, fragment_uniform, FullScreenPass,
};
use super::targets::SizedTargets;
use super::timer::{PassTimer, TimedPass};
use super::Renderer;
use crate::error::{Result, RuntimeError};
use crate::params::Background;
use crate::shading::ShadingParams;
use crate::uniform::ShadeUniform;
use crate::HostView;

/// A colour target of a host's prepass and its format.
#[derive(Clone, Copy, Debug)]
pub struct PrepassTarget<'a> {
    pub view: &'a wgpu::TextureView,
    /// Any renderable colour format: 3 or more channels for normals, 2 or more for motion.
    pub format: wgpu::TextureFormat,
}

/// Where a host wants the object in its depth prepass: its depth target (the depth its main
/// pass tests against) and the prepass's colour targets it has.
#[derive(Clone, Copy, Debug)]
pub struct HostPrepass<'a> {
    /// The depth target, holding the depth of the host's meshes drawn in its prepass; the
    /// object's depth is written into it where the object is nearer.
    pub depth: &'a wgpu::TextureView,
    /// Its format (a depth format).
    pub depth_format: wgpu::TextureFormat,
    /// The host's depth test, as [`HostTarget::depth_compare`](super::HostTarget).
    pub depth_compare: wgpu::CompareFunction,
    /// Samples per pixel of every target: 1, or 2, 4, 8 (MSAA). The object is written to every
    /// sample its pixel covers.
    pub sample_count: u32,
    /// Size of the targets in pixels.
    pub width: u32,
    pub height: u32,
    /// World-space normals as n · ½ + ½ (Bevy's normal prepass), if the host keeps them.
    pub normal: Option<PrepassTarget<'a>>,
    /// Screen motion since the previous frame, in UV units (x right, y down), as Bevy's motion
    /// vector prepass stores it, if the host keeps it.
    pub motion: Option<PrepassTarget<'a>>,
    /// World from the object's space (the store's, as [`HostView::view`] is view from it):
    /// its inverse transpose turns the object's normals into world space. Finite and
    /// invertible.
    pub world_from_local: Mat4,
    /// Clip from the object's space at the previous frame, without jitter (the host's
    /// previous unjittered `clip_from_world` times the object's previous `world_from_local`;
    /// the current one where there is no previous frame): what the motion is measured from.
    pub previous_clip_from_local: Mat4,
}

impl HostPrepass<'_> {
    /// Checks the prepass; returns whether its depth is reversed, and what turns the object's
    /// normals into world space ([`normal_from_local`]).
    fn validate(&self) -> Result<(bool, Mat4)> {
        const HOST: &str = "HostPrepass";
        let reversed = check_host_depth(
            HOST,
            self.sample_count,
            self.depth_format,
            self.depth_compare,
        )?;
        if let Some(t) = &self.normal {
            check_color_format(HOST, "normal.format", t.format)?;
        }
        if let Some(t) = &self.motion {
            check_color_format(HOST, "motion.format", t.format)?;
        }
        let finite = |m: &Mat4| m.to_cols_array().iter().all(|v| v.is_finite());
        let normals = normal_from_local(self.world_from_local);
        if !finite(&self.world_from_local)
            || self.world_from_local.determinant().abs() <= 1e-30
            || !finite(&normals)
        {
            return Err(RuntimeError::Parameter(
                "HostPrepass::world_from_local: must be finite and invertible".into(),
            ));
        }
        if !finite(&self.previous_clip_from_local) {
            return Err(RuntimeError::Parameter(
                "HostPrepass::previous_clip_from_local: must be finite".into(),
            ));
        }
        Ok((reversed, normals))
    }
}

/// What turns the object's normals into world space: `world_from_local`'s inverse transpose,
/// which keeps them perpendicular to the surface under uneven scales and shears.
pub fn normal_from_local(world_from_local: Mat4) -> Mat4 {
    world_from_local.inverse().transpose()
}

oslf_gpu::gpu_struct! {
    /// The prepass's uniform, `Prepass` in composite.wgsl: the object's clip space now and at
    /// the previous frame, from its G-buffer's coordinates (the object's space relative to its
    /// mesh's origin), and what turns its normals into world space (`world_from_local`'s
    /// inverse transpose).
    #[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
    pub struct PrepassUniform as "Prepass" {
        pub clip_from_patch: [[f32; 4]; 4],
        pub previous_clip_from_patch: [[f32; 4]; 4],
        pub normal_from_local: [[f32; 4]; 4],
    }
}

/// A prepass recorded into the host's encoder whose G-buffer the view's frame shades.
pub(super) struct Prepassed {
    /// The shading uniform it rasterised with: the frame whose uniform is the same shades it.
    pub(super) uniform: ShadeUniform,
    /// The feedback slot its G-buffer pass was timed into.
    pub(super) slot: Option<usize>,
}

impl Prepassed {
    /// Whether the frame of uniform `u` shades this prepass's G-buffer (the same view, size
    /// and parameters).
    pub(super) fn shades(&self, u: &ShadeUniform) -> bool {
        bytemuck::bytes_of(&self.uniform) == bytemuck::bytes_of(u)
    }
}

/// The prepass pipelines, one per kind of host prepass, their bind-group layout and uniform.
pub(super) struct Prepasses {
    pipelines: std::collections::HashMap<PrepassKey, wgpu::RenderPipeline>,
    layout: wgpu::BindGroupLayout,
    uniform: wgpu::Buffer,
}

/// What a prepass pipeline depends on: sample count, depth format and test, whether depth is
/// reversed, and the colour targets' formats.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
struct PrepassKey {
    samples: u32,
    depth: wgpu::TextureFormat,
    compare: wgpu::CompareFunction,
    reversed: bool,
    normal: Option<wgpu::TextureFormat>,
    motion: Option<wgpu::TextureFormat>,
}

impl Prepasses {
    pub(super) fn new(device: &wgpu::Device) -> Self {
        Self {
            pipelines: Default::default(),
            layout: prepass_layout(device),
            uniform: device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("prepass"),
                size: std::mem::size_of::<PrepassUniform>() as u64,
                usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            }),
        }
    }
}

impl Renderer {
    /// Records the object's prepass into the host's `encoder`, seen through `view`: the
    /// G-buffer pass (at the prepass's size), then the object's depth, normals and motion
    /// vectors written into `prepass`'s targets where it passes the host's depth test (a
    /// full-screen pass, every sample of a multisampled target). Record it before the host's
    /// main pass, and [`Renderer::encode_into`] with the same view, parameters and size after
    /// it: that frame shades this G-buffer. Errors as [`Renderer::encode_into`] does, before
    /// anything is recorded.
    pub fn encode_prepass_into(
        &mut self,
        encoder: &mut wgpu::CommandEncoder,
        view: &HostView,
        prepass: &HostPrepass<'_>,
        params: &ShadingParams,
    ) -> Result<()> {
        let (reversed, normals) = prepass.validate()?;
        let camera = view.camera()?;
        self.check_frame(params, Background::None)?;
        let gpu = self.gpu.clone();
        let (u, pipeline) = gpu.scoped(|| {
            let size = [prepass.width, prepass.height];
            let u = self.prepare_host_view(view, &camera, params, size, reversed)?;
            self.ensure_prepass_group()?;
            let pipeline = self.prepass_pipeline(prepass, reversed)?;
            Ok::<_, RuntimeError>((u, pipeline))
        })?;
        let origin = Mat4::from_translation(self.mesh.origin);
        let uniform = PrepassUniform {
            clip_from_patch: (view.projection * view.view * origin).to_cols_array_2d(),
            previous_clip_from_patch: (prepass.previous_clip_from_local * origin)
                .to_cols_array_2d(),
            normal_from_local: normals.to_cols_array_2d(),
        };
        gpu.scoped(|| {
            let pass = bytemuck::bytes_of(&uniform);
            self.record_host_uniforms(encoder, &u, pass, &self.prepasses.uniform);
            let slot = self.record_host_gbuffer(encoder)?;
            let (targets, timer) = self.host_passes(slot)?;
            encode_prepass(encoder, prepass, &pipeline, targets, timer)?;
            self.prepassed = Some(Prepassed { uniform: u, slot });
            Ok(())
        })
    }

    /// The prepass pipeline for `prepass`'s targets, made once the device took it.
    fn prepass_pipeline(
        &mut self,
        prepass: &HostPrepass<'_>,
        reversed: bool,
    ) -> Result<wgpu::RenderPipeline> {
        let key = PrepassKey {
            samples: prepass.sample_count,
            depth: prepass.depth_format,
            compare: prepass.depth_compare,
            reversed,
            normal: prepass.normal.map(|t| t.format),
            motion: prepass.motion.map(|t| t.format),
        };
        if let Some(pipeline) = self.prepasses.pipelines.get(&key) {
            return Ok(pipeline.clone());
        }
        let (device, layout) = (&self.gpu.device, &self.prepasses.layout);
        let pipeline = self
            .gpu
            .scoped(|| Ok::<_, RuntimeError>(prepass_pipeline(device, layout, key)))?;
        self.prepasses.pipelines.insert(key, pipeline.clone());
        Ok(pipeline)
    }

    /// Makes the prepass's bind group for the current targets, unless they have one.
    fn ensure_prepass_group(&mut self) -> Result<()> {
        let targets = self
            .targets
            .as_mut()
            .ok_or_else(|| RuntimeError::gpu("render targets missing"))?;
        if targets.prepass_group.is_some() {
            return Ok(());
        }
        let view = |t: &wgpu::Texture| t.create_view(&Default::default());
        let (depth, position, normal) = (
            view(&targets.depth),
            view(&targets.gb_position),
            view(&targets.gb_normal),
        );
        let texture = |binding, view| wgpu::BindGroupEntry {
            binding,
            resource: wgpu::BindingResource::TextureView(view),
        };
        let group = self
            .gpu
            .device
            .create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("prepass"),
                layout: &self.prepasses.layout,
                entries: &[
                    texture(1, &depth),
                    texture(3, &position),
                    texture(4, &normal),
                    wgpu::BindGroupEntry {
                        binding: 5,
                        resource: self.prepasses.uniform.as_entire_binding(),
                    },
                ],
            });
        targets.prepass_group = Some(group);
        Ok(())
    }
}

/// Records the prepass: a full-screen triangle writing the object's depth, normal and motion
/// into `prepass`'s targets where it passes the host's depth test; timed where `timer`.
fn encode_prepass<'a>(
    encoder: &mut wgpu::CommandEncoder,
    prepass: &HostPrepass<'a>,
    pipeline: &wgpu::RenderPipeline,
    targets: &SizedTargets,
    timer: Option<&PassTimer>,
) -> Result<()> {
    fn keep<V>() -> wgpu::Operations<V> {
        wgpu::Operations {
            load: wgpu::LoadOp::Load,
            store: wgpu::StoreOp::Store,
        }
    }
    let color = |t: PrepassTarget<'a>| wgpu::RenderPassColorAttachment {
        view: t.view,
        depth_slice: None,
        resolve_target: None,
        ops: keep(),
    };
    let attachments = color_slots(prepass.normal.map(color), || prepass.motion.map(color));
    let timestamp_writes = timer.map(|t| {
        let (query_set, begin, end) = t.writes(TimedPass::Prepass);
        wgpu::RenderPassTimestampWrites {
            query_set,
            beginning_of_pass_write_index: begin,
            end_of_pass_write_index: end,
        }
    });
    let group = targets
        .prepass_group
        .as_ref()
        .ok_or_else(|| RuntimeError::gpu("prepass bind group missing"))?;
    let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
        label: Some("prepass"),
        color_attachments: &attachments,
        depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
            view: prepass.depth,
            depth_ops: Some(keep()),
            stencil_ops: prepass.depth_format.has_stencil_aspect().then(keep),
        }),
        timestamp_writes,
        occlusion_query_set: None,
        multiview_mask: None,
    });
    pass.set_pipeline(pipeline);
    pass.set_bind_group(0, group, &[]);
    pass.draw(0..3, 0..1);
    Ok(())
}

/// The colour slots of a prepass in Bevy's order (normals at location 0, motion at 1): none
/// when it has neither, one when it has normals alone.
fn color_slots<T>(normal: Option<T>, motion: impl FnOnce() -> Option<T>) -> Vec<Option<T>> {
    match (normal, motion()) {
        (None, None) => vec![],
        (normal, None) => vec![normal],
        (normal, motion) => vec![normal, motion],
    }
}

/// composite.wgsl's `fs_prepass` bindings: the G-buffer's depth, position and normal, and the
/// prepass's uniform.
fn prepass_layout(device: &wgpu::Device) -> wgpu::BindGroupLayout {
    let float = wgpu::TextureSampleType::Float { filterable: false };
    device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some("prepass"),
        entries: &[
            fragment_texture(1, wgpu::TextureSampleType::Depth),
            fragment_texture(3, float),
            fragment_texture(4, float),
            fragment_uniform(5),
        ],
    })
}

/// A full-screen triangle writing the host's prepass targets and testing its depth as it
/// does.
fn prepass_pipeline(
    device: &wgpu::Device,
    layout: &wgpu::BindGroupLayout,
    key: PrepassKey,
) -> wgpu::RenderPipeline {
    // Written whole, unblended.
    let target = wgpu::ColorTargetState::from;
    let pass = FullScreenPass {
        label: "prepass",
        entry_point: "fs_prepass",
        depth: key.depth,
        compare: key.compare,
        samples: key.samples,
        reversed: key.reversed,
    };
    pass.pipeline(
        device,
        layout,
        &color_slots(key.normal.map(target), || key.motion.map(target)),
    )
}
