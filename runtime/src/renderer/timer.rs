//! GPU timestamps of the frame's passes (where the device has `TIMESTAMP_QUERY`).

use crate::buffers::TIMESTAMP_BYTES;
use crate::Gpu;

/// Timestamps at the start and end of the G-buffer pass (queries 0, 1), of the shading pass
/// (2, 3), of a host frame's composite pass (4, 5) and of its prepass (6, 7), resolved into `resolve` (one pair per
/// 256-byte resolve offset) and copied behind the feedback masks
/// (`StoreBuffers::feedback_readback`), so one map per frame reads them.
pub(super) struct PassTimer {
    queries: wgpu::QuerySet,
    resolve: wgpu::Buffer,
    /// Nanoseconds per tick (`Queue::get_timestamp_period`).
    period_ns: f64,
}

/// A pass's pair of timestamps: G-buffer, shading or (host frames) composite and prepass.
#[derive(Clone, Copy)]
pub(super) enum TimedPass {
    GBuffer = 0,
    Shade = 1,
    Composite = 2,
    Prepass = 3,
}

/// The timed passes.
const PASSES: u32 = 4;
// Each pass's pair is two u64 ticks behind the feedback masks.
const _: () = assert!(TIMESTAMP_BYTES == 16 * PASSES as u64);

impl TimedPass {
    /// Its two queries' indices.
    pub(super) fn queries(self) -> std::ops::Range<u32> {
        2 * self as u32..2 * self as u32 + 2
    }

    /// Where its pair is resolved (resolve offsets are multiples of 256 bytes).
    pub(super) fn resolve_offset(self) -> u64 {
        wgpu::QUERY_RESOLVE_BUFFER_ALIGNMENT * self as u64
    }

    /// Where its pair lies behind the feedback masks.
    pub(super) fn readback_offset(self) -> u64 {
        TIMESTAMP_BYTES / u64::from(PASSES) * self as u64
    }
}

impl PassTimer {
    pub(super) fn new(gpu: &Gpu) -> Option<Self> {
        if !gpu.has_timestamps() {
            return None;
        }
        Some(Self {
            queries: gpu.device.create_query_set(&wgpu::QuerySetDescriptor {
                label: Some("pass timestamps"),
                ty: wgpu::QueryType::Timestamp,
                count: 2 * PASSES,
            }),
            resolve: gpu.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("pass timestamps"),
                size: u64::from(PASSES) * wgpu::QUERY_RESOLVE_BUFFER_ALIGNMENT,
                usage: wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
                mapped_at_creation: false,
            }),
            period_ns: f64::from(gpu.queue.get_timestamp_period()),
        })
    }

    /// The timestamp writes of `pass` for its pass descriptor.
    pub(super) fn writes(&self, pass: TimedPass) -> (&wgpu::QuerySet, Option<u32>, Option<u32>) {
        let q = pass.queries();
        (&self.queries, Some(q.start), Some(q.start + 1))
    }

    /// Encodes resolving `pass`'s pair and copying it behind the feedback masks at `stamps`.
    pub(super) fn encode_copy(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        pass: TimedPass,
        readback: &wgpu::Buffer,
        stamps: u64,
    ) {
        encoder.resolve_query_set(
            &self.queries,
            pass.queries(),
            &self.resolve,
            pass.resolve_offset(),
        );
        encoder.copy_buffer_to_buffer(
            &self.resolve,
            pass.resolve_offset(),
            readback,
            stamps + pass.readback_offset(),
            Some(TIMESTAMP_BYTES / u64::from(PASSES)),
        );
    }

    /// Seconds between `pass`'s two timestamps in `bytes` (the read-back from `stamps` on;
    /// start, end as u64 ticks); `None` for an end before the start (a device whose counter
    /// wrapped or was reset between them).
    pub(super) fn seconds(&self, bytes: &[u8], pass: TimedPass) -> Option<f64> {
        let at = pass.readback_offset() as usize;
        let start = u64::from_le_bytes(bytes.get(at..at + 8)?.try_into().ok()?);
        let end = u64::from_le_bytes(bytes.get(at + 8..at + 16)?.try_into().ok()?);
        let ticks = end.checked_sub(start)?;
        Some(ticks as f64 * self.period_ns * 1e-9)
    }
}
