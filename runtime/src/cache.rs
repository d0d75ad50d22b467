//! The two-level LRU cube-map cache (thesis §4.3, Tables 6.3–6.7).
//!
//! * **RAM level**: decoded faces (the store's raw face bytes after zstd and the prediction
//!   filter, ready to upload: [`FaceLayout`] payloads, BC6H blocks included) under a byte
//!   budget of their real size, least recently used evicted first.
//! * **GPU level**: a pool of cube-map *slots* (six faces each, laid side by side in the
//!   layers of up to [`MAX_POOL_TEXTURES`] 2D texture arrays: a layer holds as many faces as
//!   the device's widest texture allows, an array at most `max_texture_array_layers` layers). An indirection table maps each cube (sample point) to
//!   `slot << 6 | resident-face mask`; the shader reads only faces whose bit is set.
//!
//! Each frame the shader marks, in a feedback buffer, every face it *would* read with
//! everything resident. [`CubeCache::plan`] turns those masks into statistics and a list of
//! uploads: it touches what is resident, gives missing cubes a free slot or the least
//! recently used slot not needed this frame, takes their faces from the RAM level or decodes
//! them (in parallel on the rayon pool), and reports what the budget could not hold.
//! Granularity [`Granularity::Cube`] loads all six faces of a cube on any miss (the thesis's
//! "read full image"); [`Granularity::Face`] loads faces on demand.
//!
//! Fallback when a needed face is not resident (documented in shade.wgsl): the sample point is
//! left out of the blend and the others renormalized; reconstruction takes the nearest
//! *resident* candidate; with no usable candidate, reflections use the environment cube
//! (pinned, always resident) and reconstruction gives 0. The shader never reads a slot that
//! does not hold the cube asked for.

use std::collections::{HashMap, HashSet};
use std::sync::mpsc::{channel, Receiver, Sender};
use std::sync::Arc;
use std::time::Instant;

use crate::face::FaceLayout;
use oslf_format::Store;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::error::{Param, RuntimeError};

/// Most texture arrays in the GPU pool (bindings `pool0..pool3` in shade.wgsl).
pub const MAX_POOL_TEXTURES: u32 = 4;
/// Indirection entry of a cube that has no slot.
pub const NO_SLOT: u32 = 0;

/// What one cache miss loads.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Granularity {
    /// All six faces of the cube (the thesis's "read full image").
    Cube,
    /// Only the faces asked for.
    Face,
}

impl std::str::FromStr for Granularity {
    type Err = RuntimeError;
    fn from_str(s: &str) -> Result<Self, RuntimeError> {
        match s {
            "cube" => Ok(Self::Cube),
            "face" => Ok(Self::Face),
            _ => Err(RuntimeError::Parameter(format!(
                "unknown cache granularity {s:?} (cube or face)"
            ))),
        }
    }
}

/// Counters of one frame, or summed over frames. A *unit* is a cube ([`Granularity::Cube`])
/// or a face ([`Granularity::Face`]).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct CacheStats {
    /// Frames counted.
    pub frames: u64,
    /// Units the frame needed (the pinned environment cube counts as one each frame).
    pub requests: u64,
    /// Needed units that were resident when the frame was shaded.
    pub hits: u64,
    /// Needed units that were not (`requests - hits`).
    pub misses: u64,
    /// `misses / requests` (0 without requests).
    pub miss_rate: f64,
    /// Units made resident on the GPU.
    pub loads: u64,
    /// Cubes evicted from GPU slots.
    pub evictions: u64,
    /// Needed units the GPU budget could not hold this frame.
    pub unresolved: u64,
    /// Faces found in the RAM level.
    pub ram_hits: u64,
    /// Faces decoded from the store.
    pub ram_misses: u64,
    /// Faces dropped from the RAM level.
    pub ram_evictions: u64,
    /// Bytes of encoded texels decoded (zstd + filter) from the store.
    pub bytes_decoded: u64,
    /// Bytes of cube-map texels uploaded to the GPU.
    pub bytes_uploaded: u64,
    /// Writes of the indirection table (which slot holds which cube's faces) to the GPU: one in
    /// a frame whose resident set changed, none in a frame where it did not.
    #[serde(default)]
    pub table_writes: u64,
    /// Wall time spent decoding.
    pub decode_seconds: f64,
    /// Wall time spent handing uploads to the GPU queue.
    pub upload_seconds: f64,
    /// Faces that failed to decode (checksum, damaged frame); their sample point falls back.
    pub decode_errors: u64,
    /// Wall time of the cache's whole per-frame work on the CPU: reading the feedback masks,
    /// planning, decoding, uploading and writing the indirection table.
    pub cache_seconds: f64,
}

