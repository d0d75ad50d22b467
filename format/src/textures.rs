//! An object's material textures: the texture record that ends a mesh
//! object's record, with its texture coordinates, tangents and images (see `docs/format.md`,
//! "Texture record").

use crate::bytes::{ByteReader, ByteWriter};
use crate::Error;

/// Largest width or height of a stored texture.
pub const MAX_TEXTURE_SIDE: u32 = 16384;
/// How far from 1 a stored tangent's length may be (as a mesh record's normals).
pub const TANGENT_LENGTH_TOLERANCE: f32 = 1e-3;
/// Most texels of one stored texture (8192², 256 MiB of RGBA8).
pub const MAX_TEXTURE_TEXELS: u64 = 1 << 26;

/// The kinds of texture a texture record may hold, in the order of its flag bits and of its
/// images.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TextureKind {
    /// glTF `baseColorTexture` times `baseColorFactor`: sRGB-encoded RGB (alpha unused).
    BaseColor,
    /// glTF `metallicRoughnessTexture` times its factors: roughness in G, metallic in B, linear.
    MetallicRoughness,
    /// glTF `normalTexture`: tangent-space normal, linear, `2c − 1` per channel.
    Normal,
    /// glTF `occlusionTexture`: occlusion in R, linear.
    Occlusion,
    /// glTF `emissiveTexture`: sRGB-encoded RGB, times the material's emission.
    Emissive,
}

impl TextureKind {
    /// Every kind, in flag-bit order.
    pub const ALL: [TextureKind; 5] = [
        TextureKind::BaseColor,
        TextureKind::MetallicRoughness,
        TextureKind::Normal,
        TextureKind::Occlusion,
        TextureKind::Emissive,
    ];

    /// Whether the RGB channels are sRGB-encoded (base colour and emissive).
    pub fn is_srgb(self) -> bool {
        matches!(self, TextureKind::BaseColor | TextureKind::Emissive)
    }

    /// Its name in messages and documents.
    pub fn name(self) -> &'static str {
        match self {
            TextureKind::BaseColor => "base colour",
            TextureKind::MetallicRoughness => "metallic-roughness",
            TextureKind::Normal => "normal",
            TextureKind::Occlusion => "occlusion",
            TextureKind::Emissive => "emissive",
        }
    }
}

/// One texture image: RGBA8 texels, row-major, row 0 at the top. Texel `(x, y)` is centred at
/// texture coordinates `((x + ½)/w, 1 − (y + ½)/h)`; lookups are bilinear and repeat in both
/// directions (a glTF sampler's clamp or mirror wrap is resampled into the image by the bake).
#[derive(Clone, Debug, PartialEq)]
pub struct TextureImage {
    pub width: u32,
    pub height: u32,
    /// `width × height` texels.
    pub texels: Vec<[u8; 4]>,
}

/// A mesh object's textures and the per-vertex data they need.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ObjectTextures {
    /// Texture coordinates, one per mesh vertex (finite; any range: lookups repeat).
    pub texcoords: Vec<[f32; 2]>,
    /// Unit tangents (object space) with the bitangent's sign in `w` (±1), one per mesh vertex;
    /// present exactly when there is a normal texture (MikkTSpace where the asset had none).
    pub tangents: Vec<[f32; 4]>,
    /// glTF `normalTexture.scale` (finite).
    pub normal_scale: f32,
    /// glTF `occlusionTexture.strength`, in `[0, 1]`.
    pub occlusion_strength: f32,
    /// The images, at most one per kind, in [`TextureKind::ALL`] order.
    pub images: Vec<(TextureKind, TextureImage)>,
}

impl ObjectTextures {
    /// The image of `kind`, if any.
    pub fn image(&self, kind: TextureKind) -> Option<&TextureImage> {
        self.images.iter().find(|(k, _)| *k == kind).map(|(_, i)| i)
    }

