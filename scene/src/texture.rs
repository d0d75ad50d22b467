//! Textures: constants, checkerboards and images, all linear RGB.
//!
//! Image convention: pixel row 0 is the *top* of the file; texture coordinate `v = 0` is the
//! *bottom* (the OBJ / OpenGL convention), so texel `(x, y)` has its centre at
//! `uv = ((x + ½)/w, 1 − (y + ½)/h)`. Lookups are bilinear and wrap (repeat) in both directions.

use std::io::Cursor;
use std::path::Path;
use std::sync::Arc;

use glam::{Vec2, Vec3};
use oslf_shading::color::srgb_to_linear;

use crate::input::{read_input, InputKind, MAX_IMAGE_PIXELS};
use crate::{BakeError, Result};

/// A texture evaluated at surface texture coordinates.
#[derive(Clone, Debug)]
pub enum Texture {
    /// The same value everywhere.
    Constant(Vec3),
    /// Squares of side `1/scale` in uv, `a` where `⌊u·scale⌋ + ⌊v·scale⌋` is even, else `b`.
    Checker { a: Vec3, b: Vec3, scale: f32 },
    /// A linear RGB image (bilinear, wrapping).
    Image(Arc<ImageTexture>),
}

impl Texture {
    /// The texture value at `uv`. Never NaN for finite texture data; a non-finite `uv` reads the
    /// texel at `uv = 0`.
    pub fn eval(&self, uv: Vec2) -> Vec3 {
        let uv = if uv.is_finite() { uv } else { Vec2::ZERO };
        match self {
            Texture::Constant(c) => *c,
            Texture::Checker { a, b, scale } => {
                let s = if scale.is_finite() { *scale } else { 1.0 };
                let ix = (uv.x * s).floor() as i64;
                let iy = (uv.y * s).floor() as i64;
                if (ix + iy).rem_euclid(2) == 0 {
                    *a
                } else {
                    *b
                }
            }
            Texture::Image(img) => img.eval(uv),
        }
    }
}

/// A linear RGB image, row 0 at the top.
#[derive(Clone, Debug, PartialEq)]
pub struct ImageTexture {
    pub width: u32,
    pub height: u32,
    /// `width × height` texels, row-major, all finite and non-negative.
    pub pixels: Vec<Vec3>,
}

impl ImageTexture {
    /// Loads an image with [`load_linear_rgb`].
    pub fn load(path: &Path) -> Result<ImageTexture> {
        let (width, height, pixels) = load_linear_rgb(path)?;
        Ok(ImageTexture {
            width,
            height,
            pixels,
        })
    }

    /// An image from linear texels (row-major, row 0 at the top). Errors on a size mismatch or
    /// a NaN, infinite or negative texel.
    pub fn from_pixels(width: u32, height: u32, pixels: Vec<Vec3>) -> Result<ImageTexture> {
        check_pixels(Path::new("<memory>"), width, height, &pixels)?;
        Ok(ImageTexture {
            width,
            height,
            pixels,
        })
    }

    /// The texel at integer coordinates, wrapping.
    pub fn texel(&self, x: i64, y: i64) -> Vec3 {
        let x = x.rem_euclid(self.width as i64) as usize;
        let y = y.rem_euclid(self.height as i64) as usize;
        self.pixels[y * self.width as usize + x]
    }

    /// Bilinear lookup at `uv` (v up), wrapping in both directions.
    pub fn eval(&self, uv: Vec2) -> Vec3 {
        if self.pixels.is_empty() || !uv.is_finite() {
            return Vec3::ZERO;
        }
        let u = uv.x - uv.x.floor();
        let v = uv.y - uv.y.floor();
        let x = u * self.width as f32 - 0.5;
        let y = (1.0 - v) * self.height as f32 - 0.5;
        let x0 = x.floor();
        let y0 = y.floor();
        let fx = (x - x0).clamp(0.0, 1.0);
        let fy = (y - y0).clamp(0.0, 1.0);
        let (x0, y0) = (x0 as i64, y0 as i64);
        let top = self.texel(x0, y0).lerp(self.texel(x0 + 1, y0), fx);
        let bottom = self.texel(x0, y0 + 1).lerp(self.texel(x0 + 1, y0 + 1), fx);
        top.lerp(bottom, fy)
    }

