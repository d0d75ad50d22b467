//! `oslf render` end to end: outputs, statistics, and errors that say what and where.

use crate::common;

use common::{oslf, read_exr, runtime_fixture};

fn render(args: &[&str]) -> std::process::Output {
    oslf("render").args(args).output().unwrap()
}

#[test]
fn renders_exr_and_png_and_prints_cache_statistics() {
    let store = runtime_fixture::store_path();
    let dir = store.parent().unwrap().join("cli");
    std::fs::create_dir_all(&dir).unwrap();
    let exr = dir.join("frame.exr");
    let json = dir.join("stats.json");
    let out = render(&[
        store.to_str().unwrap(),
        "-o",
        exr.to_str().unwrap(),
        "--mode",
        "recon-glossy",
        "--blend",
        "r",
        "-N",
        "8",
        "-M",
        "4",
        "--nu",
        "1000",
        "--nv",
        "10",
        "--width",
        "64",
        "--height",
        "48",
        "--granularity",
        "face",
        "--stats-json",
        json.to_str().unwrap(),
    ]);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{stdout}\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(stdout.contains("miss rate"), "{stdout}");
    let (_, px) = read_exr(&exr);
    assert_eq!(px.len(), 64 * 48);
    assert!(px.iter().any(|p| p[3] == 1.0) && px.iter().any(|p| p[3] == 0.0));
    assert!(px.iter().all(|p| p.iter().all(|c| c.is_finite())));
    assert!(exr.with_extension("png").exists());
    let stats: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    assert!(stats["frame"]["requests"].as_u64().unwrap() > 0);
    // The passes' GPU times where the adapter has timestamp queries (lavapipe and desktop
    // GPUs do), null where not; printed when known.
    for key in ["shade_gpu_seconds", "gbuffer_gpu_seconds"] {
        let gpu = &stats[key];
        match gpu.as_f64() {
            Some(s) => assert!(
                s > 0.0 && s.is_finite() && stdout.contains("on the GPU"),
                "{s}"
            ),
            None => assert!(gpu.is_null() && !stdout.contains("on the GPU"), "{gpu}"),
        }
    }
}

/// Renders the test store at 64×48 into `name`.exr with `extra` flags.
fn render_background(
    name: &str,
    store: &std::path::Path,
    extra: &[&str],
) -> (std::process::Output, std::path::PathBuf) {
    let dir = runtime_fixture::store_path()
        .parent()
        .unwrap()
        .join("cli-background");
    std::fs::create_dir_all(&dir).unwrap();
    let exr = dir.join(format!("{name}.exr"));
    let mut args = vec![
        store.to_str().unwrap(),
        "-o",
        exr.to_str().unwrap(),
        "--width",
        "64",
        "--height",
        "48",
    ];
    args.extend_from_slice(extra);
    (render(&args), exr)
}

/// The PNG beside `exr` as 8-bit RGB.
fn read_png(exr: &std::path::Path) -> Vec<[u8; 3]> {
    let png = image::open(exr.with_extension("png")).unwrap().to_rgb8();
    png.pixels().map(|p| p.0).collect()
}

