//! `oslf store`: inspect, verify, convert and export OSLF stores.

use std::path::{Path, PathBuf};

use anyhow::{bail, Context, Result};
use clap::{Subcommand, ValueEnum};
use oslf_format::cube::{FACES, FACE_NAMES};
use oslf_format::{Encoding, SampleMaps, Store, StoreWriter, INVALID_INDEX};
use oslf_util::door::Door;

use super::args::StoreAccessArgs;
use super::paths::{InputPath, OutputPath};

/// Inspect, verify, convert and export OSLF stores.
#[derive(clap::Args, Debug)]
pub struct Args {
    #[command(subcommand)]
    command: Command,
    #[command(flatten)]
    access: StoreAccessArgs,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Print a summary: header, counts, resolutions, bake parameters, sizes.
    Info {
        store: InputPath,
        /// Print JSON instead of text.
        #[arg(long)]
        json: bool,
    },
    /// Check every checksum, that every padding byte is zero, and decode every face, checking
    /// the decoded texels against the store's checksum of them (non-zero exit on failure).
    Verify { store: InputPath },
    /// Join the shard files of `oslf bake --shard I/N` (all N of them, any order) into the
    /// store a single bake writes, byte for byte. Checks that they come from the same scene,
    /// settings and seed and that every shard index is there exactly once; writes
    /// OUTPUT.partial, syncs it and renames it to OUTPUT.
    Merge {
        #[arg(required = true)]
        shards: Vec<InputPath>,
        #[arg(short, long)]
        output: OutputPath,
    },
    /// Re-encode a store's cube maps in another encoding (e.g. bc6h), keeping everything else:
    /// metadata, bake parameters (but the encoding; mantissa_bits becomes 9 unless both
    /// encodings are rgb9e5), sample points, sample maps, the environment cube and the distance
    /// planes. Writes OUT.partial and renames it to OUT. Prints the encode time and the
    /// converted texels' error against IN's (RMSLE, relative error per texel).
    Convert {
        input: InputPath,
        output: OutputPath,
        /// The encoding of OUT: rgb9e5, rgba16f, rgba32f or bc6h.
        #[arg(long, value_parser = parse_encoding)]
        encoding: Encoding,
        /// Worker threads [default: all cores]. OUT is byte-identical for any count.
        #[arg(short = 'j', long)]
        threads: Option<usize>,
    },
    /// Export one cube as OpenEXR (f32 RGB) or as a KTX2 cube map (RGBA16F), the container
    /// engines load environment maps from. The last cube of a store with an environment cube
    /// is that cube (`oslf store info` says which)
    ExportCube {
        store: InputPath,
        index: u32,
        #[arg(short, long)]
        output: OutputPath,
        /// exr, or ktx2: one cube-map texture (faces +X −X +Y −Y +Z −Z in Vulkan's cube-map
        /// convention, the scene's axes: a Y-up engine turns it by −90° about x for a scene
        /// that turned a Y-up file by +90°)
        #[arg(long, value_enum, default_value_t = CubeFormat::Exr)]
        format: CubeFormat,
        /// The layout of OpenEXR output [default: cross]
        #[arg(long, value_enum)]
        layout: Option<Layout>,
    },
    /// Export one sample map as a false-colour PNG (colour from a hash of the index; missing
    /// entries black)
    ExportSampleMap {
        store: InputPath,
        /// The map: a Bézier patch, or a page of a mesh object's atlas (`oslf store info` lists
        /// each object's maps).
        #[arg(value_name = "MAP")]
        patch: u32,
        #[arg(short, long)]
        output: OutputPath,
        /// Which of the 4 entries to show (0 = nearest).
        #[arg(long, default_value_t = 0, value_parser = clap::value_parser!(u8).range(0..4))]
        channel: u8,
        /// Pixels per sample-map texel.
        #[arg(long, default_value_t = 4, value_parser = clap::value_parser!(u32).range(1..=64))]
        scale: u32,
    },
}