    /// Number of texels with some component above `limit`.
    pub fn count_above(&self, limit: f32) -> usize {
        self.pixels
            .iter()
            .filter(|p| p.max_element() > limit)
            .count()
    }
}

fn check_pixels(path: &Path, width: u32, height: u32, pixels: &[Vec3]) -> Result<()> {
    if width == 0 || height == 0 || (width as usize) * (height as usize) != pixels.len() {
        return Err(BakeError::Image {
            path: path.to_path_buf(),
            message: format!(
                "{} pixels for a {width} × {height} image (must be non-empty)",
                pixels.len()
            ),
        });
    }
    for (i, p) in pixels.iter().enumerate() {
        for value in p.to_array() {
            if !value.is_finite() || value < 0.0 {
                return Err(BakeError::BadPixel {
                    path: path.to_path_buf(),
                    x: (i % width as usize) as u32,
                    y: (i / width as usize) as u32,
                    value,
                });
            }
        }
    }
    Ok(())
}

const EXR_MAGIC: [u8; 4] = [0x76, 0x2f, 0x31, 0x01];

/// Loads an image as linear RGB: `(width, height, pixels)`, row-major, row 0 at the top.
///
/// The file is read with the image limits of [`crate::input`] (a regular file of at most
/// [`crate::input::MAX_IMAGE_BYTES`], at most [`crate::input::MAX_IMAGE_PIXELS`] pixels as its
/// header declares them) and decoded from memory. The format is recognised from the file's
/// content, not its name:
/// - OpenEXR (via the `exr` crate; the first layer with R, G and B channels, alpha ignored) and
///   Radiance HDR (`.hdr`, RGBE) are linear already;
/// - PNG and JPEG (8 or 16 bit, grey or colour, alpha ignored) are sRGB-encoded and are
///   converted to linear with [`srgb_to_linear`].
///
/// Errors: [`BakeError::Input`] if the file cannot be read, is not a regular file or is too
/// large, [`BakeError::Image`] if it cannot be decoded, is empty or declares too many pixels,
/// [`BakeError::BadPixel`] for the first NaN, infinite or negative component (scanning rows
/// from the top).
pub fn load_linear_rgb(path: &Path) -> Result<(u32, u32, Vec<Vec3>)> {
    let image_err = |message: String| BakeError::Image {
        path: path.to_path_buf(),
        message,
    };
    let bytes = read_input(path, InputKind::Image)?;
    if bytes.len() < 4 {
        return Err(image_err(format!(
            "file is too short to be an image ({} bytes)",
            bytes.len()
        )));
    }
    let check_pixel_count = |w: u64, h: u64| {
        if w.saturating_mul(h) > MAX_IMAGE_PIXELS {
            Err(image_err(format!(
                "{w} × {h} pixels are more than the {MAX_IMAGE_PIXELS} an image may have"
            )))
        } else {
            Ok(())
        }
    };
    let (width, height, pixels) = if bytes[..4] == EXR_MAGIC {
        let meta = exr::meta::MetaData::read_from_buffered(Cursor::new(&bytes[..]), false)
            .map_err(|e| image_err(format!("cannot read OpenEXR: {e}")))?;
        for header in &meta.headers {
            check_pixel_count(header.layer_size.0 as u64, header.layer_size.1 as u64)?;
        }
        load_exr(&bytes).map_err(|e| image_err(format!("cannot read OpenEXR: {e}")))?
    } else {
        let reader = || {
            image::ImageReader::new(Cursor::new(&bytes[..]))
                .with_guessed_format()
                .expect("reading from memory cannot fail")
        };
        let (w, h) = reader()
            .into_dimensions()
            .map_err(|e| image_err(format!("cannot decode image: {e}")))?;
        check_pixel_count(u64::from(w), u64::from(h))?;
        let reader = reader();
        let format = reader.format();
        let img = reader
            .decode()
            .map_err(|e| image_err(format!("cannot decode image: {e}")))?;
        let linear = matches!(
            img,
            image::DynamicImage::ImageRgb32F(_) | image::DynamicImage::ImageRgba32F(_)
        ) || format == Some(image::ImageFormat::Hdr);
        let rgb = img.to_rgb32f();
        let (w, h) = rgb.dimensions();
        let pixels: Vec<Vec3> = rgb
            .pixels()
            .map(|p| {
                let c = Vec3::new(p.0[0], p.0[1], p.0[2]);
                if linear {
                    c
                } else {
                    Vec3::new(
                        srgb_to_linear(c.x),
                        srgb_to_linear(c.y),
                        srgb_to_linear(c.z),
                    )
                }
            })
            .collect();
        (w, h, pixels)
    };
    check_pixels(path, width, height, &pixels)?;
    Ok((width, height, pixels))
}

