//! The GPU: a headless wgpu device, or one the application owns, and the error sink that turns
//! wgpu's validation errors into [`GpuError::Gpu`].

use std::sync::{Arc, Mutex};

use crate::GpuError;

type Result<T> = std::result::Result<T, GpuError>;

/// A wgpu device and queue with the limits the renderer may use.
///
/// Build one with [`Gpu::headless`], or wrap an application's own device with
/// [`Gpu::from_device`]. Uncaptured wgpu errors are collected, and every renderer call checks
/// them ([`Gpu::take_errors`]), so a validation error surfaces as an error, never as a silent
/// black image. A clone shares the device (and its error list): several renderers can run on
/// one device.
#[derive(Clone)]
pub struct Gpu {
    /// The device.
    pub device: wgpu::Device,
    /// Its queue.
    pub queue: wgpu::Queue,
    /// The adapter's name, driver and backend, for reports.
    pub adapter_name: String,
    /// Whether the "GPU" is the CPU (lavapipe, llvmpipe, WARP): its textures then live in
    /// system memory, which `oslf render` counts before it starts.
    pub shares_system_memory: bool,
    /// Whether the device has `TEXTURE_COMPRESSION_BC` enabled: BC6H stores are then uploaded
    /// as their blocks ([`Gpu::has_bc`]).
    bc: bool,
    errors: Arc<Mutex<Vec<String>>>,
    /// A host's device with the host's own uncaptured-error handler ([`Gpu::from_host_device`]):
    /// the renderer catches its errors in error scopes ([`Gpu::scoped`]).
    host_watched: bool,
}

impl Gpu {
    /// Creates a headless device on the best adapter there is (a real GPU, else a software
    /// rasterizer such as lavapipe), requesting the adapter's own limits: wgpu's defaults
    /// allow only 256 texture array layers.
    ///
    /// Vulkan, Metal and DX12 are tried first; the GL backend only when none of them has an
    /// adapter, so a machine with a Vulkan driver never probes EGL (whose platform probing
    /// prints stray errors). `WGPU_BACKEND` overrides the choice.
    ///
    /// The device gets `TEXTURE_COMPRESSION_BC` when the adapter offers it (lavapipe and
    /// desktop GPUs do), so BC6H stores are uploaded as they are ([`Gpu::has_bc`]), and
    /// `TIMESTAMP_QUERY` when offered, so frames report their shading pass's GPU time
    /// (the runtime's `Frame::shade_gpu_seconds`).
    ///
    /// Errors with [`GpuError::NoAdapter`], naming what to install, when there is none.
    pub fn headless() -> Result<Self> {
        Self::headless_with_bc(true)
    }

    /// [`Gpu::headless`] on a device without `TEXTURE_COMPRESSION_BC`, whatever the adapter
    /// offers: BC6H stores are then decoded on the CPU and uploaded as RGB9E5 (`--no-bc`).
    pub fn headless_without_bc() -> Result<Self> {
        Self::headless_with_bc(false)
    }

    /// [`Gpu::headless`], requesting BC texture compression only when `bc` (and the adapter
    /// offers it).
    pub fn headless_with_bc(bc: bool) -> Result<Self> {
        quiet_device_select_layer();
        let order = match wgpu::Backends::from_env() {
            Some(backends) => vec![backends],
            None => vec![wgpu::Backends::PRIMARY, wgpu::Backends::GL],
        };
        let mut last = String::from("no backend enabled");
        for backends in order {
            let mut desc = wgpu::InstanceDescriptor::new_without_display_handle_from_env();
            desc.backends = backends;
            let instance = wgpu::Instance::new(desc);
            match pollster::block_on(instance.request_adapter(&wgpu::RequestAdapterOptions {
                power_preference: wgpu::PowerPreference::HighPerformance,
                force_fallback_adapter: false,
                compatible_surface: None,
                apply_limit_buckets: false,
            })) {
                Ok(adapter) => return Self::on_adapter_with_bc(&adapter, bc),
                Err(e) => last = format!("{backends:?}: {e}"),
            }
        }
        Err(GpuError::NoAdapter(last))
    }

    /// Creates a device on `adapter` with the adapter's limits, and BC texture compression
    /// when the adapter offers it.
    pub fn on_adapter(adapter: &wgpu::Adapter) -> Result<Self> {
        Self::on_adapter_with_bc(adapter, true)
    }