#[derive(Clone, Copy, Debug, PartialEq, ValueEnum)]
enum CubeFormat {
    Exr,
    Ktx2,
}

#[derive(Clone, Copy, Debug, ValueEnum)]
enum Layout {
    /// One 4x3 horizontal-cross image (+Y above, -X +Z +X -Z across, -Y below).
    Cross,
    /// Six files OUT_px.exr, OUT_nx.exr, OUT_py.exr, OUT_ny.exr, OUT_pz.exr, OUT_nz.exr.
    Faces,
}

fn parse_encoding(s: &str) -> std::result::Result<Encoding, String> {
    s.parse().map_err(|e: oslf_format::Error| e.to_string())
}

/// `oslf render --verify`: [`Store::verify`] (every frame, padding byte and the checksum of
/// the decoded faces) before the render. A failure is an error under `strict`, else a
/// warning on stderr.
pub(super) fn verify_for_render(store: &Store, path: &Path, strict: bool) -> Result<()> {
    match store.verify() {
        Ok(_) => {}
        Err(e) if strict => {
            bail!(
                "{} failed verification (--verify --strict; nothing rendered): {e}",
                path.display()
            )
        }
        Err(e) => eprintln!(
            "warning: {} failed verification, the image may be wrong: {e}",
            path.display()
        ),
    }
    Ok(())
}

/// Every file the subcommand reads and writes, checked before any work.
fn door(command: &Command) -> Door {
    let mut door = Door::new();
    let partial = |o: &Path| oslf_format::writer::partial_path(o);
    match command {
        Command::Info { store, .. } | Command::Verify { store } => {
            door.input("STORE", store);
        }
        Command::Merge { shards, output } => {
            for shard in shards {
                door.input("SHARDS", shard);
            }
            door.output("--output", output)
                .output("the partial store of --output", &partial(output));
        }
        Command::Convert { input, output, .. } => {
            door.input("INPUT", input)
                .output("OUTPUT", output)
                .output("the partial store of OUTPUT", &partial(output));
        }
        Command::ExportCube {
            store,
            output,
            format,
            layout,
            ..
        } => {
            door.input("STORE", store);
            match (format, layout) {
                (CubeFormat::Exr, Some(Layout::Faces)) => {
                    for (name, path) in FACE_NAMES.iter().zip(face_paths(output)) {
                        door.output(format!("the {name} face file of --output"), &path);
                    }
                }
                _ => {
                    door.output("--output", output);
                }
            }
        }
        Command::ExportSampleMap { store, output, .. } => {
            door.input("STORE", store).output("--output", output);
        }
    }
    door
}

pub fn run(cli: Args) -> Result<()> {
    door(&cli.command).check()?;
    let access = cli.access;
    match cli.command {
        Command::Info { store, json } => info(&store, &access.open(&store)?, json),
        Command::Verify { store } => {
            let s = access.open(&store)?;
            let r = s
                .verify()
                .with_context(|| format!("{} failed verification", store.display()))?;
            println!(
                "{}: OK — {} cubes, {} faces, {} compressed bytes, {} raw bytes, {} padding bytes checked; the decoded faces match their checksum",
                store.display(),
                r.cubes,
                r.faces,
                r.compressed_bytes,
                r.raw_bytes,
                r.padding_bytes,
            );
            Ok(())
        }
        Command::Merge { shards, output } => {
            let paths: Vec<PathBuf> = shards.iter().map(|s| s.0.clone()).collect();
            let s = oslf_format::shard::merge(&paths, &output)
                .map_err(|e| match e {
                    oslf_format::Error::UnfinishedShard { .. } => {
                        anyhow::anyhow!("{e}; finish its bake with --resume")
                    }
                    e => e.into(),
                })
                .with_context(|| format!("cannot merge into {}", output.display()))?;
            println!(
                "{}: {} shards merged — {} cubes, {} sample points, {} bytes",
                output.display(),
                shards.len(),
                s.cubes,
                s.sample_points,
                s.file_size
            );
            Ok(())
        }
        Command::Convert {
            input,
            output,
            encoding,
            threads,
        } => super::args::in_pool(threads, || convert(&input, &output, encoding, access)),
        Command::ExportCube {
            store,
            index,
            output,
            format,
            layout,
        } => {
            match (format, layout) {
                (CubeFormat::Ktx2, Some(_)) => {
                    bail!("--layout applies to OpenEXR output; a KTX2 file holds the cube as a cube map")
                }
                (CubeFormat::Ktx2, None) => export_cube_ktx2(&access.open(&store)?, index, &output),
                (CubeFormat::Exr, layout) => export_cube(
                    &access.open(&store)?,
                    index,
                    &output,
                    layout.unwrap_or(Layout::Cross),
                ),
            }
        }
        Command::ExportSampleMap {
            store,
            patch,
            output,
            channel,
            scale,
        } => export_sample_map(
            &access.open(&store)?,
            patch,
            &output,
            channel as usize,
            scale,
        ),
    }
}

