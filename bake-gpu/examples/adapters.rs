//! Lists the adapters wgpu finds and what the GPU bake cares about on each: the device type,
//! whether it shares system memory, hardware ray queries (`EXPERIMENTAL_RAY_QUERY`), and the
//! storage-buffer and workgroup limits the capture sizes its batches by.
//!
//! `cargo run --release -p oslf-bake-gpu --example adapters`

fn main() {
    let backends = wgpu::Backends::from_env().unwrap_or(wgpu::Backends::all());
    let mut desc = wgpu::InstanceDescriptor::new_without_display_handle_from_env();
    desc.backends = backends;
    let instance = wgpu::Instance::new(desc);
    let adapters = pollster::block_on(instance.enumerate_adapters(backends));
    if adapters.is_empty() {
        eprintln!("no adapter found");
        std::process::exit(1);
    }
    for adapter in adapters {
        let info = adapter.get_info();
        let features = adapter.features();
        let limits = adapter.limits();
        println!(
            "{} ({}, {:?}, {:?})",
            info.name, info.driver_info, info.backend, info.device_type
        );
        println!(
            "  ray queries: {}, ray-tracing pipelines: {}",
            features.contains(wgpu::Features::EXPERIMENTAL_RAY_QUERY),
            features.contains(wgpu::Features::EXPERIMENTAL_RAY_TRACING_PIPELINES)
        );
        println!(
            "  max storage buffer: {} MiB, max buffer: {} MiB, max workgroup invocations: {}",
            limits.max_storage_buffer_binding_size >> 20,
            limits.max_buffer_size >> 20,
            limits.max_compute_invocations_per_workgroup
        );
    }
}
