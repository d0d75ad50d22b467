//! The sample-map domains of the OSLF objects: what "texel (x, y) of sample map k" means on
//! the surface.
//!
//! A Bézier-patch object has one sample map per patch over its (u, v) square (thesis §3.3). A
//! triangle-mesh object has its sample maps in a UV atlas ([`oslf_geometry::atlas`]): a k×k
//! grid of *pages*, each one ordinary m×m sample map, so the store, the runtime and the
//! shading see only sample maps. Global map indices run over the objects in order: an
//! object's patches, or its k² pages (row-major over the grid).
//!
//! Normals: on a mesh the shading normal is the *interpolated* vertex normal (barycentric,
//! renormalized), in the bake (sample points, texel normals of Eq. 3.10), in the runtime's
//! G-buffer and in `oslf truth`; the geometric normal offsets sample points and rays and tells
//! sides apart.
//!
//! Sample points are drawn over all domains with density proportional to area
//! ([`Surfaces::sample`], or over one object with [`Surfaces::sample_object`] where objects have
//! spacings of their own): a patch's area is tabulated on a grid of (u, v) cells, a mesh's per
//! triangle.

use std::sync::Arc;

use glam::{Vec2, Vec3};
use oslf_geometry::atlas::{Atlas, AtlasOptions};

use oslf_geometry::bezier::BezierPatch;
use oslf_scene::error::{BakeError, Result};
use oslf_scene::scene::{BakeSettings, OslfObject, SampleDensity};
use oslf_shading::random::Rng;

/// Cells per patch side used to tabulate surface area.
const AREA_GRID: usize = 32;

/// Atlas texels per sample spacing: a mesh's atlas texel is the bake's sample spacing
/// divided by this (so a sample point's Voronoi cell spans about 8 × 8 texels, as a patch of
/// the teapot's quick preset does).
pub const ATLAS_TEXELS_PER_SPACING: f32 = 8.0;

/// The largest atlas grid side (pages) of one mesh object.
pub const MAX_ATLAS_GRID: u32 = 64;

/// One sample map's domain.
#[derive(Clone, Copy, Debug)]
pub enum MapDomain<'a> {
    /// A Bézier patch (world space) over its (u, v) square.
    Patch { object: u32, patch: &'a BezierPatch },
    /// Page `page` (row-major over the grid) of a mesh object's atlas.
    Page {
        object: u32,
        atlas: &'a Atlas,
        page: u32,
    },
}

impl MapDomain<'_> {
    /// The object the map belongs to.
    pub fn object(&self) -> u32 {
        match *self {
            MapDomain::Patch { object, .. } | MapDomain::Page { object, .. } => object,
        }
    }

    /// Whether texel `(x, y)` stands for a surface point ([`MapDomain::texel`] is `Some`),
    /// without evaluating it.
    pub fn covers(&self, x: u32, y: u32) -> bool {
        match *self {
            MapDomain::Patch { .. } => true,
            MapDomain::Page { atlas, page, .. } => atlas.texel(page, x, y).is_some(),
        }
    }

    /// Surface point and unit shading normal of texel `(x, y)` of a `resolution`² map (centred
    /// at u = (x + ½)/res, v = (y + ½)/res); `None` for atlas texels no chart touches.
    pub fn texel(&self, x: u32, y: u32, resolution: u32) -> Option<(Vec3, Vec3)> {
        match *self {
            MapDomain::Patch { patch, .. } => {
                let u = (x as f32 + 0.5) / resolution as f32;
                let v = (y as f32 + 0.5) / resolution as f32;
                Some((patch.eval(u, v), patch.normal(u, v)))
            }
            MapDomain::Page { atlas, page, .. } => {
                let t = atlas.texel(page, x, y)?;
                Some(atlas.sample_surface(t.triangle, t.bary))
            }
        }
    }

    /// Surface point, unit shading normal and unit offset direction ([`SurfacePoint::offset`])
    /// of texel `(x, y)`, as [`MapDomain::texel`].
    pub fn texel_offset(&self, x: u32, y: u32, resolution: u32) -> Option<(Vec3, Vec3, Vec3)> {
        match *self {
            MapDomain::Patch { .. } => {
                let (p, n) = self.texel(x, y, resolution)?;
                Some((p, n, n))
            }
            MapDomain::Page { atlas, page, .. } => {
                let t = atlas.texel(page, x, y)?;
                let (p, n) = atlas.sample_surface(t.triangle, t.bary);
                Some((p, n, atlas.offset_normal(t.triangle, n)))
            }
        }
    }
}

/// One area cell: a patch's (u, v) cell or a mesh triangle.
#[derive(Clone, Copy, Debug)]
enum Cell {
    /// Object, patch of the object, cell column and row.
    Patch {
        object: u32,
        patch: u32,
        i: u16,
        j: u16,
    },
    /// Object index and triangle.
    Triangle { object: u32, triangle: u32 },
}

