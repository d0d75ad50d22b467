//! The LRU cube-map cache: budgets, granularity, fallback, statistics.

use crate::common;
use crate::common::knobs::Knobs;

use common::{all_finite, compare, mean, open_store};
use oslf_runtime::reference::StoreCubes;
use oslf_runtime::{CacheConfig, Gpu, Granularity, Mode, RenderOptions, Renderer};

fn options() -> RenderOptions {
    RenderOptions {
        width: 80,
        height: 60,
        ..Default::default()
    }
}

fn renderer(slots: Option<u32>, granularity: Granularity) -> Renderer {
    let config = CacheConfig {
        gpu_slots: slots,
        ram_bytes: 1 << 20,
        granularity,
        slots_per_texture: None,
    };
    Renderer::new(Gpu::headless().unwrap(), open_store(), config).unwrap()
}

#[test]
fn a_budget_holding_the_working_set_gives_the_unlimited_image_and_less_degrades_gracefully() {
    let params = Knobs::default(); // recon + C_s mirror, B^n N=4
    let mut full = renderer(None, Granularity::Cube);
    let camera = full.default_view();
    let exact = full.render(&camera, &params.params(), &options()).unwrap();
    let working_set = exact.stats.requests as u32;
    assert!(working_set > 10 && working_set < full.store().cube_count());
    assert_eq!(
        exact.stats.misses,
        exact.stats.requests - 1,
        "cold: only the pinned environment cube hits"
    );

    // Exactly the working set: the same image, bit for bit.
    let mut fit = renderer(Some(working_set), Granularity::Cube);
    let frame = fit.render(&camera, &params.params(), &options()).unwrap();
    assert_eq!(frame.stats.unresolved, 0);
    assert_eq!(
        frame.pixels, exact.pixels,
        "a budget that holds the working set changes the image"
    );
    // Warm: the next frame hits everything and loads nothing.
    let warm = fit.render(&camera, &params.params(), &options()).unwrap();
    assert_eq!(
        (warm.stats.hits, warm.stats.misses, warm.stats.loads),
        (warm.stats.requests, 0, 0)
    );
    assert_eq!(warm.passes, 1);

    // Half the working set: finite, close, and the shortfall reported.
    let mut half = renderer(Some(working_set / 2), Granularity::Cube);
    let frame = half.render(&camera, &params.params(), &options()).unwrap();
    assert!(frame.stats.unresolved > 0, "{:?}", frame.stats);
    assert!(all_finite(&frame.pixels));
    assert_ne!(frame.pixels, exact.pixels);
    let (_, _, mae) = compare(&frame.pixels, &exact.pixels, 1e-3);
    println!(
        "half budget: mean |Δ| {mae:.4} of mean {:.4}",
        mean(&exact.pixels)
    );
    assert!(mae < 0.5 * mean(&exact.pixels), "fallback far off: {mae}");

    // The CPU reference with the same residency reproduces the fallback image.
    let mut cubes = StoreCubes::decode(half.store()).unwrap();
    cubes.masks = Some(half.cache().indirection());
    let (cpu, _) = half
        .reference_image(&camera, &params.params(), &cubes)
        .unwrap();
    let (_, share, _) = compare(&frame.pixels, &cpu, 2e-3);
    assert!(share >= 0.995, "fallback parity {share}");
}

#[test]
fn cube_granularity_loads_whole_cubes_and_face_granularity_only_what_is_read() {
    let params = Knobs {
        mode: Mode::Recon,
        ..Default::default()
    };
    let mut cube = renderer(None, Granularity::Cube);
    let mut face = renderer(None, Granularity::Face);
    let camera = cube.default_view();
    let a = cube.render(&camera, &params.params(), &options()).unwrap();
    let b = face.render(&camera, &params.params(), &options()).unwrap();
    assert_eq!(a.pixels, b.pixels);
    println!("cube: {:?}\nface: {:?}", a.stats, b.stats);
    assert!(b.stats.bytes_uploaded < a.stats.bytes_uploaded);
    assert!(b.stats.requests > a.stats.requests, "faces outnumber cubes");
    // A face's payload: its texels, their mip levels and its distance plane.
    let face_bytes = cube.face_layout().payload_bytes() as u64;
    assert!(face_bytes > (cube.store().cube_resolution().pow(2) * 4) as u64);
    assert_eq!(a.stats.bytes_uploaded, a.stats.loads * 6 * face_bytes);
    assert_eq!(b.stats.bytes_uploaded, b.stats.loads * face_bytes);
}

#[test]
fn lru_evicts_the_least_recently_used_and_statistics_add_up() {
    let params = Knobs::default();
    let mut r = renderer(Some(40), Granularity::Cube);
    let camera = r.default_view();
    let mut other = camera;
    other.position = camera.target + (camera.target - camera.position); // the far side
    for c in [camera, other, camera] {
        let f = r.render(&c, &params.params(), &options()).unwrap();
        assert!(all_finite(&f.pixels));
        assert_eq!(f.stats.hits + f.stats.misses, f.stats.requests);
    }
    let s = r.cache().cumulative.clone();
    println!("{s:?}");
    assert_eq!(s.frames, 3);
    assert!(s.evictions > 0, "a 40-slot cache over two views must evict");
    assert!(
        s.ram_hits > 0,
        "the RAM level serves faces evicted from the GPU"
    );
    assert!(s.miss_rate > 0.0 && s.miss_rate < 1.0);
    let json = serde_json::to_string(&s).unwrap();
    assert!(json.contains("\"miss_rate\""));
}

