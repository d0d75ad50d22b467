//! Sample maps: per patch, per texel, the indices of the 4 nearest sample points.

use crate::Error;

/// A missing entry, in memory. On disk it is `0xFFFF` in `u16` maps and `0xFFFF_FFFF` in
/// `u32` maps.
pub const INVALID_INDEX: u32 = u32::MAX;
/// Entries per sample-map texel.
pub const ENTRIES_PER_TEXEL: usize = 4;

const INVALID_U16: u16 = u16::MAX;

/// How sample-map indices are stored: `U16` if and only if the sample count is at most 65535.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum IndexWidth {
    U16,
    U32,
}

impl IndexWidth {
    /// The width a store with `sample_count` sample points uses.
    pub fn for_sample_count(sample_count: u64) -> Self {
        if sample_count <= u64::from(u16::MAX) {
            IndexWidth::U16
        } else {
            IndexWidth::U32
        }
    }
    /// Bytes per index: 2 or 4.
    pub fn bytes(self) -> usize {
        match self {
            IndexWidth::U16 => 2,
            IndexWidth::U32 => 4,
        }
    }
}

/// All patches' sample maps, as the writer takes them.
#[derive(Clone, Debug, PartialEq)]
pub struct SampleMaps {
    /// Texels per edge of each patch's map.
    pub resolution: u32,
    /// Patch-major, then row `v` (`y`), then column `u` (`x`); texel `(x, y)` is centred at
    /// `u = (x + 0.5) / res`, `v = (y + 0.5) / res`. Entries sorted nearest first, with
    /// [`INVALID_INDEX`] padding at the end only.
    pub indices: Vec<[u32; 4]>,
}

/// A zero-copy view of one patch's sample map inside a store.
#[derive(Clone, Copy, Debug)]
pub struct SampleMapView<'a> {
    pub(crate) resolution: u32,
    pub(crate) data: MapData<'a>,
}

#[derive(Clone, Copy, Debug)]
pub(crate) enum MapData<'a> {
    U16(&'a [u16]),
    U32(&'a [u32]),
}

impl<'a> SampleMapView<'a> {
    /// Texels per edge.
    pub fn resolution(&self) -> u32 {
        self.resolution
    }
    /// The on-disk index width.
    pub fn width(&self) -> IndexWidth {
        match self.data {
            MapData::U16(_) => IndexWidth::U16,
            MapData::U32(_) => IndexWidth::U32,
        }
    }
    /// The 4 entries of texel `(x, y)`, nearest first, [`INVALID_INDEX`] for missing ones;
    /// `None` outside the map.
    pub fn get(&self, x: u32, y: u32) -> Option<[u32; 4]> {
        if x >= self.resolution || y >= self.resolution {
            return None;
        }
        let texel = (y as usize)
            .checked_mul(self.resolution as usize)?
            .checked_add(x as usize)?;
        let start = texel.checked_mul(ENTRIES_PER_TEXEL)?;
        let end = start.checked_add(ENTRIES_PER_TEXEL)?;
        let mut out = [INVALID_INDEX; 4];
        match self.data {
            MapData::U16(d) => {
                for (o, v) in out.iter_mut().zip(d.get(start..end)?) {
                    *o = if *v == INVALID_U16 {
                        INVALID_INDEX
                    } else {
                        u32::from(*v)
                    };
                }
            }
            MapData::U32(d) => out.copy_from_slice(d.get(start..end)?),
        }
        Some(out)
    }
    /// The raw `u16` entries (4 per texel, row-major; `0xFFFF` = missing) if the store uses
    /// `u16` indices.
    pub fn as_u16(&self) -> Option<&'a [u16]> {
        match self.data {
            MapData::U16(d) => Some(d),
            MapData::U32(_) => None,
        }
    }
    /// The raw `u32` entries (4 per texel, row-major; `0xFFFF_FFFF` = missing) if the store
    /// uses `u32` indices.
    pub fn as_u32(&self) -> Option<&'a [u32]> {
        match self.data {
            MapData::U32(d) => Some(d),
            MapData::U16(_) => None,
        }
    }
}

