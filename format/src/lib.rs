//! # The OSLF store
//!
//! An OSLF store holds an *offset surface light field* (Jason Ang, 2003): HDR cube maps captured
//! at sample points offset by ε above the surfaces of its objects (bicubic Bézier patches or
//! triangle meshes), plus *sample maps* giving, for each texel of a map's (u, v) domain, the 4
//! nearest sample points it sees. This crate writes stores ([`StoreWriter`], [`encode_cube`]),
//! reads them ([`Store`]: positioned reads by default, a memory map on request), joins the
//! shards of a sharded bake ([`shard::merge`]) and checks every byte it is given before it
//! trusts it: a damaged, truncated or hostile file is a typed [`Error`] naming the section and
//! byte offset, never a panic or an out-of-bounds read.
//!
//! **The specification is `docs/format.md`** in the repository: format 1.2, byte by byte,
//! written for a person implementing a reader in another language. This crate is its reference
//! implementation: where a module implements a part of it, its docs name the section.
//!
//! ## Format 1.2
//!
//! Header bytes 8..12 hold [`VERSION`] (`0x0001_0002`: major 1, minor 2), the version this
//! crate writes. Format 1.1 added the irradiance section ([`irradiance`]: each cube's radiance
//! in spherical harmonics, projected from its stored texels) to format 1.0; format 1.2 adds
//! the sampling record to the bake parameters ([`Sampling`]: the adaptive sampling's target
//! and whether the cubes were denoised). Readers read all three ([`VERSION_1_1`],
//! [`VERSION_1_0`]; [`Store::irradiance`] is `None` in 1.0, [`BakeParams::sampling`] `None`
//! before 1.2). Stores of the development builds before 1.0 (version numbers 1
//! to [`LAST_DEVELOPMENT_VERSION`]) are refused with [`Error::UnsupportedVersion`], which
//! says to bake the scene again; [`StoreWriter::resume`] and [`shard::merge`] continue only
//! format 1.2 files.
//!
//! ## Map of the crate
//!
//! | part of the format (`docs/format.md`) | module |
//! |---|---|
//! | Header | [`header`] |
//! | Metadata: bake parameters, camera, object, mesh, material and texture records | [`meta`], [`textures`] |
//! | Sample maps | [`sample_map`] |
//! | Cube payload, table of contents | [`cube`], [`toc`] |
//! | Irradiance section | [`irradiance`] |
//! | Texel encodings, quantized RGB9E5 | [`encoding`], [`bc6h`] |
//! | Distance plane and lattice | [`distance`] |
//! | Face filters | [`filter`] |
//! | Shard files (Appendix A) | [`shard`] |
//! | Reading, verification | [`store`] |
//! | Writing, resuming after an interruption | [`writer`] |
//!
//! ## Host requirements
//!
//! The zero-copy views ([`Store::sample_points`], [`SampleMapView::as_u16`]) reinterpret the
//! little-endian bytes in place, so [`Store::open`] and [`Store::from_bytes`] return
//! [`Error::BigEndianHost`] on big-endian hosts. The writer works on any host.
//!
//! ## Writing
//!
//! [`StoreWriter`] writes `<path>.partial` beside the target, appends cube records as they
//! come ([`encode_cube`] is pure, so encode in parallel), syncs every 64 cubes or 64 MiB, and
//! `finish()` writes the table of contents, patches the header (flags, payload size, TOC
//! position, file size, checksum of the decoded faces, header checksum — bytes 12..16,
//! 120..152, 180..188 and 248..256), syncs, renames over the target and syncs the directory:
//! a crash leaves either no store or a complete one under the final name.

pub mod bc6h;
pub(crate) mod bytes;
pub mod cube;
mod differences;
pub mod distance;
pub mod encoding;
mod encoding_kind;
mod error;
mod face_decoder;
mod file_stamp;
pub mod filter;
pub mod header;
pub mod irradiance;
pub mod meta;
mod output_file;
mod prefix;
mod resume;
pub mod sample_map;
pub mod shard;
pub mod store;
pub mod textures;
pub mod toc;
pub mod writer;

pub use cube::{encode_cube, encode_cube_with_filter, CubeImage, EncodeStats, EncodedCube};
pub use distance::DistancePlane;
pub use encoding_kind::Encoding;
pub use error::Error;
pub use filter::Filter;
pub use meta::{
    BakeParams, CameraInfo, MeshInfo, ObjectInfo, ObjectMaterial, Patch, SamplePoint, Sampling,
    StoreMeta,
};
pub use output_file::{check_not_input, check_output, same_file};
pub use sample_map::{IndexWidth, SampleMapView, SampleMaps, INVALID_INDEX};
pub use shard::{ShardSpec, ShardSummary, ShardWriter};
pub use store::{Store, StoreAccess, VerifyReport};
pub use textures::{ObjectTextures, TextureImage, TextureKind};
pub use toc::FaceEntry;
pub use writer::{StoreSummary, StoreWriter};

/// The first 8 bytes of every store.
pub const MAGIC: [u8; 8] = *b"OSLFSTOR";
/// The first 8 bytes of every shard file ([`shard`]); a store reader that finds them says the
/// file is a shard.
pub const SHARD_MAGIC: [u8; 8] = *b"OSLFSHRD";
/// The format version, header bytes 8..12: format 1.2, major version 1 in the high 16 bits,
/// minor 2 in the low 16. The version this crate writes.
pub const VERSION: u32 = 0x0001_0002;
/// Format 1.1 (header bytes 8..12 `0x0001_0001`): format 1.2 without the sampling record in
/// the bake parameters. Readers read it; writers write [`VERSION`].
pub const VERSION_1_1: u32 = 0x0001_0001;
/// Format 1.0 (header bytes 8..12 `0x0001_0000`): format 1.1 without the irradiance section.
/// Readers read it; writers write [`VERSION`].
pub const VERSION_1_0: u32 = 0x0001_0000;
/// Version numbers 1 to 8 in header bytes 8..12 mark stores written by development builds
/// before format 1.0; readers refuse them with [`Error::UnsupportedVersion`], which says to
/// bake the scene again.
pub const LAST_DEVELOPMENT_VERSION: u32 = 8;

/// `version` as "major.minor" (`VERSION` is "1.2").
pub fn version_name(version: u32) -> String {
    format!("{}.{}", version >> 16, version & 0xffff)
}
/// Largest cube-map face resolution a store may declare.
pub const MAX_CUBE_RESOLUTION: u32 = 16384;
/// Largest sample-map resolution a store may declare.
pub const MAX_SAMPLE_MAP_RESOLUTION: u32 = 16384;
/// Largest object name, in bytes.
pub const MAX_NAME_BYTES: usize = 4096;
