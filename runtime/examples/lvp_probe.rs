//! Times a compute shader with one `rgba32float` storage-texture binding (`@group(0)
//! @binding(0)`, entry point `main`, 8×8 workgroups over 656×464 pixels) on the default
//! adapter: the probe that showed lavapipe paying for code a frame never runs.
//!
//! ```sh
//! cargo run --release -p oslf-runtime --example lvp_probe            # a shader that only stores
//! cargo run --release -p oslf-runtime --example lvp_probe -- my.wgsl
//! ```

use std::time::Instant;
fn main() -> anyhow::Result<()> {
    let gpu = oslf_runtime::Gpu::headless()?;
    let d = &gpu.device;
    let src = std::env::args()
        .nth(1)
        .map(std::fs::read_to_string)
        .transpose()?
        .unwrap_or_else(|| {
            r#"
@group(0) @binding(0) var out_image: texture_storage_2d<rgba32float, write>;
@compute @workgroup_size(8, 8, 1)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    textureStore(out_image, vec2<i32>(gid.xy), vec4<f32>(1.0));
}"#
            .to_string()
        });
    let m = d.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: None,
        source: wgpu::ShaderSource::Wgsl(src.into()),
    });
    let tex = d.create_texture(&wgpu::TextureDescriptor {
        label: None,
        size: wgpu::Extent3d {
            width: 656,
            height: 464,
            depth_or_array_layers: 1,
        },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: wgpu::TextureFormat::Rgba32Float,
        usage: wgpu::TextureUsages::STORAGE_BINDING,
        view_formats: &[],
    });
    let p = d.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: None,
        layout: None,
        module: &m,
        entry_point: Some("main"),
        compilation_options: Default::default(),
        cache: None,
    });
    let bg = d.create_bind_group(&wgpu::BindGroupDescriptor {
        label: None,
        layout: &p.get_bind_group_layout(0),
        entries: &[wgpu::BindGroupEntry {
            binding: 0,
            resource: wgpu::BindingResource::TextureView(&tex.create_view(&Default::default())),
        }],
    });
    for _ in 0..5 {
        let t = Instant::now();
        let mut e = d.create_command_encoder(&Default::default());
        {
            let mut pass = e.begin_compute_pass(&Default::default());
            pass.set_pipeline(&p);
            pass.set_bind_group(0, &bg, &[]);
            pass.dispatch_workgroups(82, 58, 1);
        }
        gpu.queue.submit([e.finish()]);
        gpu.wait()?;
        gpu.take_errors()?;
        println!("{:.1} ms", t.elapsed().as_secs_f64() * 1e3);
    }
    Ok(())
}
