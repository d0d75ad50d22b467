//! The GPU cube-map pool: how many cube slots the device and the cache budget allow and how they
//! lie in up to [`MAX_POOL_TEXTURES`] 2D texture arrays ([`PoolLayout`]), the textures
//! themselves, and the uploads of decoded faces into them ([`CubePool`]).
//!
//! Each array has the faces' mip chain ([`FaceLayout::levels`]; at level `l` a face is
//! `res >> l` wide and lies at `x >> l`), and, for stores with a distance channel, a twin
//! R16Float array of the same size holds the distance planes (level 0 only): shade.wgsl's
//! `pool0` … `pool3` and `dpool0` … `dpool3`.
//!
//! On an adapter with BC texture compression, BC6H stores are held as `Bc6hRgbUfloat` blocks
//! (1 byte per texel at level 0; [`FaceLayout`] keeps every level of every face whole blocks
//! at block-aligned x). shade.wgsl reads them with `textureLoad` like any float texture: the
//! hardware decodes the block.

use std::time::Instant;

use oslf_format::Encoding;

use crate::cache::{CacheConfig, Upload, MAX_POOL_TEXTURES};
use crate::error::{Result, RuntimeError};
use crate::face::FaceLayout;

/// The GPU pool's default size when no slot budget is given: 1 GiB of cube-map payloads (the
/// real bytes of [`FaceLayout::payload_bytes`]: blocks for BC6H, mips and distance planes).
pub const DEFAULT_POOL_BYTES: u64 = 1 << 30;

/// Where the pool's cubes lie, from the device's limits, the store and the cache configuration.
#[derive(Clone, Copy, Debug)]
pub(crate) struct PoolLayout {
    /// GPU cache slots (cubes) in all.
    pub slots: u32,
    /// Cubes per texture array.
    pub slots_per_texture: u32,
    /// 2^face_shift faces side by side in each pool layer.
    pub face_shift: u32,
    /// The side of a cube face in texels.
    pub cube_res: u32,
    /// What one face holds: encoding, mip levels, distance plane.
    pub face: FaceLayout,
}

impl PoolLayout {
    /// Sizes the pool for a store of `cube_count` cubes whose faces `face` describes.
    ///
    /// Errors with [`RuntimeError::Parameter`] for a zero slot count in `config`, and with
    /// [`RuntimeError::Limits`] when `config` asks for more than the device holds.
    pub fn plan(
        limits: &wgpu::Limits,
        face: FaceLayout,
        cube_count: u32,
        config: &CacheConfig,
    ) -> Result<Self> {
        let res = face.res;
        // Faces lie side by side in a layer, 2^face_shift per layer (as many as the widest 2D
        // texture takes): one array then holds far more cubes than its layer count allows,
        // and lavapipe, which runs every branch under a mask, reads one array instead of
        // several (docs/measurements.md, "Figures behind code comments").
        let row_max = (limits.max_texture_dimension_2d / res).max(1);
        let shift_max = 31 - row_max.leading_zeros();
        let device_per_texture = ((u64::from(limits.max_texture_array_layers) << shift_max) / 6)
            .min(u64::from(u32::MAX / MAX_POOL_TEXTURES)) as u32;
        let slots_per_texture = match config.slots_per_texture {
            Some(0) => {
                return Err(RuntimeError::Parameter(
                    "slots per pool texture must be at least 1".into(),
                ))
            }
            Some(s) if s > device_per_texture => {
                return Err(RuntimeError::Limits(format!(
                    "{s} cubes per texture array need {} layers; the device allows {}",
                    u64::from(s) * 6,
                    limits.max_texture_array_layers
                )))
            }
            Some(s) => s,
            None => device_per_texture,
        };
        if slots_per_texture == 0 {
            return Err(RuntimeError::Limits(
                "the device allows fewer than 6 texture array layers".into(),
            ));
        }
        let device_slots = slots_per_texture * MAX_POOL_TEXTURES;
        let slots = match config.gpu_slots {
            Some(0) => {
                return Err(RuntimeError::Parameter(
                    "the GPU cache needs at least one slot".into(),
                ))
            }
            Some(s) if s > device_slots => {
                return Err(RuntimeError::Limits(format!(
                    "{s} GPU cache slots asked for; this device holds at most {device_slots} \
                     ({MAX_POOL_TEXTURES} arrays of {slots_per_texture} cubes)"
                )))
            }
            Some(s) => s,
            None => {
                // Every cube, up to DEFAULT_POOL_BYTES of texels.
                let cube_bytes = 6 * face.payload_bytes() as u64;
                let by_memory =
                    (DEFAULT_POOL_BYTES / cube_bytes.max(1)).clamp(1, u64::from(u32::MAX));
                cube_count.clamp(1, device_slots).min(by_memory as u32)
            }
        };
        // No wider than one array's share of the pool needs.
        let faces_per_texture = u64::from(slots.min(slots_per_texture)) * 6;
        let face_shift = (64 - (faces_per_texture.max(1) - 1).leading_zeros()).min(shift_max);
        Ok(Self {
            slots,
            slots_per_texture,
            face_shift,
            cube_res: res,
            face,
        })
    }

