//! Joining a complete set of shard files into the store a single bake writes.

use std::fs::File;
use std::io::{BufReader, Read};
use std::path::{Path, PathBuf};

use xxhash_rust::xxh3::xxh3_64;

use crate::bytes::align8;
use crate::differences::prefix_difference;
use crate::error::io_at;
use crate::header::{Header, Section, HEADER_BYTES};
use crate::meta::{decode_meta, StoreMeta};
use crate::output_file::check_not_input;
use crate::shard::file::{read_record, ShardHeader, SHARD_COMPLETE, SHARD_HEADER_BYTES};
use crate::{Error, StoreSummary, StoreWriter};

/// An open shard file, checked up to its first record.
struct OpenShard {
    path: PathBuf,
    header: ShardHeader,
    reader: BufReader<File>,
    pos: u64,
    file_len: u64,
}

fn open_shard(path: &Path) -> Result<OpenShard, Error> {
    let bad = |detail: String| Error::InvalidShard {
        path: path.to_path_buf(),
        detail,
    };
    let (file, file_len) =
        oslf_util::input_file::open(path).map_err(crate::error::open_error(path))?;
    // Small buffers: the merge holds every shard open at once.
    let mut reader = BufReader::with_capacity(64 << 10, file);
    let mut b = [0u8; SHARD_HEADER_BYTES];
    if file_len < SHARD_HEADER_BYTES as u64 {
        return Err(bad(format!(
            "it has {file_len} bytes, less than a {SHARD_HEADER_BYTES}-byte shard header"
        )));
    }
    reader.read_exact(&mut b).map_err(io_at(path, "read"))?;
    let header = ShardHeader::parse(&b).map_err(bad)?;
    if header.flags & SHARD_COMPLETE == 0 {
        return Err(Error::UnfinishedShard {
            path: path.to_path_buf(),
            index: header.spec.index(),
            count: header.spec.count(),
        });
    }
    if header.file_size != file_len {
        return Err(bad(format!(
            "shard {} has {file_len} bytes, but its header says {} (truncated or appended to?)",
            header.spec, header.file_size
        )));
    }
    if header.records_offset() > file_len {
        return Err(bad(format!(
            "shard {} ends at byte {file_len}, inside its store prefix (bytes {}..{})",
            header.spec,
            SHARD_HEADER_BYTES,
            header.records_offset()
        )));
    }
    Ok(OpenShard {
        path: path.to_path_buf(),
        header,
        reader,
        pos: SHARD_HEADER_BYTES as u64,
        file_len,
    })
}

/// Reads a shard's store prefix and checks it against the shard header's checksum.
fn read_prefix(s: &mut OpenShard) -> Result<Vec<u8>, Error> {
    let size = usize::try_from(s.header.prefix_size).unwrap_or(usize::MAX);
    let mut b = vec![0u8; size];
    s.reader
        .read_exact(&mut b)
        .map_err(io_at(&s.path, "read"))?;
    s.pos += s.header.prefix_size;
    let computed = xxh3_64(&b);
    if computed != s.header.prefix_checksum {
        return Err(Error::InvalidShard {
            path: s.path.clone(),
            detail: format!(
                "its store prefix (bytes {}..{}) is damaged: checksum {computed:#018x}, its shard header says {:#018x}",
                SHARD_HEADER_BYTES,
                s.header.records_offset(),
                s.header.prefix_checksum
            ),
        });
    }
    Ok(b)
}

/// Checks that `prefix` is what `create()` writes before the first cube of a store: a
/// store header (COMPLETE clear), sections in order ending at the
/// payload offset `prefix.len()`, valid section checksums and metadata. Returns the header
/// and the metadata.
fn check_prefix(prefix: &[u8]) -> Result<(Header, StoreMeta), String> {
    let h = Header::parse(prefix).map_err(|e| format!("its store header is damaged: {e}"))?;
    if h.version != crate::VERSION {
        return Err(format!(
            "its store header is of format {}, and this oslf merges only format {} shards: bake the shards again",
            crate::version_name(h.version),
            crate::version_name(crate::VERSION)
        ));
    }
    if h.is_complete() {
        return Err(format!(
            "its store header is not an unfinished store (flags {:#x})",
            h.flags
        ));
    }
    let after = |s: Section| align8(s.end());
    let in_order = h.meta.offset == HEADER_BYTES as u64
        && Some(h.points.offset) == after(h.meta)
        && Some(h.maps.offset) == after(h.points)
        && Some(h.payload.offset) == after(h.maps)
        && h.payload.offset == prefix.len() as u64;
    if !in_order {
        return Err("its store header's sections are not where the writer puts them".into());
    }
    for (name, s, sum) in [
        ("metadata", h.meta, h.meta_checksum),
        ("sample points", h.points, h.points_checksum),
        ("sample maps", h.maps, h.maps_checksum),
    ] {
        let bytes = &prefix[s.offset as usize..s.end() as usize];
        let computed = xxh3_64(bytes);
        if computed != sum {
            return Err(format!(
                "its {name} section (byte offset {} of the store prefix) is damaged: checksum {computed:#018x}, the store header says {sum:#018x}",
                s.offset
            ));
        }
    }
    let meta = decode_meta(
        &prefix[h.meta.offset as usize..h.meta.end() as usize],
        h.meta.offset,
        h.version,
    )
    .map_err(|e| format!("its metadata is damaged: {e}"))?;
    Ok((h, meta))
}

