//! Frame times of every shading mode, cold and warm cache, at 655×460 and 1280×720.
//!
//! ```sh
//! cargo bench -p oslf-runtime --bench frame                 # bakes examples/gazebo.toml (quick preset) once
//! OSLF_STORE=path/to/store.oslf cargo bench -p oslf-runtime --bench frame
//! OSLF_BENCH_FILTER=mirror cargo bench -p oslf-runtime --bench frame   # only matching modes
//! ```
//!
//! *Cold*: a new renderer's first frame (empty cache: decode, upload, two shading passes).
//! *Warm*: the median of 7 frames after it, every cube resident (one pass, nothing loaded).
//! *Cache per warm frame*: the CPU time the cache costs a frame whose cubes are all resident
//! (copying the feedback masks out, planning, writing the indirection table), included in the
//! warm time; cold − warm is the cost of filling the cache (and of compiling the pipeline).
//! Frames are timed to GPU completion without reading the image back. Then, for each mirror
//! blend, OSLF and environment-map frames interleaved (21 each, medians) give the ratio of the
//! two in the same machine state; for four Ashikhmin–Shirley lobes, filtered importance sampling
//! at M = 16 (with and without depth correction) against the thesis's point sampling at M = 256,
//! likewise interleaved, frame times and (where the device has timestamp queries) the shading
//! pass's GPU time, which leaves out what every frame pays alike (G-buffer, feedback read-back,
//! cache), and the G-buffer pass's (`OSLF_BENCH_FILTER="glossy ratio"` runs only this part,
//! `OSLF_BENCH_ROUNDS` sets its rounds, `OSLF_BENCH_SIZE=1920x1080` its image size, 655×460
//! unless given). Writes Markdown tables to stdout and CSV to
//! `target/frame-times.csv` (`OSLF_BENCH_CSV` to write it elsewhere).

use std::path::{Path, PathBuf};
use std::time::Instant;

use oslf_bake::bake::{bake, BakeOptions};
use oslf_format::Store;
use oslf_runtime::{Blend, CacheConfig, Gpu, Mode, RenderOptions, Renderer, Source};
use oslf_scene::scene::Scene;

#[path = "../tests/common/knobs.rs"]
mod knobs;
use knobs::Knobs;

fn store_path() -> PathBuf {
    if let Ok(p) = std::env::var("OSLF_STORE") {
        return PathBuf::from(p);
    }
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..");
    let out = root.join("target").join("bench-gazebo.oslf");
    if !out.exists() {
        eprintln!(
            "baking examples/gazebo.toml (quick preset) to {}",
            out.display()
        );
        let scene = Scene::load(&root.join("examples").join("gazebo.toml"), None).unwrap();
        let options = BakeOptions {
            output: out.clone(),
            resume: false,
            progress: None,
            cube_limit: None,
            refuse_empty_texels: false,
            device: None,
        };
        bake(&scene, &options).unwrap();
    }
    out
}

/// A renderer of the store at `path` on `gpu` with the default cache (every cube fits).
fn renderer(gpu: &Gpu, path: &Path) -> Renderer {
    Renderer::new(
        gpu.clone(),
        Store::open(path).unwrap(),
        CacheConfig::default(),
    )
    .unwrap()
}

