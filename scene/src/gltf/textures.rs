//! Textures: images decoded to linear RGB, the samplers' wrap modes and
//! `KHR_texture_transform` realised on the crate's always-repeating textures.

use std::borrow::Cow;
use std::sync::Arc;

use glam::{Vec2, Vec3};
use gltf::texture::WrappingMode;

use super::loader::Loader;
use crate::input::{InputKind, MAX_IMAGE_PIXELS};
use oslf_shading::color::srgb_to_linear;

use crate::texture::ImageTexture;
use crate::Result;

impl<'d> Loader<'d> {
    /// How a primitive's texture coordinates map into the texture of `info`, the material's
    /// `slot` (`baseColorTexture`, `metallicRoughnessTexture`), whose image holds colours
    /// (`srgb`) or data.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn uv_map(
        &mut self,
        m: &gltf::Material,
        slot: &str,
        srgb: bool,
        info: &gltf::texture::Info,
        transform: Option<&gltf::texture::TextureTransform>,
        set: u32,
    ) -> Result<UvMap> {
        let texture = info.texture();
        let image = self.image(&texture.source(), srgb)?;
        let sampler = texture.sampler();
        let (offset, rotation, scale) = match transform {
            Some(t) => (Vec2::from(t.offset()), t.rotation(), Vec2::from(t.scale())),
            None => (Vec2::ZERO, 0.0, Vec2::ONE),
        };
        if !(offset.is_finite() && rotation.is_finite() && scale.is_finite()) {
            let at = match m.index() {
                Some(i) => format!("materials[{i}]"),
                None => "materials".into(),
            };
            return Err(self.err(
                format!("{at}.pbrMetallicRoughness.{slot}.extensions.KHR_texture_transform"),
                "offset, rotation and scale must be finite",
            ));
        }
        Ok(UvMap {
            set,
            offset,
            rotation,
            scale,
            wrap: [
                axis_map(sampler.wrap_s(), image.width),
                axis_map(sampler.wrap_t(), image.height),
            ],
        })
    }

    /// How a texture without `KHR_texture_transform` (glTF's `normalTexture` or
    /// `occlusionTexture`) maps texture coordinates: its set `set` and its sampler's wraps.
    pub(super) fn plain_uv_map(&mut self, texture: &gltf::Texture, set: u32) -> Result<UvMap> {
        let image = self.image(&texture.source(), false)?;
        let sampler = texture.sampler();
        Ok(UvMap {
            set,
            offset: Vec2::ZERO,
            rotation: 0.0,
            scale: Vec2::ONE,
            wrap: [
                axis_map(sampler.wrap_s(), image.width),
                axis_map(sampler.wrap_t(), image.height),
            ],
        })
    }

    /// An image decoded to linear RGB, from sRGB where `srgb` (colours) or as stored (data such
    /// as metallic-roughness), cached by index and decoding.
    pub(super) fn image(&mut self, image: &gltf::Image, srgb: bool) -> Result<Arc<ImageTexture>> {
        if let Some(img) = self.images.get(&(image.index(), srgb)) {
            return Ok(img.clone());
        }
        let i = image.index();
        let at = format!("images[{i}]");
        // From the JSON: `Image::source` unwraps a missing mimeType or uri.
        let json = &self.doc.as_json().images[i];
        let bytes: Cow<[u8]> = match (&json.buffer_view, &json.uri) {
            (Some(view), _) => {
                let view = self.doc.views().nth(view.value()).ok_or_else(|| {
                    self.err(
                        format!("{at}.bufferView"),
                        "refers to a missing buffer view",
                    )
                })?;
                Cow::Borrowed(self.view_bytes(&view))
            }
            (None, Some(uri)) => {
                Cow::Owned(self.read_uri(uri, &format!("{at}.uri"), &InputKind::Image.limit())?)
            }
            (None, None) => return Err(self.err(&at, "has neither a uri nor a bufferView")),
        };
        // The pixel count its header declares, checked before decoding (crate::input).
        let declared = image::ImageReader::new(std::io::Cursor::new(&bytes[..]))
            .with_guessed_format()
            .ok()
            .and_then(|r| r.into_dimensions().ok());
        if let Some((w, h)) = declared {
            if u64::from(w) * u64::from(h) > MAX_IMAGE_PIXELS {
                return Err(self.err(
                    &at,
                    format!(
                        "{w} × {h} pixels are more than the {MAX_IMAGE_PIXELS} an image may have"
                    ),
                ));
            }
        }
        let decoded = image::load_from_memory(&bytes)
            .map_err(|e| self.err(&at, format!("cannot decode the image: {e}")))?;
        let rgb = decoded.to_rgb32f();
        let (w, h) = rgb.dimensions();
        let pixels: Vec<Vec3> = rgb
            .pixels()
            .map(|p| {
                let c = Vec3::from(p.0);
                if srgb {
                    c.map(srgb_to_linear)
                } else {
                    c
                }
            })
            .collect();
        let img = ImageTexture::from_pixels(w, h, pixels)
            .map_err(|e| self.err(&at, format!("unusable image: {e}")))?;
        let img = Arc::new(img);
        self.images.insert((i, srgb), img.clone());
        Ok(img)
    }
}

