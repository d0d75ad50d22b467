//! Which texel encoding a store uses ([`Encoding`]) and what follows from it: bytes per
//! texel and per face, the largest value. A leaf:
//! the codecs ([`crate::encoding`]) and the errors that name an encoding build on it.

/// Largest finite RGB9E5 value: `511/512 * 2^16`.
pub const MAX_RGB9E5: f32 = 65408.0;
/// Largest finite IEEE binary16 value.
pub const MAX_F16: f32 = 65504.0;

/// How cube-map texels are stored.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Default)]
pub enum Encoding {
    /// Shared-exponent RGB, 4 bytes per texel (the default).
    #[default]
    Rgb9e5,
    /// Half-float RGBA, 8 bytes per texel.
    Rgba16f,
    /// Float RGBA, 16 bytes per texel.
    Rgba32f,
    /// Unsigned BC6H blocks, 16 bytes per 4×4 texels (1 byte per texel when the face side is
    /// a multiple of 4).
    Bc6h,
}

impl Encoding {
    /// All encodings, in tag order.
    pub const ALL: [Encoding; 4] = [
        Encoding::Rgb9e5,
        Encoding::Rgba16f,
        Encoding::Rgba32f,
        Encoding::Bc6h,
    ];

    /// The per-texel encodings (all but the block-compressed [`Encoding::Bc6h`]), in tag order:
    /// those [`crate::encoding::encode_texels`] and [`crate::encoding::decode_texels`] take.
    pub const PER_TEXEL: [Encoding; 3] = [Encoding::Rgb9e5, Encoding::Rgba16f, Encoding::Rgba32f];

    /// Bytes one texel takes: 4, 8 or 16; for [`Encoding::Bc6h`] 1, the average over a face
    /// whose side is a multiple of 4 (use [`Encoding::face_bytes`] for the exact size of a face).
    pub fn bytes_per_texel(self) -> usize {
        match self {
            Encoding::Rgb9e5 => 4,
            Encoding::Rgba16f => 8,
            Encoding::Rgba32f => 16,
            Encoding::Bc6h => 1,
        }
    }

    /// Whether texels are encoded in blocks of a face rather than one by one
    /// ([`Encoding::Bc6h`]).
    pub fn is_block_compressed(self) -> bool {
        self == Encoding::Bc6h
    }

    /// Bytes of the encoded texels of one face of `resolution`² texels: `resolution² ×
    /// bytes_per_texel`, or `⌈resolution / 4⌉² × 16` for BC6H. `None` on overflow.
    pub fn face_bytes(self, resolution: u32) -> Option<usize> {
        match self {
            Encoding::Bc6h => bc6h_face_bytes(resolution),
            _ => (resolution as usize)
                .checked_mul(resolution as usize)?
                .checked_mul(self.bytes_per_texel()),
        }
    }

    /// `"rgb9e5"`, `"rgba16f"`, `"rgba32f"` or `"bc6h"`.
    pub fn name(self) -> &'static str {
        match self {
            Encoding::Rgb9e5 => "rgb9e5",
            Encoding::Rgba16f => "rgba16f",
            Encoding::Rgba32f => "rgba32f",
            Encoding::Bc6h => "bc6h",
        }
    }

    /// The on-disk tag: 0, 1, 2 or 3.
    pub fn tag(self) -> u32 {
        match self {
            Encoding::Rgb9e5 => 0,
            Encoding::Rgba16f => 1,
            Encoding::Rgba32f => 2,
            Encoding::Bc6h => 3,
        }
    }

    /// The encoding with on-disk tag `tag`.
    pub fn from_tag(tag: u32) -> Option<Self> {
        match tag {
            0 => Some(Encoding::Rgb9e5),
            1 => Some(Encoding::Rgba16f),
            2 => Some(Encoding::Rgba32f),
            3 => Some(Encoding::Bc6h),
            _ => None,
        }
    }

    /// Largest finite value a channel can hold; larger values are clamped to it.
    pub fn max_value(self) -> f32 {
        match self {
            Encoding::Rgb9e5 => MAX_RGB9E5,
            Encoding::Rgba16f | Encoding::Bc6h => MAX_F16,
            Encoding::Rgba32f => f32::MAX,
        }
    }
}

impl std::fmt::Display for Encoding {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// Bytes of one BC6H face of `resolution`² texels: `⌈resolution / 4⌉²` blocks of 16 bytes;
/// `None` on overflow.
pub(crate) fn bc6h_face_bytes(resolution: u32) -> Option<usize> {
    let b = (resolution as usize).div_ceil(4);
    b.checked_mul(b)?.checked_mul(16)
}
