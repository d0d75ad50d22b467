//! The textured objects' material textures on the GPU: one bind group per
//! textured object for gbuffer.wgsl's group 1 (`T`, `tex_base_color`, …), and one of 1×1
//! textures with no flags for the objects without textures.

use oslf_format::{ObjectInfo, StoreMeta, TextureImage, TextureKind};
use wgpu::util::DeviceExt;

/// The kinds gbuffer.wgsl reads, in the order of its group-1 texture bindings (1, 2, …) and
/// of `TextureParams`' flag bits.
pub(crate) const BOUND_KINDS: [TextureKind; 5] = [
    TextureKind::BaseColor,
    TextureKind::MetallicRoughness,
    TextureKind::Normal,
    TextureKind::Emissive,
    TextureKind::Occlusion,
];

oslf_gpu::gpu_struct! {
    /// gbuffer.wgsl's `TextureParams`, declared from these fields ([`TextureParams::wgsl`]):
    /// which textures the object has, and the normal texture's scale and the occlusion
    /// texture's strength.
    #[derive(Clone, Copy, Debug, Default, bytemuck::Pod, bytemuck::Zeroable)]
    pub(crate) struct TextureParams as "TextureParams" {
        /// Bit `i` set when the object has [`BOUND_KINDS`]`[i]`.
        pub flags: u32,
        pub normal_scale: f32,
        pub occlusion_strength: f32,
        pub pad: u32,
    }
}

/// The bind groups of the store's textured objects.
pub(crate) struct ObjectTextureGroups {
    /// gbuffer.wgsl's group 1.
    pub layout: wgpu::BindGroupLayout,
    /// One per object of the store (the untextured ones' bind 1×1 textures and flags 0).
    pub groups: Vec<wgpu::BindGroup>,
}

impl ObjectTextureGroups {
    /// Uploads every textured object's images; `None` when no object has textures (the
    /// G-buffer pass then draws without group 1).
    pub fn new(device: &wgpu::Device, queue: &wgpu::Queue, meta: &StoreMeta) -> Option<Self> {
        meta.objects.iter().any(|o| o.textures.is_some()).then(|| {
            let layout = bind_group_layout(device);
            let blank = TextureImage {
                width: 1,
                height: 1,
                texels: vec![[0; 4]],
            };
            let groups = meta
                .objects
                .iter()
                .map(|o| {
                    let (params, images) = object_textures(o);
                    let views: Vec<wgpu::TextureView> = BOUND_KINDS
                        .iter()
                        .zip(images)
                        .map(|(&kind, image)| upload(device, queue, image.unwrap_or(&blank), kind))
                        .collect();
                    group(device, &layout, &params, &views)
                })
                .collect();
            Self { layout, groups }
        })
    }
}

/// An object's [`TextureParams`] and its images in the order of [`BOUND_KINDS`] (`None`
/// where it has no such texture: a 1×1 texture is bound there and its flag is clear).
pub(crate) fn object_textures(o: &ObjectInfo) -> (TextureParams, [Option<&TextureImage>; 5]) {
    let t = o.textures.as_ref();
    let mut params = TextureParams::default();
    let images = BOUND_KINDS.map(|kind| t.and_then(|t| t.image(kind)));
    for (bit, image) in images.iter().enumerate() {
        if image.is_some() {
            params.flags |= 1 << bit;
        }
    }
    if let Some(t) = t {
        params.normal_scale = t.normal_scale;
        params.occlusion_strength = t.occlusion_strength;
    }
    (params, images)
}

/// gbuffer.wgsl's group 1: the uniform, then one texture per [`BOUND_KINDS`].
fn bind_group_layout(device: &wgpu::Device) -> wgpu::BindGroupLayout {
    let fs = wgpu::ShaderStages::FRAGMENT;
    let mut entries = vec![wgpu::BindGroupLayoutEntry {
        binding: 0,
        visibility: fs,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Uniform,
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    }];
    for b in 0..BOUND_KINDS.len() as u32 {
        entries.push(wgpu::BindGroupLayoutEntry {
            binding: b + 1,
            visibility: fs,
            ty: wgpu::BindingType::Texture {
                sample_type: wgpu::TextureSampleType::Float { filterable: false },
                view_dimension: wgpu::TextureViewDimension::D2,
                multisampled: false,
            },
            count: None,
        });
    }
    device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some("object textures"),
        entries: &entries,
    })
}

/// `image` as an `Rgba8Unorm` texture (sRGB kinds are decoded in the shader, as on the CPU).
fn upload(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    image: &TextureImage,
    kind: TextureKind,
) -> wgpu::TextureView {
    let texture = device.create_texture_with_data(
        queue,
        &wgpu::TextureDescriptor {
            label: Some(kind.name()),
            size: wgpu::Extent3d {
                width: image.width,
                height: image.height,
                depth_or_array_layers: 1,
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: wgpu::TextureFormat::Rgba8Unorm,
            usage: wgpu::TextureUsages::TEXTURE_BINDING,
            view_formats: &[],
        },
        wgpu::util::TextureDataOrder::LayerMajor,
        bytemuck::cast_slice(&image.texels),
    );
    texture.create_view(&Default::default())
}

/// One object's group: its [`TextureParams`] and texture views.
fn group(
    device: &wgpu::Device,
    layout: &wgpu::BindGroupLayout,
    params: &TextureParams,
    views: &[wgpu::TextureView],
) -> wgpu::BindGroup {
    let uniform = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some("texture params"),
        contents: bytemuck::bytes_of(params),
        usage: wgpu::BufferUsages::UNIFORM,
    });
    let mut entries = vec![wgpu::BindGroupEntry {
        binding: 0,
        resource: uniform.as_entire_binding(),
    }];
    for (i, v) in views.iter().enumerate() {
        entries.push(wgpu::BindGroupEntry {
            binding: i as u32 + 1,
            resource: wgpu::BindingResource::TextureView(v),
        });
    }
    device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("object textures"),
        layout,
        entries: &entries,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every kind of texture the format holds is bound, so a store's textures are all drawn.
    #[test]
    fn every_texture_kind_is_bound() {
        for kind in TextureKind::ALL {
            assert!(BOUND_KINDS.contains(&kind), "{kind:?} is not bound");
        }
        assert_eq!(BOUND_KINDS.len(), TextureKind::ALL.len());
    }
}