impl CacheStats {
    /// Adds another frame's counters.
    pub fn add(&mut self, o: &CacheStats) {
        self.frames += o.frames;
        self.requests += o.requests;
        self.hits += o.hits;
        self.misses += o.misses;
        let unresolved = self.unresolved + o.unresolved;
        self.add_loading(o);
        self.unresolved = unresolved;
    }

    /// Adds what another shading pass of the same frame loaded and spent (its requests,
    /// hits and misses are the frame's again and are not counted twice); the over-budget count
    /// becomes the later pass's.
    pub fn add_loading(&mut self, o: &CacheStats) {
        self.loads += o.loads;
        self.evictions += o.evictions;
        self.unresolved = o.unresolved;
        self.ram_hits += o.ram_hits;
        self.ram_misses += o.ram_misses;
        self.ram_evictions += o.ram_evictions;
        self.bytes_decoded += o.bytes_decoded;
        self.bytes_uploaded += o.bytes_uploaded;
        self.table_writes += o.table_writes;
        self.decode_seconds += o.decode_seconds;
        self.upload_seconds += o.upload_seconds;
        self.decode_errors += o.decode_errors;
        self.cache_seconds += o.cache_seconds;
        self.update_rate();
    }

    fn update_rate(&mut self) {
        self.miss_rate = if self.requests == 0 {
            0.0
        } else {
            self.misses as f64 / self.requests as f64
        };
    }
}

/// Cache sizes.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct CacheConfig {
    /// GPU slots (cubes); `None` = one per cube of the store, as far as the device allows and
    /// up to [`crate::renderer::DEFAULT_POOL_BYTES`] of texels.
    pub gpu_slots: Option<u32>,
    /// RAM level budget in bytes of decoded faces.
    pub ram_bytes: u64,
    /// Unit of loading.
    pub granularity: Granularity,
    /// Most cubes per pool texture array; `None` = as many as the device's array-layer limit
    /// allows (`max_texture_array_layers / 6`). Lower it to spread the pool over several
    /// arrays (tests do, to exercise that path on any device).
    pub slots_per_texture: Option<u32>,
}

impl Default for CacheConfig {
    fn default() -> Self {
        Self {
            gpu_slots: None,
            ram_bytes: 256 << 20,
            granularity: Granularity::Cube,
            slots_per_texture: None,
        }
    }
}

/// A face ready to upload: cube, face, slot, texels.
type ReadyFace = (u32, u8, u32, Arc<[u8]>);

/// One face to copy into a slot.
#[derive(Clone, Debug)]
pub struct Upload {
    pub cube: u32,
    pub face: usize,
    pub slot: u32,
    /// The face's payload: its texels in the pool's encoding, their mip levels and the
    /// distance plane, laid out as [`FaceLayout`] says.
    pub texels: Arc<[u8]>,
}

struct RamEntry {
    texels: Arc<[u8]>,
    used: u64,
}

/// The cache's bookkeeping (no GPU objects: the renderer applies [`Upload`]s and the
/// [`CubeCache::indirection`] table).
pub struct CubeCache {
    granularity: Granularity,
    slot_owner: Vec<u32>,
    slot_used: Vec<u64>,
    cube_slot: Vec<u32>,
    cube_faces: Vec<u8>,
    pinned: Option<u32>,
    failed: Vec<bool>,
    ram: HashMap<(u32, u8), RamEntry>,
    ram_used: u64,
    ram_budget: u64,
    frame: u64,
    face: FaceLayout,
    in_flight: HashSet<(u32, u8)>,
    arrivals_tx: Sender<Arrival>,
    arrivals_rx: Receiver<Arrival>,
    /// Counters since the cache was made (the renderer adds each frame's).
    pub cumulative: CacheStats,
    /// Decode errors met so far, for reports.
    pub errors: Vec<DecodeFailure>,
}

