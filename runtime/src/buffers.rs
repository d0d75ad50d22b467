//! The renderer's GPU buffers and its sample-map texture: what is uploaded once when a store
//! is opened (sample points, patches, the tessellated mesh, the sample maps) and what the
//! frames write and read (the uniform, the cube-slot table, the feedback masks).

use glam::Vec3;
use oslf_format::{IndexWidth, Store};
use wgpu::util::DeviceExt;

use crate::error::{Result, RuntimeError};
use crate::geometry::ObjectMesh;
use crate::uniform::ShadeUniform;
use crate::Gpu;

/// The vec4s of one patch in the `patches` buffer (shade.wgsl's `PatchGpu`): its 16 control
/// points, then its base colour.
pub(crate) const PATCH_VEC4S: usize = 19;

/// The buffers of a store on the GPU. Storage buffers may not be empty: those that could be
/// are padded with one element.
pub(crate) struct StoreBuffers {
    /// The [`ShadeUniform`] (`P` in both shaders).
    pub uniform: wgpu::Buffer,
    /// The mesh's vertices (gbuffer.wgsl's `vertices`).
    pub vertices: wgpu::Buffer,
    /// The mesh's triangle indices (u32).
    pub indices: wgpu::Buffer,
    /// Indices in `indices`.
    pub index_count: u32,
    /// Sample-point positions, object-relative, w = 1 (shade.wgsl's `samples`).
    pub samples: wgpu::Buffer,
    /// Per sample map its 16 control points (zero for a mesh's atlas page) and its object's
    /// base colour (shade.wgsl's `patches`).
    pub patches: wgpu::Buffer,
    /// The cache's indirection table, one entry per cube (shade.wgsl's `slots`).
    pub slots: wgpu::Buffer,
    /// One mask of needed faces per cube, written by the shader (shade.wgsl's `feedback`).
    pub feedback: wgpu::Buffer,
    /// Where `feedback` is copied to be read on the CPU, followed at `timestamps_offset` by
    /// the G-buffer and shading passes' GPU timestamps where the device has timestamp queries
    /// (the renderer's `PassTimer`): one map per pass reads both.
    pub feedback_readback: wgpu::Buffer,
    /// Byte offset of the timestamps in `feedback_readback`.
    pub timestamps_offset: u64,
}

impl StoreBuffers {
    /// Uploads `store`'s sample points and `mesh` (whose origin the sample points are made
    /// relative to) and creates the per-frame buffers for `cube_count` cubes.
    pub fn new(device: &wgpu::Device, store: &Store, mesh: &ObjectMesh, cube_count: u32) -> Self {
        let storage = wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST;
        let samples = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("sample points"),
            contents: bytemuck::cast_slice(&sample_point_data(store, mesh)),
            usage: storage,
        });
        let patch_data = patch_data(mesh);
        let patches = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("patches"),
            contents: bytemuck::cast_slice(&patch_data),
            usage: storage,
        });
        let table_len = (cube_count.max(1) as u64) * 4;
        let slots = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("cube slots"),
            size: table_len,
            usage: storage,
            mapped_at_creation: false,
        });
        let feedback = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("feedback"),
            size: table_len,
            usage: wgpu::BufferUsages::STORAGE
                | wgpu::BufferUsages::COPY_SRC
                | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let feedback_readback = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("feedback readback"),
            size: table_len + TIMESTAMP_BYTES,
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let uniform = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("params"),
            size: std::mem::size_of::<ShadeUniform>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let vertices = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("vertices"),
            contents: bytemuck::cast_slice(&mesh.vertices),
            usage: wgpu::BufferUsages::STORAGE,
        });
        let indices = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("indices"),
            contents: bytemuck::cast_slice(&mesh.indices),
            usage: wgpu::BufferUsages::INDEX,
        });
        Self {
            uniform,
            vertices,
            indices,
            index_count: mesh.indices.len() as u32,
            samples,
            patches,
            slots,
            feedback,
            feedback_readback,
            timestamps_offset: table_len,
        }
    }
}

/// Where [`sample_point_data`] puts the store's irradiance section: after the sample points
/// (or the one zero point of a store without any). `None` for a store without one.
pub(crate) fn irradiance_base(store: &Store) -> Option<u32> {
    store
        .irradiance()
        .map(|_| store.sample_points().len().max(1) as u32)
}

/// The store's irradiance section as the reference reads it: per cube nine RGB coefficients
/// (empty for a store without one).
pub(crate) fn irradiance_coefficients(store: &Store) -> Vec<[Vec3; 9]> {
    store
        .irradiance()
        .unwrap_or_default()
        .iter()
        .map(|c| c.map(Vec3::from_array))
        .collect()
}

