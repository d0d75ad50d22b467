//! The crate's one error type.

use std::path::PathBuf;

/// Everything that can go wrong while encoding, writing, opening or reading a store.
///
/// Every variant says *what* is wrong and *where*: the section, the cube and face, the texel,
/// the byte offset in the file.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// An I/O error; `context` names the file and the operation. The I/O error is part of the
    /// message and not a source, so that a chain of causes (`{:#}`) prints it once.
    #[error("{context}: {error}")]
    Io {
        context: String,
        error: std::io::Error,
    },
    /// A store's file no longer holds bytes it held when it was opened: it was changed,
    /// truncated or overwritten (e.g. `cp` over it) while open.
    #[error(
        "{path}: the file changed on disk while open (reading byte offset {offset}: {detail}); \
         reopen it once it is complete (writers should replace stores by rename, as `oslf bake` does)"
    )]
    ChangedOnDisk {
        path: std::path::PathBuf,
        offset: u64,
        detail: String,
    },
    /// The zero-copy views need a little-endian host.
    #[error("OSLF stores can only be read on little-endian hosts")]
    BigEndianHost,
    /// The first 8 bytes are not [`crate::MAGIC`].
    #[error("not an OSLF store: magic is {found:02x?} (expected {expected:02x?})")]
    BadMagic { found: [u8; 8], expected: [u8; 8] },
    /// The file is a shard of `oslf bake --shard I/N` (its magic is `OSLFSHRD`), not a store.
    #[error("this is a shard of a sharded bake (magic \"OSLFSHRD\"), not a store: join all the shards into one store with `oslf store merge`")]
    IsShard,
    /// An input that is not a regular file (a FIFO, device, directory), refused before it is
    /// opened for reading, or that cannot be opened.
    #[error(transparent)]
    Input(Box<oslf_util::UtilError>),
    /// A format version other than 1.0 at header bytes 8..12: a store of a pre-1.0
    /// development build (1 to [`crate::LAST_DEVELOPMENT_VERSION`]), to be baked again, or of
    /// a format this reader does not know.
    #[error("{}", unsupported_version(*found))]
    UnsupportedVersion { found: u32 },
    /// The file ends before a structure it must contain.
    #[error(
        "truncated store: {section} needs bytes {offset}..{end} but the file has {file_size} bytes"
    )]
    Truncated {
        section: &'static str,
        offset: u64,
        end: u64,
        file_size: u64,
    },
    /// A checksum over a section (header, metadata, sample points, sample maps, table of
    /// contents, cube record header) does not match.
    #[error("{section} checksum mismatch at byte offset {offset}: stored {stored:#018x}, computed {computed:#018x}")]
    ChecksumMismatch {
        section: &'static str,
        offset: u64,
        stored: u64,
        computed: u64,
    },
    /// A header field with an impossible value.
    #[error("invalid header field `{field}` (byte offset {offset}): {detail}")]
    InvalidHeader {
        field: &'static str,
        offset: u64,
        detail: String,
    },
    /// A section that does not lie inside the file (or whose end overflows).
    #[error("section {section} at byte offset {offset} with size {size} does not fit in the file ({file_size} bytes)")]
    SectionOutOfBounds {
        section: &'static str,
        offset: u64,
        size: u64,
        file_size: u64,
    },
    /// A section offset that is not a multiple of 8.
    #[error("section {section} starts at byte offset {offset}, which is not 8-byte aligned")]
    Misaligned { section: &'static str, offset: u64 },
    /// Two sections that overlap or are out of order.
    #[error("section {second} at byte offset {offset} overlaps section {first}, which ends at {first_end}")]
    SectionOverlap {
        first: &'static str,
        first_end: u64,
        second: &'static str,
        offset: u64,
    },
    /// A section whose size does not match the counts and resolutions in the header.
    #[error("section {section} has size {found} bytes but the header's counts require {expected}")]
    SectionSize {
        section: &'static str,
        found: u64,
        expected: u64,
    },
    /// A problem inside the metadata section (or in a [`crate::StoreMeta`] given to the writer).
    #[error("invalid metadata at byte offset {offset}: {detail}")]
    InvalidMetadata { offset: u64, detail: String },
    /// A sample point with a non-finite or out-of-range field.
    #[error("invalid sample point {index}: {detail}")]
    InvalidSamplePoint { index: u64, detail: String },
    /// A sample-map entry that is out of range or not in canonical form.
    #[error(
        "invalid sample map entry: patch {patch}, texel ({x}, {y}), channel {channel}: {detail}"
    )]
    InvalidSampleMap {
        patch: u32,
        x: u32,
        y: u32,
        channel: usize,
        detail: String,
    },
    /// Sample maps given to the writer whose shape does not match the metadata.
    #[error("sample maps: {0}")]
    SampleMapShape(String),
    /// A table-of-contents entry that is out of range or overlaps another.
    #[error("invalid table of contents entry for cube {cube}, face {face} (byte offset {offset}): {detail}")]
    InvalidToc {
        cube: u32,
        face: usize,
        offset: u64,
        detail: String,
    },
    /// A compressed face frame whose checksum does not match its table-of-contents entry.
    #[error("cube {cube}, face {face}: frame checksum mismatch at byte offset {offset}: stored {stored:#018x}, computed {computed:#018x}")]
    FaceChecksum {
        cube: u32,
        face: usize,
        offset: u64,
        stored: u64,
        computed: u64,
    },
    /// A face frame that does not decompress to exactly its declared raw size.
    #[error("cube {cube}, face {face}: zstd frame at byte offset {offset} is corrupt: {detail}")]
    Decompress {
        cube: u32,
        face: usize,
        offset: u64,
        detail: String,
    },
    /// A cube record header in the payload that disagrees with the table of contents.
    #[error("cube {cube}: record header at byte offset {offset}: {detail}")]
    InvalidCubeRecord {
        cube: u32,
        offset: u64,
        detail: String,
    },
    /// zstd failed to compress a face.
    #[error("cube {cube}, face {face}: zstd compression failed: {detail}")]
    Compress {
        cube: u32,
        face: usize,
        detail: String,
    },
    /// Radiance that is NaN, infinite or negative.
    #[error("cube {cube}, face {face}, texel ({x}, {y}): radiance {value:?} is not finite and non-negative")]
    InvalidRadiance {
        cube: u32,
        face: usize,
        x: u32,
        y: u32,
        value: [f32; 3],
    },
    /// A distance that is NaN, infinite or negative (escaped rays are stored as `f32::MAX`).
    #[error("cube {cube}, face {face}, texel ({x}, {y}): distance {value} is not finite and non-negative (use f32::MAX for escaped rays)")]
    InvalidDistance {
        cube: u32,
        face: usize,
        x: u32,
        y: u32,
        value: f32,
    },
    /// A texel given to [`crate::encoding::encode_texels`] that is NaN, infinite or negative.
    #[error("texel {index}: radiance {value:?} is not finite and non-negative")]
    InvalidTexel { index: usize, value: [f32; 3] },
    /// An RGB9E5 texel given to filter 3 whose mantissas are not all on the store's mantissa
    /// lattice (multiples of `2^(9 − mantissa_bits)`).
    #[error("texel {texel}: RGB9E5 mantissas are not quantized to {mantissa_bits} bits, as filter 3 (predict-packed) requires")]
    Unquantized { texel: usize, mantissa_bits: u32 },
    /// A distance that is not on the distance lattice of `bits` mantissa bits (nor the no-hit
    /// value `f32::MAX`), given to filters 1 to 3 of a version-6 distance plane
    /// ([`crate::distance::quantize_distance`] puts it there).
    #[error(
        "texel {texel}: distance {value} is not on the {bits}-bit distance lattice the store holds"
    )]
    UnquantizedDistance { texel: usize, value: f32, bits: u32 },
    /// A cube image whose shape does not match the bake parameters.
    #[error("cube {cube}: {detail}")]
    CubeShape { cube: u32, detail: String },

    /// Full verification: a cube's irradiance record is not the projection of its faces.
    #[error("irradiance section: the record of cube {cube} (byte offset {offset}) is not the projection of the cube's stored faces")]
    IrradianceMismatch { cube: u32, offset: u64 },

    /// A coefficient of the irradiance section is not finite (byte offset of the `f32`).
    #[error("irradiance section: cube {cube}, coefficient {coefficient}, channel {channel} (byte offset {offset}) is {value}, not finite")]
    InvalidIrradiance {
        cube: u64,
        coefficient: usize,
        channel: usize,
        offset: u64,
        value: f32,
    },
    /// A caller-supplied buffer of the wrong length.
    #[error("{what}: buffer has {actual} elements, expected {expected}")]
    BufferSize {
        what: &'static str,
        expected: u64,
        actual: u64,
    },
    /// A cube index past the end of the store.
    #[error("cube index {cube} out of range (the store has {count} cubes)")]
    CubeOutOfRange { cube: u32, count: u32 },
    /// A face index that is not 0..6.
    #[error("face index {face} out of range (0..6)")]
    FaceOutOfRange { face: usize },
    /// A sample-map index (a patch or an atlas page) past the end of the store.
    #[error("sample map {patch} out of range (the store has {count} sample maps: patches and atlas pages)")]
    PatchOutOfRange { patch: u32, count: u32 },
    /// A distance plane was requested from a store baked without one.
    #[error("the store has no distance channel")]
    NoDistanceChannel,
    /// A cube appended out of order.
    #[error("cube {got} appended, but the next cube must be {expected}")]
    CubeOutOfOrder { expected: u32, got: u32 },
    /// Bake parameters that cannot encode a cube (e.g. `mantissa_bits` outside 1..=9, or
    /// below 9 with an encoding other than RGB9E5).
    #[error("cannot encode cube {cube}: {detail}")]
    InvalidBakeParams { cube: u32, detail: String },
    /// An encoded cube produced with parameters that differ from the store's.
    #[error("cube {cube} was encoded with different parameters: {detail}")]
    CubeParamsMismatch { cube: u32, detail: String },
    /// `finish()` before every cube was appended.
    #[error("store is incomplete: {present} of {total} cubes written")]
    Incomplete { present: u32, total: u32 },
    /// The file is a partial store that `finish()` never completed.
    #[error("the store was never finished (the COMPLETE flag is clear); resume the bake")]
    NotFinished,
    /// `resume()` found a partial file started with other settings than the bake's:
    /// `differences` names each (`"seed 1 (this bake: 2)"`), with both values. It can only be
    /// continued with the settings it was started with, or the store created again.
    #[error("cannot resume {path}: it was started with different settings: {}", differences.join(", "))]
    ResumeSettings {
        path: PathBuf,
        differences: Vec<String>,
    },
    /// `resume()` found a partial file it cannot continue although the settings agree: damaged,
    /// not a partial store of a version it continues, another shard, or written by another
    /// version of the writer (`what` says which). The store must be created again.
    #[error("cannot resume {path}: {what}")]
    ResumeMismatch { path: PathBuf, what: String },
    /// `resume()` found a partial file whose fixed sections (header, metadata, sample points,
    /// sample maps) were never completely written: `create()` was interrupted, so it holds no
    /// finished cube maps and the store must be created again.
    #[error("{path} was never completely created ({detail}), so it holds no finished cube maps")]
    PartialNeverCreated { path: PathBuf, detail: String },
    /// Another writer holds the partial file `partial` of the output `path` (an exclusive
    /// lock, held until it renames the file into place); `holder` names it where the system
    /// says (`process 1234 (oslf bake …)`), else `another process`.
    #[error("{path} is being written by {holder}, which holds {partial}; wait for it to finish, or write to another path")]
    Busy {
        path: PathBuf,
        partial: PathBuf,
        holder: String,
    },
    /// An output path (or its partial file) that exists and is not a regular file: renaming a
    /// store over it would replace a device, a FIFO, a directory or a symbolic link.
    #[error("{path} is {kind}, not a regular file; a store can only be written to a new path or over a regular file")]
    NotRegularFile { path: PathBuf, kind: &'static str },
    /// An output that is one of the inputs (the same device and inode, however it is spelled).
    #[error("the output {output} is the input {input} (the same file); write to another path")]
    SameFile { input: PathBuf, output: PathBuf },
    /// `resume()` found no partial file.
    #[error("no partial store to resume at {0}")]
    NoPartial(PathBuf),
    /// A padding byte that is not zero (between sections, or after a cube record's frames).
    #[error(
        "padding byte at byte offset {offset} ({region}) is {value:#04x}; padding must be zero"
    )]
    NonZeroPadding {
        region: String,
        offset: u64,
        value: u8,
    },
    /// The faces decode (decompressed and unfiltered) to other bytes than the writer encoded:
    /// the checksum of the decoded faces (header bytes 180..188) does not
    /// match.
    #[error("the decoded cube faces do not match their checksum at header byte offset 180 (stored {stored:#018x}, computed {computed:#018x}): the frames decode to other texels than were written, e.g. the face filter id at byte 176 or the metadata's mantissa_bits was changed")]
    DecodedChecksum { stored: u64, computed: u64 },
    /// A face filter id this reader does not know (header bytes 176..180).
    #[error(
        "unknown face filter id {id} at byte offset {offset} (this reader knows 0 none, 1 predict, 2 predict-rows, 3 predict-packed)"
    )]
    UnknownFilter { id: u32, offset: u64 },
    /// An unknown encoding name.
    #[error("unknown encoding {0:?} (expected rgb9e5, rgba16f, rgba32f or bc6h)")]
    UnknownEncoding(String),
    /// A BC6H block whose mode field (the low 5 bits of its first byte) is one of the four
    /// reserved values: the face is damaged (a GPU would decode the block to black).
    #[error("cube {cube}, face {face}, BC6H block {block} (byte {byte} of the face's texels): reserved mode {mode:#07b}", byte = block * 16)]
    ReservedBc6hMode {
        cube: u32,
        face: usize,
        block: usize,
        mode: u8,
    },
    /// A block-compressed encoding (BC6H) passed to a per-texel encoder or decoder, which
    /// cannot split a face into its 4×4 blocks.
    #[error("{encoding} encodes whole faces in 4×4 blocks, not single texels (use encode_face_texels / decode_face_texels)")]
    WholeFaceEncoding {
        encoding: crate::encoding_kind::Encoding,
    },
    /// A shard argument that is not `I/N` with `N ≥ 1` and `I < N`.
    #[error("invalid shard {0:?}: expected I/N with N at least 1 and I in 0..N (e.g. 0/4)")]
    InvalidShardSpec(String),
    /// A shard file that cannot be used: not a shard, damaged or truncated (`detail` says
    /// which, with the byte offset where one applies).
    #[error("shard file {path}: {detail}")]
    InvalidShard { path: PathBuf, detail: String },
    /// A shard file, shard `index` of `count`, whose bake never finished it (a partial shard):
    /// its bake must be resumed before the shards can be merged.
    #[error(
        "shard file {path}: shard {index}/{count} was never finished (the COMPLETE flag is clear)"
    )]
    UnfinishedShard {
        path: PathBuf,
        index: u32,
        count: u32,
    },
    /// Shard files that do not make one store together: missing or repeated shard indices,
    /// different shard counts, or different scenes or settings (`0` names them).
    #[error("cannot merge the shards: {0}")]
    ShardSet(String),
    /// A cube appended to a shard that does not hold it, or not in the shard's cube order.
    #[error("cube {got} appended to shard {shard}, but its next cube is {expected}")]
    ShardCubeOrder {
        shard: String,
        expected: String,
        got: u32,
    },
    /// A value past a documented limit.
    #[error("{what} is {value}, above the limit {max}")]
    Limit {
        what: &'static str,
        value: u64,
        max: u64,
    },
}

