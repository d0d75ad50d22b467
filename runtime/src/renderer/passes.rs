//! Encoding a frame's two passes: the G-buffer pass and the shading pass.

use super::targets::SizedTargets;
use super::timer::{PassTimer, TimedPass};
use super::Renderer;
use crate::error::{Result, RuntimeError};
use crate::pipelines::{DEPTH_CLEAR, WORKGROUP};

impl Renderer {
    /// Encodes the G-buffer pass: clears depth and rasterizes the mesh into the targets. The
    /// colour targets are not cleared: the shading pass and `read_gbuffer` take a pixel as
    /// covered where its depth is below [`DEPTH_CLEAR`] and ignore the colour elsewhere, so
    /// the pass does not spend its time clearing two Rgba32Float targets. `timer`: where its
    /// GPU timestamps go, if anywhere.
    pub(super) fn encode_gbuffer(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        targets: &SizedTargets,
        timer: Option<&PassTimer>,
    ) {
        let gp = targets.gb_position.create_view(&Default::default());
        let gn = targets.gb_normal.create_view(&Default::default());
        let gm = targets.gb_material.create_view(&Default::default());
        let dv = targets.depth.create_view(&Default::default());
        let keep = wgpu::Operations {
            load: wgpu::LoadOp::Load,
            store: wgpu::StoreOp::Store,
        };
        let attachments = [
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
            // Cleared: a pixel whose object has no textures reads flags 0.
            self.textures
                .as_ref()
                .map(|_| wgpu::RenderPassColorAttachment {
                    view: &gm,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT),
                        store: wgpu::StoreOp::Store,
                    },
                }),
        ];
        let used = 2 + usize::from(self.textures.is_some());
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("gbuffer"),
            color_attachments: &attachments[..used],
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: &dv,
                depth_ops: Some(wgpu::Operations {
                    load: wgpu::LoadOp::Clear(DEPTH_CLEAR),
                    store: wgpu::StoreOp::Store,
                }),
                stencil_ops: None,
            }),
            timestamp_writes: timer.map(|t| {
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
        match &self.textures {
            None => pass.draw_indexed(0..self.buffers.index_count, 0, 0..1),
            // Each object's triangles with its textures bound.
            Some(t) => {
                for (range, object) in &self.mesh.draws {
                    if let Some(group) = t.groups.get(*object as usize) {
                        pass.set_bind_group(1, group, &[]);
                        pass.draw_indexed(range.clone(), 0, 0..1);
                    }
                }
            }
        }
    }

    /// Encodes the shading pass of the current frame's pipeline over every pixel; `timer` as
    /// for [`Renderer::encode_gbuffer`].
    pub(super) fn encode_shading(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        targets: &SizedTargets,
        timer: Option<&PassTimer>,
    ) -> Result<()> {
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("shade"),
            timestamp_writes: timer.map(|t| {
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
            .ok_or_else(|| RuntimeError::gpu("no shading pipeline for this mode"))?;
        pass.set_pipeline(pipeline);
        pass.set_bind_group(0, &targets.shade_group, &[]);
        pass.dispatch_workgroups(
            targets.width.div_ceil(WORKGROUP),
            targets.height.div_ceil(WORKGROUP),
            1,
        );
        Ok(())
    }
}
