//! The prefiltered environment on the GPU: built from the store's environment cube the first
//! time a frame asks for the split-sum baseline, then kept ([`crate::prefilter`]).

use crate::error::{Result, RuntimeError};
use crate::prefilter::{level_size, PrefilteredEnv};
use crate::Gpu;

use super::Renderer;

/// The texture `prefiltered` of shade.wgsl holding `env`: 12 layers of RGBA f32, one mip per
/// specular level.
pub(super) fn upload(gpu: &Gpu, env: &PrefilteredEnv) -> wgpu::TextureView {
    let n = env.resolution.max(1);
    let levels = env.specular.len() as u32;
    let texture = gpu.device.create_texture(&wgpu::TextureDescriptor {
        label: Some("prefiltered environment"),
        size: wgpu::Extent3d {
            width: n,
            height: n,
            depth_or_array_layers: 12,
        },
        mip_level_count: levels,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: wgpu::TextureFormat::Rgba32Float,
        usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
        view_formats: &[],
    });
    for level in 0..levels {
        let side = level_size(n, level);
        let texels = env.texture_level(level);
        gpu.queue.write_texture(
            wgpu::TexelCopyTextureInfo {
                texture: &texture,
                mip_level: level,
                origin: wgpu::Origin3d::ZERO,
                aspect: wgpu::TextureAspect::All,
            },
            bytemuck::cast_slice(&texels),
            wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(side * 16),
                rows_per_image: Some(side),
            },
            wgpu::Extent3d {
                width: side,
                height: side,
                depth_or_array_layers: 12,
            },
        );
    }
    texture.create_view(&wgpu::TextureViewDescriptor {
        dimension: Some(wgpu::TextureViewDimension::D2Array),
        ..Default::default()
    })
}

impl Renderer {
    /// Prefilters the store's environment cube and binds it, unless done already. The shading
    /// bind group is rebuilt on the next frame.
    pub(super) fn ensure_prefiltered(&mut self) -> Result<()> {
        if self.prefiltered.is_some() {
            return Ok(());
        }
        let Some(env) = self.store.env_cube_index() else {
            return Err(RuntimeError::Parameter(
                "glossy filter split-sum: the store has no environment cube to prefilter \
                 (bake with env_cube = true)"
                    .into(),
            ));
        };
        let cube = self
            .store
            .read_cube(env)
            .map_err(|error| RuntimeError::Store {
                path: format!("environment cube {env}").into(),
                error,
            })?;
        let prefiltered = PrefilteredEnv::new(&cube);
        self.prefiltered_view = upload(&self.gpu, &prefiltered);
        self.prefiltered = Some(prefiltered);
        self.targets = None;
        Ok(())
    }
}