    /// [`Gpu::on_adapter`], requesting `TEXTURE_COMPRESSION_BC` only when `bc` and the adapter
    /// offers it.
    pub fn on_adapter_with_bc(adapter: &wgpu::Adapter, bc: bool) -> Result<Self> {
        let info = adapter.get_info();
        let adapter_name = format!("{} ({}, {:?})", info.name, info.driver, info.backend);
        // The runtime's G-buffer and output are Rgba32Float render targets; GL adapters
        // such as llvmpipe over EGL cannot render to them, so stop here with the fix.
        let float_target = wgpu::TextureFormat::Rgba32Float;
        let usages = adapter
            .get_texture_format_features(float_target)
            .allowed_usages;
        if !usages.contains(wgpu::TextureUsages::RENDER_ATTACHMENT) {
            return Err(GpuError::Device {
                adapter: adapter_name,
                message: format!(
                    "it cannot render to {float_target:?} textures, which the G-buffer needs; \
                     install a Vulkan driver (Debian/Ubuntu: `apt-get install mesa-vulkan-drivers`) \
                     or use a GPU with Vulkan, Metal or DX12"
                ),
            });
        }
        let limits = adapter.limits();
        let mut features = adapter.features() & wgpu::Features::TIMESTAMP_QUERY;
        if bc {
            features |= adapter.features() & wgpu::Features::TEXTURE_COMPRESSION_BC;
        }
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("oslf"),
            required_features: features,
            required_limits: limits,
            experimental_features: wgpu::ExperimentalFeatures::disabled(),
            memory_hints: wgpu::MemoryHints::Performance,
            trace: wgpu::Trace::Off,
        }))
        .map_err(|e| GpuError::Device {
            adapter: adapter_name.clone(),
            message: e.to_string(),
        })?;
        let mut gpu = Self::from_device(device, queue, adapter_name);
        gpu.shares_system_memory = info.device_type == wgpu::DeviceType::Cpu;
        Ok(gpu)
    }

    /// Wraps a device and queue the application owns. Create it with the limits the store
    /// needs (the runtime's `Renderer::new` says which it lacks). BC6H stores are uploaded as blocks
    /// when the device has `TEXTURE_COMPRESSION_BC` enabled ([`Gpu::without_bc`] turns that
    /// off).
    pub fn from_device(device: wgpu::Device, queue: wgpu::Queue, adapter_name: String) -> Self {
        let mut gpu = Self::from_host_device(device, queue, adapter_name);
        gpu.host_watched = false;
        let sink = Arc::clone(&gpu.errors);
        gpu.device
            .on_uncaptured_error(Arc::new(move |e: wgpu::Error| {
                if let Ok(mut v) = sink.lock() {
                    v.push(e.to_string());
                }
            }));
        gpu
    }

    /// Wraps a device and queue that a host application owns and watches (an engine with its
    /// own uncaptured-error handler): unlike [`Gpu::from_device`], no handler is installed, so
    /// the host's stays. The renderer catches the errors of its own calls in error scopes
    /// instead ([`Gpu::scoped`]): the host's handler never sees the renderer's errors, nor the
    /// renderer the host's.
    pub fn from_host_device(
        device: wgpu::Device,
        queue: wgpu::Queue,
        adapter_name: String,
    ) -> Self {
        let bc = device
            .features()
            .contains(wgpu::Features::TEXTURE_COMPRESSION_BC);
        Self {
            device,
            queue,
            adapter_name,
            shares_system_memory: false,
            bc,
            errors: Arc::new(Mutex::new(Vec::new())),
            host_watched: true,
        }
    }

    /// Runs `f` and returns the validation and out-of-memory errors the device reported while
    /// it ran as [`GpuError::Gpu`] (else `f`'s result): in error scopes on a host's device
    /// ([`Gpu::from_host_device`]), otherwise from the error list ([`Gpu::take_errors`]).
    pub fn scoped<T, E: From<GpuError>>(
        &self,
        f: impl FnOnce() -> std::result::Result<T, E>,
    ) -> std::result::Result<T, E> {
        if !self.host_watched {
            let out = f();
            self.take_errors()?;
            return out;
        }
        let out_of_memory = self.device.push_error_scope(wgpu::ErrorFilter::OutOfMemory);
        let validation = self.device.push_error_scope(wgpu::ErrorFilter::Validation);
        let out = f();
        // Native error scopes resolve at once: nothing waits for the GPU here.
        let invalid = pollster::block_on(validation.pop());
        let memory = pollster::block_on(out_of_memory.pop());
        match invalid.or(memory) {
            Some(e) => Err(GpuError::Gpu(e.to_string()).into()),
            None => out,
        }
    }

    /// Whether renderers on this GPU upload BC6H stores as their blocks (`Bc6hRgbUfloat`): the
    /// device has `TEXTURE_COMPRESSION_BC` and it was not turned off. Otherwise BC6H faces are
    /// decoded on the CPU and uploaded as RGB9E5.
    pub fn has_bc(&self) -> bool {
        self.bc
    }

    /// This GPU with BC uploads turned off (the RGB9E5 fallback), the device unchanged.
    pub fn without_bc(mut self) -> Self {
        self.bc = false;
        self
    }

    /// Whether the device has `TIMESTAMP_QUERY` enabled: renderers on it then time their
    /// shading passes on the GPU (the runtime's `Frame::shade_gpu_seconds`).
    pub fn has_timestamps(&self) -> bool {
        self.device
            .features()
            .contains(wgpu::Features::TIMESTAMP_QUERY)
    }

    /// The limits of the device.
    pub fn limits(&self) -> wgpu::Limits {
        self.device.limits()
    }

    /// Returns an error if wgpu reported any since the last call.
    pub fn take_errors(&self) -> Result<()> {
        let mut v = self
            .errors
            .lock()
            .map_err(|_| GpuError::Gpu("the GPU error log was poisoned by a panic".to_string()))?;
        if v.is_empty() {
            Ok(())
        } else {
            let all = v.join("; ");
            v.clear();
            Err(GpuError::Gpu(all))
        }
    }

    /// Maps `buffer` (created with `MAP_READ`), waits for the GPU, and copies its bytes out.
    pub fn read_buffer(&self, buffer: &wgpu::Buffer) -> Result<Vec<u8>> {
        let (tx, rx) = std::sync::mpsc::channel();
        buffer.map_async(wgpu::MapMode::Read, .., move |r| {
            let _ = tx.send(r);
        });
        self.wait()?;
        rx.recv()
            .map_err(|_| GpuError::Gpu("buffer mapping was dropped".into()))?
            .map_err(|e| GpuError::Gpu(format!("cannot map a buffer: {e}")))?;
        let bytes = {
            let view = buffer
                .get_mapped_range(..)
                .map_err(|e| GpuError::Gpu(format!("cannot read a mapped buffer: {e}")))?;
            view.to_vec()
        };
        buffer.unmap();
        Ok(bytes)
    }

    /// Waits until the GPU has finished all submitted work.
    pub fn wait(&self) -> Result<()> {
        self.device
            .poll(wgpu::PollType::wait_indefinitely())
            .map_err(|e| GpuError::Gpu(e.to_string()))?;
        Ok(())
    }
}

