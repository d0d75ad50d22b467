//! Which device captures a bake's cube maps ([`DeviceChoice`]), and why: shared by `oslf
//! bake` and the sweep.

use std::sync::Arc;

use oslf_gpu::Gpu;
use oslf_scene::scene::{DeviceChoice, Scene};

use crate::capture::GpuCapture;
use crate::error::Result;

/// The GPU capture for `scene` by `choice` (`None`: the CPU path tracer), and the reason, in
/// words; `asked_by` names what made the choice (`--device`, `[bake] device`).
///
/// - `cpu`: the CPU.
/// - `gpu`: the best adapter there is (a CPU adapter such as lavapipe too, saying that the
///   CPU path is usually faster there); an error when there is none or it cannot take the
///   scene.
/// - `auto`: a hardware adapter when there is one and it takes the scene, else the CPU,
///   saying why.
pub fn capture_device(
    scene: &Scene,
    choice: DeviceChoice,
    asked_by: &str,
) -> Result<(Option<Arc<GpuCapture>>, String)> {
    match choice {
        DeviceChoice::Cpu => Ok((None, format!("CPU, as {asked_by} asks"))),
        DeviceChoice::Gpu => {
            let gpu = Gpu::headless()?;
            let reason = if gpu.shares_system_memory {
                format!(
                    "GPU {}, as {asked_by} asks (a CPU adapter: the CPU path is usually faster there)",
                    gpu.adapter_name
                )
            } else {
                format!("GPU {}, as {asked_by} asks", gpu.adapter_name)
            };
            let capture = GpuCapture::for_scene(gpu, scene)?;
            Ok((Some(Arc::new(capture)), reason))
        }
        DeviceChoice::Auto => match Gpu::headless() {
            Ok(gpu) if !gpu.shares_system_memory => {
                let name = gpu.adapter_name.clone();
                match GpuCapture::for_scene(gpu, scene) {
                    Ok(capture) => Ok((
                        Some(Arc::new(capture)),
                        format!("GPU {name} (auto: a hardware adapter)"),
                    )),
                    // A scene the GPU cannot hold (a buffer over its limits, say) bakes on the
                    // CPU, saying why; `gpu` makes that an error.
                    Err(e) => Ok((
                        None,
                        format!("CPU (auto: {name} cannot take this scene: {e})"),
                    )),
                }
            }
            Ok(gpu) => Ok((
                None,
                format!(
                    "CPU (auto: the only adapter, {}, runs on the CPU, where the CPU path is faster; --device gpu uses it anyway)",
                    gpu.adapter_name
                ),
            )),
            Err(e) => Ok((None, format!("CPU (auto: no GPU adapter: {e})"))),
        },
    }
}
