//! Capture devices: what captures the cube maps of a bake when it is not this crate's CPU path
//! tracer ([`oslf_trace::capture`]). The GPU path tracer (crate `oslf-bake-gpu`, which this crate
//! never depends on: the bake has no wgpu) implements [`CaptureDevice`]; the bake hands it
//! batches of cubes in store order ([`crate::bake::BakeOptions::device`]), so resuming,
//! sharding and merging work as with the CPU path.

use glam::Vec3;
use oslf_format::CubeImage;

use oslf_scene::Result;
use oslf_trace::capture::CaptureSettings;
use oslf_trace::integrator::RayStats;
use oslf_trace::noise::NoiseStats;

/// One cube to capture.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CubeJob {
    /// Where the cube is captured from.
    pub origin: Vec3,
    /// The cube's index in the store: it selects the random streams, so a cube's texels are
    /// the same in whatever batch it is captured.
    pub index: u32,
    /// Whether the OSLF objects are part of the scene this cube sees: false for the
    /// environment-map baseline's cube at the objects' centre.
    pub sees_objects: bool,
}

/// A captured cube: its texels (and distance plane), the rays traced for it, and the noise of
/// its texels ([`oslf_trace::noise`]; empty for the environment-map baseline's cube).
pub type CapturedCube = (CubeImage, RayStats, NoiseStats);

/// A cube-map capture backend for a scene it was built for.
pub trait CaptureDevice: Send + Sync + std::fmt::Debug {
    /// What captures, for reports: the adapter's name, driver and backend.
    fn describe(&self) -> String;

    /// Capture rays per second this device was measured at for this scene (the preflight's
    /// time estimate uses it), if it was.
    fn rays_per_second(&self) -> Option<f64>;

    /// How many cubes of `settings` one [`CaptureDevice::capture`] call should get (bounded
    /// memory: the device keeps one batch's texels at a time).
    fn batch_cubes(&self, settings: &CaptureSettings) -> usize;

    /// The device memory a capture of `settings` holds, bytes: the scene uploaded once and
    /// one batch's buffers (the preflight reports it); `None` if the device does not say.
    fn memory_bytes(&self, _settings: &CaptureSettings) -> Option<u64> {
        None
    }

    /// The cubes of `jobs`, in order, each the capture [`oslf_trace::capture::capture_cube`]
    /// computes (the same estimator, so the same expected texels). The bake calls it from a
    /// thread of its own while it encodes the previous batch, so the device never waits for
    /// the encoder.
    fn capture(&self, jobs: &[CubeJob], settings: &CaptureSettings) -> Result<Vec<CapturedCube>>;
}