    /// Pool textures that hold slots (the rest are one-texel placeholders).
    pub fn textures_in_use(&self) -> u32 {
        self.slots.div_ceil(self.slots_per_texture)
    }

    /// The size of pool texture `t`: its slots' faces, 2^face_shift side by side per layer
    /// (multiples of 4 for BC6H, whose faces are); `None` when it holds no slot (the pool then
    /// makes a placeholder).
    pub(crate) fn texture_size(&self, t: u32) -> Option<wgpu::Extent3d> {
        let in_this = self
            .slots
            .saturating_sub(t * self.slots_per_texture)
            .min(self.slots_per_texture);
        let faces = in_this * 6;
        let per_layer = 1u32 << self.face_shift;
        (in_this > 0).then(|| wgpu::Extent3d {
            width: self.cube_res * faces.min(per_layer),
            height: self.cube_res,
            depth_or_array_layers: faces.div_ceil(per_layer),
        })
    }

    /// Pool texture, array layer and x offset of `face` of `slot`.
    fn place(&self, slot: u32, face: u32) -> (usize, u32, u32) {
        let tex = (slot / self.slots_per_texture) as usize;
        let g = (slot % self.slots_per_texture) * 6 + face;
        let layer = g >> self.face_shift;
        let x = (g & ((1 << self.face_shift) - 1)) * self.cube_res;
        (tex, layer, x)
    }
}

/// The texture format of a pool encoding.
fn texture_format(e: Encoding) -> wgpu::TextureFormat {
    match e {
        Encoding::Rgb9e5 => wgpu::TextureFormat::Rgb9e5Ufloat,
        Encoding::Rgba16f => wgpu::TextureFormat::Rgba16Float,
        Encoding::Rgba32f => wgpu::TextureFormat::Rgba32Float,
        Encoding::Bc6h => wgpu::TextureFormat::Bc6hRgbUfloat,
    }
}

/// The pool's [`MAX_POOL_TEXTURES`] texture arrays, bound to shade.wgsl's `pool0` … `pool3`,
/// and their distance twins `dpool0` … `dpool3`.
pub(crate) struct CubePool {
    layout: PoolLayout,
    textures: Vec<wgpu::Texture>,
    views: Vec<wgpu::TextureView>,
    depth_textures: Vec<wgpu::Texture>,
    depth_views: Vec<wgpu::TextureView>,
}

/// A 2D texture array of `size` and `levels` mip levels, and its array view.
fn array_texture(
    device: &wgpu::Device,
    label: &str,
    size: wgpu::Extent3d,
    levels: u32,
    format: wgpu::TextureFormat,
) -> (wgpu::Texture, wgpu::TextureView) {
    let tex = device.create_texture(&wgpu::TextureDescriptor {
        label: Some(label),
        size,
        mip_level_count: levels,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format,
        usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
        view_formats: &[],
    });
    let view = tex.create_view(&wgpu::TextureViewDescriptor {
        dimension: Some(wgpu::TextureViewDimension::D2Array),
        ..Default::default()
    });
    (tex, view)
}

