//! Writing rendered images: OpenEXR (linear f32, for measurement) and tone-mapped PNG (for eyes).
//!
//! Every image is written through [`crate::output_file::write_with`]: to a temporary file beside
//! its path, checked and synced, then renamed into place, so a failed write leaves whatever was
//! at the path as it was and removes only the temporary file it created. A path that exists and
//! is not a regular file (a device, a FIFO, a directory) is refused before anything is written.

use std::path::Path;

use exr::prelude::{Encoding, Image, LineOrder, SpecificChannels, Vec2, WritableImage as _};
use glam::Vec3;

use oslf_shading::color::{aces, linear_to_srgb};

use crate::error::{Result, UtilError};
use crate::output_file::write_with;

/// Writes linear RGB as a 32-bit float OpenEXR file. `pixels` is row-major, top row first.
pub fn write_exr(path: &Path, width: u32, height: u32, pixels: &[Vec3]) -> Result<()> {
    check_size(path, width, height, pixels.len())?;
    let w = width as usize;
    let channels = SpecificChannels::rgb(|Vec2(x, y): Vec2<usize>| {
        let p = pixels[y * w + x];
        (p.x, p.y, p.z)
    });
    write_with(path, |out| {
        Image::from_encoded_channels((w, height as usize), exr_encoding(), channels)
            .write()
            .to_buffered(out)
            .map_err(|e| std::io::Error::other(format!("OpenEXR: {e}")))
    })
}

/// Writes linear RGB and alpha (an object mask) as a 32-bit float OpenEXR file. `pixels` is
/// row-major, top row first.
pub fn write_exr_rgba(path: &Path, width: u32, height: u32, pixels: &[[f32; 4]]) -> Result<()> {
    check_size(path, width, height, pixels.len())?;
    let w = width as usize;
    let channels = SpecificChannels::rgba(|Vec2(x, y): Vec2<usize>| {
        let p = pixels[y * w + x];
        (p[0], p[1], p[2], p[3])
    });
    write_with(path, |out| {
        Image::from_encoded_channels((w, height as usize), exr_encoding(), channels)
            .write()
            .to_buffered(out)
            .map_err(|e| std::io::Error::other(format!("OpenEXR: {e}")))
    })
}

/// The exr crate's default encoding with scan lines in increasing order: it compresses blocks
/// in parallel, and with the line order unspecified writes each as it finishes, so the same
/// pixels would make different files from run to run.
fn exr_encoding() -> Encoding {
    Encoding {
        line_order: LineOrder::Increasing,
        ..Encoding::default()
    }
}

/// Tone maps linear RGB (exposure, then the ACES filmic fit of Narkowicz 2015, then the sRGB
/// curve) and writes an 8-bit PNG. NaN or negative values map to black.
pub fn write_png(
    path: &Path,
    width: u32,
    height: u32,
    pixels: &[Vec3],
    exposure: f32,
) -> Result<()> {
    check_size(path, width, height, pixels.len())?;
    let mut bytes = Vec::with_capacity(pixels.len() * 3);
    for p in pixels {
        for c in p.to_array() {
            bytes.push(to_srgb8(aces(c * exposure)));
        }
    }
    let format = image::ImageFormat::from_path(path).map_err(|e| UtilError::Image {
        path: path.to_path_buf(),
        message: format!("cannot write PNG: {e}"),
    })?;
    write_with(path, |out| {
        image::write_buffer_with_format(out, &bytes, width, height, image::ColorType::Rgb8, format)
            .map_err(|e| std::io::Error::other(format!("PNG: {e}")))
    })
}

fn check_size(path: &Path, width: u32, height: u32, pixels: usize) -> Result<()> {
    if width == 0 || height == 0 || pixels != width as usize * height as usize {
        return Err(UtilError::Image {
            path: path.to_path_buf(),
            message: format!("{pixels} pixels do not make a {width}x{height} image"),
        });
    }
    Ok(())
}