#[test]
fn the_background_is_the_environment_cube_by_default_black_or_a_colour_on_request() {
    let store = runtime_fixture::store_path();
    let ok = |out: &std::process::Output| {
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        )
    };

    let (out, exr) = render_background("default", &store, &[]);
    ok(&out);
    let (w, env) = read_exr(&exr);
    assert_eq!((w, env.len()), (64, 64 * 48));
    assert!(env.iter().all(|p| p.iter().all(|c| c.is_finite())));
    assert!(
        env.iter().all(|p| p[3] == 0.0 || p[3] == 1.0),
        "alpha is the mask"
    );
    let background: Vec<usize> = (0..env.len()).filter(|&i| env[i][3] == 0.0).collect();
    assert!(
        background.len() > 64 * 48 / 10,
        "{} background pixels",
        background.len()
    );
    let lit = background
        .iter()
        .filter(|&&i| env[i][0] + env[i][1] + env[i][2] > 0.0)
        .count();
    assert!(
        lit * 100 >= background.len() * 99,
        "{lit} of {} background pixels show the environment",
        background.len()
    );
    let png = read_png(&exr);
    assert!(
        background.iter().any(|&i| png[i] != [0, 0, 0]),
        "the PNG shows the background"
    );

    let (out, exr) = render_background("none", &store, &["--background", "none"]);
    ok(&out);
    let (_, none) = read_exr(&exr);
    let png = read_png(&exr);
    for (i, (a, b)) in env.iter().zip(&none).enumerate() {
        assert_eq!(
            a[3], b[3],
            "the object mask does not depend on the background"
        );
        if b[3] == 0.0 {
            assert_eq!(*b, [0.0; 4]);
            assert_eq!(png[i], [0, 0, 0]);
        } else {
            assert_eq!(a, b, "object pixels do not depend on the background");
        }
    }

    let (out, exr) = render_background("colour", &store, &["--background", "0.25,0.5,2"]);
    ok(&out);
    let (_, colour) = read_exr(&exr);
    for p in colour.iter().filter(|p| p[3] == 0.0) {
        assert_eq!(*p, [0.25, 0.5, 2.0, 0.0]);
    }

    for (value, says) in [
        ("1,2", "three finite"),
        ("1,-2,3", "negative"),
        ("sky", "none, env, or a linear colour R,G,B"),
    ] {
        let (out, _) = render_background("bad", &store, &["--background", value]);
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success(), "--background {value}");
        assert!(
            err.contains("--background") && err.contains(value) && err.contains(says),
            "--background {value}: {err}"
        );
    }
}

#[test]
fn a_store_without_an_environment_cube_gets_a_black_background_and_a_note() {
    let store = runtime_fixture::store_path_without_env_cube();
    let (out, exr) = render_background("no-env", &store, &[]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{err}");
    let note = format!(
        "note: {} has no environment cube; background is black (bake with env_cube = true)",
        store.display()
    );
    assert_eq!(err.lines().filter(|l| *l == note).count(), 1, "{err}");
    let (_, px) = read_exr(&exr);
    assert!(px.iter().any(|p| p[3] == 0.0));
    assert!(px.iter().filter(|p| p[3] == 0.0).all(|p| *p == [0.0; 4]));

    let (out, _) = render_background("no-env-explicit", &store, &["--background", "env"]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success(), "{err}");
    assert!(
        err.contains("no environment cube") && err.contains("teapot.oslf"),
        "{err}"
    );
    assert!(!err.contains("note:"), "{err}");
}

/// `-o` ending in .png would make the EXR and the PNG one file, and an unwritable
/// `--stats-json` would fail after the render: both are refused before any work, and nothing
/// is written.
#[test]
fn outputs_are_checked_before_any_work() {
    let store = runtime_fixture::store_path();
    let dir = tempfile::tempdir().unwrap();
    let png = dir.path().join("y.png");
    let out = render(&[store.to_str().unwrap(), "-o", png.to_str().unwrap()]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success());
    assert!(err.contains("y.png") && err.contains("y.exr"), "{err}");
    let exr = dir.path().join("x.exr");
    let json = dir.path().join("missing").join("stats.json");
    let out = render(&[
        store.to_str().unwrap(),
        "-o",
        exr.to_str().unwrap(),
        "--stats-json",
        json.to_str().unwrap(),
    ]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success());
    assert!(
        err.contains("--stats-json") && err.contains("missing"),
        "{err}"
    );
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
    // A directory where the image would go is refused and left alone.
    let sub = dir.path().join("sub.exr");
    std::fs::create_dir(&sub).unwrap();
    let out = render(&[store.to_str().unwrap(), "-o", sub.to_str().unwrap()]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success());
    assert!(
        err.contains("sub.exr") && err.contains("directory"),
        "{err}"
    );
    assert!(sub.is_dir());
}

#[test]
fn bad_inputs_give_clear_errors_and_a_failing_exit() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    let missing = dir.join("nope.oslf");
    let out = render(&[missing.to_str().unwrap()]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success());
    assert!(err.contains("nope.oslf"), "{err}");

    let foreign = dir.join("foreign.oslf");
    std::fs::write(&foreign, b"this is not a store, just some bytes of text").unwrap();
    let out = render(&[foreign.to_str().unwrap()]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success());
    assert!(err.contains("foreign.oslf"), "{err}");

    let store = runtime_fixture::store_path();
    let mut bytes = std::fs::read(&store).unwrap();
    // A version this reader does not know.
    bytes[8..12].copy_from_slice(&99u32.to_le_bytes());
    let other = dir.join("version99.oslf");
    std::fs::write(&other, bytes).unwrap();
    let out = render(&[other.to_str().unwrap()]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success());
    assert!(
        err.contains("version99.oslf") && err.contains("version"),
        "{err}"
    );

    for (flag, value, says) in [
        ("--nu", "-1", "n_u"),
        ("--mode", "shiny", "shiny"),
        ("-M", "0", "M = 0"),
        ("--cache-slots", "0", "at least one slot"),
        ("--roughness", "1.5", "roughness = 1.5"),
        ("--metallic", "-0.1", "metallic = -0.1"),
    ] {
        let out = render(&[
            store.to_str().unwrap(),
            flag,
            value,
            "-o",
            dir.join("x.exr").to_str().unwrap(),
        ]);
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success(), "{flag} {value}");
        assert!(err.contains(says), "{flag} {value}: {err}");
    }
}

