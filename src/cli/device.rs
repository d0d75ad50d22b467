//! `--device auto|cpu|gpu`: which device captures a bake's cube maps, and why.

use std::sync::Arc;

use anyhow::Context;
use oslf_bake::scene::DeviceChoice;
use oslf_bake::scene::Scene;
use oslf_bake_gpu::GpuCapture;
use oslf_runtime::Gpu;

/// The GPU capture for `scene` by `choice` (`None`: the CPU path tracer), and the reason, for
/// the summary; said on stderr unless `quiet`. The GPU also renders the bake's preview.
pub fn capture_device(
    scene: &Scene,
    choice: DeviceChoice,
    flag: &str,
    quiet: bool,
) -> anyhow::Result<(Option<Arc<GpuCapture>>, String)> {
    let chosen = choose(scene, choice, flag)?;
    if !quiet {
        eprintln!("capture on {}", chosen.1);
    }
    Ok(chosen)
}

fn choose(
    scene: &Scene,
    choice: DeviceChoice,
    flag: &str,
) -> anyhow::Result<(Option<Arc<GpuCapture>>, String)> {
    match choice {
        DeviceChoice::Cpu => Ok((None, format!("CPU, as {flag} asks"))),
        DeviceChoice::Gpu => {
            let gpu = Gpu::headless().with_context(|| format!("{flag} gpu: no GPU to bake on"))?;
            let reason = if gpu.shares_system_memory {
                format!(
                    "GPU {}, as {flag} asks (a CPU adapter: the CPU path is usually faster there)",
                    gpu.adapter_name
                )
            } else {
                format!("GPU {}, as {flag} asks", gpu.adapter_name)
            };
            let capture = GpuCapture::for_scene(gpu, scene).context("the GPU capture")?;
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
                    // CPU, saying why; --device gpu makes that an error.
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