/// How a wrap mode is realised along one axis of a texture that always repeats: the image
/// is resampled (see [`wrapped_image`]) and the coordinate mapped into it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) enum AxisMap {
    /// REPEAT: as is.
    Repeat,
    /// MIRRORED_REPEAT: the image followed by its mirror image, coordinates halved.
    Mirror,
    /// CLAMP_TO_EDGE: the image with a one-texel border copying its edge, so that bilinear
    /// lookups within [0, 1] clamp: exact where texture coordinates lie within [0, 1]; beyond,
    /// the image repeats (warned about).
    Clamp { texels: u32 },
}

pub(super) fn axis_map(mode: WrappingMode, texels: u32) -> AxisMap {
    match mode {
        WrappingMode::Repeat => AxisMap::Repeat,
        WrappingMode::MirroredRepeat => AxisMap::Mirror,
        WrappingMode::ClampToEdge => AxisMap::Clamp { texels },
    }
}

impl AxisMap {
    pub(super) fn apply(self, t: f32) -> f32 {
        match self {
            AxisMap::Repeat => t,
            AxisMap::Mirror => 0.5 * t,
            AxisMap::Clamp { texels } => {
                let n = texels as f32;
                (t * n + 1.0) / (n + 2.0)
            }
        }
    }

    /// Resampled size and the source texel of each resampled texel.
    pub(super) fn source(self, size: u32) -> (u32, Box<dyn Fn(u32) -> u32>) {
        match self {
            AxisMap::Repeat => (size, Box::new(|x| x)),
            AxisMap::Mirror => (
                2 * size,
                Box::new(move |x| if x < size { x } else { 2 * size - 1 - x }),
            ),
            AxisMap::Clamp { .. } => (
                size + 2,
                Box::new(move |x| x.saturating_sub(1).min(size - 1)),
            ),
        }
    }
}

/// How a primitive's glTF texture coordinates become the crate's: `KHR_texture_transform`,
/// then the wrap modes ([`AxisMap`]), then `v` flipped (glTF's origin is the top-left).
#[derive(Clone, Debug, PartialEq)]
pub(super) struct UvMap {
    pub(super) set: u32,
    offset: Vec2,
    rotation: f32,
    scale: Vec2,
    wrap: [AxisMap; 2],
}

impl UvMap {
    /// Whether `uv` (as in the file) falls outside [0, 1] along a clamped axis, where the
    /// import cannot clamp (see [`AxisMap::Clamp`]).
    pub(super) fn beyond_clamp(&self, uv: Vec2) -> bool {
        const SLACK: f32 = 1e-4;
        let t = texture_transform(uv, self.offset, self.rotation, self.scale);
        [t.x, t.y]
            .iter()
            .zip(&self.wrap)
            .any(|(c, w)| matches!(w, AxisMap::Clamp { .. }) && !(-SLACK..=1.0 + SLACK).contains(c))
    }

    pub(super) fn apply(&self, uv: Vec2) -> Vec2 {
        let uv = texture_transform(uv, self.offset, self.rotation, self.scale);
        let u = self.wrap[0].apply(uv.x);
        let v = self.wrap[1].apply(uv.y);
        Vec2::new(u, 1.0 - v)
    }
}

