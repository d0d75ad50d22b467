//! The render targets of one image size (G-buffer, depth, output) and what a frame of a size
//! costs in bytes.

use crate::pipelines::{DEPTH_FORMAT, GBUFFER_FORMAT, MATERIAL_FORMAT, OUTPUT_FORMAT};

/// The textures of one image size and the shading bind group that binds them.
pub(super) struct SizedTargets {
    pub(super) width: u32,
    pub(super) height: u32,
    pub(super) gb_position: wgpu::Texture,
    pub(super) gb_normal: wgpu::Texture,
    /// The material target of a store with textured objects; 1×1 (and unused) otherwise.
    pub(super) gb_material: wgpu::Texture,
    pub(super) depth: wgpu::Texture,
    pub(super) output: wgpu::Texture,
    pub(super) shade_group: wgpu::BindGroup,
    /// The host frame's composite bind group over `output` and `depth`, made at the first
    /// host frame of this size (`host.rs`).
    pub(super) composite_group: Option<wgpu::BindGroup>,
    /// The host prepass's bind group over `depth`, `gb_position` and `gb_normal`, likewise
    /// (`prepass.rs`).
    pub(super) prepass_group: Option<wgpu::BindGroup>,
}

impl SizedTargets {
    /// Creates the G-buffer (with a material target where `textured`), depth and output
    /// textures for `width` × `height` and the shading bind group `bind` makes of the views of
    /// position, normal, output, depth and material.
    pub(super) fn new(
        device: &wgpu::Device,
        width: u32,
        height: u32,
        textured: bool,
        bind: impl FnOnce(
            &wgpu::TextureView,
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
        let make_sized = |label, format, usage, size| {
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
        let make = |label, format, usage| make_sized(label, format, usage, size);
        let rt = wgpu::TextureUsages::RENDER_ATTACHMENT
            | wgpu::TextureUsages::TEXTURE_BINDING
            | wgpu::TextureUsages::COPY_SRC;
        let gb_position = make("gbuffer position", GBUFFER_FORMAT, rt);
        let gb_normal = make("gbuffer normal", GBUFFER_FORMAT, rt);
        let one = wgpu::Extent3d {
            width: 1,
            height: 1,
            depth_or_array_layers: 1,
        };
        let gb_material = make_sized(
            "gbuffer material",
            MATERIAL_FORMAT,
            rt,
            if textured { size } else { one },
        );
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
            &view(&gb_material),
        );
        Self {
            width,
            height,
            gb_position,
            gb_normal,
            gb_material,
            depth,
            output,
            shade_group,
            composite_group: None,
            prepass_group: None,
        }
    }
}

/// What one frame of a given size needs besides the store and its cube-map pool.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct FrameBytes {
    /// The render targets on the GPU: two G-buffer textures, depth and the output.
    pub gpu: u64,
    /// With [`RenderOptions::read_pixels`](super::RenderOptions::read_pixels): the read-back buffer and [`Frame::pixels`](super::Frame::pixels).
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

/// Bytes of one row of `width` texels of `bytes_per_texel`, padded for buffer copies.
pub(super) fn padded_row(width: u32, bytes_per_texel: u32) -> u32 {
    let row = width * bytes_per_texel;
    row.div_ceil(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT) * wgpu::COPY_BYTES_PER_ROW_ALIGNMENT
}