#[test]
fn compare_reports_cielab_and_rgb_errors_between_renders() {
    let store = runtime_fixture::store_path();
    let dir = store.parent().unwrap().join("compare");
    std::fs::create_dir_all(&dir).unwrap();
    let exr = |name: &str| dir.join(name).to_str().unwrap().to_string();
    for (name, mode, w) in [
        ("a.exr", "recon", "64"),
        ("b.exr", "recon-mirror", "64"),
        ("c.exr", "recon", "32"),
    ] {
        let out = render(&[
            store.to_str().unwrap(),
            "-o",
            &exr(name),
            "--mode",
            mode,
            "--width",
            w,
            "--height",
            "48",
        ]);
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
    }
    let compare = |args: &[&str]| oslf("compare").args(args).output().unwrap();
    let json = exr("m.json");
    let out = compare(&[&exr("a.exr"), &exr("b.exr"), "--json", &json]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let m: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    assert!(m["pixels"].as_u64().unwrap() > 100);
    assert!(
        m["rmse_lab"][0].as_f64().unwrap() > 0.1,
        "adding reflections changes L*"
    );
    let out = compare(&[&exr("a.exr"), &exr("a.exr")]);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success() && stdout.contains("inf dB"),
        "{stdout}"
    );
    let out = compare(&[&exr("a.exr"), &exr("c.exr")]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        !out.status.success() && err.contains("64x48") && err.contains("32x48"),
        "{err}"
    );
}

/// Forced onto the GL backend (llvmpipe over EGL here), the render either works or stops with
/// an error that names the adapter, the missing capability and the fix; never a bare wgpu
/// validation message.
#[test]
fn gl_backend_renders_or_names_the_missing_capability_and_the_fix() {
    let store = runtime_fixture::store_path();
    let dir = store.parent().unwrap().join("cli-gl");
    std::fs::create_dir_all(&dir).unwrap();
    let exr = dir.join("frame.exr");
    let out = oslf("render")
        .env("WGPU_BACKEND", "gl")
        .args([
            store.to_str().unwrap(),
            "-o",
            exr.to_str().unwrap(),
            "--width",
            "32",
            "--height",
            "24",
        ])
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    if out.status.success() {
        assert!(exr.exists(), "exit 0 without an image; stderr: {stderr}");
    } else {
        assert!(
            stderr.contains("Rgba32Float")
                && stderr.contains("mesa-vulkan-drivers")
                && stderr.contains("Gl"),
            "the GL failure must name the adapter, the capability and the fix: {stderr}"
        );
        assert!(!stderr.contains("Validation Error"), "{stderr}");
    }
}