/// The first RGB layer of the OpenEXR file in `bytes`.
fn load_exr(bytes: &[u8]) -> std::result::Result<(u32, u32, Vec<Vec3>), exr::error::Error> {
    use exr::prelude::*;
    let image = read()
        .no_deep_data()
        .largest_resolution_level()
        .rgba_channels(
            |resolution, _channels: &RgbaChannels| {
                (
                    resolution.width(),
                    vec![Vec3::ZERO; resolution.width() * resolution.height()],
                )
            },
            |(w, pixels): &mut (usize, Vec<Vec3>), pos, (r, g, b, _a): (f32, f32, f32, f32)| {
                pixels[pos.y() * *w + pos.x()] = Vec3::new(r, g, b);
            },
        )
        .first_valid_layer()
        .all_attributes()
        .from_buffered(Cursor::new(bytes))?;
    let size = image.layer_data.size;
    let (_, pixels) = image.layer_data.channel_data.pixels;
    Ok((size.width() as u32, size.height() as u32, pixels))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn checker_squares() {
        let t = Texture::Checker {
            a: Vec3::ONE,
            b: Vec3::ZERO,
            scale: 4.0,
        };
        assert_eq!(t.eval(Vec2::new(0.1, 0.1)), Vec3::ONE);
        assert_eq!(t.eval(Vec2::new(0.3, 0.1)), Vec3::ZERO);
        assert_eq!(t.eval(Vec2::new(0.3, 0.3)), Vec3::ONE);
        assert_eq!(t.eval(Vec2::new(-0.1, 0.1)), Vec3::ZERO);
        assert!(t.eval(Vec2::NAN).is_finite());
    }

    #[test]
    fn image_bilinear_wraps() {
        let img = ImageTexture::from_pixels(
            2,
            1,
            vec![Vec3::new(1.0, 0.0, 0.0), Vec3::new(0.0, 0.0, 1.0)],
        )
        .unwrap();
        // Texel centres.
        assert!((img.eval(Vec2::new(0.25, 0.5)) - Vec3::X).length() < 1e-6);
        assert!((img.eval(Vec2::new(0.75, 0.5)) - Vec3::Z).length() < 1e-6);
        // Half-way between texel 1 and (wrapped) texel 0.
        let edge = img.eval(Vec2::new(0.0, 0.5));
        assert!((edge - Vec3::new(0.5, 0.0, 0.5)).length() < 1e-6);
        assert_eq!(
            img.eval(Vec2::new(1.25, 3.5)),
            img.eval(Vec2::new(0.25, 0.5))
        );
        assert!(ImageTexture::from_pixels(1, 1, vec![Vec3::splat(-1.0)]).is_err());
        assert!(ImageTexture::from_pixels(2, 1, vec![Vec3::ONE]).is_err());
    }
}