/// A face that could not be decoded from the store (checksum, damaged frame). Its cube is never
/// made resident; the shader falls back as for any face that is not resident.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct DecodeFailure {
    pub cube: u32,
    pub face: u8,
    /// The store's error, with its byte offset.
    pub message: String,
}

impl std::fmt::Display for DecodeFailure {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "cube {} face {}: {}", self.cube, self.face, self.message)
    }
}

const FREE: u32 = u32::MAX;

/// A face decoded in the background: cube, face, its texels or the error, seconds taken.
type Arrival = (u32, u8, Result<Arc<[u8]>, oslf_format::Error>, f64);

/// Decompresses one face and builds its payload (texels, mip levels, distance plane).
fn decode_face(
    store: &Store,
    cube: u32,
    face: u8,
    layout: &FaceLayout,
) -> Result<Arc<[u8]>, oslf_format::Error> {
    Ok(Arc::from(layout.build(store, cube, face)?))
}

impl CubeCache {
    /// An empty cache for `cube_count` cubes with `slots` GPU slots, whose faces are built as
    /// `face` lays them out.
    pub fn new(
        cube_count: u32,
        slots: u32,
        granularity: Granularity,
        ram_budget: u64,
        face: FaceLayout,
    ) -> Self {
        let (arrivals_tx, arrivals_rx) = channel();
        Self {
            granularity,
            slot_owner: vec![FREE; slots as usize],
            slot_used: vec![0; slots as usize],
            cube_slot: vec![FREE; cube_count as usize],
            cube_faces: vec![0; cube_count as usize],
            pinned: None,
            failed: vec![false; cube_count as usize],
            ram: HashMap::new(),
            ram_used: 0,
            ram_budget,
            frame: 0,
            face,
            in_flight: HashSet::new(),
            arrivals_tx,
            arrivals_rx,
            cumulative: CacheStats::default(),
            errors: Vec::new(),
        }
    }

    /// The number of GPU slots.
    pub fn slots(&self) -> u32 {
        self.slot_owner.len() as u32
    }

    /// What each face's payload holds (encoding, mip levels, distance plane): the layout the
    /// GPU pool uses.
    pub fn face_layout(&self) -> FaceLayout {
        self.face
    }

    /// Bytes of the faces the RAM level holds now.
    pub fn ram_bytes_used(&self) -> u64 {
        self.ram_used
    }

    /// The granularity.
    pub fn granularity(&self) -> Granularity {
        self.granularity
    }

    /// Keeps `cube` resident whatever the frame needs (the environment cube).
    pub fn pin(&mut self, cube: u32) {
        self.pinned = Some(cube);
    }

    /// The indirection table: per cube `slot << 6 | face mask`, 0 when nothing is resident.
    pub fn indirection(&self) -> Vec<u32> {
        self.cube_slot
            .iter()
            .zip(&self.cube_faces)
            .map(|(&s, &m)| {
                if s == FREE || m == 0 {
                    NO_SLOT
                } else {
                    (s << 6) | u32::from(m)
                }
            })
            .collect()
    }

    /// Resident face mask of `cube`.
    pub fn resident_faces(&self, cube: u32) -> u8 {
        self.cube_faces.get(cube as usize).copied().unwrap_or(0)
    }