/// All of `s`'s sample maps, as the writer takes them.
fn sample_maps(s: &Store) -> Result<SampleMaps> {
    let res = s.meta().bake.sample_map_resolution;
    let patches = s.header().patch_count;
    let mut indices = Vec::with_capacity((patches as usize).saturating_mul((res as usize).pow(2)));
    for patch in 0..patches {
        let patch = u32::try_from(patch).context("too many patches")?;
        let view = s.sample_map(patch)?;
        for y in 0..res {
            for x in 0..res {
                indices.push(
                    view.get(x, y).with_context(|| {
                        format!("patch {patch}: no sample-map texel ({x}, {y})")
                    })?,
                );
            }
        }
    }
    Ok(SampleMaps {
        resolution: res,
        indices,
    })
}

/// `oslf store convert`: `input`'s cube maps re-encoded as `encoding` into `output`.
fn convert(input: &Path, output: &Path, encoding: Encoding, access: StoreAccessArgs) -> Result<()> {
    use rayon::prelude::*;
    // The door has refused an output that is the input; this checks the partial file's lock.
    oslf_format::check_output(output)?;
    let src = access.open(input)?;
    let mut meta = src.meta().clone();
    let from = meta.bake.encoding;
    meta.bake.encoding = encoding;
    if !(from == Encoding::Rgb9e5 && encoding == Encoding::Rgb9e5) {
        meta.bake.mantissa_bits = oslf_format::encoding::RGB9E5_FULL_MANTISSA_BITS;
    }
    let maps = sample_maps(&src)?;
    let mut w = StoreWriter::create(output, &meta, src.sample_points(), &maps)
        .with_context(|| format!("cannot create {}", output.display()))?;
    let n = src.cube_count();
    // Chunks of cubes encoded in parallel, appended in order (the output does not depend on
    // the thread count).
    let chunk = (rayon::current_num_threads() * 4).max(1) as u32;
    let mut encode_secs = 0f64;
    let mut clamped = 0u64;
    let mut start = 0;
    while start < n {
        let end = (start + chunk).min(n);
        let done: Vec<_> = (start..end)
            .into_par_iter()
            .map(|i| -> Result<_> {
                let cube = src
                    .read_cube(i)
                    .with_context(|| format!("cannot read cube {i} of {}", input.display()))?;
                let t = std::time::Instant::now();
                let (enc, stats) = oslf_format::encode_cube(&cube, &meta.bake, i)?;
                let secs = t.elapsed().as_secs_f64();
                Ok((enc, stats, secs))
            })
            .collect::<Result<_>>()?;
        for (enc, stats, secs) in done {
            w.append(enc)?;
            encode_secs += secs;
            clamped += stats.clamped_texels;
        }
        start = end;
    }
    let summary = w.finish()?;
    // What the converted cubes decode to, against the input's texels.
    let out = access.open(output)?;
    let error = (0..n)
        .into_par_iter()
        .map(|i| -> Result<_> {
            let (a, b) = (src.read_cube(i)?, out.read_cube(i)?);
            Ok(a.faces
                .iter()
                .zip(&b.faces)
                .map(|(a, b)| oslf_format::bc6h::face_error(a, b, 1e-3))
                .fold(oslf_format::bc6h::FaceError::default(), |x, y| x.merge(y)))
        })
        .collect::<Result<Vec<_>>>()?
        .into_iter()
        .fold(oslf_format::bc6h::FaceError::default(), |x, y| x.merge(y));
    let texels = u64::from(n) * 6 * u64::from(src.cube_resolution()).pow(2);
    let per_texel = |bytes: u64| bytes as f64 / texels.max(1) as f64;
    println!(
        "{}: {n} cubes {from} → {encoding} — {} bytes ({:.3} bytes per cube-map texel, input {:.3}); encode {:.2} ms per cube (one thread); {clamped} texels clamped",
        output.display(),
        summary.file_size,
        per_texel(summary.cube_bytes),
        per_texel(src.cube_bytes()),
        1e3 * encode_secs / f64::from(n.max(1)),
    );
    println!(
        "error against {}: RMSLE {:.3e}, relative error per texel max {:.3e}, mean {:.3e} (error of any channel over the texel's largest, at least 1e-3)",
        input.display(),
        error.rmsle,
        error.max_relative,
        error.mean_relative
    );
    Ok(())
}