/// A point drawn on the surface: where a sample point's base lies.
#[derive(Clone, Copy, Debug)]
pub struct SurfacePoint {
    pub position: Vec3,
    /// Unit shading normal.
    pub normal: Vec3,
    /// Unit direction of the ε offset: the geometric normal of the face the point lies on
    /// (on a patch, its normal; on a mesh, the triangle's, on the shading normal's side).
    pub offset: Vec3,
    /// Parameter on its map, in `[0, 1]²` (patch (u, v), or local page uv).
    pub uv: Vec2,
    /// Global map index.
    pub map: u32,
    pub object: u32,
}

/// The sample-map domains of all OSLF objects of a scene, with the atlases of its meshes.
pub struct Surfaces<'s> {
    objects: &'s [OslfObject],
    /// Per object: its atlas (mesh objects) and first global map index.
    atlases: Vec<Option<Arc<Atlas>>>,
    first_map: Vec<u32>,
    map_count: u32,
    cells: Vec<Cell>,
    /// Running area sums (accumulated in f64, stored as f32), one per cell.
    cdf: Vec<f32>,
    area: f32,
    /// Per object: its cells (a range of `cells` and `cdf`) and its area.
    object_cells: Vec<(std::ops::Range<usize>, f32)>,
    /// Per object: the sample spacing its atlas texel and its sample points follow (its own
    /// `sample_spacing`, else the bake's).
    spacing: Vec<f32>,
}

impl<'s> Surfaces<'s> {
    /// Lays out the maps of `objects`: builds each mesh object's atlas at the settings' sample
    /// map resolution, with a texel of the sample spacing / [`ATLAS_TEXELS_PER_SPACING`], and
    /// tabulates the area.
    pub fn new(objects: &'s [OslfObject], settings: &BakeSettings) -> Result<Self> {
        let mut cells = Vec::new();
        let mut cdf = Vec::new();
        let mut total = 0f64;
        let mut push = |cell: Cell, area: f32, cells: &mut Vec<Cell>, cdf: &mut Vec<f32>| {
            total += if area.is_finite() && area > 0.0 {
                f64::from(area)
            } else {
                0.0
            };
            cells.push(cell);
            cdf.push(total as f32);
        };
        let n = AREA_GRID;
        let cell = 1.0 / n as f32;
        let mut object_cells = Vec::with_capacity(objects.len());
        for (o, object) in objects.iter().enumerate() {
            let (first, before) = (cells.len(), cdf.last().copied().unwrap_or(0.0));
            for (p, patch) in object.patches.iter().enumerate() {
                for j in 0..n {
                    for i in 0..n {
                        let (du, dv) =
                            patch.partials((i as f32 + 0.5) * cell, (j as f32 + 0.5) * cell);
                        let area = du.cross(dv).length() * cell * cell;
                        let c = Cell::Patch {
                            object: o as u32,
                            patch: p as u32,
                            i: i as u16,
                            j: j as u16,
                        };
                        push(c, area, &mut cells, &mut cdf);
                    }
                }
            }
            if let Some(source) = &object.mesh {
                for (t, tri) in source.mesh.triangles.iter().enumerate() {
                    let area = source
                        .mesh
                        .corners(tri)
                        .map_or(0.0, |[a, b, c]| 0.5 * (b - a).cross(c - a).length());
                    let c = Cell::Triangle {
                        object: o as u32,
                        triangle: t as u32,
                    };
                    push(c, area, &mut cells, &mut cdf);
                }
            }
            let after = cdf.last().copied().unwrap_or(0.0);
            object_cells.push((first..cells.len(), after - before));
        }
        let area = total as f32;
        // `sample_count` spreads over the objects without a spacing of their own.
        let shared_area: f32 = if objects.iter().all(|o| o.sample_spacing.is_none()) {
            area
        } else {
            objects
                .iter()
                .zip(&object_cells)
                .filter(|(o, _)| o.sample_spacing.is_none())
                .map(|(_, (_, a))| a)
                .sum()
        };
        let shared = match settings.sample_count {
            SampleDensity::Spacing(h) => h,
            // Hexagonal packing: each point covers (√3/2)·h².
            SampleDensity::Count(c) => (shared_area / (0.866_025_4 * c.max(1) as f32)).sqrt(),
        };
        let spacing: Vec<f32> = objects
            .iter()
            .map(|o| o.sample_spacing.unwrap_or(shared))
            .collect();
        let mut atlases = Vec::with_capacity(objects.len());
        let mut first_map = Vec::with_capacity(objects.len());
        let mut next = 0u32;
        for (object, &spacing) in objects.iter().zip(&spacing) {
            first_map.push(next);
            next += object.patches.len() as u32;
            let atlas = match &object.mesh {
                None => None,
                Some(source) => {
                    let options = AtlasOptions {
                        page_resolution: settings.sample_map_resolution,
                        texel_size: spacing / ATLAS_TEXELS_PER_SPACING,
                        max_grid: MAX_ATLAS_GRID,
                    };
                    let atlas = source.atlas(&options).map_err(|e| {
                        BakeError::Invalid(format!(
                            "object {:?}: its sample-map atlas: {e} (the atlas texel is the \
                             sample spacing / {ATLAS_TEXELS_PER_SPACING}: fewer sample points or a \
                             larger sample_map_resolution make room)",
                            object.name
                        ))
                    })?;
                    next += atlas.grid * atlas.grid;
                    Some(atlas)
                }
            };
            atlases.push(atlas);
        }
        Ok(Surfaces {
            objects,
            atlases,
            first_map,
            map_count: next,
            cells,
            cdf,
            area,
            object_cells,
            spacing,
        })
    }

