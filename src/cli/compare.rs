//! `oslf compare`: RMSE in CIELAB and linear RGB, and PSNR, between two OpenEXR images over a
//! mask (thesis §6.1). See `oslf_measure::metrics` for the exact conversion.

use std::path::Path;

use anyhow::{bail, Context};
use glam::Vec3;
use oslf_measure::metrics::{compare, Metrics};
use oslf_measure::reference_noise::{self, Corrected};
use oslf_util::image_file;
use oslf_util::input_file::{byte_size, Limit};

use super::paths::{InputPath, OutputPath};

/// The most bytes of an OpenEXR image `oslf compare` reads: 4 GiB.
const MAX_EXR_BYTES: u64 = 4 << 30;

/// Compare a rendered image against a reference: RMSE of L*, a*, b* (raw and divided by 100,
/// the thesis's scale), RMSE of linear R, G, B, and PSNR, over the reference's object mask.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// The reference image (OpenEXR; linear RGB, alpha = object mask).
    reference: InputPath,
    /// The image to judge (OpenEXR, same size).
    test: InputPath,
    /// A second render of the reference, independent of the first (`oslf truth --seed` with
    /// another seed): the test is judged against the two's mean, and the mean's own noise
    /// (half the two's RMSE) is taken out of its error in quadrature (the `corrected` line).
    #[arg(long, value_name = "REFERENCE2")]
    second_reference: Option<InputPath>,
    /// Which pixels count: `reference` (its alpha > 0.5), `both` (both alphas), `all`.
    #[arg(long, default_value = "reference")]
    mask: String,
    /// The linear value that is reference white (L* = 100), 1e-6 to 1e6.
    #[arg(long, default_value_t = 1.0)]
    white: f64,
    /// Also write the result as JSON to this file.
    #[arg(long)]
    json: Option<OutputPath>,
    /// Also append the result as one CSV row (header written when the file is new).
    #[arg(long)]
    csv: Option<OutputPath>,
    /// Also write a PNG with the test image on the left and the reference on the right (with
    /// --second-reference, the two references' mean: what the test is judged against), tone
    /// mapped alike (whole images: background pixels too).
    #[arg(long, value_name = "PNG")]
    side_by_side: Option<OutputPath>,
    /// Exposure of --side-by-side, 1e-6 to 1e6.
    #[arg(long, default_value_t = 1.0, value_parser = super::args::parse_exposure)]
    exposure: f32,
}

/// Pixels between the two halves of `--side-by-side`.
const GAP: usize = 8;

/// `test | gap | reference`, one image of `2 w + GAP` by `h` linear RGB pixels.
fn side_by_side(test: &[[f32; 4]], reference: &[[f32; 4]], w: usize, h: usize) -> Vec<Vec3> {
    let mut out = Vec::with_capacity((2 * w + GAP) * h);
    for y in 0..h {
        let row = |img: &[[f32; 4]]| {
            img[y * w..(y + 1) * w]
                .iter()
                .map(|p| Vec3::new(p[0], p[1], p[2]))
                .collect::<Vec<_>>()
        };
        out.extend(row(test));
        out.extend(std::iter::repeat_n(Vec3::ONE, GAP));
        out.extend(row(reference));
    }
    out
}

fn read_exr(path: &Path) -> anyhow::Result<(usize, usize, Vec<[f32; 4]>)> {
    use exr::prelude::traits::{ReadChannels as _, ReadLayers as _};
    use exr::prelude::{RgbaChannels, Vec2};
    type Pixels = (usize, Vec<[f32; 4]>);
    fn create(res: Vec2<usize>, _: &RgbaChannels) -> Pixels {
        (res.width(), vec![[0f32; 4]; res.width() * res.height()])
    }
    fn set((w, px): &mut Pixels, pos: Vec2<usize>, (r, g, b, a): (f32, f32, f32, f32)) {
        px[pos.y() * *w + pos.x()] = [r, g, b, a]
    }
    let limit = Limit::new(
        MAX_EXR_BYTES,
        format!("the {} allowed for an image", byte_size(MAX_EXR_BYTES)),
    );
    // Through the one door in: a regular file, never blocking, within the limit.
    let file = oslf_util::input_file::open_within(path, &limit)?;
    let image = exr::prelude::read()
        .no_deep_data()
        .largest_resolution_level()
        .rgba_channels(create, set)
        .first_valid_layer()
        .all_attributes()
        .from_buffered(std::io::BufReader::new(file))
        // The exr crate's I/O error prints its cause and also gives it as its source: flattened to
        // its message, so the cause prints once.
        .map_err(|e| anyhow::anyhow!("cannot read OpenEXR {}: {e}", path.display()))?;
    let size = image.layer_data.size;
    let (_, pixels) = image.layer_data.channel_data.pixels;
    Ok((size.width(), size.height(), pixels))
}