/// Merges a complete set of shard files into the store at `output`, byte-identical to the
/// store a single bake of the same scene and settings writes. Checks first that the shards
/// are finished, undamaged, baked for the same shard count, each index exactly once, and
/// from the same scene, settings and seed (naming what differs); then writes
/// `<output>.partial`, syncs it and renames it over `output` ([`StoreWriter::finish`]).
/// Every frame checksum and raw-face checksum record is checked on the way; a damaged shard
/// removes the partial file. The output must not be one of the shards ([`Error::SameFile`]).
pub fn merge(shards: &[PathBuf], output: &Path) -> Result<StoreSummary, Error> {
    if shards.is_empty() {
        return Err(Error::ShardSet("no shard files given".into()));
    }
    for shard in shards {
        check_not_input(shard, output)?;
    }
    let mut open = shards
        .iter()
        .map(|p| open_shard(p))
        .collect::<Result<Vec<_>, _>>()?;

    // One shard count, every index once.
    let count = open[0].header.spec.count();
    check_complete_set(&open)?;
    open.sort_by_key(|s| s.header.spec.index());

    // The same store prefix (scene, settings, seed, sample points, sample maps) in all.
    let prefix = read_prefix(&mut open[0])?;
    let (header, meta) = check_prefix(&prefix).map_err(|detail| Error::InvalidShard {
        path: open[0].path.clone(),
        detail,
    })?;
    for i in 1..open.len() {
        let same = open[i].header.prefix_size == open[0].header.prefix_size
            && open[i].header.prefix_checksum == open[0].header.prefix_checksum;
        if same {
            // Skip (and check) the prefix: its checksum equals the first shard's.
            read_prefix(&mut open[i])?;
            continue;
        }
        let other = read_prefix(&mut open[i])?;
        let label = format!("shard {} ({})", open[0].header.spec, open[0].path.display());
        let what = prefix_difference(&other, &prefix, &label);
        return Err(Error::ShardSet(format!(
            "shard {} ({}) does not belong with the others: {what}",
            open[i].header.spec,
            open[i].path.display()
        )));
    }
    for s in &open {
        if s.header.cube_count != header.cube_count {
            return Err(Error::InvalidShard {
                path: s.path.clone(),
                detail: format!(
                    "its shard header says the store has {} cubes, its store header {}",
                    s.header.cube_count, header.cube_count
                ),
            });
        }
    }

    let mut writer = StoreWriter::create_from_prefix(output, &prefix, header.clone(), &meta.bake)?;
    let result = (|| -> Result<(), Error> {
        for i in 0..writer.total_cubes() {
            let s = &mut open[(i % count) as usize];
            let (mut cube, len) = read_record(&mut s.reader, s.pos, s.file_len, i, &header)
                .map_err(|detail| Error::InvalidShard {
                    path: s.path.clone(),
                    detail,
                })?;
            cube.mantissa_bits = meta.bake.mantissa_bits;
            s.pos += len;
            writer.append(cube)?;
        }
        for s in &open {
            if s.pos != s.file_len {
                return Err(Error::InvalidShard {
                    path: s.path.clone(),
                    detail: format!(
                        "it has {} bytes after its last cube (byte offset {})",
                        s.file_len - s.pos,
                        s.pos
                    ),
                });
            }
        }
        Ok(())
    })();
    match result {
        Ok(()) => writer.finish(),
        Err(e) => {
            writer.discard();
            Err(e)
        }
    }
}

/// Checks that the shards `open` (at least one) form one complete set: baked for the same
/// shard count, each index exactly once ([`Error::ShardSet`] names every index missing or
/// given twice).
fn check_complete_set(open: &[OpenShard]) -> Result<(), Error> {
    let count = open[0].header.spec.count();
    if let Some(other) = open.iter().find(|s| s.header.spec.count() != count) {
        return Err(Error::ShardSet(format!(
            "the shards were baked for different shard counts: {} is shard {}, {} is shard {}",
            open[0].path.display(),
            open[0].header.spec,
            other.path.display(),
            other.header.spec
        )));
    }
    let mut by_index: std::collections::BTreeMap<u32, Vec<&Path>> = Default::default();
    for s in open {
        by_index
            .entry(s.header.spec.index())
            .or_default()
            .push(&s.path);
    }
    let mut problems = Vec::new();
    let missing_count = count as usize - by_index.len();
    if missing_count > 0 {
        // Name the first few (N may be large).
        const NAMED: usize = 20;
        let mut missing: Vec<String> = (0..count)
            .filter(|i| !by_index.contains_key(i))
            .take(NAMED)
            .map(|i| i.to_string())
            .collect();
        if missing_count > NAMED {
            missing.push(format!("… ({missing_count} in all)"));
        }
        problems.push(format!(
            "shard{} {} of {count} {} missing",
            if missing_count > 1 { "s" } else { "" },
            missing.join(", "),
            if missing_count > 1 { "are" } else { "is" }
        ));
    }
    for (i, paths) in &by_index {
        if paths.len() > 1 {
            let names: Vec<String> = paths.iter().map(|p| p.display().to_string()).collect();
            problems.push(format!(
                "shard {i}/{count} is given {} times ({})",
                paths.len(),
                names.join(", ")
            ));
        }
    }
    if problems.is_empty() {
        Ok(())
    } else {
        Err(Error::ShardSet(problems.join("; ")))
    }
}