/// `store` with one RGB9E5 texel of cube `cube`, face 0 changed and every checksum but that of
/// the decoded faces resealed (frame checksum in the table of contents and the cube record,
/// their own checksums, the header's): every frame reads, only the decoded faces differ from
/// what the header's checksum of them says. The face is re-encoded with `encode_cube`, trying
/// texels until the frame keeps its compressed size, so no offset moves.
fn resealed_with_an_altered_face(store: &std::path::Path, cube: u32) -> Vec<u8> {
    use xxhash_rust::xxh3::xxh3_64;
    let bytes = std::fs::read(store).unwrap();
    let s = oslf_format::Store::from_bytes(&bytes).unwrap();
    let e = s.face_entry(cube, 0).unwrap();
    let image = s.read_cube(cube).unwrap();
    let put = |b: &mut Vec<u8>, at: u64, v: u64| {
        b[at as usize..at as usize + 8].copy_from_slice(&v.to_le_bytes())
    };
    for texel in 0..image.faces[0].len() {
        let mut altered = image.clone();
        let t = &mut altered.faces[0][texel];
        *t = [t[0] * 4.0 + 1.0, t[1], t[2] * 0.25];
        let (enc, _) = oslf_format::encode_cube(&altered, &s.meta().bake, cube).unwrap();
        let frame = &enc.frames()[0];
        if frame.len() as u64 != e.compressed_size {
            continue;
        }
        let mut b = bytes.clone();
        b[e.offset as usize..(e.offset + e.compressed_size) as usize].copy_from_slice(frame);
        let sum = xxh3_64(frame);
        // The table of contents: face entry (offset, sizes, checksum), then its checksum.
        let toc = s.header().toc;
        put(&mut b, toc.offset + (u64::from(cube) * 6) * 32 + 24, sum);
        let toc_end = toc.offset + toc.size - 8;
        let toc_sum = xxh3_64(&b[toc.offset as usize..toc_end as usize]);
        put(&mut b, toc_end, toc_sum);
        // The cube record: magic, index, per face (compressed, raw, checksum), checksum.
        let rec = e.offset - 160;
        put(&mut b, rec + 8 + 16, sum);
        let rec_sum = xxh3_64(&b[rec as usize..rec as usize + 152]);
        put(&mut b, rec + 152, rec_sum);
        let header_sum = xxh3_64(&b[..248]);
        put(&mut b, 248, header_sum);
        return b;
    }
    panic!("no altered texel keeps the frame's size");
}

/// `--verify` checks the store's checksum of its decoded faces before rendering: a store
/// with a face altered and resealed renders (silently wrong) without it, with a warning with
/// it, and not at all with `--verify --strict` (exit 1, the store and the checksum named, no
/// image written). An intact store renders with `--verify --strict`.
#[test]
fn verify_catches_a_resealed_store_before_rendering() {
    let store = runtime_fixture::store_path();
    let dir = tempfile::tempdir().unwrap();
    let bad = dir.path().join("resealed.oslf");
    std::fs::write(&bad, resealed_with_an_altered_face(&store, 7)).unwrap();
    let e = oslf_format::Store::open(&bad)
        .unwrap()
        .verify()
        .unwrap_err();
    assert!(
        matches!(e, oslf_format::Error::DecodedChecksum { .. }),
        "{e}"
    );
    let exr = dir.path().join("x.exr");
    let run = |path: &std::path::Path, flags: &[&str]| {
        let mut args = vec![path.to_str().unwrap(), "-o", exr.to_str().unwrap()];
        args.extend_from_slice(&["--width", "32", "--height", "24"]);
        args.extend_from_slice(flags);
        let out = render(&args);
        (
            out.status.success(),
            String::from_utf8_lossy(&out.stderr).into_owned(),
        )
    };
    let (ok, err) = run(&bad, &[]);
    assert!(ok && !err.contains("verification"), "{err}");
    let (ok, err) = run(&bad, &["--verify"]);
    assert!(ok, "{err}");
    assert!(
        err.contains("warning")
            && err.contains("resealed.oslf")
            && err.contains("header byte offset 180"),
        "{err}"
    );
    std::fs::remove_file(&exr).unwrap();
    let (ok, err) = run(&bad, &["--verify", "--strict"]);
    assert!(!ok);
    assert!(
        err.contains("resealed.oslf failed verification") && err.contains("header byte offset 180"),
        "{err}"
    );
    assert!(!exr.exists(), "nothing written under --strict");
    let (ok, err) = run(&store, &["--verify", "--strict"]);
    assert!(ok && exr.exists(), "{err}");
}
