//! The web viewer for real: `oslf serve` and `oslf export-web` started as processes, the page
//! (web/oslf-viewer.js) loaded in headless Chromium with WebGPU on SwiftShader, driven by
//! Playwright (web/tests/drive.mjs; `npm ci` in web/tests installs it, `.ci/run` does). The
//! page's canvas is compared with `oslf render`'s PNG of the same store and size.
//!
//! These tests fail, never skip, without Node.js, Playwright or Chromium: the message says
//! what to install.

use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::sync::OnceLock;

use super::common::{oslf, run_ok};

/// The image size of every comparison: small, as SwiftShader runs the shader on the CPU.
const W: u32 = 160;
const H: u32 = 120;

/// One browser test at a time: SwiftShader runs the shaders on the CPU, and several browsers
/// at once on a 2-core machine take minutes where one takes seconds.
fn one_browser() -> std::sync::MutexGuard<'static, ()> {
    static LOCK: std::sync::Mutex<()> = std::sync::Mutex::new(());
    LOCK.lock().unwrap_or_else(|e| e.into_inner())
}

/// A running `oslf serve` (or static server), stopped when dropped.
struct Server {
    child: Child,
    url: String,
}

impl Drop for Server {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// Starts `oslf serve` on a free port with `args` (stores and flags) and waits for its URL.
fn serve(args: &[&std::ffi::OsStr]) -> Server {
    let mut child = oslf("serve")
        .args(["--port", "0"])
        .args(args)
        .stdout(Stdio::piped())
        .stderr(Stdio::inherit())
        .spawn()
        .unwrap();
    let stdout = child.stdout.take().unwrap();
    let mut lines = BufReader::new(stdout).lines();
    let url = loop {
        let Some(Ok(line)) = lines.next() else {
            let status = child.wait().unwrap();
            panic!("oslf serve ended ({status}) before printing its URL");
        };
        if let Some(rest) = line.strip_prefix("serving") {
            break rest.split_whitespace().next().unwrap().to_string();
        }
    };
    // Keep reading stdout so that the server never blocks on a full pipe.
    std::thread::spawn(move || for _ in lines {});
    Server { child, url }
}

/// The Playwright driver, checked once: Node.js, web/tests/node_modules, Chromium.
fn driver() -> &'static Path {
    static DRIVER: OnceLock<PathBuf> = OnceLock::new();
    DRIVER.get_or_init(|| {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("web/tests");
        assert!(
            Command::new("node")
                .arg("--version")
                .output()
                .is_ok_and(|o| o.status.success()),
            "the web tests need Node.js (`node`): install it (apt-get install nodejs)"
        );
        assert!(
            dir.join("node_modules/playwright-core").is_dir(),
            "the web tests need Playwright: run `npm ci` in {}",
            dir.display()
        );
        let chromium = std::env::var("CHROMIUM").unwrap_or_else(|_| "/usr/bin/chromium".into());
        assert!(
            Path::new(&chromium).exists(),
            "the web tests need Chromium at {chromium} (apt-get install chromium, or set CHROMIUM)"
        );
        dir.join("drive.mjs")
    })
}

/// Loads `url` in headless Chromium, waits for the viewer to finish streaming (or to show an
/// error) and returns what it reported; with `png`, screenshots its canvas there.
fn drive(url: &str, png: Option<&Path>, extra: &[&str]) -> serde_json::Value {
    let mut cmd = Command::new("node");
    cmd.arg(driver()).arg(url).args(extra);
    if let Some(p) = png {
        cmd.arg("--png").arg(p);
    }
    let out = cmd.output().unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{cmd:?} failed:\n{stdout}\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: serde_json::Value = serde_json::from_str(stdout.trim())
        .unwrap_or_else(|e| panic!("driver output is not JSON ({e}): {stdout}"));
    assert!(v.get("driverError").is_none(), "the browser failed: {v}");
    v
}