/// shade.wgsl's `samples`: each sample point relative to the mesh's origin, w = 1 (one zero
/// point for a store without points, as a binding cannot be empty); then, for a store with an
/// irradiance section, from [`irradiance_base`] on each cube's nine spherical-harmonic
/// coefficients (RGB, w = 0), cube after cube.
pub(crate) fn sample_point_data(store: &Store, mesh: &ObjectMesh) -> Vec<[f32; 4]> {
    let mut positions: Vec<[f32; 4]> = store
        .sample_points()
        .iter()
        .map(|s| {
            (Vec3::from_array(s.position) - mesh.origin)
                .extend(1.0)
                .to_array()
        })
        .collect();
    if positions.is_empty() {
        positions.push([0.0; 4]);
    }
    for cube in store.irradiance().unwrap_or_default() {
        positions.extend(cube.iter().map(|c| [c[0], c[1], c[2], 0.0]));
    }
    positions
}

/// shade.wgsl's `patches`: per patch its 16 control points, colour, material and emission
/// ([`PATCH_VEC4S`] vec4s).
pub(crate) fn patch_data(mesh: &ObjectMesh) -> Vec<[f32; 4]> {
    let mut patch_data: Vec<[f32; 4]> = Vec::with_capacity(mesh.patches.len() * PATCH_VEC4S);
    for (((p, c), m), e) in mesh
        .patches
        .iter()
        .zip(&mesh.colors)
        .zip(&mesh.materials)
        .zip(&mesh.emissions)
    {
        patch_data.extend(p.cp.iter().map(|v| v.extend(0.0).to_array()));
        patch_data.push(c.extend(1.0).to_array());
        patch_data.push(*m);
        patch_data.push(*e);
    }
    patch_data
}

/// The sample maps' texture format and bytes per texel: four u16 indices, or four u32.
pub(crate) fn sample_map_format(store: &Store) -> (wgpu::TextureFormat, u32) {
    if store.index_width() == IndexWidth::U16 {
        (wgpu::TextureFormat::Rgba16Uint, 8)
    } else {
        (wgpu::TextureFormat::Rgba32Uint, 16)
    }
}

/// The texels of sample map `map` (a Bézier patch or an atlas page), row-major, as the
/// texture holds them; errors name the store's damaged map.
pub(crate) fn sample_map_bytes(store: &Store, map: u32) -> Result<Vec<u8>> {
    let view = store.sample_map(map).map_err(|error| RuntimeError::Store {
        path: "sample maps".into(),
        error,
    })?;
    Ok(match (view.as_u16(), view.as_u32()) {
        (Some(d), _) => bytemuck::cast_slice(d).to_vec(),
        (_, Some(d)) => bytemuck::cast_slice(d).to_vec(),
        _ => unreachable!("a sample map is either u16 or u32"),
    })
}

/// Bytes of the G-buffer, shading, composite and prepass passes' GPU timestamps (u64 ticks,
/// start and end of each).
pub const TIMESTAMP_BYTES: u64 = 64;

/// Uploads `store`'s sample maps as stored (zero-copy): one integer array layer per sample map
/// (Bézier patch or atlas page),
/// `Rgba16Uint` or `Rgba32Uint` by the store's index width. Returns the `D2Array` view
/// (shade.wgsl's `sample_maps`).
///
/// Errors with [`RuntimeError::Store`] when a sample map cannot be read.
pub(crate) fn upload_sample_maps(gpu: &Gpu, store: &Store) -> Result<wgpu::TextureView> {
    let map_res = store.header().sample_map_resolution;
    let patch_count = store.meta().map_count() as u32;
    let (map_format, texel) = sample_map_format(store);
    let map_texture = gpu.device.create_texture(&wgpu::TextureDescriptor {
        label: Some("sample maps"),
        size: wgpu::Extent3d {
            width: map_res,
            height: map_res,
            depth_or_array_layers: patch_count,
        },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: map_format,
        usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
        view_formats: &[],
    });
    for patch in 0..patch_count {
        let bytes = sample_map_bytes(store, patch)?;
        gpu.queue.write_texture(
            wgpu::TexelCopyTextureInfo {
                texture: &map_texture,
                mip_level: 0,
                origin: wgpu::Origin3d {
                    x: 0,
                    y: 0,
                    z: patch,
                },
                aspect: wgpu::TextureAspect::All,
            },
            &bytes,
            wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(map_res * texel),
                rows_per_image: Some(map_res),
            },
            wgpu::Extent3d {
                width: map_res,
                height: map_res,
                depth_or_array_layers: 1,
            },
        );
    }
    Ok(map_texture.create_view(&wgpu::TextureViewDescriptor {
        dimension: Some(wgpu::TextureViewDimension::D2Array),
        ..Default::default()
    }))
}
