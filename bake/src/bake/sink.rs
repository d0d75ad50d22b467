//! Where a bake's cubes go: the store, or one shard of it, created or resumed from its
//! partial file.

use std::path::Path;

use oslf_format::writer::partial_path;
use oslf_format::{
    EncodedCube, SampleMaps, SamplePoint, ShardSpec, ShardWriter, StoreMeta, StoreWriter,
};

use oslf_scene::error::Result;

/// Where the cubes go: the store, or one shard of it.
pub(super) enum Sink {
    Store(Box<StoreWriter>),
    Shard(Box<ShardWriter>),
}

impl Sink {
    /// Opens the store or shard at `out`, resuming its partial file if `resume` asks and
    /// there is one.
    pub(super) fn open(
        out: &Path,
        resume: bool,
        shard: Option<ShardSpec>,
        meta: &StoreMeta,
        points: &[SamplePoint],
        maps: &SampleMaps,
        restarted: &mut bool,
    ) -> Result<Sink> {
        let create = || -> Result<Sink> {
            Ok(match shard {
                Some(spec) => Sink::Shard(Box::new(ShardWriter::create(
                    out, spec, meta, points, maps,
                )?)),
                None => Sink::Store(Box::new(StoreWriter::create(out, meta, points, maps)?)),
            })
        };
        if !(resume && partial_path(out).exists()) {
            return create();
        }
        let resumed = match shard {
            Some(spec) => {
                ShardWriter::resume(out, spec, meta, points, maps).map(|w| Sink::Shard(Box::new(w)))
            }
            None => StoreWriter::resume(out, meta, points, maps).map(|w| Sink::Store(Box::new(w))),
        };
        match resumed {
            // create() was interrupted: there are no finished cube maps to keep.
            Err(oslf_format::Error::PartialNeverCreated { path, detail }) => {
                eprintln!(
                    "{} was never completely created ({detail}): it holds no finished cube maps, so the bake starts from scratch",
                    path.display()
                );
                *restarted = true;
                create()
            }
            result => Ok(result?),
        }
    }

    /// Cubes already in (the first ones of [`Sink::cube`]'s order).
    pub(super) fn done(&self) -> u32 {
        match self {
            Sink::Store(w) => w.next_cube(),
            Sink::Shard(w) => w.appended(),
        }
    }

    /// Cubes the finished store or shard holds.
    pub(super) fn total(&self) -> u32 {
        match self {
            Sink::Store(w) => w.total_cubes(),
            Sink::Shard(w) => w.shard_cubes(),
        }
    }

    /// Cubes in the merged store (the shard's store, for a shard).
    pub(super) fn store_cubes(&self) -> u32 {
        match self {
            Sink::Store(w) => w.total_cubes(),
            Sink::Shard(w) => w.store_cubes(),
        }
    }

    /// The store's index of the `k`-th cube this sink takes.
    pub(super) fn cube(&self, k: u32) -> u32 {
        match self {
            Sink::Store(_) => k,
            Sink::Shard(w) => w.spec().cube(k),
        }
    }

    pub(super) fn append(&mut self, cube: EncodedCube) -> Result<()> {
        match self {
            Sink::Store(w) => w.append(cube)?,
            Sink::Shard(w) => w.append(cube)?,
        }
        Ok(())
    }
}