fn info(path: &Path, s: &Store, json: bool) -> Result<()> {
    let sizes = Sizes::of(s);
    if json {
        println!(
            "{}",
            serde_json::to_string_pretty(&info_json(path, s, &sizes))?
        );
    } else {
        print_info(path, s, &sizes);
    }
    Ok(())
}

/// What `store info` reports of the cube data's size.
struct Sizes {
    texels: u64,
    cube_bytes: u64,
    raw_bytes: u64,
    bytes_per_texel: f64,
    ratio: f64,
    scene_hash: String,
}

impl Sizes {
    fn of(s: &Store) -> Sizes {
        let h = s.header();
        let texels = u64::from(s.cube_count()) * FACES as u64 * u64::from(h.cube_resolution).pow(2);
        let cube_bytes = s.cube_bytes();
        let raw_bytes = u64::from(s.cube_count()) * FACES as u64 * s.face_raw_size() as u64;
        let bytes_per_texel = if texels > 0 {
            cube_bytes as f64 / texels as f64
        } else {
            0.0
        };
        let ratio = if cube_bytes > 0 {
            raw_bytes as f64 / cube_bytes as f64
        } else {
            0.0
        };
        let scene_hash = s
            .meta()
            .bake
            .scene_hash
            .iter()
            .map(|v| format!("{v:02x}"))
            .collect();
        Sizes {
            texels,
            cube_bytes,
            raw_bytes,
            bytes_per_texel,
            ratio,
            scene_hash,
        }
    }
}

/// The text `store info` prints for the sampling record.
fn sampling_line(sampling: Option<oslf_format::Sampling>) -> String {
    let Some(s) = sampling else {
        return "not recorded (format 1.0 and 1.1 stores do not say)".into();
    };
    let samples = if s.target_noise > 0.0 {
        format!(
            "each texel sampled down to a relative error of {} (samples per texel the cap)",
            s.target_noise
        )
    } else {
        "the same samples in every texel".into()
    };
    let filter = if s.denoised {
        "cubes denoised"
    } else {
        "cubes not denoised"
    };
    format!("{samples}, {filter}")
}