/// The comparison `oslf compare` reports: the metrics and, with a second reference, the error
/// corrected for the references' noise.
#[derive(serde::Serialize)]
struct Report {
    #[serde(flatten)]
    metrics: Metrics,
    /// `null` without `--second-reference`.
    corrected: Option<Corrected>,
}

pub fn run(args: Args) -> anyhow::Result<()> {
    let mut door = oslf_util::door::Door::new();
    door.input("REFERENCE", &args.reference)
        .input("TEST", &args.test);
    if let Some(path) = &args.second_reference {
        door.input("--second-reference", path);
    }
    for (role, path) in [
        ("--json", &args.json),
        ("--csv", &args.csv),
        ("--side-by-side", &args.side_by_side),
    ] {
        if let Some(path) = path {
            door.output(role, path);
        }
    }
    door.check()?;
    let (w, h, mut a) = read_exr(&args.reference)?;
    let (w2, h2, b) = read_exr(&args.test)?;
    let same_size = |path: &Path, (w2, h2): (usize, usize)| {
        if (w, h) == (w2, h2) {
            Ok(())
        } else {
            Err(anyhow::anyhow!(
                "{} is {w}x{h} but {} is {w2}x{h2}",
                args.reference.display(),
                path.display()
            ))
        }
    };
    same_size(&args.test, (w2, h2))?;
    let second = match &args.second_reference {
        Some(path) => {
            let (w3, h3, c) = read_exr(path)?;
            same_size(path, (w3, h3))?;
            Some((path, c))
        }
        None => None,
    };
    let measure = |reference: &[[f32; 4]], test: &[[f32; 4]], what: &Path| {
        let (r, t) = (reference, test);
        match args.mask.as_str() {
            "reference" => compare(r, t, w, |i| r[i][3] > 0.5, args.white),
            "both" => compare(r, t, w, |i| r[i][3] > 0.5 && t[i][3] > 0.5, args.white),
            "all" => compare(r, t, w, |_| true, args.white),
            other => bail!("unknown --mask {other:?} (reference, both or all)"),
        }
        .with_context(|| {
            format!(
                "comparing {} with {}",
                what.display(),
                args.reference.display()
            )
        })
    };
    let mut between = None;
    if let Some((path, c)) = &second {
        between = Some(measure(&a, c, path)?);
        a = reference_noise::mean_image(&a, c)?;
    }
    let m = measure(&a, &b, &args.test)?;
    if m.pixels == 0 {
        bail!(
            "the mask selects no pixel (is the reference's alpha an object mask? try --mask all)"
        );
    }
    let corrected = between.map(|between| reference_noise::corrected(&m, &between));
    print_report(&args, &m, corrected.as_ref());
    if let Some(path) = &args.side_by_side {
        let pixels = side_by_side(&b, &a, w, h);
        image_file::write_png(path, (2 * w + GAP) as u32, h as u32, &pixels, args.exposure)?;
        let right = match &second {
            Some((path2, _)) => format!(
                "the mean of {} and {}",
                args.reference.display(),
                path2.display()
            ),
            None => args.reference.display().to_string(),
        };
        println!(
            "side by side {} (left {}, right {right})",
            path.display(),
            args.test.display(),
        );
    }
    let report = Report {
        metrics: m,
        corrected,
    };
    if let Some(path) = &args.json {
        oslf_util::output_file::write_bytes(
            path,
            serde_json::to_string_pretty(&report)?.as_bytes(),
        )?;
    }
    if let Some(path) = &args.csv {
        append_csv_row(path, &args, &report)?;
    }
    Ok(())
}