/// Mean absolute difference of two 8-bit RGB images, as a fraction of full scale.
fn mean_abs_diff(a: &Path, b: &Path) -> f64 {
    let a = image::open(a).unwrap().to_rgb8();
    let b = image::open(b).unwrap().to_rgb8();
    assert_eq!(a.dimensions(), b.dimensions(), "image sizes differ");
    let sum: u64 = a
        .as_raw()
        .iter()
        .zip(b.as_raw())
        .map(|(&x, &y)| u64::from(x.abs_diff(y)))
        .sum();
    sum as f64 / (a.as_raw().len() as f64 * 255.0)
}

/// Bakes example `scene` (with the files it reads) into `dir` at a tiny preset, with `extra`
/// bake flags, as `name`.oslf.
fn bake_example(
    dir: &Path,
    scene: &str,
    files: &[&str],
    preset: &str,
    extra: &[&str],
    name: &str,
) -> PathBuf {
    let examples = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples");
    for f in files {
        std::fs::copy(examples.join(f), dir.join(f)).unwrap();
    }
    let mut text = std::fs::read_to_string(examples.join(scene)).unwrap();
    text.push_str(&format!("\n[presets.webtest]\n{preset}\n"));
    let path = dir.join(format!("{name}.toml"));
    std::fs::write(&path, text).unwrap();
    let store = dir.join(format!("{name}.oslf"));
    run_ok(
        oslf("bake")
            .arg(&path)
            .args([
                "--preset",
                "webtest",
                "--device",
                "cpu",
                "--preview",
                "none",
                "-q",
            ])
            .args(extra)
            .arg("-o")
            .arg(&store),
    );
    store
}

/// The test stores, baked once: Bézier patches as RGB9E5 and as BC6H, triangle meshes, and a
/// textured metallic-roughness object.
fn stores() -> &'static [PathBuf] {
    static STORES: OnceLock<(tempfile::TempDir, Vec<PathBuf>)> = OnceLock::new();
    &STORES
        .get_or_init(|| {
            let dir = tempfile::tempdir().unwrap();
            let d = dir.path();
            let gazebo = "sample_count = 40\ncube_resolution = 8\nsample_map_resolution = 32\nsamples_per_texel = 1";
            let stores = vec![
                bake_example(d, "gazebo.toml", &[], gazebo, &[], "gazebo"),
                bake_example(d, "gazebo.toml", &[], gazebo, &["--encoding", "bc6h"], "gazebo-bc6h"),
                bake_example(
                    d,
                    "meshes.toml",
                    &["blob.glb", "room.glb"],
                    "sample_spacing = 0.2\ncube_resolution = 8\nsample_map_resolution = 32\nsamples_per_texel = 1",
                    &[],
                    "meshes",
                ),
                bake_example(
                    d,
                    "orb.toml",
                    &["orb.glb", "room.glb"],
                    "sample_count = 40\ncube_resolution = 8\nsample_map_resolution = 32\nsamples_per_texel = 1",
                    &[],
                    "orb",
                ),
            ];
            (dir, stores)
        })
        .1
}

/// `oslf render`'s PNG of `store` at W×H with `flags`, into `out` (an .exr beside it).
fn render_png(store: &Path, out: &Path, flags: &[&str]) -> PathBuf {
    run_ok(
        oslf("render")
            .arg(store)
            .args(["--width", &W.to_string(), "--height", &H.to_string()])
            .args(flags)
            .arg("-o")
            .arg(out.with_extension("exr")),
    );
    out.with_extension("png")
}