    /// The record's flag word: bit `i` set when [`TextureKind::ALL`]`[i]` is present.
    fn flags(&self) -> u32 {
        self.images.iter().fold(0, |f, (k, _)| {
            f | 1 << TextureKind::ALL.iter().position(|a| a == k).unwrap_or(31)
        })
    }
}

/// Appends the texture record of an object (`None`: the flag word 0).
pub(crate) fn encode_textures(w: &mut ByteWriter, t: Option<&ObjectTextures>, zstd_level: i32) {
    let Some(t) = t else {
        w.u32(0);
        return;
    };
    w.u32(t.flags());
    w.f32(t.normal_scale);
    w.f32(t.occlusion_strength);
    for v in t
        .texcoords
        .iter()
        .flatten()
        .chain(t.tangents.iter().flatten())
    {
        w.f32(*v);
    }
    for (_, image) in &t.images {
        w.u32(image.width);
        w.u32(image.height);
        let raw: Vec<u8> = image.texels.iter().flatten().copied().collect();
        // A frame that fails to compress is written empty; decode_textures (run by the writer
        // on what it encodes) then refuses it.
        let frame = zstd::bulk::compress(&raw, zstd_level).unwrap_or_default();
        w.u32(u32::try_from(frame.len()).unwrap_or(u32::MAX));
        w.bytes(&frame);
    }
}

fn bad(offset: u64, detail: impl Into<String>) -> Error {
    Error::InvalidMetadata {
        offset,
        detail: detail.into(),
    }
}

/// Parses and validates object `i`'s texture record; `vertices` is its mesh's vertex count
/// (`None` for a Bézier object, which may hold no textures).
pub(crate) fn decode_textures(
    r: &mut ByteReader<'_>,
    i: usize,
    vertices: Option<usize>,
) -> Result<Option<ObjectTextures>, Error> {
    let at = r.offset();
    let flags = r.u32()?;
    if flags == 0 {
        return Ok(None);
    }
    if flags >> TextureKind::ALL.len() != 0 {
        return Err(bad(
            at,
            format!("object {i}: texture flags {flags:#x} set unknown bits (0x1f are defined)"),
        ));
    }
    let Some(v) = vertices else {
        return Err(bad(
            at,
            format!("object {i}: a Bézier object has textures (flags {flags:#x}); only meshes may"),
        ));
    };
    let at = r.offset();
    let normal_scale = r.finite_f32("normal scale")?;
    let occlusion_strength = r.finite_f32("occlusion strength")?;
    if !(0.0..=1.0).contains(&occlusion_strength) {
        return Err(bad(
            at + 4,
            format!("object {i}: occlusion strength {occlusion_strength} outside [0, 1]"),
        ));
    }
    let has_normal = flags & 4 != 0;
    let floats = v as u64 * if has_normal { 6 } else { 2 };
    if floats * 4 > r.remaining() as u64 {
        return Err(bad(
            r.offset(),
            format!(
                "object {i}: {v} vertices' texture coordinates{} need {} bytes but {} remain",
                if has_normal { " and tangents" } else { "" },
                floats * 4,
                r.remaining()
            ),
        ));
    }
    let mut texcoords = Vec::with_capacity(v);
    for _ in 0..v {
        texcoords.push([
            r.finite_f32("texture coordinate")?,
            r.finite_f32("texture coordinate")?,
        ]);
    }
    let mut tangents = Vec::with_capacity(if has_normal { v } else { 0 });
    for k in 0..if has_normal { v } else { 0 } {
        tangents.push(decode_tangent(r, i, k)?);
    }
    let mut images = Vec::new();
    for (bit, kind) in TextureKind::ALL.into_iter().enumerate() {
        if flags & (1 << bit) != 0 {
            images.push((kind, decode_image(r, i, kind)?));
        }
    }
    Ok(Some(ObjectTextures {
        texcoords,
        tangents,
        normal_scale,
        occlusion_strength,
        images,
    }))
}