/// `store info --json`.
fn info_json(path: &Path, s: &Store, z: &Sizes) -> serde_json::Value {
    let h = s.header();
    let m = s.meta();
    let b = &m.bake;
    serde_json::json!({
        "path": path.display().to_string(),
        "format": oslf_format::version_name(h.version),
        "flags": h.flags,
        // Bytes of the irradiance section (each cube's spherical harmonics); null in format 1.0.
        "irradiance_bytes": h.has_irradiance().then_some(h.irradiance.size),
        "encoding": b.encoding.name(),
        "mantissa_bits": b.mantissa_bits,
        "face_filter": h.filter.name(),
        "encoded_bytes_per_texel": b.encoding.bytes_per_texel(),
        "distance_channel": b.distance_channel,
        "env_cube_index": s.env_cube_index(),
        "sample_points": h.sample_count,
        "cubes": s.cube_count(),
        // Sample maps: Bézier patches plus mesh atlas pages.
        "patches": m.map_count(),
        "sample_maps": m.map_count(),
        "bezier_patches": m.patches.len(),
        "objects": m.objects.iter().map(|o| {
            let mut v = serde_json::json!({
                "name": o.name, "first_patch": o.first_patch, "patch_count": o.patch_count,
                "base_color": o.base_color,
                "kind": if o.mesh.is_some() { "mesh" } else { "bezier" },
                "material": {
                    "model": if o.material.is_metallic_roughness() { "metallic-roughness" } else { "lambertian" },
                    "metallic": o.material.metallic,
                    "roughness": o.material.roughness,
                    "emission": o.material.emission,
                },
            });
            if let Some(mesh) = &o.mesh {
                v["vertices"] = mesh.positions.len().into();
                v["triangles"] = mesh.triangles.len().into();
                v["atlas_grid"] = mesh.atlas_grid.into();
            }
            if let Some(t) = &o.textures {
                v["textures"] = t.images.iter().map(|(k, i)| serde_json::json!({
                    "kind": k.name(), "width": i.width, "height": i.height,
                })).collect::<Vec<_>>().into();
                v["normal_scale"] = t.normal_scale.into();
            }
            v
        }).collect::<Vec<_>>(),
        "cube_resolution": b.cube_resolution,
        "sample_map_resolution": b.sample_map_resolution,
        "index_width_bytes": s.index_width().bytes(),
        "bake": {
            "epsilon": b.epsilon, "phi_samplemap_deg": b.phi_samplemap_deg,
            "samples_per_texel": b.samples_per_texel, "bounces": b.bounces,
            "seed": b.seed, "zstd_level": b.zstd_level, "scene_hash": z.scene_hash,
            // Format 1.2's sampling record; both null in a store of format 1.0 or 1.1.
            "target_noise": b.sampling.map(|s| s.target_noise),
            "denoised": b.sampling.map(|s| s.denoised),
        },
        "camera": m.camera.as_ref().map(|c| serde_json::json!({
            "position": c.position, "target": c.target, "up": c.up, "vfov_deg": c.vfov_deg,
        })),
        "file_size": s.file_size(),
        "face_raw_size": s.face_raw_size(),
        "cube_bytes": z.cube_bytes,
        "raw_cube_bytes": z.raw_bytes,
        "texels": z.texels,
        "disk_bytes_per_texel": z.bytes_per_texel,
        "compression_ratio": z.ratio,
    })
}

/// `store info`'s irradiance line.
fn irradiance_info(h: &oslf_format::header::Header) -> String {
    if h.has_irradiance() {
        format!(
            "{} bytes: each cube's radiance in spherical harmonics (bands 0-2), the diffuse part's source",
            h.irradiance.size
        )
    } else {
        "none (format 1.0: the diffuse part is sampled from the cube maps)".to_string()
    }
}

