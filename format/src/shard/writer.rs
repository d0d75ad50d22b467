//! Writing one shard's cubes to a shard file: streaming, crash-safe, resumable, like the
//! store writer.

use std::fs::File;
use std::io::{BufReader, BufWriter, Read, Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};

use xxhash_rust::xxh3::xxh3_64;

use crate::bytes::zero_pad;
use crate::cube::EncodedCube;
use crate::differences::prefix_difference;
use crate::error::io_at;
use crate::header::Header;
use crate::meta::{SamplePoint, StoreMeta};
use crate::output_file::{open_partial, Open};
use crate::prefix::Prefix;
use crate::sample_map::SampleMaps;
use crate::shard::file::{
    read_record, record_header, record_len, trailer, ShardHeader, SHARD_COMPLETE,
    SHARD_HEADER_BYTES,
};
use crate::shard::spec::ShardSpec;
use crate::toc::RECORD_HEADER_BYTES;
use crate::writer::{check_cube_params, partial_path, sync_partial, SyncBatch};
use crate::{Error, Filter};

/// What [`ShardWriter::finish`] wrote.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ShardSummary {
    /// Size of the shard file in bytes.
    pub file_size: u64,
    /// Cubes in the shard.
    pub cubes: u32,
    /// Compressed bytes of the shard's cube faces.
    pub cube_bytes: u64,
    /// Bytes of the store prefix (header, metadata, sample points, sample maps) it carries.
    pub prefix_bytes: u64,
}

/// Appends one shard's cubes to a shard file; see the module docs.
pub struct ShardWriter {
    path: PathBuf,
    partial: PathBuf,
    file: BufWriter<File>,
    header: ShardHeader,
    store: Header,
    mantissa_bits: u32,
    pos: u64,
    next: u32,
    total: u32,
    cube_bytes: u64,
    unsynced: SyncBatch,
    failed: bool,
}

impl ShardWriter {
    /// Starts shard `spec` of the store these inputs make: writes `<path>.partial` (replacing
    /// any old one) with the shard header and the store prefix, and syncs it.
    pub fn create(
        path: &Path,
        spec: ShardSpec,
        meta: &StoreMeta,
        points: &[SamplePoint],
        maps: &SampleMaps,
    ) -> Result<Self, Error> {
        let prefix = build_prefix(meta, points, maps)?;
        let bytes = prefix.to_bytes();
        let header = ShardHeader {
            flags: 0,
            spec,
            cube_count: u64::from(prefix.total),
            shard_cubes: u64::from(spec.cubes_of(prefix.total)),
            prefix_size: bytes.len() as u64,
            prefix_checksum: xxh3_64(&bytes),
            file_size: 0,
        };
        let partial = partial_path(path);
        let file = open_partial(path, &partial, Open::Create)?;
        let mut w = BufWriter::with_capacity(1 << 20, file);
        w.write_all(&header.to_bytes())
            .and_then(|()| w.write_all(&bytes))
            .and_then(|()| w.flush())
            .and_then(|()| w.get_ref().sync_data())
            .map_err(io_at(&partial, "write"))?;
        Ok(ShardWriter {
            path: path.to_path_buf(),
            partial,
            file: w,
            pos: header.records_offset(),
            header,
            store: prefix.header,
            mantissa_bits: meta.bake.mantissa_bits,
            next: 0,
            total: spec.cubes_of(prefix.total),
            cube_bytes: 0,
            unsynced: SyncBatch::default(),
            failed: false,
        })
    }

    /// Reopens `<path>.partial` after an interruption: checks that it is shard `spec` and
    /// that its prefix is exactly what [`ShardWriter::create`] writes for these inputs, keeps
    /// every complete cube record (valid record header, frame checksums and trailer),
    /// truncates the rest and continues.
    ///
    /// Errors as [`crate::StoreWriter::resume`]: [`Error::NoPartial`], [`Error::PartialNeverCreated`]
    /// (start over with `create`), [`Error::ResumeMismatch`] naming what differs.
    pub fn resume(
        path: &Path,
        spec: ShardSpec,
        meta: &StoreMeta,
        points: &[SamplePoint],
        maps: &SampleMaps,
    ) -> Result<Self, Error> {
        let partial = partial_path(path);
        let prefix = build_prefix(meta, points, maps)?;
        let bytes = prefix.to_bytes();
        let mut file = open_partial(path, &partial, Open::Resume)?;
        let file_len = file.metadata().map_err(io_at(&partial, "stat"))?.len();
        let mismatch = |what: String| Error::ResumeMismatch {
            path: partial.clone(),
            what,
        };
        let never_created = |detail: String| Error::PartialNeverCreated {
            path: partial.clone(),
            detail,
        };
        if file_len < SHARD_HEADER_BYTES as u64 {
            return Err(never_created(format!(
                "it has {file_len} bytes, less than its {SHARD_HEADER_BYTES}-byte shard header"
            )));
        }
        let mut rd = BufReader::with_capacity(1 << 20, &mut file);
        let mut got = [0u8; SHARD_HEADER_BYTES];
        rd.read_exact(&mut got).map_err(io_at(&partial, "read"))?;
        if got.iter().all(|b| *b == 0) {
            return Err(never_created("its shard header is all zero bytes".into()));
        }
        let old = ShardHeader::parse(&got).map_err(&mismatch)?;
        if old.spec != spec {
            return Err(mismatch(format!(
                "it is shard {}, and this bake is shard {spec}",
                old.spec
            )));
        }
        let records = old.records_offset();
        if file_len < records {
            return Err(never_created(format!(
                "it has {file_len} bytes, less than the {records} bytes of its headers, metadata, sample points and sample maps"
            )));
        }
        // Bounded by the file's length, checked above.
        let mut old_prefix = vec![0u8; old.prefix_size as usize];
        rd.read_exact(&mut old_prefix)
            .map_err(io_at(&partial, "read"))?;
        if old_prefix != bytes {
            return Err(mismatch(prefix_difference(
                &old_prefix,
                &bytes,
                "this bake",
            )));
        }
        drop(old_prefix);

        let total = spec.cubes_of(prefix.total);
        let mut pos = records;
        let mut next = 0u32;
        let mut cube_bytes = 0u64;
        while next < total {
            match read_record(&mut rd, pos, file_len, spec.cube(next), &prefix.header) {
                Ok((cube, len)) => {
                    cube_bytes += cube.compressed_bytes();
                    pos += len;
                    next += 1;
                }
                Err(_) => break,
            }
        }
        drop(rd);
        let header = ShardHeader {
            flags: 0,
            file_size: 0,
            ..old
        };
        let wr = io_at(&partial, "truncate");
        file.set_len(pos).map_err(wr)?;
        file.seek(SeekFrom::Start(0))
            .and_then(|_| file.write_all(&header.to_bytes()))
            .and_then(|()| file.seek(SeekFrom::Start(pos)))
            .and_then(|_| file.sync_all())
            .map_err(io_at(&partial, "write"))?;
        Ok(ShardWriter {
            path: path.to_path_buf(),
            partial,
            file: BufWriter::with_capacity(1 << 20, file),
            header,
            store: prefix.header,
            mantissa_bits: meta.bake.mantissa_bits,
            pos,
            next,
            total,
            cube_bytes,
            unsynced: SyncBatch::default(),
            failed: false,
        })
    }