/// Parses vertex `k`'s tangent: unit xyz (within [`TANGENT_LENGTH_TOLERANCE`]), `w` ±1.
fn decode_tangent(r: &mut ByteReader<'_>, i: usize, k: usize) -> Result<[f32; 4], Error> {
    let at = r.offset();
    let mut t = [0f32; 4];
    for x in &mut t {
        *x = r.finite_f32("tangent")?;
    }
    let len = t[..3]
        .iter()
        .map(|x| f64::from(*x).powi(2))
        .sum::<f64>()
        .sqrt();
    if (len - 1.0).abs() > f64::from(TANGENT_LENGTH_TOLERANCE) || t[3].abs() != 1.0 {
        return Err(bad(
            at,
            format!("object {i}: vertex {k} tangent {t:?} is not a unit vector with w = ±1"),
        ));
    }
    Ok(t)
}

/// Parses one image: size, then a zstd frame holding exactly its RGBA8 texels.
fn decode_image(
    r: &mut ByteReader<'_>,
    i: usize,
    kind: TextureKind,
) -> Result<TextureImage, Error> {
    let at = r.offset();
    let (width, height) = (r.u32()?, r.u32()?);
    let texels = u64::from(width) * u64::from(height);
    if width == 0
        || height == 0
        || width > MAX_TEXTURE_SIDE
        || height > MAX_TEXTURE_SIDE
        || texels > MAX_TEXTURE_TEXELS
    {
        return Err(bad(
            at,
            format!(
                "object {i}: {} texture of {width}×{height} texels (each side 1..={MAX_TEXTURE_SIDE}, at most {MAX_TEXTURE_TEXELS} texels)",
                kind.name()
            ),
        ));
    }
    let at = r.offset();
    let len = r.u32()? as usize;
    let frame = r.take(len)?;
    let want = texels as usize * 4;
    let raw = zstd::bulk::decompress(frame, want).map_err(|e| {
        bad(
            at + 4,
            format!(
                "object {i}: {} texture does not decompress: {e}",
                kind.name()
            ),
        )
    })?;
    if raw.len() != want {
        return Err(bad(
            at + 4,
            format!(
                "object {i}: {} texture decompresses to {} bytes, not the {want} of {width}×{height} RGBA8",
                kind.name(),
                raw.len()
            ),
        ));
    }
    Ok(TextureImage {
        width,
        height,
        texels: raw
            .chunks_exact(4)
            .map(|c| [c[0], c[1], c[2], c[3]])
            .collect(),
    })
}

/// What is wrong with `t` on a mesh of `v` vertices, if anything.
pub(crate) fn check(t: &ObjectTextures, v: usize) -> Option<String> {
    let has_normal = t.image(TextureKind::Normal).is_some();
    let kinds: Vec<usize> = t
        .images
        .iter()
        .filter_map(|(k, _)| TextureKind::ALL.iter().position(|a| a == k))
        .collect();
    if t.images.is_empty() {
        Some("a texture record without images (use None)".into())
    } else if kinds.windows(2).any(|w| w[0] >= w[1]) {
        Some("texture images must be in TextureKind::ALL order, one per kind".into())
    } else if t.texcoords.len() != v {
        Some(format!(
            "{} texture coordinates for {v} vertices",
            t.texcoords.len()
        ))
    } else if t.tangents.len() != if has_normal { v } else { 0 } {
        Some(format!(
            "{} tangents for {v} vertices (one per vertex exactly when there is a normal texture)",
            t.tangents.len()
        ))
    } else {
        t.images.iter().find_map(|(k, im)| {
            (im.texels.len() as u64 != u64::from(im.width) * u64::from(im.height)).then(|| {
                format!(
                    "{} texture of {}×{} has {} texels",
                    k.name(),
                    im.width,
                    im.height,
                    im.texels.len()
                )
            })
        })
    }
}