    /// Turns a frame's feedback masks (bit `f` of `needed[cube]` = face `f` read) into the
    /// frame's statistics and the uploads that make the needed faces resident, as far as the
    /// budget allows. Needed cubes are served in index order (deterministic).
    ///
    /// With `wait`, faces missing from the RAM level are decoded now (in parallel) and uploaded
    /// this frame. Without, they are decoded on the rayon pool in the background and uploaded
    /// by the first `plan` after they arrive (streaming, for interactive viewers).
    pub fn plan(
        &mut self,
        needed: &[u32],
        store: &Arc<Store>,
        wait: bool,
    ) -> (Vec<Upload>, CacheStats) {
        self.frame += 1;
        let frame = self.frame;
        let mut stats = CacheStats {
            frames: 1,
            ..Default::default()
        };
        self.receive_arrivals(frame, &mut stats);
        let needed = self.frame_needs(needed);
        self.count_hits(&needed, frame, &mut stats);
        let wanted_faces = self.assign_slots(&needed, frame, &mut stats);
        let ready = self.gather_faces(&wanted_faces, store, wait, frame, &mut stats);
        let uploads = self.make_uploads(ready, &mut stats);
        stats.update_rate();
        (uploads, stats)
    }

    /// Books the faces that background decodes delivered since the last plan (streaming).
    fn receive_arrivals(&mut self, frame: u64, stats: &mut CacheStats) {
        while let Ok((cube, face, r, seconds)) = self.arrivals_rx.try_recv() {
            self.in_flight.remove(&(cube, face));
            stats.decode_seconds += seconds;
            let _ = self.record_decoded(cube, face, r, frame, stats);
        }
    }

    /// The faces a frame needs per cube (bits 0–5 of its feedback mask; all six for the
    /// pinned cube), one entry per cube.
    fn frame_needs(&self, needed: &[u32]) -> Vec<u8> {
        let mut needed: Vec<u8> = needed.iter().map(|&m| (m & 63) as u8).collect();
        needed.resize(self.cube_slot.len(), 0);
        if let Some(p) = self.pinned {
            if let Some(n) = needed.get_mut(p as usize) {
                *n = 63;
            }
        }
        needed
    }

    /// Counts the frame's requests and hits against what was resident when it was shaded,
    /// and marks the slots it used (the pinned cube's never ages).
    fn count_hits(&mut self, needed: &[u8], frame: u64, stats: &mut CacheStats) {
        for (cube, &want) in needed.iter().enumerate() {
            if want == 0 {
                continue;
            }
            let have = self.cube_faces[cube];
            match self.granularity {
                Granularity::Cube => {
                    stats.requests += 1;
                    if have & want == want {
                        stats.hits += 1;
                    }
                }
                Granularity::Face => {
                    stats.requests += u64::from(want.count_ones());
                    stats.hits += u64::from((have & want).count_ones());
                }
            }
            let slot = self.cube_slot[cube];
            if slot != FREE {
                self.slot_used[slot as usize] = frame;
            }
        }
        stats.misses = stats.requests - stats.hits;
        if let Some(p) = self.pinned {
            if let Some(&s) = self.cube_slot.get(p as usize) {
                if s != FREE {
                    self.slot_used[s as usize] = u64::MAX;
                }
            }
        }
    }

    /// Gives slots to the cubes that miss faces, evicting the least recently used; returns the
    /// faces to load as (cube, face, slot). Faces the budget cannot hold count as unresolved.
    fn assign_slots(
        &mut self,
        needed: &[u8],
        frame: u64,
        stats: &mut CacheStats,
    ) -> Vec<(u32, u8, u32)> {
        let mut wanted_faces: Vec<(u32, u8, u32)> = Vec::new();
        for (cube, &want) in needed.iter().enumerate() {
            if want == 0 || self.failed[cube] {
                continue;
            }
            let want = match self.granularity {
                Granularity::Cube => 63,
                Granularity::Face => want,
            };
            let missing = want & !self.cube_faces[cube];
            if missing == 0 {
                continue;
            }
            let slot = match self.cube_slot[cube] {
                FREE => match self.take_slot(frame) {
                    Some((slot, evicted)) => {
                        stats.evictions += u64::from(evicted);
                        self.slot_owner[slot as usize] = cube as u32;
                        self.slot_used[slot as usize] = if Some(cube as u32) == self.pinned {
                            u64::MAX
                        } else {
                            frame
                        };
                        self.cube_slot[cube] = slot;
                        slot
                    }
                    None => {
                        stats.unresolved += match self.granularity {
                            Granularity::Cube => 1,
                            Granularity::Face => u64::from(missing.count_ones()),
                        };
                        continue;
                    }
                },
                s => s,
            };
            for face in 0..6u8 {
                if missing & (1 << face) != 0 {
                    wanted_faces.push((cube as u32, face, slot));
                }
            }
        }

        wanted_faces
    }

