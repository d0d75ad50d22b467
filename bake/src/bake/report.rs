//! What a bake did: the report the CLI summarizes and tools read (`--report-json`).

use std::path::PathBuf;

use oslf_geometry::atlas::UvSource;

use super::noise_report::NoiseReport;
use crate::coverage::ObjectCoverage;
use crate::sample_map::SampleMapStats;
use crate::sample_points::Surfaces;
use oslf_scene::normals::{NormalRule, NormalsUsed};
use oslf_scene::scene::Scene;

/// What a bake did, for the summary and for tools (`--report-json`).
#[derive(Clone, Debug, Default, serde::Serialize)]
pub struct BakeReport {
    pub output: PathBuf,
    /// Whether the store was completed (false when `cube_limit` stopped the run early).
    pub finished: bool,
    pub triangles: usize,
    pub bvh_build_seconds: f64,
    pub sample_points: usize,
    pub points_placed: usize,
    pub points_removed_close: usize,
    pub points_removed_inside: usize,
    /// Points added where sample-map texels found fewer than four (§6.3).
    pub points_added: usize,
    /// Points, placed or added, kept nearer their surface than ε because another surface
    /// lay near (`near_surface = "lower"`).
    pub points_lowered: usize,
    /// The bake's ε (scene units): the sample points' offset.
    pub epsilon: f32,
    /// The settings chosen from the scene where its file leaves them unset, each with why
    /// (`epsilon = 0.0029: 1/64 of object "can"'s size 0.1860`; [`oslf_scene::bake_defaults`]).
    pub chosen: Vec<String>,
    pub sample_maps: SampleMapStats,
    /// Per OSLF object with sample-map texels, in object order: its short and empty texels,
    /// where they lie and why ([`crate::coverage`]).
    pub coverage: Vec<ObjectCoverage>,
    /// The atlas of each mesh object, in object order.
    pub atlases: Vec<AtlasReport>,
    /// The normals of each mesh object, in object order.
    pub normals: Vec<NormalsReport>,
    /// Cubes of this store (or, for a shard, of this shard).
    pub cubes: u32,
    /// `I/N` when this bake was shard `I` of `N`; `cubes` then counts the shard's cubes.
    pub shard: Option<String>,
    /// Cubes in the merged store (equal to `cubes` unless this is a shard).
    pub store_cubes: u32,
    /// Cubes recovered from an interrupted bake instead of being traced again.
    pub cubes_resumed: u32,
    /// Whether `resume` found a partial file that was never completely created and started
    /// over (a line on stderr says so).
    pub restarted: bool,
    pub cube_resolution: u32,
    pub samples_per_texel: u32,
    /// The Monte Carlo noise of this run's cubes, and what to raise when it shows (`None`
    /// when this run captured no cube).
    pub noise: Option<NoiseReport>,
    pub rays_closest: u64,
    pub rays_shadow: u64,
    /// BVH nodes and triangles those rays tested, where the capture device counts them (the
    /// GPU path tracer; 0 on the CPU, which does not).
    pub traversal_nodes: u64,
    pub traversal_triangles: u64,
    /// Capture rays per second, millions (closest + shadow, this run's cubes only).
    pub mrays_per_second: f64,
    pub placement_seconds: f64,
    /// Pilot cubes captured to place the points (`placement = "adaptive"`; 0 otherwise).
    pub pilot_cubes: usize,
    pub sample_map_seconds: f64,
    pub capture_seconds: f64,
    /// What captured the cube maps: `CPU (N threads)`, or the capture device's description
    /// ([`crate::device::CaptureDevice::describe`]).
    pub capture_device: String,
    /// CPU time all of the process's threads spent during the capture, where the system
    /// reports it (Linux). On a shared machine, capture rays per CPU-second do not depend on
    /// what else runs; `mrays_per_second` (wall time) does.
    pub capture_cpu_seconds: Option<f64>,
    pub total_seconds: f64,
    /// CPU time of the whole bake, all threads (Linux; see `capture_cpu_seconds`).
    pub cpu_seconds: Option<f64>,
    pub store_bytes: u64,
    /// Compressed cube-map bytes per texel.
    pub bytes_per_texel: f64,
    /// Texels whose radiance exceeded the encoding's range and were clamped.
    pub clamped_texels: u64,
}