#[test]
fn the_page_draws_what_oslf_render_draws() {
    let _browser = one_browser();
    let stores = stores();
    let dir = tempfile::tempdir().unwrap();
    let server = serve(&stores.iter().map(|s| s.as_os_str()).collect::<Vec<_>>());
    // Each store in its default mode and background (as `oslf render` without flags), and the
    // BC6H one also decoded to RGB9E5 (an adapter without BC compression). Glossy and pbr
    // frames point-sampled: SwiftShader does not finish compiling shade.wgsl's filtered
    // (FILTER) specialization (docs/web.md).
    let cases: Vec<(usize, &str, Vec<&str>)> = vec![
        (0, "", vec![]),
        (1, "", vec![]),
        (1, "&no-bc", vec!["--no-bc"]),
        (2, "&glossy-filter=point", vec!["--glossy-filter", "point"]),
        (3, "&glossy-filter=point", vec!["--glossy-filter", "point"]),
        (
            0,
            "&mode=recon-glossy&glossy-filter=point",
            vec!["--mode", "recon-glossy", "--glossy-filter", "point"],
        ),
    ];
    let mut report = Vec::new();
    for (i, query, flags) in cases {
        let name = format!("{i}{}", query.replace(['&', '='], "-"));
        let reference = render_png(
            &stores[i],
            &dir.path().join(format!("render-{name}")),
            &flags,
        );
        let page = dir.path().join(format!("page-{name}.png"));
        let url = format!("{}?store={i}&width={W}&height={H}{query}", server.url);
        let v = drive(&url, Some(&page), &[]);
        assert!(v["error"].is_null(), "{url}: the page shows an error: {v}");
        assert_eq!(
            v["lastFrame"]["misses"], 0,
            "{url}: cubes still missing: {v}"
        );
        let mad = mean_abs_diff(&page, &reference);
        report.push(format!(
            "{} {query}: {:.4} ({}, {} fetches retried)",
            stores[i].display(),
            mad,
            v["variant"],
            v["stats"]["retries"]
        ));
        assert!(
            mad < 0.01,
            "{url}: the page differs from oslf render by {:.2} % (mean absolute difference); \
             see {} and {}",
            mad * 100.0,
            page.display(),
            reference.display()
        );
    }
    eprintln!("page against oslf render:\n  {}", report.join("\n  "));
}

#[test]
fn the_page_streams_within_its_cache_budget() {
    let _browser = one_browser();
    let stores = stores();
    let store = stores[0].as_os_str();
    // The whole working set fits: the first frame misses, the cache fills, and the last frame
    // has everything.
    let server = serve(&[store]);
    let url = format!("{}?width={W}&height={H}", server.url);
    let first = drive(&url, None, &["--first-frame"]);
    assert!(
        first["stats"]["firstFrameMisses"].as_u64().unwrap() > 0,
        "{first}"
    );
    let full = drive(&url, None, &[]);
    let s = &full["stats"];
    assert!(full["error"].is_null(), "{full}");
    assert!(s["frames"].as_u64().unwrap() >= 2, "{full}");
    assert!(s["firstFrameMisses"].as_u64().unwrap() > 0, "{full}");
    assert_eq!(full["lastFrame"]["misses"], 0, "{full}");
    // Each needed cube once, and the environment cube.
    assert_eq!(
        s["loads"].as_u64().unwrap(),
        full["lastFrame"]["requests"].as_u64().unwrap(),
        "{full}"
    );
    drop(server);
    // A budget of 6 cubes: never more resident, and the frames go on with fallbacks.
    let server = serve(&[store, "--cache-slots".as_ref(), "6".as_ref()]);
    let small = drive(&format!("{}?width={W}&height={H}", server.url), None, &[]);
    let s = &small["stats"];
    assert!(small["error"].is_null(), "{small}");
    assert_eq!(small["slots"], 6, "{small}");
    assert!(s["maxResident"].as_u64().unwrap() <= 6, "{small}");
    assert!(s["maxInFlight"].as_u64().unwrap() <= 6, "{small}");
    assert!(
        small["lastFrame"]["misses"].as_u64().unwrap() > 0,
        "{small}"
    );
}