/// `store info` as text.
fn print_info(path: &Path, s: &Store, z: &Sizes) {
    let h = s.header();
    let m = s.meta();
    let b = &m.bake;
    println!("store            {}", path.display());
    println!(
        "format           {} (flags {:#x})",
        oslf_format::version_name(h.version),
        h.flags
    );
    println!("irradiance       {}", irradiance_info(h));
    println!("face filter      {} (id {})", h.filter, h.filter.id());
    println!(
        "encoding         {} ({} bytes/texel raw){}",
        b.encoding,
        b.encoding.bytes_per_texel(),
        if b.distance_channel {
            format!(" + distance ({})", h.distance_plane())
        } else {
            String::new()
        }
    );
    println!(
        "mantissa bits    {}{}",
        b.mantissa_bits,
        if b.mantissa_bits < 9 {
            format!(
                " of 9 (quantized: per-channel error < 2^-{} of the exponent's scale)",
                b.mantissa_bits
            )
        } else {
            " (lossless RGB9E5 / full precision)".to_string()
        }
    );
    println!(
        "cubes            {} ({} sample points{})",
        s.cube_count(),
        h.sample_count,
        match s.env_cube_index() {
            Some(i) => format!(" + environment cube {i}"),
            None => String::new(),
        }
    );
    println!(
        "objects          {} ({} sample maps: {} Bézier patches, {} atlas pages)",
        m.objects.len(),
        m.map_count(),
        m.patches.len(),
        m.map_count() - m.patches.len()
    );
    for o in &m.objects {
        let range = format!(
            "{}..{}",
            o.first_patch,
            u64::from(o.first_patch) + u64::from(o.patch_count)
        );
        match &o.mesh {
            None => println!("  {:?}: Bézier patches {range}", o.name),
            Some(mesh) => println!(
                "  {:?}: triangle mesh, {} vertices, {} triangles, {k}x{k} atlas pages (maps {range})",
                o.name,
                mesh.positions.len(),
                mesh.triangles.len(),
                k = mesh.atlas_grid
            ),
        }
        let c = o.base_color;
        let material = if o.material.is_metallic_roughness() {
            format!(
                "metallic-roughness, base colour {c:?}, metallic {}, roughness {}",
                o.material.metallic, o.material.roughness
            )
        } else {
            format!("Lambertian, base colour {c:?}")
        };
        let emits = o.material.emission.iter().any(|&e| e > 0.0);
        let emission = if emits {
            format!(", emission {:?}", o.material.emission)
        } else {
            String::new()
        };
        println!("    material: {material}{emission}");
        if let Some(t) = &o.textures {
            let images: Vec<String> = t
                .images
                .iter()
                .map(|(k, i)| format!("{} {}x{}", k.name(), i.width, i.height))
                .collect();
            println!("    textures: {}", images.join(", "));
        }
    }
    println!("cube resolution  {0}x{0} per face", b.cube_resolution);
    println!(
        "sample maps      {0}x{0} per patch or atlas page, {1}-byte indices",
        b.sample_map_resolution,
        s.index_width().bytes()
    );
    println!(
        "bake             epsilon {}, phi {} deg, {} spp, {} bounces, seed {}, zstd level {}",
        b.epsilon, b.phi_samplemap_deg, b.samples_per_texel, b.bounces, b.seed, b.zstd_level
    );
    println!("sampling         {}", sampling_line(b.sampling));
    println!("scene hash       {}", z.scene_hash);
    if let Some(c) = &m.camera {
        println!(
            "camera           position {:?}, target {:?}, up {:?}, vfov {} deg",
            c.position, c.target, c.up, c.vfov_deg
        );
    }
    println!("file size        {} bytes", s.file_size());
    println!(
        "cube data        {} bytes compressed, {} raw, {} texels",
        z.cube_bytes, z.raw_bytes, z.texels
    );
    println!(
        "on disk          {:.3} bytes/texel, compression ratio {:.2}x",
        z.bytes_per_texel, z.ratio
    );
}

/// The six files of `export-cube --layout faces`: OUT_px.exr … OUT_nz.exr (OUT without its
/// extension), in layer order.
fn face_paths(out: &Path) -> Vec<PathBuf> {
    let stem = out.with_extension("");
    FACE_NAMES
        .iter()
        .map(|name| {
            let mut file = stem.as_os_str().to_os_string();
            file.push(format!("_{name}.exr"));
            PathBuf::from(file)
        })
        .collect()
}

