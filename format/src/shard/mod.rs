//! Shards: a deterministic share of a store's cube maps, baked on its own machine and merged
//! into the store later ([`merge()`]), byte for byte the store a single bake writes.
//!
//! Shard `I/N` holds the cubes `i` with `i % N == I` (interleaved: neighbouring sample points
//! cost about the same to trace, so every shard gets a fair share of the expensive ones, and
//! shards differ by at most one cube). Every shard recomputes the sample points and sample
//! maps (they are deterministic) and stores them, so shards need no coordination and any
//! one of them carries everything but the other shards' cubes.
//!
//! ## Shard file layout (shard format version 1)
//!
//! Little-endian, checksums xxh3-64 with seed 0, as in the store.
//!
//! | offset | type      | field |
//! |-------:|-----------|-------|
//! | 0      | `[u8; 8]` | magic [`SHARD_MAGIC`] = `"OSLFSHRD"` |
//! | 8      | `u32`     | shard format version = [`SHARD_VERSION`] (1) |
//! | 12     | `u32`     | flags: bit 0 COMPLETE (set by [`ShardWriter::finish`]); other bits 0 |
//! | 16     | `u32`     | shard index `I` |
//! | 20     | `u32`     | shard count `N` (`I < N`) |
//! | 24     | `u64`     | cube_count of the whole store |
//! | 32     | `u64`     | cubes in this shard (`i < cube_count` with `i % N == I`) |
//! | 40     | `u64`     | prefix size `P` |
//! | 48     | `u64`     | checksum of the prefix's `P` bytes |
//! | 56     | `u64`     | file size (0 until finished) |
//! | 64     | 56 bytes  | reserved, zero |
//! | 120    | `u64`     | checksum of bytes 0..120 |
//!
//! Then the *prefix*: the first `P` bytes of the (unfinished) store exactly as
//! [`crate::StoreWriter::create`] writes them — store header with the COMPLETE flag clear,
//! metadata, sample points, sample maps and their padding; `P` is the cube payload offset.
//! Then, for each cube of the shard in increasing index, the store's cube record (record
//! header, six frames, zero padding to a multiple of 8; see `docs/format.md`) followed by a
//! 56-byte *trailer*: the six `u64` checksums of the raw faces (what the store's
//! decoded-faces checksum hashes) and a `u64` checksum of those 48 bytes.
//!
//! A shard is written to `<path>.partial` and renamed when finished, like a store;
//! [`ShardWriter::resume`] keeps its complete records after a kill. [`merge()`] checks that the
//! shards form one complete set (same shard count, every index once, identical prefixes),
//! then writes the store through [`crate::StoreWriter`]: the prefix, the records in cube
//! order, the table of contents.

mod file;
mod merge;
mod spec;
mod writer;

pub use file::{SHARD_HEADER_BYTES, SHARD_MAGIC, SHARD_VERSION, TRAILER_BYTES};
pub use merge::merge;
pub use spec::ShardSpec;
pub use writer::{ShardSummary, ShardWriter};
