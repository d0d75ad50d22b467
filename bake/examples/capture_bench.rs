//! Cube-map capture throughput on one thread, without the sample maps: builds the scene's BVH,
//! places its sample points and captures cube maps at the first `N` of them, printing rays per
//! CPU-second of this thread and a hash of every captured texel (to compare builds).
//!
//! `cargo run --release -p oslf-bake --example capture_bench -- SCENE [N] [FIRST]`

use std::path::Path;
use std::time::Instant;

use glam::Vec3;
use oslf_scene::scene::Scene;
use oslf_trace::bvh::TriangleScene;
use oslf_trace::capture::{capture_cube, CaptureSettings};
use oslf_trace::integrator::{Integrator, RayStats};

/// CPU nanoseconds run by this thread (Linux `schedstat`).
fn thread_cpu_ns() -> u64 {
    std::fs::read_to_string("/proc/thread-self/schedstat")
        .ok()
        .and_then(|s| s.split_whitespace().next()?.parse().ok())
        .unwrap_or(0)
}

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().collect();
    let scene = Scene::load(Path::new(&args[1]), None)?;
    let n: usize = args.get(2).map_or(Ok(16), |s| s.parse())?;
    let first: usize = args.get(3).map_or(Ok(0), |s| s.parse())?;
    let settings = &scene.bake;
    let geometry = TriangleScene::build(oslf_trace::bvh::scene_instances(
        &scene,
        true,
        settings.epsilon * oslf_scene::tolerance::TESSELLATION_ERROR,
    ))?;
    let placement = oslf_bake::sample_points::place(
        &oslf_bake::surface::Surfaces::new(&scene.objects, settings)?,
        settings,
        &geometry,
    )?;
    let capture = CaptureSettings::from_bake(settings);
    let integrator = Integrator::for_scene(&scene, &geometry);
    let mut hash = 0xcbf2_9ce4_8422_2325u64;
    let mut rays = RayStats::default();
    let wall = Instant::now();
    let cpu = thread_cpu_ns();
    for (i, p) in placement.points.iter().enumerate().skip(first).take(n) {
        let (cube, stats) = capture_cube(
            &integrator,
            Vec3::from_array(p.position),
            i as u32,
            &capture,
        );
        rays.add(&stats);
        for face in &cube.faces {
            for t in face {
                for c in t {
                    hash = (hash ^ c.to_bits() as u64).wrapping_mul(0x100_0000_01b3);
                }
            }
        }
    }
    let cpu_s = (thread_cpu_ns() - cpu) as f64 / 1e9;
    println!(
        "{} closest + {} shadow rays, {:.2} CPU-s, {:.2} wall-s: {:.3} Mrays per CPU-second; hash {hash:016x}",
        rays.closest,
        rays.shadow,
        cpu_s,
        wall.elapsed().as_secs_f64(),
        rays.total() as f64 / cpu_s / 1e6
    );
    Ok(())
}