/// Checks one texel's entries (already widened, `INVALID_INDEX` for missing): every index
/// `< sample_count`, missing entries only at the end.
pub(crate) fn check_texel(
    entries: [u32; 4],
    sample_count: u64,
    patch: u32,
    texel: usize,
    resolution: u32,
) -> Result<(), Error> {
    let mut seen_invalid = false;
    for (channel, e) in entries.iter().enumerate() {
        let fail = |detail: String| Error::InvalidSampleMap {
            patch,
            x: (texel % resolution.max(1) as usize) as u32,
            y: (texel / resolution.max(1) as usize) as u32,
            channel,
            detail,
        };
        if *e == INVALID_INDEX {
            seen_invalid = true;
        } else if seen_invalid {
            return Err(fail(format!(
                "index {e} follows a missing entry (missing entries must be trailing)"
            )));
        } else if u64::from(*e) >= sample_count {
            return Err(fail(format!(
                "index {e} out of range ({sample_count} sample points)"
            )));
        }
    }
    Ok(())
}

/// Validates the writer's input maps and encodes them for disk.
pub(crate) fn encode_maps(
    maps: &SampleMaps,
    patch_count: usize,
    expected_resolution: u32,
    sample_count: u64,
) -> Result<(IndexWidth, Vec<u8>), Error> {
    if maps.resolution != expected_resolution {
        return Err(Error::SampleMapShape(format!(
            "resolution {} differs from the bake's sample_map_resolution {expected_resolution}",
            maps.resolution
        )));
    }
    let per_patch = (maps.resolution as usize)
        .checked_mul(maps.resolution as usize)
        .ok_or_else(|| Error::SampleMapShape("resolution overflows".into()))?;
    let expected = per_patch.checked_mul(patch_count);
    if expected != Some(maps.indices.len()) {
        return Err(Error::SampleMapShape(format!(
            "{} texels given, expected {patch_count} patches x {}^2",
            maps.indices.len(),
            maps.resolution
        )));
    }
    let width = IndexWidth::for_sample_count(sample_count);
    let mut out = Vec::with_capacity(maps.indices.len() * ENTRIES_PER_TEXEL * width.bytes());
    for (i, entries) in maps.indices.iter().enumerate() {
        let patch = (i / per_patch.max(1)) as u32;
        check_texel(
            *entries,
            sample_count,
            patch,
            i % per_patch.max(1),
            maps.resolution,
        )?;
        for e in entries {
            match width {
                // Valid indices are < sample_count <= 65535, so they fit; INVALID -> 0xFFFF.
                IndexWidth::U16 => out.extend_from_slice(&(*e as u16).to_le_bytes()),
                IndexWidth::U32 => out.extend_from_slice(&e.to_le_bytes()),
            }
        }
    }
    Ok((width, out))
}

/// Validates the sample-map section of a store (already cast to its index type).
pub(crate) fn validate_section(
    data: MapData<'_>,
    resolution: u32,
    sample_count: u64,
) -> Result<(), Error> {
    let per_patch = (resolution as usize).saturating_mul(resolution as usize);
    let per_patch_entries = per_patch.saturating_mul(ENTRIES_PER_TEXEL).max(1);
    let check = |i: usize, entries: [u32; 4]| {
        let patch = (i / per_patch_entries) as u32;
        let texel = (i % per_patch_entries) / ENTRIES_PER_TEXEL;
        check_texel(entries, sample_count, patch, texel, resolution)
    };
    match data {
        MapData::U16(d) => {
            for (n, c) in d.chunks_exact(ENTRIES_PER_TEXEL).enumerate() {
                let w = |v: u16| {
                    if v == INVALID_U16 {
                        INVALID_INDEX
                    } else {
                        u32::from(v)
                    }
                };
                check(n * ENTRIES_PER_TEXEL, [w(c[0]), w(c[1]), w(c[2]), w(c[3])])?;
            }
        }
        MapData::U32(d) => {
            for (n, c) in d.chunks_exact(ENTRIES_PER_TEXEL).enumerate() {
                check(n * ENTRIES_PER_TEXEL, [c[0], c[1], c[2], c[3]])?;
            }
        }
    }
    Ok(())
}
