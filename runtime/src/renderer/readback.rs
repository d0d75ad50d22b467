//! Reading a frame back: the image and the G-buffer, mapped from the GPU, and the CPU
//! reference's image of the same G-buffer.

use glam::Vec3;
use oslf_geometry::Camera;

use super::targets::{padded_row, SizedTargets};
use super::Renderer;
use crate::error::{Result, RuntimeError};
use crate::pipelines::DEPTH_CLEAR;
use crate::reference::GTexel;
use crate::shading::ShadingParams;
use crate::Gpu;

impl Renderer {
    /// Reads one of the targets (an `Rgba32Float` texture) back to the CPU, row-major.
    pub(super) fn read_texture_rgba32f(
        &self,
        pick: impl Fn(&SizedTargets) -> &wgpu::Texture,
    ) -> Result<Vec<[f32; 4]>> {
        self.read_texture(pick, wgpu::TextureAspect::All)
    }

    /// Reads aspect `aspect` of a render target back, texel type `T`, row-major.
    pub(super) fn read_texture<T: bytemuck::Pod>(
        &self,
        pick: impl Fn(&SizedTargets) -> &wgpu::Texture,
        aspect: wgpu::TextureAspect,
    ) -> Result<Vec<T>> {
        let texel = std::mem::size_of::<T>();
        let targets = self
            .targets
            .as_ref()
            .ok_or_else(|| RuntimeError::gpu("render targets missing"))?;
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
        let m: Vec<[u32; 4]> = match self.textures {
            Some(_) => self.read_texture(|t| &t.gb_material, wgpu::TextureAspect::All)?,
            None => vec![[0; 4]; z.len()],
        };
        Ok(p.into_iter()
            .zip(n)
            .zip(z)
            .zip(m)
            .map(|(((position_patch, normal_uv), z), material)| {
                if z < DEPTH_CLEAR {
                    GTexel {
                        position_patch,
                        normal_uv,
                        material,
                    }
                } else {
                    GTexel::default()
                }
            })
            .collect())
    }

    /// Shades the last frame's G-buffer on the CPU with the reference implementation, reading
    /// cube maps from `cubes`, with the last frame's size and [`RenderOptions::background`](super::RenderOptions::background).
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
            .map_err(|error| RuntimeError::Store {
                path: "sample maps".into(),
                error,
            })?;
        let feedback: Vec<AtomicU32> = (0..self.cube_count).map(|_| AtomicU32::new(0)).collect();
        let irradiance = crate::buffers::irradiance_coefficients(&self.store);
        let shader = crate::reference::Shader {
            uniform: self.uniform(camera, params, w, h, self.background),
            samples: &samples,
            irradiance: &irradiance,
            patches: &self.mesh.patches,
            colors: &self.mesh.colors,
            materials: &self.mesh.materials,
            emissions: &self.mesh.emissions,
            maps: &maps,
            cubes,
            feedback: &feedback,
            prefiltered: match &self.prefiltered {
                Some(p) => p,
                None => &crate::reference::NoPrefiltered,
            },
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

/// Maps a MAP_READ buffer, waits, and copies its bytes out ([`Gpu::read_buffer`]).
pub(super) fn map_read(gpu: &Gpu, buffer: &wgpu::Buffer) -> Result<Vec<u8>> {
    Ok(gpu.read_buffer(buffer)?)
}