/// `KHR_texture_transform`: scale, then rotate, then offset:
/// `u' = offset.x + cos r · s.x·u + sin r · s.y·v`, `v' = offset.y − sin r · s.x·u + cos r · s.y·v`
/// (the rotation as the extension's example and three.js, Blender and the sample models have
/// it: `offset = [0, 1]`, `rotation = π/2`, `scale = [½, ½]` maps the unit square onto the
/// image's lower-left quadrant).
pub fn texture_transform(uv: Vec2, offset: Vec2, rotation: f32, scale: Vec2) -> Vec2 {
    let s = uv * scale;
    let (sin, cos) = rotation.sin_cos();
    offset + Vec2::new(cos * s.x + sin * s.y, -sin * s.x + cos * s.y)
}

/// The image resampled for the wrap modes (see [`AxisMap`]), multiplied by `factor`.
pub(super) fn wrapped_image(
    img: &ImageTexture,
    s: WrappingMode,
    t: WrappingMode,
    factor: Vec3,
) -> ImageTexture {
    let (w, fx) = axis_map(s, img.width).source(img.width);
    let (h, fy) = axis_map(t, img.height).source(img.height);
    let mut pixels = Vec::with_capacity(w as usize * h as usize);
    for y in 0..h {
        let sy = fy(y) as usize;
        for x in 0..w {
            let sx = fx(x) as usize;
            pixels.push(img.pixels[sy * img.width as usize + sx] * factor);
        }
    }
    ImageTexture {
        width: w,
        height: h,
        pixels,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn texture_transform_matches_the_extension_example() {
        // offset [0, 1], rotation π/2, scale ½: the unit square onto the lower-left quadrant
        // (v down).
        let f = |uv: Vec2| {
            texture_transform(
                uv,
                Vec2::new(0.0, 1.0),
                std::f32::consts::FRAC_PI_2,
                Vec2::splat(0.5),
            )
        };
        assert!((f(Vec2::ZERO) - Vec2::new(0.0, 1.0)).length() < 1e-6);
        assert!((f(Vec2::X) - Vec2::new(0.0, 0.5)).length() < 1e-6);
        assert!((f(Vec2::Y) - Vec2::new(0.5, 1.0)).length() < 1e-6);
        assert!((f(Vec2::ONE) - Vec2::new(0.5, 0.5)).length() < 1e-6);
    }

    #[test]
    fn wrap_modes_resample_exactly() {
        let img = ImageTexture::from_pixels(
            2,
            1,
            vec![Vec3::new(1.0, 0.0, 0.0), Vec3::new(0.0, 0.0, 1.0)],
        )
        .unwrap();
        let mirrored = wrapped_image(
            &img,
            WrappingMode::MirroredRepeat,
            WrappingMode::Repeat,
            Vec3::ONE,
        );
        assert_eq!(mirrored.width, 4);
        assert_eq!(mirrored.pixels[2], Vec3::Z);
        assert_eq!(mirrored.pixels[3], Vec3::X);
        // Mirrored: u = 1.25 reads what u = 0.75 reads.
        let m = AxisMap::Mirror;
        let a = mirrored.eval(Vec2::new(m.apply(1.25), 0.5));
        let b = mirrored.eval(Vec2::new(m.apply(0.75), 0.5));
        assert!((a - b).length() < 1e-6);
        // Clamped: u = 0 reads the first texel alone, not a blend with the last.
        let clamped = wrapped_image(
            &img,
            WrappingMode::ClampToEdge,
            WrappingMode::Repeat,
            Vec3::splat(0.5),
        );
        let c = AxisMap::Clamp { texels: 2 };
        let e = clamped.eval(Vec2::new(c.apply(0.0), 0.5));
        assert!((e - Vec3::new(0.5, 0.0, 0.0)).length() < 1e-6, "{e}");
        let e = clamped.eval(Vec2::new(c.apply(1.0), 0.5));
        assert!((e - Vec3::new(0.0, 0.0, 0.5)).length() < 1e-6, "{e}");
    }
}