    /// The OSLF objects, in order.
    pub fn objects(&self) -> &'s [OslfObject] {
        self.objects
    }

    /// The surface area of object `o`.
    pub fn object_area(&self, o: usize) -> f32 {
        self.object_cells[o].1
    }

    /// The sample spacing of object `o`: its own `sample_spacing`, else the bake's
    /// (`sample_spacing`, or the spacing `sample_count` points give over the objects without
    /// one).
    pub fn spacing(&self, o: usize) -> f32 {
        self.spacing[o]
    }

    /// A point drawn on object `o` alone, with density proportional to area.
    pub fn sample_object(&self, o: usize, rng: &mut Rng) -> SurfacePoint {
        let (range, area) = self.object_cells[o].clone();
        let before = range.start.checked_sub(1).map_or(0.0, |i| self.cdf[i]);
        let target = before + rng.next_f32() * area;
        let k = range.start
            + self.cdf[range.clone()]
                .partition_point(|&c| c <= target)
                .min(range.len().saturating_sub(1));
        self.sample_cell(k, rng)
    }

    /// Total surface area of the OSLF objects.
    pub fn area(&self) -> f32 {
        self.area
    }

    /// Number of sample maps (patches and atlas pages).
    pub fn map_count(&self) -> u32 {
        self.map_count
    }

    /// The atlas of object `o`, if it is a mesh.
    pub fn atlas(&self, o: usize) -> Option<&Atlas> {
        self.atlases.get(o).and_then(Option::as_deref)
    }

    /// The first global map index of object `o`.
    pub fn first_map(&self, o: usize) -> u32 {
        self.first_map[o]
    }

    /// Every map's domain, in global map order.
    pub fn maps(&self) -> Vec<MapDomain<'_>> {
        let mut out = Vec::with_capacity(self.map_count as usize);
        for (o, object) in self.objects.iter().enumerate() {
            let object_index = o as u32;
            out.extend(object.patches.iter().map(|patch| MapDomain::Patch {
                object: object_index,
                patch,
            }));
            if let Some(atlas) = self.atlases[o].as_deref() {
                out.extend((0..atlas.grid * atlas.grid).map(|page| MapDomain::Page {
                    object: object_index,
                    atlas,
                    page,
                }));
            }
        }
        out
    }

    /// A point drawn with density proportional to area (exact per triangle; within each patch
    /// cell's linearisation).
    pub fn sample(&self, rng: &mut Rng) -> SurfacePoint {
        let target = rng.next_f32() * self.area;
        let k = self
            .cdf
            .partition_point(|&c| c <= target)
            .min(self.cells.len().saturating_sub(1));
        self.sample_cell(k, rng)
    }

    /// A point drawn uniformly by area within cell `k`.
    fn sample_cell(&self, k: usize, rng: &mut Rng) -> SurfacePoint {
        let (a, b) = (rng.next_f32(), rng.next_f32());
        match self.cells[k] {
            Cell::Patch {
                object,
                patch,
                i,
                j,
            } => {
                let n = AREA_GRID as f32;
                let u = (f32::from(i) + a) / n;
                let v = (f32::from(j) + b) / n;
                let bezier = &self.objects[object as usize].patches[patch as usize];
                let normal = bezier.normal(u, v);
                SurfacePoint {
                    position: bezier.eval(u, v),
                    normal,
                    offset: normal,
                    uv: Vec2::new(u, v),
                    map: self.first_map[object as usize] + patch,
                    object,
                }
            }
            Cell::Triangle { object, triangle } => {
                // Uniform on the triangle (pbrt-v4's `SampleUniformTriangle`, square-root form).
                let s = a.sqrt();
                let bary = [1.0 - s, b * s, s * (1.0 - b)];
                self.mesh_point(object, triangle, bary)
            }
        }
    }

    /// The surface point of object `object`'s input triangle `triangle` at `bary`.
    fn mesh_point(&self, object: u32, triangle: u32, bary: [f32; 3]) -> SurfacePoint {
        let atlas = self.atlases[object as usize]
            .as_deref()
            .expect("triangle cells belong to mesh objects");
        let (position, normal) = atlas.sample_surface(triangle, bary);
        let (page, uv) = atlas.locate(triangle, bary);
        SurfacePoint {
            position,
            normal,
            offset: atlas.offset_normal(triangle, normal),
            uv: Vec2::from_array(uv),
            map: self.first_map[object as usize] + page,
            object,
        }
    }
}
