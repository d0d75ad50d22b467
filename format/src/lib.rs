//! OSLF store (layout documented below; filled in at the end).

pub(crate) mod bytes;
pub mod cube;
pub mod encoding;
mod error;
pub mod header;
pub mod meta;
pub mod sample_map;
pub mod store;
pub mod toc;
pub mod writer;

pub use cube::{encode_cube, CubeImage, EncodeStats, EncodedCube};
pub use encoding::Encoding;
pub use error::Error;
pub use meta::{BakeParams, CameraInfo, ObjectInfo, Patch, SamplePoint, StoreMeta};
pub use sample_map::{IndexWidth, SampleMapView, SampleMaps, INVALID_INDEX};
pub use store::{Store, VerifyReport};
pub use toc::FaceEntry;
pub use writer::{StoreSummary, StoreWriter};

/// The first 8 bytes of every store.
pub const MAGIC: [u8; 8] = *b"OSLFSTOR";
/// The format version this crate writes and reads.
pub const VERSION: u32 = 1;
/// Largest cube-map face resolution a store may declare.
pub const MAX_CUBE_RESOLUTION: u32 = 16384;
/// Largest sample-map resolution a store may declare.
pub const MAX_SAMPLE_MAP_RESOLUTION: u32 = 16384;
/// Largest object name, in bytes.
pub const MAX_NAME_BYTES: usize = 4096;
