//! The GPU cube-map pool: how many cube slots the device and the cache budget allow and how they
//! lie in up to [`MAX_POOL_TEXTURES`] 2D texture arrays ([`PoolLayout`]), the textures
//! themselves, and the uploads of decoded faces into them ([`CubePool`]).

use std::time::Instant;

use oslf_format::header::Header;
use oslf_format::Encoding;

use crate::cache::{CacheConfig, Upload, MAX_POOL_TEXTURES};
use crate::error::{Result, RuntimeError};

/// The GPU pool's default size when no slot budget is given: 1 GiB of cube-map texels.
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
}

impl PoolLayout {
    /// Sizes the pool for a store of `cube_count` cubes described by `header`.
    ///
    /// Errors with [`RuntimeError::Parameter`] for a zero slot count in `config`, and with
    /// [`RuntimeError::Limits`] when `config` asks for more than the device holds.
    pub fn plan(
        limits: &wgpu::Limits,
        header: &Header,
        cube_count: u32,
        config: &CacheConfig,
    ) -> Result<Self> {
        let res = header.cube_resolution;
        // Faces lie side by side in a layer, 2^face_shift per layer (as many as the widest 2D
        // texture takes): one array then holds far more cubes than its layer count allows,
        // and lavapipe, which runs every branch under a mask, reads one array instead of
        // several (a measured 2.23× → 1.67× for mirror B^n against the baseline).
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
                let cube_bytes =
                    6 * u64::from(res).pow(2) * header.encoding.bytes_per_texel() as u64;
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
        })
    }

    /// Pool textures that hold slots (the rest are one-texel placeholders).
    pub fn textures_in_use(&self) -> u32 {
        self.slots.div_ceil(self.slots_per_texture)
    }

    /// The size of pool texture `t`: its slots' faces, 2^face_shift side by side per layer;
    /// one texel when it holds no slot.
    fn texture_size(&self, t: u32) -> wgpu::Extent3d {
        let in_this = self
            .slots
            .saturating_sub(t * self.slots_per_texture)
            .min(self.slots_per_texture);
        let faces = in_this * 6;
        let per_layer = 1u32 << self.face_shift;
        if in_this == 0 {
            wgpu::Extent3d {
                width: 1,
                height: 1,
                depth_or_array_layers: 1,
            }
        } else {
            wgpu::Extent3d {
                width: self.cube_res * faces.min(per_layer),
                height: self.cube_res,
                depth_or_array_layers: faces.div_ceil(per_layer),
            }
        }
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

/// The texture format of a cube-map encoding.
fn texture_format(e: Encoding) -> wgpu::TextureFormat {
    match e {
        Encoding::Rgb9e5 => wgpu::TextureFormat::Rgb9e5Ufloat,
        Encoding::Rgba16f => wgpu::TextureFormat::Rgba16Float,
        Encoding::Rgba32f => wgpu::TextureFormat::Rgba32Float,
    }
}

/// The pool's [`MAX_POOL_TEXTURES`] texture arrays, bound to shade.wgsl's `pool0` … `pool3`.
pub(crate) struct CubePool {
    layout: PoolLayout,
    bytes_per_texel: u32,
    textures: Vec<wgpu::Texture>,
    views: Vec<wgpu::TextureView>,
}

impl CubePool {
    /// Creates the arrays: as many as the slots need, each at most `slots_per_texture` cubes.
    /// Unused bindings get a one-texel array: the shader (specialized on POOLS) never reads
    /// them, and at 2048² a one-slot array would be 96 MiB.
    pub fn new(device: &wgpu::Device, layout: PoolLayout, encoding: Encoding) -> Self {
        let format = texture_format(encoding);
        let mut textures = Vec::new();
        let mut views = Vec::new();
        for t in 0..MAX_POOL_TEXTURES {
            let tex = device.create_texture(&wgpu::TextureDescriptor {
                label: Some("cube pool"),
                size: layout.texture_size(t),
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format,
                usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
                view_formats: &[],
            });
            views.push(tex.create_view(&wgpu::TextureViewDescriptor {
                dimension: Some(wgpu::TextureViewDimension::D2Array),
                ..Default::default()
            }));
            textures.push(tex);
        }
        Self {
            layout,
            bytes_per_texel: encoding.bytes_per_texel() as u32,
            textures,
            views,
        }
    }

    /// One view per array, in binding order.
    pub fn views(&self) -> &[wgpu::TextureView] {
        &self.views
    }

    /// Copies uploads into their slots; returns the seconds spent.
    pub fn upload(&self, queue: &wgpu::Queue, uploads: &[Upload]) -> f64 {
        let start = Instant::now();
        let res = self.layout.cube_res;
        for u in uploads {
            let (tex, layer, x) = self.layout.place(u.slot, u.face as u32);
            queue.write_texture(
                wgpu::TexelCopyTextureInfo {
                    texture: &self.textures[tex],
                    mip_level: 0,
                    origin: wgpu::Origin3d { x, y: 0, z: layer },
                    aspect: wgpu::TextureAspect::All,
                },
                &u.texels,
                wgpu::TexelCopyBufferLayout {
                    offset: 0,
                    bytes_per_row: Some(res * self.bytes_per_texel),
                    rows_per_image: Some(res),
                },
                wgpu::Extent3d {
                    width: res,
                    height: res,
                    depth_or_array_layers: 1,
                },
            );
        }
        start.elapsed().as_secs_f64()
    }
}