impl CubePool {
    /// Creates the arrays: as many as the slots need, each at most `slots_per_texture` cubes.
    /// Unused bindings get a one-texel array: the shader (specialized on POOLS) never reads
    /// them, and at 2048² a one-slot array would be 96 MiB. Without a distance channel every
    /// distance array is such a placeholder (shade.wgsl's DEPTH is off).
    pub fn new(device: &wgpu::Device, layout: PoolLayout) -> Self {
        let face = layout.face;
        let format = texture_format(face.encoding);
        let one = wgpu::Extent3d {
            width: 1,
            height: 1,
            depth_or_array_layers: 1,
        };
        // Block-compressed placeholders are one block.
        let (bw, bh) = format.block_dimensions();
        let placeholder = wgpu::Extent3d {
            width: bw,
            height: bh,
            depth_or_array_layers: 1,
        };
        let mut pool = Self {
            layout,
            textures: Vec::new(),
            views: Vec::new(),
            depth_textures: Vec::new(),
            depth_views: Vec::new(),
        };
        for t in 0..MAX_POOL_TEXTURES {
            let (size, levels) = match layout.texture_size(t) {
                None => (placeholder, 1),
                Some(size) => (size, face.levels),
            };
            let (tex, view) = array_texture(device, "cube pool", size, levels, format);
            pool.textures.push(tex);
            pool.views.push(view);
            let dsize = match layout.texture_size(t) {
                Some(size) if face.depth => size,
                _ => one,
            };
            let (tex, view) = array_texture(
                device,
                "cube distance pool",
                dsize,
                1,
                wgpu::TextureFormat::R16Float,
            );
            pool.depth_textures.push(tex);
            pool.depth_views.push(view);
        }
        pool
    }

    /// One view per array, in binding order.
    pub fn views(&self) -> &[wgpu::TextureView] {
        &self.views
    }

    /// One view per distance array, in binding order.
    pub fn depth_views(&self) -> &[wgpu::TextureView] {
        &self.depth_views
    }

    /// Copies uploads (every mip level, and the distance plane) into their slots; returns the
    /// seconds spent.
    pub fn upload(&self, queue: &wgpu::Queue, uploads: &[Upload]) -> f64 {
        let start = Instant::now();
        let face = self.layout.face;
        for u in uploads {
            let (tex, layer, x) = self.layout.place(u.slot, u.face as u32);
            for l in 0..face.levels {
                let at = face.level_offset(l);
                write_region(
                    queue,
                    &self.textures[tex],
                    l,
                    (x >> l, layer),
                    face.side(l),
                    face.level_rows(l),
                    &u.texels[at..at + face.level_bytes(l)],
                );
            }
            if face.depth {
                let res = face.res;
                write_region(
                    queue,
                    &self.depth_textures[tex],
                    0,
                    (x, layer),
                    res,
                    (res * 2, res),
                    &u.texels[face.depth_offset()..],
                );
            }
        }
        start.elapsed().as_secs_f64()
    }
}

/// Writes a `side`² region (texels) of `texture`'s mip `level` at `(x, 0, layer)` from `bytes`:
/// `rows` rows of `row_bytes` (rows of texels, or for BC6H rows of 4×4 blocks, as wgpu's
/// `TexelCopyBufferLayout` counts them).
fn write_region(
    queue: &wgpu::Queue,
    texture: &wgpu::Texture,
    level: u32,
    (x, layer): (u32, u32),
    side: u32,
    (row_bytes, rows): (u32, u32),
    bytes: &[u8],
) {
    queue.write_texture(
        wgpu::TexelCopyTextureInfo {
            texture,
            mip_level: level,
            origin: wgpu::Origin3d { x, y: 0, z: layer },
            aspect: wgpu::TextureAspect::All,
        },
        bytes,
        wgpu::TexelCopyBufferLayout {
            offset: 0,
            bytes_per_row: Some(row_bytes),
            rows_per_image: Some(rows),
        },
        wgpu::Extent3d {
            width: side,
            height: side,
            depth_or_array_layers: 1,
        },
    );
}