/// Keeps Mesa's Vulkan device-selection layer from printing
/// `error: XDG_RUNTIME_DIR is invalid or not set in the environment.` (twice) on a machine with
/// no display server.
///
/// `VK_LAYER_MESA_device_select` is an *implicit* layer (loaded into every Vulkan instance by
/// the loader): to order GPUs by the one the desktop uses, it connects to Wayland, and
/// libwayland-client prints that line when `XDG_RUNTIME_DIR` is missing. Without
/// `XDG_RUNTIME_DIR` and without `DISPLAY` there is no desktop to ask, so the layer can only
/// print; its documented switch `NODEVICE_SELECT=1` turns it off. The adapter is then chosen by
/// wgpu's power preference as everywhere else. A user's own `NODEVICE_SELECT` is kept.
fn quiet_device_select_layer() {
    let runtime_dir_ok = std::env::var_os("XDG_RUNTIME_DIR")
        .map(|d| std::path::Path::new(&d).is_dir())
        .unwrap_or(false);
    let display = std::env::var_os("DISPLAY").is_some_and(|d| !d.is_empty());
    if !runtime_dir_ok && !display && std::env::var_os("NODEVICE_SELECT").is_none() {
        // Set before the first Vulkan instance exists, so the loader reads it when it loads
        // the layer; nothing else in this process reads the variable.
        std::env::set_var("NODEVICE_SELECT", "1");
    }
}
