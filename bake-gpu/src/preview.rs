//! The bake's preview on the GPU: the scene camera's image path traced by
//! shader/preview.wgsl with the capture's integrator, as `oslf_trace::preview::render` does on
//! the CPU (the same strata and random streams, so the same image up to rounding).

use glam::Vec3;
use oslf_geometry::camera::Camera;

use crate::capture::{GpuCapture, Params};
use crate::error::Result;
pub use crate::layouts::PreviewCamera;

impl GpuCapture {
    /// `camera`'s `width × height` image, `spp` samples per pixel (at least 1), random
    /// streams from `seed`: linear RGB, row-major.
    pub fn preview(
        &self,
        camera: &Camera,
        width: u32,
        height: u32,
        spp: u32,
        seed: u64,
    ) -> Result<Vec<Vec3>> {
        let (right, up, forward) = camera.basis();
        let vfov = if camera.vfov_deg.is_finite() {
            camera.vfov_deg.clamp(1e-3, 179.0)
        } else {
            60.0
        };
        let lens = PreviewCamera {
            position: camera.position.to_array(),
            width,
            right: right.to_array(),
            height,
            up: up.to_array(),
            tan_half: (0.5 * vfov.to_radians()).tan(),
            forward: forward.to_array(),
            spp: spp.max(1),
        };
        let device = &self.gpu.device;
        let pixels = u64::from(width) * u64::from(height);
        let bytes = pixels.max(1) * 16;
        let camera_buffer = wgpu::util::DeviceExt::create_buffer_init(
            device,
            &wgpu::util::BufferInitDescriptor {
                label: Some("preview camera"),
                contents: bytemuck::bytes_of(&lens),
                usage: wgpu::BufferUsages::UNIFORM,
            },
        );
        let (out, staging) = self.output_buffers("preview pixels", bytes);
        let uniform = self.params_buffer("preview params");
        let mut entries = self.scene_entries(&uniform);
        entries.extend([(12, &camera_buffer), (13, &out)]);
        let bind_group = self.bind_group(&self.preview, &entries);
        let params = Params {
            seed: [seed as u32, (seed >> 32) as u32],
            ..self.base
        };
        self.dispatch(
            &self.preview,
            &bind_group,
            &uniform,
            params,
            pixels,
            u64::from(lens.spp),
        );
        let mut encoder = device.create_command_encoder(&Default::default());
        encoder.copy_buffer_to_buffer(&out, 0, &staging, 0, bytes);
        self.gpu.queue.submit([encoder.finish()]);
        let read = self.read(&staging)?;
        self.check("rendering the preview")?;
        Ok(bytemuck::cast_slice::<u8, [f32; 4]>(&read)
            .iter()
            .take(pixels as usize)
            .map(|p| Vec3::new(p[0], p[1], p[2]))
            .collect())
    }
}