fn export_cube(s: &Store, index: u32, out: &Path, layout: Layout) -> Result<()> {
    let cube = s.read_cube(index)?;
    let n = cube.resolution as usize;
    match layout {
        Layout::Faces => {
            for (face, path) in face_paths(out).iter().enumerate() {
                let texels: Vec<glam::Vec3> = cube.faces[face]
                    .iter()
                    .map(|&t| glam::Vec3::from(t))
                    .collect();
                oslf_util::image_file::write_exr(path, n as u32, n as u32, &texels)?;
                println!("wrote {}", path.display());
            }
        }
        Layout::Cross => {
            // (column, row) of each face in the 4x3 cross, faces in layer order.
            const CELLS: [(usize, usize); FACES] = [(2, 1), (0, 1), (1, 0), (1, 2), (1, 1), (3, 1)];
            let (w, h) = (4 * n, 3 * n);
            let pixels: Vec<glam::Vec3> = (0..w * h)
                .map(|i| {
                    let (x, y) = (i % w, i / w);
                    let (cx, cy) = (x / n.max(1), y / n.max(1));
                    let face = CELLS.iter().position(|c| *c == (cx, cy));
                    let t = face
                        .and_then(|f| cube.faces[f].get((y % n) * n + x % n))
                        .copied()
                        .unwrap_or([0.0; 3]);
                    glam::Vec3::from(t)
                })
                .collect();
            oslf_util::image_file::write_exr(out, w as u32, h as u32, &pixels)?;
            println!("wrote {}", out.display());
        }
    }
    Ok(())
}

/// `export-cube --format ktx2`: the cube as a KTX2 cube map, written atomically.
fn export_cube_ktx2(s: &Store, index: u32, out: &Path) -> Result<()> {
    let cube = s.read_cube(index)?;
    let writer = concat!("oslf ", env!("CARGO_PKG_VERSION"));
    let clamped = oslf_util::ktx2::write_cube_file(out, cube.resolution, &cube.faces, writer)?;
    println!(
        "wrote {} ({}² × 6 faces, RGBA16F)",
        out.display(),
        cube.resolution
    );
    if clamped > 0 {
        eprintln!(
            "warning: {clamped} channel values above {} (the largest half float) were written as it",
            oslf_util::ktx2::F16_MAX
        );
    }
    Ok(())
}

/// A bright colour from a hash of a sample index.
fn index_colour(i: u32) -> [u8; 3] {
    let h = xxhash_rust::xxh3::xxh3_64(&i.to_le_bytes());
    let c = |shift: u32| 64 + ((h >> shift) & 0xff) as u8 % 192;
    [c(0), c(8), c(16)]
}

fn export_sample_map(s: &Store, patch: u32, out: &Path, channel: usize, scale: u32) -> Result<()> {
    let view = s.sample_map(patch)?;
    let res = view.resolution();
    let Some(size) = res.checked_mul(scale).filter(|v| *v <= 65536) else {
        bail!("image too large: {res} x {scale}");
    };
    let img = image::RgbImage::from_fn(size, size, |x, y| {
        let e = view.get(x / scale, y / scale).unwrap_or([INVALID_INDEX; 4]);
        let i = e.get(channel).copied().unwrap_or(INVALID_INDEX);
        image::Rgb(if i == INVALID_INDEX {
            [0, 0, 0]
        } else {
            index_colour(i)
        })
    });
    let format = image::ImageFormat::from_path(out)
        .with_context(|| format!("cannot write {}", out.display()))?;
    // Through the one way out: a temporary file beside it, every write checked, renamed.
    oslf_util::output_file::write_with(out, |w| {
        img.write_to(w, format).map_err(std::io::Error::other)
    })?;
    println!("wrote {}", out.display());
    Ok(())
}