#[test]
fn a_missing_store_a_damaged_one_a_lost_device_and_no_webgpu_each_say_so() {
    let _browser = one_browser();
    let stores = stores();
    let dir = tempfile::tempdir().unwrap();
    // A copy of the store with every cube but the environment's damaged: the store opens,
    // and each cube the page asks for fails its checksum.
    let damaged = dir.path().join("damaged.oslf");
    let store = oslf_format::Store::open(&stores[0]).unwrap();
    let mut bytes = std::fs::read(&stores[0]).unwrap();
    for cube in (0..store.cube_count()).filter(|&c| Some(c) != store.env_cube_index()) {
        for face in 0..6 {
            let e = store.face_entry(cube, face).unwrap();
            bytes[e.offset as usize + (e.compressed_size as usize) / 2] ^= 0x5a;
        }
    }
    std::fs::write(&damaged, &bytes).unwrap();
    let server = serve(&[stores[0].as_os_str(), damaged.as_os_str()]);
    let missing = drive(&format!("{}?store=7", server.url), None, &[]);
    assert_eq!(missing["error"]["kind"], "missing", "{missing}");
    assert_eq!(missing["messageShown"], true, "{missing}");
    assert!(
        missing["message"].as_str().unwrap().contains("404"),
        "{missing}"
    );
    let bad = drive(
        &format!("{}?store=1&width={W}&height={H}", server.url),
        None,
        &[],
    );
    assert_eq!(bad["messageShown"], true, "{bad}");
    assert!(
        bad["message"].as_str().unwrap().contains("damaged.oslf"),
        "the message names the store: {bad}"
    );
    let lost = drive(
        &format!("{}?width={W}&height={H}", server.url),
        None,
        &["--lose-device"],
    );
    assert_eq!(lost["error"]["kind"], "device-lost", "{lost}");
    assert!(lost["message"].as_str().unwrap().contains("lost"), "{lost}");
    let none = drive(&server.url, None, &["--no-webgpu"]);
    assert_eq!(none["error"]["kind"], "no-webgpu", "{none}");
    assert!(
        none["message"].as_str().unwrap().contains("WebGPU"),
        "{none}"
    );
}

#[test]
fn export_web_writes_a_site_any_static_server_serves() {
    let _browser = one_browser();
    let stores = stores();
    let dir = tempfile::tempdir().unwrap();
    let site = dir.path().join("site");
    let out = run_ok(oslf("export-web").arg(&stores[1]).arg(&site).arg("-q"));
    assert!(out.contains("files"), "{out}");
    for f in [
        "index.html",
        "oslf-viewer.js",
        "shaders/shade.wgsl",
        "stores/0/manifest.json",
    ] {
        assert!(site.join(f).is_file(), "{f} missing: {out}");
    }
    // Both encodings of the BC6H store: a page on an adapter without BC compression reads
    // the RGB9E5 cubes.
    assert!(site.join("stores/0/cubes/bc6h/0.bin").is_file());
    assert!(site.join("stores/0/cubes/rgb9e5/0.bin").is_file());
    // Nothing already in the directory is replaced.
    let again = oslf("export-web")
        .arg(&stores[1])
        .arg(&site)
        .output()
        .unwrap();
    assert!(!again.status.success());
    assert!(String::from_utf8_lossy(&again.stderr).contains("not empty"));
    // Python's static file server: no oslf code serves the exported page.
    let port = free_port();
    let child = Command::new("python3")
        .args([
            "-m",
            "http.server",
            &port.to_string(),
            "--bind",
            "127.0.0.1",
            "--directory",
        ])
        .arg(&site)
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .expect("python3 for a static file server");
    let server = Server {
        child,
        url: format!("http://127.0.0.1:{port}/"),
    };
    wait_for_port(port);
    let page = dir.path().join("static.png");
    let v = drive(
        &format!("{}?width={W}&height={H}", server.url),
        Some(&page),
        &[],
    );
    assert!(v["error"].is_null(), "{v}");
    let reference = render_png(&stores[1], &dir.path().join("render"), &[]);
    let mad = mean_abs_diff(&page, &reference);
    assert!(
        mad < 0.01,
        "the exported page differs from oslf render by {:.2} %",
        mad * 100.0
    );
}

/// A TCP port nothing listens on now.
fn free_port() -> u16 {
    std::net::TcpListener::bind("127.0.0.1:0")
        .unwrap()
        .local_addr()
        .unwrap()
        .port()
}

/// Waits until something accepts connections on `port` (at most 10 s).
fn wait_for_port(port: u16) {
    for _ in 0..100 {
        if std::net::TcpStream::connect(("127.0.0.1", port)).is_ok() {
            return;
        }
        std::thread::sleep(std::time::Duration::from_millis(100));
    }
    panic!("nothing listens on port {port}");
}