    /// The texels of `wanted_faces` that are ready this frame: from the RAM level first, then
    /// decoded now in parallel (`wait`), or else sent to background decodes that arrive in a
    /// later frame.
    fn gather_faces(
        &mut self,
        wanted_faces: &[(u32, u8, u32)],
        store: &Arc<Store>,
        wait: bool,
        frame: u64,
        stats: &mut CacheStats,
    ) -> Vec<ReadyFace> {
        let layout = self.face;
        let mut ready: Vec<ReadyFace> = Vec::new();
        let mut to_decode = Vec::new();
        for &(cube, face, slot) in wanted_faces {
            match self.ram.get_mut(&(cube, face)) {
                Some(e) => {
                    e.used = frame;
                    stats.ram_hits += 1;
                    ready.push((cube, face, slot, Arc::clone(&e.texels)));
                }
                None => to_decode.push((cube, face, slot)),
            }
        }
        if wait {
            let start = Instant::now();
            let decoded: Vec<_> = to_decode
                .par_iter()
                .map(|&(cube, face, slot)| {
                    (cube, face, slot, decode_face(store, cube, face, &layout))
                })
                .collect();
            stats.decode_seconds += start.elapsed().as_secs_f64();
            for (cube, face, slot, r) in decoded {
                if let Some(texels) = self.record_decoded(cube, face, r, frame, stats) {
                    ready.push((cube, face, slot, texels));
                }
            }
        } else {
            // Streaming: decode on the rayon pool, off the render thread; the faces arrive in a
            // later frame's plan().
            for &(cube, face, _) in &to_decode {
                if self.in_flight.insert((cube, face)) {
                    let tx = self.arrivals_tx.clone();
                    let store = Arc::clone(store);
                    rayon::spawn(move || {
                        let start = Instant::now();
                        let r = decode_face(&store, cube, face, &layout);
                        let _ = tx.send((cube, face, r, start.elapsed().as_secs_f64()));
                    });
                }
            }
        }
        ready
    }

    /// Makes the ready faces resident, in (cube, face) order, and counts the loads.
    fn make_uploads(&mut self, mut ready: Vec<ReadyFace>, stats: &mut CacheStats) -> Vec<Upload> {
        ready.sort_by_key(|&(c, f, _, _)| (c, f));
        let mut uploads = Vec::with_capacity(ready.len());
        for (cube, face, slot, texels) in ready {
            if self.failed[cube as usize] && self.granularity == Granularity::Cube {
                continue;
            }
            self.cube_faces[cube as usize] |= 1 << face;
            stats.bytes_uploaded += texels.len() as u64;
            uploads.push(Upload {
                cube,
                face: face as usize,
                slot,
                texels,
            });
        }
        stats.loads = match self.granularity {
            Granularity::Cube => {
                let mut cubes: Vec<u32> = uploads.iter().map(|u| u.cube).collect();
                cubes.dedup();
                cubes.len() as u64
            }
            Granularity::Face => uploads.len() as u64,
        };
        uploads
    }

    /// Books a decoded face into the RAM level (or its failure); returns its texels.
    fn record_decoded(
        &mut self,
        cube: u32,
        face: u8,
        r: Result<Arc<[u8]>, oslf_format::Error>,
        frame: u64,
        stats: &mut CacheStats,
    ) -> Option<Arc<[u8]>> {
        stats.ram_misses += 1;
        match r {
            Ok(texels) => {
                stats.bytes_decoded += texels.len() as u64;
                self.ram_insert(cube, face, Arc::clone(&texels), frame, stats);
                Some(texels)
            }
            Err(e) => {
                stats.decode_errors += 1;
                self.failed[cube as usize] = true;
                self.errors.push(DecodeFailure {
                    cube,
                    face,
                    message: e.to_string(),
                });
                None
            }
        }
    }