/// Options for a frame of `w` × `h` that is not read back.
fn frame_options(w: u32, h: u32) -> RenderOptions {
    RenderOptions {
        width: w,
        height: h,
        read_pixels: false,
        ..Default::default()
    }
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn main() {
    // `cargo bench` passes --bench; ignore arguments.
    let path = store_path();
    // One device for every renderer: a driver may run out of devices (an NVIDIA H200 found no
    // Vulkan adapter for the 30th in one process).
    let gpu = Gpu::headless().unwrap();
    // OSLF_BENCH_FILTER=text runs only the modes whose label contains it.
    let filter = std::env::var("OSLF_BENCH_FILTER").unwrap_or_default();
    let base = Knobs::default();
    let cases: Vec<(&str, Knobs)> = vec![
        (
            "recon",
            Knobs {
                mode: Mode::Recon,
                ..base
            },
        ),
        (
            "mirror, envmap baseline",
            Knobs {
                mode: Mode::Mirror,
                source: Source::EnvMap,
                ..base
            },
        ),
        (
            "mirror, B^n N=4",
            Knobs {
                mode: Mode::Mirror,
                ..base
            },
        ),
        (
            "mirror, closest distance",
            Knobs {
                mode: Mode::Mirror,
                blend: Blend::Distance,
                ..base
            },
        ),
        (
            "mirror, closest angle",
            Knobs {
                mode: Mode::Mirror,
                blend: Blend::Angle,
                ..base
            },
        ),
        (
            "mirror, B^r N=4",
            Knobs {
                mode: Mode::Mirror,
                blend: Blend::Reflection,
                ..base
            },
        ),
        (
            "recon + mirror, B^n N=4",
            Knobs {
                mode: Mode::ReconMirror,
                ..base
            },
        ),
        (
            "recon + mirror, closest distance",
            Knobs {
                mode: Mode::ReconMirror,
                blend: Blend::Distance,
                ..base
            },
        ),
        (
            "recon + mirror, B^r N=4",
            Knobs {
                mode: Mode::ReconMirror,
                blend: Blend::Reflection,
                ..base
            },
        ),
        (
            "glossy M=16, per point",
            Knobs {
                mode: Mode::Glossy,
                m: 16,
                ..base
            },
        ),
        (
            "glossy M=16, per point, plain lookups (FIS only)",
            Knobs {
                mode: Mode::Glossy,
                m: 16,
                depth: false,
                ..base
            },
        ),
        (
            "glossy M=16, per point, plain lookups, point sampling",
            Knobs {
                mode: Mode::Glossy,
                m: 16,
                depth: false,
                glossy_filter: oslf_runtime::GlossyFilter::Point,
                ..base
            },
        ),
        (
            "glossy M=16, per direction",
            Knobs {
                mode: Mode::Glossy,
                m: 16,
                order: oslf_runtime::Order::PerDirection,
                ..base
            },
        ),
        (
            "glossy M=16, per point visible",
            Knobs {
                mode: Mode::Glossy,
                m: 16,
                order: oslf_runtime::Order::PerPointVisible,
                ..base
            },
        ),
        (
            "glossy M=16, per point searched",
            Knobs {
                mode: Mode::Glossy,
                m: 16,
                order: oslf_runtime::Order::PerPointSearched,
                ..base
            },
        ),
        (
            "recon + glossy M=16",
            Knobs {
                mode: Mode::ReconGlossy,
                m: 16,
                ..base
            },
        ),
        (
            "glossy envmap M=16",
            Knobs {
                mode: Mode::Glossy,
                m: 16,
                source: Source::EnvMap,
                ..base
            },
        ),
    ];
    let mut csv =
        String::from("mode,width,height,cold_ms,warm_ms,warm_fps,cold_passes,cubes_loaded\n");
    println!("store: {}", path.display());
    let mut adapter = String::new();
    println!("| mode | size | cold frame (ms) | warm frame (ms) | warm frames/s | cache per warm frame (ms) |");
    println!("| --- | --- | ---: | ---: | ---: | ---: |");
    for (w, h) in [(655u32, 460u32), (1280, 720)] {
        for (label, params) in &cases {
            if !filter.is_empty() && !label.contains(filter.as_str()) {
                continue;
            }
            let store = Store::open(&path).unwrap();
            adapter = gpu.adapter_name.clone();
            // OSLF_BENCH_SLOTS=n limits the GPU cache (default: every cube).
            let slots = std::env::var("OSLF_BENCH_SLOTS")
                .ok()
                .map(|s| s.parse().unwrap());
            let mut r = Renderer::new(
                gpu.clone(),
                store,
                CacheConfig {
                    gpu_slots: slots,
                    ..Default::default()
                },
            )
            .unwrap();
            let camera = r.default_view();
            let opts = RenderOptions {
                width: w,
                height: h,
                read_pixels: false,
                ..Default::default()
            };
            let t = Instant::now();
            let cold = r.render(&camera, &params.params(), &opts).unwrap();
            let cold_ms = t.elapsed().as_secs_f64() * 1e3;
            let mut warm = Vec::new();
            let mut cache = Vec::new();
            for _ in 0..7 {
                let t = Instant::now();
                let f = r.render(&camera, &params.params(), &opts).unwrap();
                warm.push(t.elapsed().as_secs_f64() * 1e3);
                cache.push(f.stats.cache_seconds * 1e3);
                assert_eq!(f.stats.misses, 0);
            }
            let warm_ms = median(warm);
            let cache_ms = median(cache);
            println!(
                "| {label} | {w}×{h} | {cold_ms:.1} | {warm_ms:.1} | {:.2} | {cache_ms:.2} |",
                1e3 / warm_ms
            );
            csv.push_str(&format!(
                "{label},{w},{h},{cold_ms:.2},{warm_ms:.2},{:.3},{cache_ms:.3},{},{}\n",
                1e3 / warm_ms,
                cold.passes,
                cold.stats.loads
            ));
        }
    }
    println!("adapter: {adapter}");

    // OSLF mirror against the environment-map baseline, frames interleaved so that both see
    // the same machine state: the median of 21 warm frames each, per blend.
    println!();
    println!("| mirror blend | size | OSLF warm (ms) | environment map warm (ms) | ratio |");
    println!("| --- | --- | ---: | ---: | ---: |");
    for (w, h) in [(655u32, 460u32), (1280, 720)] {
        let opts = frame_options(w, h);
        let env = Knobs {
            mode: Mode::Mirror,
            source: Source::EnvMap,
            ..base
        };
        let mut r_env = renderer(&gpu, &path);
        let camera = r_env.default_view();
        r_env.render(&camera, &env.params(), &opts).unwrap();
        for blend in Blend::ALL {
            if !filter.is_empty() && !"mirror ratio".contains(filter.as_str()) {
                continue;
            }
            let oslf = Knobs {
                mode: Mode::Mirror,
                blend,
                ..base
            };
            let mut r = renderer(&gpu, &path);
            r.render(&camera, &oslf.params(), &opts).unwrap();
            let (mut a, mut b) = (Vec::new(), Vec::new());
            for _ in 0..21 {
                let t = Instant::now();
                r.render(&camera, &oslf.params(), &opts).unwrap();
                a.push(t.elapsed().as_secs_f64() * 1e3);
                let t = Instant::now();
                r_env.render(&camera, &env.params(), &opts).unwrap();
                b.push(t.elapsed().as_secs_f64() * 1e3);
            }
            let (a, b) = (median(a), median(b));
            println!(
                "| {} | {w}×{h} | {a:.1} | {b:.1} | {:.2} |",
                blend.name(),
                a / b
            );
            csv.push_str(&format!("ratio {},{w},{h},,{a:.2},,,,\n", blend.name()));
        }
    }
    // Filtered importance sampling at M = 16 against the thesis's point sampling at M = 256,
    // per lobe: warm frames interleaved (OSLF_BENCH_ROUNDS rounds, default 9, medians), so the
    // ratios compare the same machine state.
    let rounds: usize = std::env::var("OSLF_BENCH_ROUNDS")
        .ok()
        .map(|s| s.parse().unwrap())
        .unwrap_or(9);
    if filter.is_empty() || "glossy ratio".contains(filter.as_str()) {
        println!();
        println!("| lobe n_u:n_v | size | thesis M=256 (ms) | FIS M=16 (ms) | ratio | FIS + depth M=16 (ms) | ratio | thesis shading GPU (ms) | FIS shading GPU (ms) | ratio | FIS + depth shading GPU (ms) | ratio | G-buffer GPU (ms) |");
        println!(
            "| --- | --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |"
        );
        let (w, h) = match std::env::var("OSLF_BENCH_SIZE") {
            Ok(s) => s
                .split_once('x')
                .and_then(|(w, h)| Some((w.parse().ok()?, h.parse().ok()?)))
                .filter(|&(w, h): &(u32, u32)| w > 0 && h > 0)
                .unwrap_or_else(|| {
                    panic!("OSLF_BENCH_SIZE={s}: expected WIDTHxHEIGHT, e.g. 1920x1080")
                }),
            Err(_) => (655, 460),
        };
        let opts = frame_options(w, h);
        let mut r = renderer(&gpu, &path);
        let camera = r.default_view();
        for (nu, nv) in [
            (10.0, 10.0),
            (100.0, 100.0),
            (1000.0, 1000.0),
            (10.0, 1000.0),
        ] {
            let fis = Knobs {
                mode: Mode::Glossy,
                m: 16,
                nu,
                nv,
                ..base
            };
            let configs = [
                Knobs {
                    m: 256,
                    depth: false,
                    glossy_filter: oslf_runtime::GlossyFilter::Point,
                    ..fis
                },
                Knobs {
                    depth: false,
                    ..fis
                },
                fis,
            ];
            let mut times = vec![Vec::new(); configs.len()];
            let mut gpu_times = vec![Vec::new(); configs.len()];
            let mut gbuffer_times = Vec::new();
            for c in &configs {
                r.render(&camera, &c.params(), &opts).unwrap();
            }
            for _ in 0..rounds {
                for ((c, t), g) in configs.iter().zip(&mut times).zip(&mut gpu_times) {
                    let start = Instant::now();
                    let frame = r.render(&camera, &c.params(), &opts).unwrap();
                    t.push(start.elapsed().as_secs_f64() * 1e3);
                    g.extend(frame.shade_gpu_seconds.map(|s| s * 1e3));
                    gbuffer_times.extend(frame.gbuffer_gpu_seconds.map(|s| s * 1e3));
                }
            }
            let m: Vec<f64> = times.into_iter().map(median).collect();
            // Shading-pass GPU times, where the device has timestamp queries.
            let g: Vec<String> = if gpu_times.iter().all(|g| g.len() == rounds) {
                let g: Vec<f64> = gpu_times.into_iter().map(median).collect();
                vec![
                    format!("{:.2}", g[0]),
                    format!("{:.2}", g[1]),
                    format!("{:.3}", g[1] / g[0]),
                    format!("{:.2}", g[2]),
                    format!("{:.3}", g[2] / g[0]),
                    format!("{:.2}", median(gbuffer_times)),
                ]
            } else {
                vec!["–".to_string(); 6]
            };
            println!(
                "| {nu}:{nv} | {w}×{h} | {:.1} | {:.1} | {:.3} | {:.1} | {:.3} | {} |",
                m[0],
                m[1],
                m[1] / m[0],
                m[2],
                m[2] / m[0],
                g.join(" | ")
            );
            csv.push_str(&format!(
                "glossy ratio {nu}:{nv},{w},{h},,{:.2},,,,\nglossy ratio {nu}:{nv} FIS M=16,{w},{h},,{:.2},,,,\nglossy ratio {nu}:{nv} FIS+depth M=16,{w},{h},,{:.2},,,,\n",
                m[0], m[1], m[2]
            ));
        }
    }
    // OSLF_BENCH_CSV: elsewhere (a binary run from another checkout, scripts/device-kit.sh).
    let out = std::env::var_os("OSLF_BENCH_CSV").map_or_else(
        || PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../target/frame-times.csv"),
        PathBuf::from,
    );
    std::fs::write(&out, csv).unwrap();
    println!("wrote {}", out.display());
}