impl BakeReport {
    /// Empty sample-map texels that no view reaches ([`crate::coverage::Cause::Unseen`]).
    pub fn unseen_empty(&self) -> u64 {
        self.coverage.iter().map(|c| c.unseen_empty).sum()
    }

    /// Empty sample-map texels a view may reach: those the store cannot reconstruct where
    /// it matters (warned about, and refused under `--strict`).
    pub fn visible_empty(&self) -> u64 {
        self.sample_maps.empty.saturating_sub(self.unseen_empty())
    }
}

/// How a mesh object's sample maps were laid out.
#[derive(Clone, Debug, serde::Serialize)]
pub struct AtlasReport {
    pub object: String,
    /// Pages per side: the object has `grid²` sample maps.
    pub grid: u32,
    /// Texels per page side (the sample-map resolution).
    pub page_resolution: u32,
    /// `lightmap` (TEXCOORD_1), `texture` (TEXCOORD_0, OBJ `vt`) or `charts` (our own).
    pub source: &'static str,
    /// Charts of our own (0 for a uv set of the mesh).
    pub charts: u32,
    /// The fraction of the atlas's texels that the surface's triangles touch.
    pub fill: f64,
    /// The fraction that stand for a surface point: those and the free texels beside them.
    pub used: f64,
    /// The uv sets tried and not used, each with why.
    pub rejected: Vec<String>,
}

/// Which normals a mesh object got and why.
#[derive(Clone, Debug, serde::Serialize)]
pub struct NormalsReport {
    pub object: String,
    /// The rule they were computed by (`"flat"`, `"smooth"`, `{"crease": {"crease_deg": 30}}`);
    /// `null` where the file's normals are used.
    pub rule: Option<NormalRule>,
    /// Why, naming the file: `box.obj has no normals; the default for OBJ`.
    pub reason: String,
}

/// `object "box": crease 30° (box.obj has no normals; the default for OBJ)`.
impl std::fmt::Display for NormalsReport {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let used = NormalsUsed {
            rule: self.rule,
            reason: self.reason.clone(),
        };
        write!(f, "object {:?}: {used}", self.object)
    }
}

/// The normals of `scene`'s mesh objects, for the report.
pub(super) fn normals_reports(scene: &Scene) -> Vec<NormalsReport> {
    scene
        .objects
        .iter()
        .filter_map(|o| {
            let used = o.normals.as_ref()?;
            Some(NormalsReport {
                object: o.name.clone(),
                rule: used.rule,
                reason: used.reason.clone(),
            })
        })
        .collect()
}

/// The atlases of `scene`'s mesh objects, for the report.
pub(super) fn atlas_reports(scene: &Scene, surfaces: &Surfaces) -> Vec<AtlasReport> {
    let name = |s: UvSource| match s {
        UvSource::Lightmap => "lightmap",
        UvSource::Texture => "texture",
        UvSource::Charts => "charts",
    };
    scene
        .objects
        .iter()
        .enumerate()
        .filter_map(|(i, o)| {
            let atlas = surfaces.atlas(i)?;
            Some(AtlasReport {
                object: o.name.clone(),
                grid: atlas.grid,
                page_resolution: atlas.page_resolution,
                source: name(atlas.source),
                charts: atlas.chart_count(),
                fill: atlas.fill(),
                used: atlas.used(),
                rejected: atlas
                    .rejected
                    .iter()
                    .map(|(s, why)| format!("{}: {why}", name(*s)))
                    .collect(),
            })
        })
        .collect()
}