/// The lines on stdout.
fn print_report(args: &Args, m: &Metrics, corrected: Option<&Corrected>) {
    let psnr = m.psnr_db.map_or("inf".to_string(), |p| format!("{p:.2}"));
    println!("pixels      {}", m.pixels);
    if let (Some(c), Some(second)) = (corrected, &args.second_reference) {
        let n = c.reference_noise_lab;
        println!(
            "reference   the mean of {} and {}; its own noise RMSE L*a*b* {:.4} {:.4} {:.4} (half the two's difference)",
            args.reference.display(),
            second.display(),
            n[0],
            n[1],
            n[2]
        );
    }
    println!(
        "RMSE L*a*b* {:.4} {:.4} {:.4}   (/100: {:.6} {:.6} {:.6})",
        m.rmse_lab[0],
        m.rmse_lab[1],
        m.rmse_lab[2],
        m.rmse_lab_normalized[0],
        m.rmse_lab_normalized[1],
        m.rmse_lab_normalized[2]
    );
    println!(
        "RMSE RGB    {:.6} {:.6} {:.6}",
        m.rmse_rgb[0], m.rmse_rgb[1], m.rmse_rgb[2]
    );
    if let Some(c) = corrected {
        let e = c.rmse_lab;
        println!(
            "corrected   RMSE L*a*b* {:.4} {:.4} {:.4}   (the reference's noise taken out in quadrature)",
            e[0], e[1], e[2]
        );
    }
    println!("PSNR        {psnr} dB (white {})", m.white);
}

/// The header of `--csv`, written when the file is new.
/// The corrected columns are empty without `--second-reference`.
const CSV_HEADER: &str = "reference,test,pixels,rmse_l,rmse_a,rmse_b,rmse_l_norm,rmse_a_norm,rmse_b_norm,rmse_r,rmse_g,rmse_b_rgb,psnr_db,white,second_reference,rmse_l_corrected,rmse_a_corrected,rmse_b_corrected";

/// The most bytes of a `--csv` file that a row is appended to: 256 MiB.
const MAX_CSV_BYTES: u64 = 256 << 20;

/// Appends one row for `m` to the CSV file at `path` (with the header if the file is new):
/// the whole file is written anew through a temporary file and renamed into place, so an
/// interrupted append leaves the old rows as they were. A file whose header is not this
/// version's is refused (its columns would not line up).
fn append_csv_row(path: &Path, args: &Args, report: &Report) -> anyhow::Result<()> {
    let m = &report.metrics;
    let mut text = if path.exists() {
        let limit = Limit::new(
            MAX_CSV_BYTES,
            format!("the {} allowed for a --csv file", byte_size(MAX_CSV_BYTES)),
        );
        let text = oslf_util::input_file::read(path, &limit)?;
        let header = text.split(|&c| c == b'\n').next().unwrap_or_default();
        if header.strip_suffix(b"\r").unwrap_or(header) != CSV_HEADER.as_bytes() {
            bail!(
                "{}: line 1 is not the header of this oslf's --csv rows ({CSV_HEADER}), so a row would not line up with its columns; append to a new file",
                path.display()
            );
        }
        text
    } else {
        format!("{CSV_HEADER}\n").into_bytes()
    };
    if text.last().is_some_and(|&b| b != b'\n') {
        text.push(b'\n');
    }
    let corrected = report.corrected.as_ref().map_or(",,".to_string(), |c| {
        format!("{},{},{}", c.rmse_lab[0], c.rmse_lab[1], c.rmse_lab[2])
    });
    let second = args
        .second_reference
        .as_ref()
        .map_or(String::new(), |p| p.display().to_string());
    let row = format!(
        "{},{},{},{},{},{},{},{},{},{},{},{},{},{},{second},{corrected}\n",
        args.reference.display(),
        args.test.display(),
        m.pixels,
        m.rmse_lab[0],
        m.rmse_lab[1],
        m.rmse_lab[2],
        m.rmse_lab_normalized[0],
        m.rmse_lab_normalized[1],
        m.rmse_lab_normalized[2],
        m.rmse_rgb[0],
        m.rmse_rgb[1],
        m.rmse_rgb[2],
        m.psnr_db.map_or("inf".to_string(), |p| p.to_string()),
        m.white
    );
    text.extend_from_slice(row.as_bytes());
    Ok(oslf_util::output_file::write_bytes(path, &text)?)
}