    /// Which shard this is.
    pub fn spec(&self) -> ShardSpec {
        self.header.spec
    }

    /// How many of the shard's cubes are already in.
    pub fn appended(&self) -> u32 {
        self.next
    }

    /// How many cubes the finished shard holds.
    pub fn shard_cubes(&self) -> u32 {
        self.total
    }

    /// How many cubes the merged store holds.
    pub fn store_cubes(&self) -> u32 {
        self.header.cube_count as u32
    }

    /// The partial file's path.
    pub fn partial_path(&self) -> &Path {
        &self.partial
    }

    /// Appends the shard's next cube (store index `spec().cube(appended())`).
    pub fn append(&mut self, cube: EncodedCube) -> Result<(), Error> {
        if self.failed {
            return Err(Error::io(
                format!("{}", self.partial.display()),
                std::io::Error::other("an earlier write failed; resume the shard to continue"),
            ));
        }
        let spec = self.header.spec;
        if self.next >= self.total || cube.cube_index != spec.cube(self.next) {
            return Err(Error::ShardCubeOrder {
                shard: spec.to_string(),
                expected: if self.next < self.total {
                    spec.cube(self.next).to_string()
                } else {
                    "none (the shard is full)".into()
                },
                got: cube.cube_index,
            });
        }
        check_cube_params(&cube, &self.store, self.mantissa_bits)?;
        let record = record_header(&cube);
        let len = record_len(&cube);
        // Records start 8-aligned.
        let pad = zero_pad(RECORD_HEADER_BYTES as u64 + cube.compressed_bytes());
        let trailer = trailer(&cube.raw_checksums);
        let result = (|| -> std::io::Result<()> {
            self.file.write_all(&record.to_bytes())?;
            for frame in &cube.frames {
                self.file.write_all(frame)?;
            }
            self.file.write_all(&[0u8; 8][..pad])?;
            self.file.write_all(&trailer)
        })();
        if let Err(e) = result {
            self.failed = true;
            return Err(io_at(&self.partial, "write")(e));
        }
        self.pos += len;
        self.cube_bytes += cube.compressed_bytes();
        self.next += 1;
        if self.unsynced.add(len) {
            sync_partial(
                &mut self.file,
                &self.partial,
                &mut self.unsynced,
                &mut self.failed,
            )?;
        }
        Ok(())
    }

    /// Marks the shard complete, syncs, renames the partial file over the target path and
    /// syncs the directory. [`Error::Incomplete`] unless every cube of the shard was appended.
    pub fn finish(mut self) -> Result<ShardSummary, Error> {
        if self.next != self.total {
            return Err(Error::Incomplete {
                present: self.next,
                total: self.total,
            });
        }
        self.header.flags |= SHARD_COMPLETE;
        self.header.file_size = self.pos;
        let header = self.header.to_bytes();
        let file = &mut self.file;
        (|| -> std::io::Result<()> {
            file.flush()?;
            file.get_ref().sync_data()?;
            let f = file.get_mut();
            f.seek(SeekFrom::Start(0))?;
            f.write_all(&header)?;
            f.sync_all()
        })()
        .map_err(io_at(&self.partial, "finish"))?;
        std::fs::rename(&self.partial, &self.path).map_err(io_at(&self.path, "rename"))?;
        sync_dir(&self.path)?;
        Ok(ShardSummary {
            file_size: self.pos,
            cubes: self.total,
            cube_bytes: self.cube_bytes,
            prefix_bytes: self.header.prefix_size,
        })
    }
}

fn build_prefix(
    meta: &StoreMeta,
    points: &[SamplePoint],
    maps: &SampleMaps,
) -> Result<Prefix, Error> {
    let filter = Filter::for_store(meta.bake.encoding, meta.bake.mantissa_bits);
    Prefix::build(meta, points, maps, filter)
}

fn sync_dir(path: &Path) -> Result<(), Error> {
    let dir = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    };
    File::open(&dir)
        .and_then(|d| d.sync_all())
        .map_err(io_at(&dir, "sync directory"))
}