#[test]
fn impossible_budgets_and_sizes_are_refused_with_the_reason() {
    let e = Renderer::new(
        Gpu::headless().unwrap(),
        open_store(),
        CacheConfig {
            gpu_slots: Some(1 << 30),
            ..Default::default()
        },
    )
    .err()
    .unwrap()
    .to_string();
    assert!(e.contains("at most"), "{e}");
    let mut r = renderer(None, Granularity::Cube);
    let camera = r.default_view();
    let e = r
        .render(
            &camera,
            &Knobs::default().params(),
            &RenderOptions {
                width: 0,
                ..options()
            },
        )
        .unwrap_err()
        .to_string();
    assert!(e.contains("image size"), "{e}");
}

#[test]
fn a_damaged_cube_map_falls_back_and_is_reported_while_the_render_goes_on() {
    let path = common::store_path();
    let store = open_store();
    let mut bytes = std::fs::read(&path).unwrap();
    // Damage one face of every cube the first frame needs: here simply faces 0..6 of cube 3.
    for face in 0..6 {
        let e = store.face_entry(3, face).unwrap();
        bytes[e.offset as usize + (e.compressed_size as usize) / 2] ^= 0x5a;
    }
    let damaged = path.with_file_name("damaged.oslf");
    std::fs::write(&damaged, &bytes).unwrap();
    let store = oslf_format::Store::open(&damaged).unwrap();
    let mut r = Renderer::new(Gpu::headless().unwrap(), store, CacheConfig::default()).unwrap();
    let camera = r.default_view();
    let params = Knobs::default();
    let mut total_errors = 0;
    // Orbit until cube 3 is needed; every frame must render.
    for k in 0..8 {
        let mut c = camera;
        let a = k as f32 * std::f32::consts::FRAC_PI_4;
        let d = c.position - c.target;
        c.position = c.target
            + glam::Vec3::new(
                d.x * a.cos() - d.y * a.sin(),
                d.x * a.sin() + d.y * a.cos(),
                d.z,
            );
        let f = r.render(&c, &params.params(), &options()).unwrap();
        assert!(all_finite(&f.pixels));
        total_errors += f.stats.decode_errors;
    }
    assert!(total_errors > 0, "cube 3 was never needed");
    let errors = &r.cache().errors;
    assert!(
        errors.iter().any(|e| e.cube == 3
            && e.to_string().contains("cube 3")
            && e.message.contains("checksum")),
        "{errors:?}"
    );
    assert_eq!(
        r.cache().resident_faces(3),
        0,
        "a damaged cube must not become resident"
    );
}

#[test]
fn streaming_decodes_off_the_render_thread_and_converges_to_the_exact_image() {
    let params = Knobs::default();
    let mut exact_r = renderer(None, Granularity::Cube);
    let camera = exact_r.default_view();
    let exact = exact_r
        .render(&camera, &params.params(), &options())
        .unwrap();

    let mut r = renderer(None, Granularity::Cube);
    let stream = RenderOptions {
        resolve_misses: false,
        ..options()
    };
    let first = r.render(&camera, &params.params(), &stream).unwrap();
    assert_eq!(first.passes, 1);
    assert!(first.stats.misses > 0);
    assert_eq!(
        first.stats.loads, 0,
        "nothing decoded yet: decoding runs in the background"
    );
    assert!(all_finite(&first.pixels));
    let mut frames = 1;
    loop {
        std::thread::sleep(std::time::Duration::from_millis(20));
        let f = r.render(&camera, &params.params(), &stream).unwrap();
        frames += 1;
        if f.stats.misses == 0 {
            assert_eq!(
                f.pixels, exact.pixels,
                "streamed image differs once everything is resident"
            );
            break;
        }
        assert!(frames < 200, "streaming never converged: {:?}", f.stats);
    }
    println!("converged after {frames} frames");
}

#[test]
fn renders_on_a_device_the_application_owns() {
    let instance =
        wgpu::Instance::new(wgpu::InstanceDescriptor::new_without_display_handle_from_env());
    let adapter = pollster::block_on(instance.request_adapter(&Default::default())).unwrap();
    let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
        required_limits: adapter.limits(),
        ..Default::default()
    }))
    .unwrap();
    let gpu = Gpu::from_device(device.clone(), queue, "application device".into());
    let mut r = Renderer::new(gpu, open_store(), CacheConfig::default()).unwrap();
    let camera = r.default_view();
    let frame = r
        .render(&camera, &Knobs::default().params(), &options())
        .unwrap();
    assert!(mean(&frame.pixels) > 1e-3);
    // The application's handle still works beside the renderer.
    let _ = device.create_buffer(&wgpu::BufferDescriptor {
        label: None,
        size: 16,
        usage: wgpu::BufferUsages::UNIFORM,
        mapped_at_creation: false,
    });
}

#[test]
fn frame_bytes_count_every_target() {
    use oslf_runtime::FrameBytes;
    // Position and normal (RGBA f32), depth (f32), output (RGBA f32): 52 bytes a pixel; the
    // read-back rows padded to 256 bytes, plus the pixel vector.
    let f = FrameBytes::of(100, 10);
    assert_eq!(f.gpu, 100 * 10 * 52);
    assert_eq!(f.readback, 1792 * 10 + 100 * 10 * 16);
    assert_eq!(FrameBytes::of(16384, 16384).gpu, 16384 * 16384 * 52);
}
