//! `--device auto|cpu|gpu`: which device captures a bake's cube maps, and why
//! ([`oslf_bake_gpu::choice`]).

use std::sync::Arc;

use anyhow::Context;
use oslf_bake_gpu::GpuCapture;
use oslf_scene::scene::{DeviceChoice, Scene};

/// The GPU capture for `scene` by `choice` (`None`: the CPU path tracer), and the reason, for
/// the summary; said on stderr unless `quiet`. The GPU also renders the bake's preview.
pub fn capture_device(
    scene: &Scene,
    choice: DeviceChoice,
    flag: &str,
    quiet: bool,
) -> anyhow::Result<(Option<Arc<GpuCapture>>, String)> {
    let chosen = oslf_bake_gpu::choice::capture_device(scene, choice, flag)
        .with_context(|| format!("{flag} {choice}: no GPU capture"))?;
    if !quiet {
        eprintln!("capture on {}", chosen.1);
    }
    Ok(chosen)
}