    /// A free slot, or the least recently used one not needed this frame (evicting its cube).
    fn take_slot(&mut self, frame: u64) -> Option<(u32, bool)> {
        if let Some(s) = self.slot_owner.iter().position(|&o| o == FREE) {
            return Some((s as u32, false));
        }
        let (slot, _) = self
            .slot_used
            .iter()
            .enumerate()
            .filter(|&(_, &u)| u < frame)
            .min_by_key(|&(i, &u)| (u, i))?;
        let old = self.slot_owner[slot];
        self.cube_slot[old as usize] = FREE;
        self.cube_faces[old as usize] = 0;
        self.slot_owner[slot] = FREE;
        Some((slot as u32, true))
    }

    fn ram_insert(
        &mut self,
        cube: u32,
        face: u8,
        texels: Arc<[u8]>,
        frame: u64,
        stats: &mut CacheStats,
    ) {
        let size = texels.len() as u64;
        if size > self.ram_budget {
            return;
        }
        while self.ram_used + size > self.ram_budget {
            let Some((&key, _)) = self.ram.iter().min_by_key(|(k, e)| (e.used, **k)) else {
                break;
            };
            if let Some(e) = self.ram.remove(&key) {
                self.ram_used -= e.texels.len() as u64;
                stats.ram_evictions += 1;
            }
        }
        self.ram_used += size;
        self.ram.insert(
            (cube, face),
            RamEntry {
                texels,
                used: frame,
            },
        );
    }
}

// Budgets given in megabytes.

/// Bytes of one cube map in the GPU pool on an adapter with (`adapter_has_bc`,
/// [`crate::Gpu::has_bc`]) or without BC texture compression: six faces of texels in the pool's
/// encoding (BC6H blocks, 1 byte per texel, or RGB9E5 for a BC6H store without BC) with their
/// mip levels, and the distance planes when the store has them ([`FaceLayout::payload_bytes`]).
pub fn cube_bytes(store: &Store, adapter_has_bc: bool) -> u64 {
    6 * FaceLayout::for_store(store, adapter_has_bc).payload_bytes() as u64
}

/// The GPU slots a budget of `mb` megabytes buys on an adapter with (`adapter_has_bc`) or without BC
/// texture compression: whole cube maps of [`cube_bytes`], at least one.
pub fn slots_for_megabytes(store: &Store, mb: f64, adapter_has_bc: bool) -> crate::Result<u32> {
    if !(mb.is_finite() && mb > 0.0) {
        return Err(crate::RuntimeError::InvalidParam {
            param: Param::CacheMegabytes,
            problem: format!("{mb} must be a positive number"),
        });
    }
    let cube_bytes = cube_bytes(store, adapter_has_bc);
    let slots = (mb * 1e6 / cube_bytes as f64).floor();
    if slots < 1.0 {
        return Err(crate::RuntimeError::InvalidParam {
            param: Param::CacheMegabytes,
            problem: format!(
                "{mb} holds no cube map ({:.3} MB each)",
                cube_bytes as f64 / 1e6
            ),
        });
    }
    Ok(slots.min(f64::from(u32::MAX)) as u32)
}

/// The RAM level's byte budget for a budget of `mb` megabytes.
pub fn ram_bytes(mb: f64) -> crate::Result<u64> {
    if !(mb.is_finite() && mb >= 0.0) {
        return Err(crate::RuntimeError::InvalidParam {
            param: Param::RamMegabytes,
            problem: format!("{mb} must be a non-negative number"),
        });
    }
    // No silent clamp to u64::MAX: a budget past 2^63 bytes is no budget any machine has.
    if mb * 1e6 >= 2f64.powi(63) {
        return Err(crate::RuntimeError::InvalidParam {
            param: Param::RamMegabytes,
            problem: format!("{mb} is more memory than any machine has (at most 9.2e12 MB)"),
        });
    }
    Ok((mb * 1e6) as u64)
}