impl Error {
    pub(crate) fn io(context: impl Into<String>, error: std::io::Error) -> Self {
        Error::Io {
            context: context.into(),
            error,
        }
    }
}

/// An [`Error`] for a file path and an operation.
pub(crate) fn io_at(path: &std::path::Path, op: &str) -> impl FnOnce(std::io::Error) -> Error {
    let context = format!("{} ({op})", path.display());
    move |error| Error::Io { context, error }
}

/// An [`Error`] for a failed [`oslf_util::input_file::open`] of `path`: a file that cannot be
/// opened is [`Error::Io`] as for any other operation; one that is not a regular file is
/// [`Error::Input`], which says what it is.
pub(crate) fn open_error(path: &std::path::Path) -> impl FnOnce(oslf_util::UtilError) -> Error {
    let context = format!("{} (open)", path.display());
    move |e| match e {
        oslf_util::UtilError::Input { error, .. } => Error::Io { context, error },
        e => Error::from(e),
    }
}

impl From<oslf_util::UtilError> for Error {
    fn from(e: oslf_util::UtilError) -> Error {
        Error::Input(Box::new(e))
    }
}

/// The message of [`Error::UnsupportedVersion`].
fn unsupported_version(found: u32) -> String {
    if (1..=crate::LAST_DEVELOPMENT_VERSION).contains(&found) {
        format!(
            "store of development format version {found} (header bytes 8..12), from before format 1.0, which this oslf reads only: bake the scene again (`oslf bake`)"
        )
    } else {
        format!(
            "unsupported OSLF store version {found:#010x} at header bytes 8..12 (this reader understands formats {}, {} and {})",
            crate::version_name(crate::VERSION_1_0),
            crate::version_name(crate::VERSION_1_1),
            crate::version_name(crate::VERSION)
        )
    }
}