/// Linear `[0, 1]` to an 8-bit sRGB value (NaN as 0, the rest clamped).
pub fn to_srgb8(linear: f32) -> u8 {
    (linear_to_srgb(linear) * 255.0 + 0.5) as u8
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn srgb8_codes_are_bounded_and_rounded() {
        assert_eq!(to_srgb8(f32::NAN), 0);
        assert_eq!(to_srgb8(-1.0), 0);
        assert_eq!(to_srgb8(f32::INFINITY), 255);
        assert_eq!(to_srgb8(0.0), 0);
        assert_eq!(to_srgb8(1.0), 255);
        assert_eq!(to_srgb8(0.5), 188);
    }

    /// The same pixels give the same file, whatever order the blocks finish compressing in,
    /// and read back exactly.
    #[test]
    fn exr_files_are_deterministic_and_exact() {
        let tmp = tempfile::tempdir().unwrap();
        let dir = tmp.path();
        let (w, h) = (257u32, 601u32);
        let pixels: Vec<[f32; 4]> = (0..w * h)
            .map(|i| {
                let v = (i as f32 * 0.618).sin().abs() * 1e4;
                [v, v * 0.5, 1.0 / (1.0 + v), (i % 2) as f32]
            })
            .collect();
        let files: Vec<Vec<u8>> = (0..8)
            .map(|k| {
                let path = dir.join(format!("{k}.exr"));
                write_exr_rgba(&path, w, h, &pixels).unwrap();
                std::fs::read(&path).unwrap()
            })
            .collect();
        assert!(
            files.iter().all(|f| *f == files[0]),
            "EXR bytes differ between writes"
        );
        let back = exr::prelude::read_first_rgba_layer_from_file(
            dir.join("0.exr"),
            |res, _| vec![[0f32; 4]; res.width() * res.height()],
            move |px, pos, (r, g, b, a): (f32, f32, f32, f32)| {
                px[pos.y() * w as usize + pos.x()] = [r, g, b, a]
            },
        )
        .unwrap();
        assert_eq!(back.layer_data.channel_data.pixels, pixels);
        let rgb: Vec<Vec3> = pixels.iter().map(|p| Vec3::new(p[0], p[1], p[2])).collect();
        let a = dir.join("rgb-a.exr");
        let b = dir.join("rgb-b.exr");
        write_exr(&a, w, h, &rgb).unwrap();
        write_exr(&b, w, h, &rgb).unwrap();
        assert_eq!(std::fs::read(&a).unwrap(), std::fs::read(&b).unwrap());
        assert!(write_exr(&a, w, h + 1, &rgb).is_err());
    }

    /// A path that is not a regular file is refused and left as it was; a failed write leaves
    /// the file at the path as it was; no temporary file stays behind.
    #[test]
    fn images_replace_only_regular_files_and_never_half_written() {
        let tmp = tempfile::tempdir().unwrap();
        let dir = tmp.path();
        let px = vec![Vec3::splat(0.5); 6];
        let sub = dir.join("a-directory.png");
        std::fs::create_dir(&sub).unwrap();
        let e = write_png(&sub, 3, 2, &px, 1.0).unwrap_err().to_string();
        assert!(e.contains("not a regular file"), "{e}");
        assert!(sub.is_dir());
        let e = write_exr(&sub, 3, 2, &px).unwrap_err().to_string();
        assert!(e.contains("not a regular file"), "{e}");
        assert!(sub.is_dir());
        let null = Path::new("/dev/null");
        if null.exists() {
            let e = write_exr(null, 3, 2, &px).unwrap_err().to_string();
            assert!(e.contains("not a regular file"), "{e}");
        }

        let png = dir.join("image.png");
        write_png(&png, 3, 2, &px, 1.0).unwrap();
        let before = std::fs::read(&png).unwrap();
        assert!(write_png(&png, 3, 3, &px, 1.0).is_err());
        assert_eq!(std::fs::read(&png).unwrap(), before);
        // A format the image crate cannot write fails before anything is written.
        assert!(write_png(&dir.join("image.unknown"), 3, 2, &px, 1.0).is_err());
        write_png(&png, 3, 2, &px, 2.0).unwrap();
        assert_ne!(std::fs::read(&png).unwrap(), before);
        let names: Vec<_> = std::fs::read_dir(dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().into_string().unwrap())
            .collect();
        assert_eq!(names.len(), 2, "{names:?}");
    }
}
