//! UV atlases of triangle meshes: where each texel of a mesh's sample maps lies on the surface.
//!
//! A mesh object's sample maps live in an atlas. Atlas uv `(s, t) ∈ [0, 1]²` spans a `k × k`
//! grid of *pages*, each an ordinary `m × m` sample map, so the atlas has `A = k·m` texels per
//! side. Page `(px, py)` with `px = min(⌊s·k⌋, k − 1)`, `py = min(⌊t·k⌋, k − 1)` is page number
//! `py·k + px` and its local uv is `(s·k − px, t·k − py)`; texel `(x, y)` of a page is centred at
//! local `((x + ½)/m, (y + ½)/m)` and is atlas texel `(px·m + x, py·m + y)`.
//!
//! [`Atlas::build`] takes the mesh's own uv sets in order of preference (the caller passes the
//! lightmap set `TEXCOORD_1` first, then `TEXCOORD_0`) and uses the first *usable* one:
//!
//! - one uv per vertex, every uv finite and inside `[0, 1]²`;
//! - no triangle with zero uv area but non-zero 3D area;
//! - non-overlapping at the atlas resolution: every texel centre that lies inside a triangle by
//!   more than 10⁻³ texel (from every edge, whatever the triangle's orientation) lies inside only
//!   one. The tolerance keeps centres on shared edges out of both triangles.
//!
//! A user set is kept as is (the returned mesh is the input with `uvs` set to it). Its grid
//! follows the texel size on average: with `S` the 3D area of the mesh and `U` the uv area its
//! triangles cover, the surface gets `A²·U/S` texels per unit area, so
//! `k = clamp(⌈√(S/U) / texel_size / m⌉, 1, limit)` where `limit` is `max_grid`, lowered so
//! that `k·m ≤` [`MAX_ATLAS_RESOLUTION`]. A user set never fails for its size: the grid is
//! capped and the set kept.
//!
//! When no set is usable the atlas is built from *charts* of our own ([`UvSource::Charts`]):
//!
//! 1. adjacent triangles are merged into charts ([`segment`]: by normal deviation, size and
//!    overlap in projection; then notches filled and large teeth split off as small charts);
//! 2. each chart is laid flat ([`flatten`]): projected on its plane, scaled so that every
//!    triangle gets at least `1/texel_size²` texels per unit area, turned to its smallest
//!    bounding rectangle;
//! 3. the charts are packed ([`pack`]) by their texel masks (conservative footprints: every
//!    texel within [`FOOTPRINT_MARGIN`] of a triangle) into the smallest grid `k ≥ 1` that holds
//!    them (more than `limit` is an [`GeometryError::AtlasTooLarge`] error), then grown together
//!    to the largest scale that still packs (bisection between 1 and the largest the grid's
//!    area allows): finer texels cost no page more; then, in rounds, each chart, largest first,
//!    is grown on its own (in both directions or in one) into the space left free
//!    ([`pack::grow`]).
//!
//! No texel is shared by two charts, so vertices are split: the returned mesh has three
//! vertices per triangle (positions and normals copied). A triangle of zero area gets a chart of
//! its own: a segment along `+s`, or for three coincident corners a single texel, so that every
//! triangle has a place. Charts need no gutter between them: sample maps are read at the texel
//! a uv falls in (nearest texel), and a uv within [`FOOTPRINT_MARGIN`] of its triangle (f32
//! rounding is far less) falls in its chart's footprint.
//!
//! The texel table ([`Atlas::texel`]) says which surface point each texel stands for: a texel
//! in a triangle's footprint gets that triangle and the barycentrics of the point of the
//! triangle (in uv) nearest the texel centre, so the point is always on the surface. A texel
//! touched by several triangles takes the one nearest its centre (ties: the lower triangle
//! index). A texel that the packing left free beside footprints (its *border* texels) takes the
//! nearest of the triangles whose footprints it borders. Other texels are empty.
//!
//! Shading normal: the bake, the runtime and the truth renderer all shade a mesh with the
//! interpolated (smooth) vertex normal, renormalized ([`Atlas::sample_surface`]); the geometric
//! normal only offsets rays and tells sides apart.
//!
//! Everything is sequential and free of hashing, so the same input builds the same atlas.

use glam::{DVec2, DVec3, Vec2, Vec3};
use rayon::prelude::*;

use crate::{GeometryError, Mesh, Result};

mod flatten;
mod pack;
mod segment;

pub use segment::{MAX_CHART_ANGLE_DEG, MAX_CHART_TRIANGLES};

/// Largest atlas side `k·m` in texels. The grid of an atlas is lowered below `max_grid` where
/// needed to stay within it (the texel table holds `(k·m)²` entries).
pub const MAX_ATLAS_RESOLUTION: u32 = 16384;

/// Distance (texels) by which a texel centre must be inside a triangle to count in the
/// overlap test of user uv sets.
const INSIDE_TOLERANCE: f64 = 1e-3;

/// Slack (texels) of the conservative texel/triangle intersection test: a texel within this
/// of a triangle is in its footprint. It covers a uv rounded off its triangle: f32 uvs of an
/// atlas of [`MAX_ATLAS_RESOLUTION`] texels are exact to about 10⁻³ texel.
const FOOTPRINT_MARGIN: f64 = 1.0 / 32.0;

/// Minimum distance (texels) between a chart and the border of its footprint cells.
const CHART_MARGIN: f64 = 1.0 / 16.0;

/// Where an atlas's uvs come from.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum UvSource {
    /// The mesh's lightmap uv set (glTF `TEXCOORD_1`).
    Lightmap,
    /// The mesh's texture uv set (glTF `TEXCOORD_0`).
    Texture,
    /// Our own charts: adjacent triangles merged, laid flat and packed.
    Charts,
}

/// How to build an atlas.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AtlasOptions {
    /// Texels per page side, `m` (the store's sample map resolution), in
    /// `1..=`[`MAX_ATLAS_RESOLUTION`].
    pub page_resolution: u32,
    /// World (object-space) size of one texel: charts get `1/texel_size²` texels per unit
    /// area. Finite and positive.
    pub texel_size: f32,
    /// Largest grid `k` (pages per atlas side) allowed, ≥ 1.
    pub max_grid: u32,
}

/// The surface point an atlas texel stands for.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TexelSurface {
    /// Triangle index in [`Atlas::mesh`].
    pub triangle: u32,
    /// Barycentrics of the point on that triangle: finite, each in `[0, 1]`, summing to 1.
    pub bary: [f32; 3],
}

/// A mesh with atlas uvs and, for every atlas texel, the surface point it stands for.
#[derive(Clone, Debug)]
pub struct Atlas {
    /// The input positions and normals, vertices split where charts need it (three per triangle
    /// for [`UvSource::Charts`]); `uvs` are atlas uvs `(s, t)` in `[0, 1]²` over the whole grid.
    /// Triangle `i` is the input's triangle `i`.
    pub mesh: Mesh,
    /// Pages per atlas side, `k` ≥ 1.
    pub grid: u32,
    /// Texels per page side, `m`.
    pub page_resolution: u32,
    /// Where the uvs come from.
    pub source: UvSource,
    /// The uv sets tried before [`Atlas::source`] and why each was not used, in order.
    pub rejected: Vec<(UvSource, String)>,
    /// Per triangle, the index of its chart ([`UvSource::Charts`]; empty for a user uv set).
    pub chart_of: Vec<u32>,
    /// `(k·m)²` entries, row-major over the whole atlas (row `t`, column `s`).
    texels: Vec<Option<TexelSurface>>,
    /// How many of them are border texels (next to a footprint, in none).
    borders: usize,
}

impl Atlas {
    /// Builds the atlas of `mesh` (see the [module documentation](self)).
    ///
    /// `uv_sets` are tried in order; a set whose source is [`UvSource::Charts`] is ignored.
    /// `mesh.uvs` is not read.
    ///
    /// # Errors
    ///
    /// [`GeometryError::Invalid`] for bad options (`texel_size` not finite and positive,
    /// `page_resolution` or `max_grid` out of range) or an unusable mesh (no triangles,
    /// a normal count different from the position count, a non-finite position, a non-finite or
    /// zero normal, an index out of range); [`GeometryError::AtlasTooLarge`] when no uv set is
    /// usable and the charts need a grid above the limit.
    pub fn build(
        mesh: &Mesh,
        uv_sets: &[(UvSource, &[Vec2])],
        options: &AtlasOptions,
    ) -> Result<Atlas> {
        check_options(options)?;
        check_mesh(mesh)?;
        let m = options.page_resolution;
        let limit = options.max_grid.min(MAX_ATLAS_RESOLUTION / m).max(1);
        let mut rejected = Vec::new();
        for &(source, uvs) in uv_sets {
            if source == UvSource::Charts {
                continue;
            }
            match user_grid(mesh, uvs, options, limit) {
                Ok(grid) => {
                    let mut out = mesh.clone();
                    out.uvs = uvs.to_vec();
                    let (texels, borders) = texel_table(&out, grid * m);
                    return Ok(Atlas {
                        mesh: out,
                        grid,
                        page_resolution: m,
                        source,
                        rejected,
                        chart_of: Vec::new(),
                        texels,
                        borders,
                    });
                }
                Err(why) => rejected.push((source, why)),
            }
        }
        let (out, grid, chart_of) = charts(mesh, options, limit)?;
        let (texels, borders) = texel_table(&out, grid * m);
        Ok(Atlas {
            mesh: out,
            grid,
            page_resolution: m,
            source: UvSource::Charts,
            rejected,
            chart_of,
            texels,
            borders,
        })
    }

    /// Number of pages, `k²`.
    pub fn page_count(&self) -> u32 {
        self.grid * self.grid
    }

    /// Atlas texels per side, `k·m`.
    pub fn resolution(&self) -> u32 {
        self.grid * self.page_resolution
    }

    /// Number of charts ([`UvSource::Charts`]; 0 for a user uv set).
    pub fn chart_count(&self) -> u32 {
        self.chart_of.iter().max().map_or(0, |&c| c + 1)
    }

    /// The fraction of the atlas's texels in a triangle's footprint (border texels not
    /// counted): how much of the atlas the surface itself fills.
    pub fn fill(&self) -> f64 {
        (self.used_texels() - self.borders) as f64 / self.texels.len().max(1) as f64
    }

    /// The fraction of the atlas's texels that stand for a surface point: footprints and
    /// border texels (the rest is empty).
    pub fn used(&self) -> f64 {
        self.used_texels() as f64 / self.texels.len().max(1) as f64
    }

    fn used_texels(&self) -> usize {
        self.texels.iter().filter(|t| t.is_some()).count()
    }

    /// The surface point of texel `(x, y)` of page `page = py·k + px`; `None` for a texel no
    /// triangle touches, or coordinates out of range.
    pub fn texel(&self, page: u32, x: u32, y: u32) -> Option<TexelSurface> {
        let (k, m) = (self.grid, self.page_resolution);
        if page >= k * k || x >= m || y >= m {
            return None;
        }
        let gx = (page % k) * m + x;
        let gy = (page / k) * m + y;
        self.atlas_texel(gx, gy)
    }

    /// The surface point of atlas texel `(gx, gy)` (over the whole grid, `0..k·m`); `None`
    /// for an empty texel or coordinates out of range.
    pub fn atlas_texel(&self, gx: u32, gy: u32) -> Option<TexelSurface> {
        let a = self.resolution();
        if gx >= a || gy >= a {
            return None;
        }
        self.texels[gy as usize * a as usize + gx as usize]
    }

    /// The page and local page uv (each in `[0, 1]`) of the point with barycentrics `bary` on
    /// `triangle`: its interpolated atlas uv, clamped to `[0, 1]²`, through
    /// [`Atlas::page_of`].
    ///
    /// # Panics
    ///
    /// If `triangle` is not a triangle of [`Atlas::mesh`].
    pub fn locate(&self, triangle: u32, bary: [f32; 3]) -> (u32, [f32; 2]) {
        let t = self.mesh.triangles[triangle as usize];
        let uv = (0..3).fold(DVec2::ZERO, |acc, c| {
            acc + f64::from(bary[c]) * self.mesh.uvs[t[c] as usize].as_dvec2()
        });
        page_of(self.grid, uv)
    }

    /// The page and local page uv of atlas uv `uv` (clamped to `[0, 1]²`) in a grid of `grid`
    /// pages per side: `px = min(⌊s·k⌋, k − 1)`, page `py·k + px`, local `s·k − px`; so
    /// `s = 1` is the far edge (local 1) of the last page.
    pub fn page_of(grid: u32, uv: Vec2) -> (u32, [f32; 2]) {
        page_of(grid, uv.as_dvec2())
    }

    /// The texel `(x, y)` of a page that holds local page uv `local`:
    /// `x = min(⌊u·m⌋, m − 1)` (local 1 is the last texel).
    pub fn page_texel(&self, local: [f32; 2]) -> (u32, u32) {
        let m = self.page_resolution;
        let f = |u: f32| ((f64::from(u.clamp(0.0, 1.0)) * f64::from(m)) as u32).min(m - 1);
        (f(local[0]), f(local[1]))
    }

    /// Position and unit shading normal of the point with barycentrics `bary` on `triangle`:
    /// the interpolated vertex normal, renormalized (the smooth normal bake, runtime and truth
    /// shade with); where it vanishes, the geometric normal `(p1 − p0) × (p2 − p0)`; for a
    /// degenerate triangle, the first vertex's normal (or `+z`).
    ///
    /// # Panics
    ///
    /// If `triangle` is not a triangle of [`Atlas::mesh`].
    pub fn sample_surface(&self, triangle: u32, bary: [f32; 3]) -> (Vec3, Vec3) {
        let t = self.mesh.triangles[triangle as usize];
        let p = t.map(|v| self.mesh.positions[v as usize]);
        let n = t.map(|v| self.mesh.normals[v as usize]);
        let position = p[0] * bary[0] + p[1] * bary[1] + p[2] * bary[2];
        let normal = (n[0] * bary[0] + n[1] * bary[1] + n[2] * bary[2])
            .try_normalize()
            .or_else(|| (p[1] - p[0]).cross(p[2] - p[0]).try_normalize())
            .or_else(|| n[0].try_normalize())
            .unwrap_or(Vec3::Z);
        (position, normal)
    }

    /// The unit direction along which a point of `triangle` is offset by ε: the triangle's
    /// geometric normal `(p1 − p0) × (p2 − p0)`, turned to the side of `shading` (the shading
    /// normal decides which side is outside); for a degenerate triangle, `shading` itself.
    /// Offsetting along the face's own normal keeps a point exactly ε from its face, so points
    /// near a hard edge do not tilt towards the neighbouring face.
    ///
    /// # Panics
    ///
    /// If `triangle` is not a triangle of [`Atlas::mesh`].
    pub fn offset_normal(&self, triangle: u32, shading: Vec3) -> Vec3 {
        let t = self.mesh.triangles[triangle as usize];
        let p = t.map(|v| self.mesh.positions[v as usize]);
        match (p[1] - p[0]).cross(p[2] - p[0]).try_normalize() {
            Some(g) if g.dot(shading) < 0.0 => -g,
            Some(g) => g,
            None => shading,
        }
    }
}

fn page_of(grid: u32, uv: DVec2) -> (u32, [f32; 2]) {
    let k = grid.max(1);
    let kf = f64::from(k);
    let split = |s: f64| {
        let s = if s.is_nan() { 0.0 } else { s.clamp(0.0, 1.0) };
        let p = ((s * kf).floor() as u32).min(k - 1);
        (p, ((s * kf - f64::from(p)).clamp(0.0, 1.0)) as f32)
    };
    let (px, u) = split(uv.x);
    let (py, v) = split(uv.y);
    (py * k + px, [u, v])
}

fn check_options(o: &AtlasOptions) -> Result<()> {
    if !(o.texel_size.is_finite() && o.texel_size > 0.0) {
        return Err(GeometryError::Invalid(format!(
            "atlas texel_size must be finite and positive, got {}",
            o.texel_size
        )));
    }
    if o.page_resolution == 0 || o.page_resolution > MAX_ATLAS_RESOLUTION {
        return Err(GeometryError::Invalid(format!(
            "atlas page_resolution must be in 1..={MAX_ATLAS_RESOLUTION}, got {}",
            o.page_resolution
        )));
    }
    if o.max_grid == 0 {
        return Err(GeometryError::Invalid(
            "atlas max_grid must be at least 1, got 0".into(),
        ));
    }
    Ok(())
}

fn check_mesh(mesh: &Mesh) -> Result<()> {
    let n = mesh.positions.len();
    if mesh.triangles.is_empty() {
        return Err(GeometryError::Invalid(
            "atlas of a mesh without triangles".into(),
        ));
    }
    // Charts split vertices: three per triangle must fit in u32 indices.
    if mesh.triangles.len() > (u32::MAX / 3) as usize {
        return Err(GeometryError::Invalid(format!(
            "atlas of a mesh with {} triangles: at most {} allowed",
            mesh.triangles.len(),
            u32::MAX / 3
        )));
    }
    if mesh.normals.len() != n {
        return Err(GeometryError::Invalid(format!(
            "atlas: mesh has {n} positions but {} normals",
            mesh.normals.len()
        )));
    }
    if let Some(i) = mesh.positions.iter().position(|p| !p.is_finite()) {
        return Err(GeometryError::Invalid(format!(
            "atlas: mesh vertex {i} has a non-finite position {}",
            mesh.positions[i]
        )));
    }
    if let Some(i) = mesh
        .normals
        .iter()
        .position(|v| !v.is_finite() || v.length_squared() == 0.0)
    {
        return Err(GeometryError::Invalid(format!(
            "atlas: mesh vertex {i} has an unusable normal {}",
            mesh.normals[i]
        )));
    }
    if let Some((i, t)) = mesh
        .triangles
        .iter()
        .enumerate()
        .find(|(_, t)| t.iter().any(|&v| v as usize >= n))
    {
        return Err(GeometryError::Invalid(format!(
            "atlas: mesh triangle {i} has index {t:?} out of range (mesh has {n} vertices)"
        )));
    }
    Ok(())
}

fn corners3(mesh: &Mesh, t: &[u32; 3]) -> [DVec3; 3] {
    t.map(|v| mesh.positions[v as usize].as_dvec3())
}

fn area3(p: &[DVec3; 3]) -> f64 {
    0.5 * (p[1] - p[0]).cross(p[2] - p[0]).length()
}

/// Twice the signed area of a 2D triangle.
fn signed_area2(p: &[DVec2; 3]) -> f64 {
    (p[1] - p[0]).perp_dot(p[2] - p[0])
}

/// The grid of a usable user uv set, or why it is not usable.
fn user_grid(
    mesh: &Mesh,
    uvs: &[Vec2],
    o: &AtlasOptions,
    limit: u32,
) -> std::result::Result<u32, String> {
    let n = mesh.positions.len();
    if uvs.len() != n {
        return Err(format!("it has {} uvs for {n} vertices", uvs.len()));
    }
    if let Some(i) = uvs
        .iter()
        .position(|uv| !(uv.is_finite() && uv.cmpge(Vec2::ZERO).all() && uv.cmple(Vec2::ONE).all()))
    {
        return Err(format!("uv of vertex {i} = {} is outside [0, 1]²", uvs[i]));
    }
    let (mut surface, mut covered) = (0.0f64, 0.0f64);
    for (i, t) in mesh.triangles.iter().enumerate() {
        let a3 = area3(&corners3(mesh, t));
        let a2 = 0.5 * signed_area2(&t.map(|v| uvs[v as usize].as_dvec2())).abs();
        if a2 == 0.0 && a3 > 0.0 {
            return Err(format!(
                "triangle {i} has zero uv area but 3D area {a3:.6e}"
            ));
        }
        surface += a3;
        covered += a2;
    }
    let m = f64::from(o.page_resolution);
    let side = (surface / covered).sqrt() / f64::from(o.texel_size);
    let k = (side / m).ceil();
    let grid = if k.is_finite() {
        k.clamp(1.0, f64::from(limit)) as u32
    } else if surface > 0.0 {
        limit
    } else {
        1
    };
    check_overlap(mesh, uvs, grid * o.page_resolution)?;
    Ok(grid)
}

/// Refuses a uv set where a texel centre lies inside two triangles (by more than
/// [`INSIDE_TOLERANCE`] texel from every edge).
fn check_overlap(mesh: &Mesh, uvs: &[Vec2], a: u32) -> std::result::Result<(), String> {
    let af = f64::from(a);
    let mut owner = vec![u32::MAX; a as usize * a as usize];
    for (i, t) in mesh.triangles.iter().enumerate() {
        let p = t.map(|v| uvs[v as usize].as_dvec2() * af);
        let area2 = signed_area2(&p);
        if area2 == 0.0 {
            continue;
        }
        let sign = area2.signum();
        // Inward edge lines: distance of q from edge (p_j, p_k), positive inside.
        let edges: [(DVec2, DVec2, f64); 3] = [0, 1, 2].map(|e| {
            let (s, d) = (p[e], p[(e + 1) % 3] - p[e]);
            (s, d, d.length())
        });
        let (lo, hi) = bbox(&p);
        let range = |l: f64, h: f64| {
            let x0 = (l - 0.5).ceil().max(0.0) as u32;
            let x1 = ((h - 0.5).floor()).min(af - 1.0);
            (x0, x1)
        };
        let (x0, x1) = range(lo.x, hi.x);
        let (y0, y1) = range(lo.y, hi.y);
        if x1 < 0.0 || y1 < 0.0 {
            continue;
        }
        for y in y0..=y1 as u32 {
            for x in x0..=x1 as u32 {
                let q = DVec2::new(f64::from(x) + 0.5, f64::from(y) + 0.5);
                let inside = edges.iter().all(|&(s, d, len)| {
                    len > 0.0 && sign * d.perp_dot(q - s) / len > INSIDE_TOLERANCE
                });
                if !inside {
                    continue;
                }
                let slot = &mut owner[y as usize * a as usize + x as usize];
                if *slot != u32::MAX {
                    return Err(format!(
                        "triangles {} and {i} overlap in uv space at atlas texel ({x}, {y}) \
                         of {a}×{a}",
                        *slot
                    ));
                }
                *slot = i as u32;
            }
        }
    }
    Ok(())
}

fn bbox(p: &[DVec2; 3]) -> (DVec2, DVec2) {
    (p[0].min(p[1]).min(p[2]), p[0].max(p[1]).max(p[2]))
}

/// Lays out, packs and places the charts of `mesh` (see the [module documentation](self));
/// returns the split mesh, the grid and each triangle's chart.
fn charts(mesh: &Mesh, o: &AtlasOptions, limit: u32) -> Result<(Mesh, u32, Vec<u32>)> {
    let ts = f64::from(o.texel_size);
    let m = o.page_resolution;
    let max_side = limit * m;
    let too_large = |needed: u64| GeometryError::AtlasTooLarge {
        triangles: mesh.triangles.len(),
        area: mesh.area(),
        texel_size: o.texel_size,
        page_resolution: m,
        needed,
        limit,
        max_grid: o.max_grid,
        max_resolution: MAX_ATLAS_RESOLUTION,
    };
    let charts = segment::segment(mesh, ts, f64::from(m));
    let flats: Vec<flatten::Flat> = charts
        .iter()
        .map(|c| flatten::flatten(mesh, c, ts))
        .collect();
    let masks = |scale: f64| -> Option<Vec<[Option<pack::Mask>; pack::TURNS]>> {
        flats
            .par_iter()
            .map(|f| {
                let all = pack::masks(f, DVec2::splat(scale), max_side);
                all.iter().any(Option::is_some).then_some(all)
            })
            .collect()
    };
    // The smallest grid that holds the charts at the asked density...
    let Some(unit) = masks(1.0) else {
        let widest = flats
            .iter()
            .map(|f| f.size.max_element())
            .fold(0.0, f64::max);
        let needed = (widest + 2.0 * CHART_MARGIN + 2.0) / f64::from(m);
        return Err(too_large(if needed.is_finite() {
            (needed.ceil() as u64).max(u64::from(limit) + 1)
        } else {
            u64::MAX
        }));
    };
    let area: u64 = unit
        .iter()
        .map(|p| p[0].as_ref().map_or(0, |k| k.count))
        .sum();
    let mut grid = ((area as f64).sqrt() / f64::from(m)).ceil().max(1.0) as u32;
    if grid > limit {
        return Err(too_large(u64::from(grid)));
    }
    let mut best = loop {
        if let Some(places) = pack::pack(&unit, grid * m) {
            break (1.0, unit, places);
        }
        if grid >= limit {
            return Err(too_large(u64::from(limit) + 1));
        }
        grid += 1;
    };
    // ...then the charts grown to fill it: a finer density costs no page more.
    let a = grid * m;
    let (mut lo, mut hi) = (1.0f64, (f64::from(a).powi(2) / area as f64).sqrt());
    for _ in 0..FILL_STEPS {
        let scale = (lo + hi) / 2.0;
        match masks(scale).and_then(|k| pack::pack(&k, a).map(|p| (k, p))) {
            Some((k, p)) => {
                lo = scale;
                best = (scale, k, p);
            }
            None => hi = scale,
        }
    }
    let (scale, masks, places) = best;
    let mut placed: Vec<pack::Placed> = masks
        .into_iter()
        .zip(&places)
        .map(|(mut turns, place)| pack::Placed {
            x: place.x,
            y: place.y,
            mask: turns[usize::from(place.turns)]
                .take()
                .expect("a placed orientation has a mask"),
            scale: DVec2::splat(scale),
        })
        .collect();
    pack::grow(&flats, &mut placed, a);
    let af = f64::from(a);
    let mut out = Mesh {
        positions: Vec::with_capacity(3 * mesh.triangles.len()),
        normals: Vec::with_capacity(3 * mesh.triangles.len()),
        uvs: vec![Vec2::ZERO; 3 * mesh.triangles.len()],
        triangles: Vec::with_capacity(mesh.triangles.len()),
    };
    for (i, t) in mesh.triangles.iter().enumerate() {
        for &v in t {
            out.positions.push(mesh.positions[v as usize]);
            out.normals.push(mesh.normals[v as usize]);
        }
        let v = 3 * i as u32;
        out.triangles.push([v, v + 1, v + 2]);
    }
    let mut chart_of = vec![0u32; mesh.triangles.len()];
    for (c, chart) in charts.iter().enumerate() {
        for (k, &t) in chart.triangles.iter().enumerate() {
            chart_of[t as usize] = c as u32;
            for (corner, &c2) in flats[c].corners[k].iter().enumerate() {
                let uv = placed[c].map(c2, &flats[c]) / af;
                out.uvs[3 * t as usize + corner] = uv.as_vec2().clamp(Vec2::ZERO, Vec2::ONE);
            }
        }
    }
    Ok((out, grid, chart_of))
}

/// Bisection steps of the chart scale that fills the grid.
const FILL_STEPS: usize = 10;

/// Whether the closed texel square `[x, x+1] × [y, y+1]` (grown by [`FOOTPRINT_MARGIN`]) meets the
/// triangle `p` (texel units; any orientation, degenerate ones included): separating axes
/// `x`, `y` and the edge normals.
fn touches(p: &[DVec2; 3], x: f64, y: f64) -> bool {
    let (lo, hi) = bbox(p);
    let e = FOOTPRINT_MARGIN;
    if hi.x < x - e || lo.x > x + 1.0 + e || hi.y < y - e || lo.y > y + 1.0 + e {
        return false;
    }
    let centre = DVec2::new(x + 0.5, y + 0.5);
    for k in 0..3 {
        let n = (p[(k + 1) % 3] - p[k]).perp();
        if n == DVec2::ZERO {
            continue;
        }
        let proj = p.map(|q| n.dot(q));
        let (tmin, tmax) = (
            proj[0].min(proj[1]).min(proj[2]),
            proj[0].max(proj[1]).max(proj[2]),
        );
        let c = n.dot(centre);
        let r = (n.x.abs() + n.y.abs()) * (0.5 + e);
        if tmax < c - r || tmin > c + r {
            return false;
        }
    }
    true
}

/// Barycentrics of the point of triangle `p` nearest `q`, and its squared distance. Robust for
/// degenerate triangles (segments, points).
fn closest_bary(p: &[DVec2; 3], q: DVec2) -> ([f64; 3], f64) {
    let area2 = signed_area2(p);
    let scale = (p[1] - p[0])
        .length_squared()
        .max((p[2] - p[1]).length_squared())
        .max((p[0] - p[2]).length_squared());
    if area2.abs() > 1e-12 * scale {
        let b1 = (q - p[0]).perp_dot(p[2] - p[0]) / area2;
        let b2 = (p[1] - p[0]).perp_dot(q - p[0]) / area2;
        let b0 = 1.0 - b1 - b2;
        if b0 >= 0.0 && b1 >= 0.0 && b2 >= 0.0 {
            return ([b0, b1, b2], 0.0);
        }
    }
    let mut best = ([1.0, 0.0, 0.0], f64::INFINITY);
    for i in 0..3 {
        let j = (i + 1) % 3;
        let d = p[j] - p[i];
        let dd = d.length_squared();
        let s = if dd > 0.0 {
            ((q - p[i]).dot(d) / dd).clamp(0.0, 1.0)
        } else {
            0.0
        };
        let dist2 = (p[i] + s * d - q).length_squared();
        if dist2 < best.1 {
            let mut b = [0.0; 3];
            b[i] = 1.0 - s;
            b[j] = s;
            best = (b, dist2);
        }
    }
    best
}

/// Barycentrics as `f32`, each in `[0, 1]`, summing to 1 (to rounding).
fn to_f32_bary(b: [f64; 3]) -> [f32; 3] {
    let b0 = (b[0] as f32).clamp(0.0, 1.0);
    let b1 = (b[1] as f32).clamp(0.0, 1.0 - b0);
    [b0, b1, (1.0 - b0 - b1).clamp(0.0, 1.0)]
}

/// The texel table of `mesh` (atlas uvs) at `a × a` texels: footprints, then the border
/// texels left free beside them; and how many border texels there are.
fn texel_table(mesh: &Mesh, a: u32) -> (Vec<Option<TexelSurface>>, usize) {
    let af = f64::from(a);
    let au = a as usize;
    let tri_uv = |t: u32| mesh.triangles[t as usize].map(|v| mesh.uvs[v as usize].as_dvec2() * af);
    let centre = |x: usize, y: usize| DVec2::new(x as f64 + 0.5, y as f64 + 0.5);
    let mut table: Vec<Option<TexelSurface>> = vec![None; au * au];
    for (i, _) in mesh.triangles.iter().enumerate() {
        let p = tri_uv(i as u32);
        let (lo, hi) = bbox(&p);
        let x0 = (lo.x - FOOTPRINT_MARGIN - 1.0).ceil().clamp(0.0, af - 1.0) as usize;
        let x1 = (hi.x + FOOTPRINT_MARGIN).floor().clamp(0.0, af - 1.0) as usize;
        let y0 = (lo.y - FOOTPRINT_MARGIN - 1.0).ceil().clamp(0.0, af - 1.0) as usize;
        let y1 = (hi.y + FOOTPRINT_MARGIN).floor().clamp(0.0, af - 1.0) as usize;
        for y in y0..=y1 {
            for x in x0..=x1 {
                if !touches(&p, x as f64, y as f64) {
                    continue;
                }
                let q = centre(x, y);
                let (b, d2) = closest_bary(&p, q);
                let slot = &mut table[y * au + x];
                let better = match slot {
                    None => true,
                    Some(s) => d2 < closest_bary(&tri_uv(s.triangle), q).1,
                };
                if better {
                    *slot = Some(TexelSurface {
                        triangle: i as u32,
                        bary: to_f32_bary(b),
                    });
                }
            }
        }
    }
    // Border: an empty texel next to footprint texels takes the nearest of their triangles.
    let mut border = Vec::new();
    for y in 0..au {
        for x in 0..au {
            if table[y * au + x].is_some() {
                continue;
            }
            let q = centre(x, y);
            let mut best: Option<(f64, u32, [f64; 3])> = None;
            for ny in y.saturating_sub(1)..=(y + 1).min(au - 1) {
                for nx in x.saturating_sub(1)..=(x + 1).min(au - 1) {
                    let Some(s) = table[ny * au + nx] else {
                        continue;
                    };
                    let (b, d2) = closest_bary(&tri_uv(s.triangle), q);
                    let wins = match best {
                        None => true,
                        Some((bd, bt, _)) => d2 < bd || (d2 == bd && s.triangle < bt),
                    };
                    if wins {
                        best = Some((d2, s.triangle, b));
                    }
                }
            }
            if let Some((_, t, b)) = best {
                border.push((y * au + x, t, b));
            }
        }
    }
    let borders = border.len();
    for (idx, triangle, b) in border {
        table[idx] = Some(TexelSurface {
            triangle,
            bary: to_f32_bary(b),
        });
    }
    (table, borders)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// xorshift64*: deterministic test randomness without a dependency.
    struct Rng(u64);

    impl Rng {
        fn next(&mut self) -> f32 {
            self.0 ^= self.0 >> 12;
            self.0 ^= self.0 << 25;
            self.0 ^= self.0 >> 27;
            (self.0.wrapping_mul(0x2545_f491_4f6c_dd1d) >> 40) as f32 / (1u64 << 24) as f32
        }

        fn bary(&mut self) -> [f32; 3] {
            let (mut a, mut b) = (self.next(), self.next());
            if a + b > 1.0 {
                (a, b) = (1.0 - a, 1.0 - b);
            }
            [1.0 - a - b, a, b]
        }
    }

    fn options(m: u32, texel_size: f32, max_grid: u32) -> AtlasOptions {
        AtlasOptions {
            page_resolution: m,
            texel_size,
            max_grid,
        }
    }

    /// A bumpy subdivided icosahedron: 20·4^levels triangles of varied sizes, no uvs.
    fn blob(levels: u32) -> Mesh {
        let Mesh {
            mut positions,
            triangles,
            ..
        } = Mesh::icosphere(levels);
        let mut rng = Rng(0x1234_5678_9abc_def1);
        for p in &mut positions {
            *p *= 0.6 + 0.8 * rng.next();
        }
        let mut mesh = Mesh {
            uvs: vec![Vec2::ZERO; positions.len()],
            normals: vec![Vec3::Z; positions.len()],
            positions,
            triangles,
        };
        mesh.compute_smooth_normals();
        mesh
    }

    /// The lumpy blob of `examples/blob.glb` (`make_blob_gltf`): a subdivided icosahedron
    /// (1 280 triangles) with smooth waves on its radius.
    fn lumpy() -> Mesh {
        let mut mesh = Mesh::icosphere(3);
        for p in &mut mesh.positions {
            let d = *p;
            let wave = 0.16 * (3.0 * d.x).sin() * (2.0 * d.z + 0.5).cos()
                + 0.10 * (4.0 * d.y + 1.0).sin()
                + 0.08 * (5.0 * d.z).cos() * d.x;
            *p = d * (1.0 + wave);
        }
        mesh.compute_smooth_normals();
        mesh
    }

    /// An n×n grid of quads on [0, 1]² (z = 0), two triangles each; uvs = (x, y).
    fn plane(n: u32) -> Mesh {
        let mut mesh = Mesh::new();
        for y in 0..=n {
            for x in 0..=n {
                let uv = Vec2::new(x as f32, y as f32) / n as f32;
                mesh.positions.push(uv.extend(0.0));
                mesh.normals.push(Vec3::Z);
                mesh.uvs.push(uv);
            }
        }
        for y in 0..n {
            for x in 0..n {
                let v = y * (n + 1) + x;
                mesh.triangles.push([v, v + 1, v + n + 2]);
                mesh.triangles.push([v, v + n + 2, v + n + 1]);
            }
        }
        mesh
    }

    fn tri_uv(atlas: &Atlas, t: usize) -> [DVec2; 3] {
        let a = f64::from(atlas.resolution());
        atlas.mesh.triangles[t].map(|v| atlas.mesh.uvs[v as usize].as_dvec2() * a)
    }

    /// Atlas texels whose square meets triangle `t`'s uv footprint.
    fn footprint(atlas: &Atlas, t: usize) -> Vec<(u32, u32)> {
        let p = tri_uv(atlas, t);
        let (lo, hi) = bbox(&p);
        let a = atlas.resolution() as i64;
        let mut out = Vec::new();
        for y in (lo.y.floor() as i64 - 1).max(0)..=(hi.y.floor() as i64 + 1).min(a - 1) {
            for x in (lo.x.floor() as i64 - 1).max(0)..=(hi.x.floor() as i64 + 1).min(a - 1) {
                if touches(&p, x as f64, y as f64) {
                    out.push((x as u32, y as u32));
                }
            }
        }
        out
    }

    fn assert_bary(b: [f32; 3]) {
        assert!(
            b.iter().all(|v| v.is_finite() && (0.0..=1.0).contains(v)),
            "{b:?}"
        );
        assert!((b.iter().sum::<f32>() - 1.0).abs() < 1e-5, "{b:?}");
    }

    fn assert_table_valid(atlas: &Atlas) {
        let a = atlas.resolution();
        for y in 0..a {
            for x in 0..a {
                if let Some(s) = atlas.atlas_texel(x, y) {
                    assert!((s.triangle as usize) < atlas.mesh.triangle_count());
                    assert_bary(s.bary);
                }
            }
        }
    }

    /// The texel that holds point `bary` of triangle `t`, through locate and the page rule.
    fn texel_of(atlas: &Atlas, t: u32, bary: [f32; 3]) -> Option<TexelSurface> {
        let (page, local) = atlas.locate(t, bary);
        assert!(page < atlas.page_count());
        assert!(local.iter().all(|u| (0.0..=1.0).contains(u)), "{local:?}");
        let (x, y) = atlas.page_texel(local);
        atlas.texel(page, x, y)
    }

    #[test]
    fn charts_cover_every_triangle() {
        let mesh = blob(3);
        assert_eq!(mesh.triangle_count(), 1280);
        let atlas = Atlas::build(&mesh, &[], &options(64, 0.02, 16)).unwrap();
        assert_eq!(atlas.source, UvSource::Charts);
        assert!(atlas.grid >= 1);
        assert_eq!(atlas.mesh.triangle_count(), mesh.triangle_count());
        assert_eq!(atlas.mesh.positions.len(), 3 * mesh.triangle_count());
        for (i, t) in mesh.triangles.iter().enumerate() {
            let split = atlas.mesh.triangles[i];
            assert_eq!(split, [3 * i as u32, 3 * i as u32 + 1, 3 * i as u32 + 2]);
            for c in 0..3 {
                assert_eq!(
                    atlas.mesh.positions[split[c] as usize],
                    mesh.positions[t[c] as usize]
                );
                assert_eq!(
                    atlas.mesh.normals[split[c] as usize],
                    mesh.normals[t[c] as usize]
                );
            }
        }
        assert!(atlas
            .mesh
            .uvs
            .iter()
            .all(|uv| uv.cmpge(Vec2::ZERO).all() && uv.cmple(Vec2::ONE).all()));
        assert_table_valid(&atlas);
        let mut rng = Rng(42);
        for i in 0..mesh.triangle_count() {
            let texels = footprint(&atlas, i);
            assert!(!texels.is_empty(), "triangle {i} has no texel");
            // Each texel of its footprint stands for a point of its chart (the triangle
            // nearest the texel centre, which may be a neighbour across a chart edge).
            let chart = atlas.chart_of[i];
            let same = |s: TexelSurface| atlas.chart_of[s.triangle as usize] == chart;
            for (x, y) in texels {
                let s = atlas.atlas_texel(x, y).unwrap();
                assert!(same(s), "texel ({x}, {y}) of triangle {i}: {s:?}");
            }
            for _ in 0..20 {
                let b = rng.bary();
                let s = texel_of(&atlas, i as u32, b).expect("sampled point on an empty texel");
                assert!(same(s), "triangle {i} at {b:?}: {s:?}");
            }
            // Corners too (uv extremes of the chart).
            for b in [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]] {
                assert!(same(texel_of(&atlas, i as u32, b).unwrap()), "triangle {i}");
            }
        }
    }

    /// No texel is in the footprints of two charts; every footprint texel stands for a point
    /// of its chart, and any other texel is empty or stands for a chart whose footprint it
    /// borders (8-neighbourhood).
    fn assert_masks_disjoint(atlas: &Atlas) {
        let a = atlas.resolution();
        let mut owner = vec![u32::MAX; (a * a) as usize];
        for i in 0..atlas.mesh.triangle_count() {
            let chart = atlas.chart_of[i];
            for (x, y) in footprint(atlas, i) {
                let o = &mut owner[(y * a + x) as usize];
                assert!(
                    *o == u32::MAX || *o == chart,
                    "texel ({x}, {y}): charts {} and {chart}",
                    *o
                );
                *o = chart;
            }
        }
        for y in 0..a {
            for x in 0..a {
                let o = owner[(y * a + x) as usize];
                let Some(s) = atlas.atlas_texel(x, y) else {
                    assert_eq!(o, u32::MAX, "texel ({x}, {y}) is in a footprint but empty");
                    continue;
                };
                let chart = atlas.chart_of[s.triangle as usize];
                if o != u32::MAX {
                    assert_eq!(chart, o, "({x}, {y})");
                    continue;
                }
                let borders = (y.saturating_sub(1)..=(y + 1).min(a - 1)).any(|ny| {
                    (x.saturating_sub(1)..=(x + 1).min(a - 1))
                        .any(|nx| owner[(ny * a + nx) as usize] == chart)
                });
                assert!(
                    borders,
                    "texel ({x}, {y}) stands for chart {chart} away from it"
                );
            }
        }
        // Within a chart, no texel centre lies inside two triangles.
        check_overlap(&atlas.mesh, &atlas.mesh.uvs, a).unwrap();
    }

    #[test]
    fn charts_do_not_share_texels() {
        let mesh = blob(2);
        let atlas = Atlas::build(&mesh, &[], &options(32, 0.05, 16)).unwrap();
        assert_masks_disjoint(&atlas);
    }

    #[test]
    fn adjacent_triangles_merge_into_charts_that_fill_the_atlas() {
        // (mesh, charts at most, fill at least, pages at most). Measured: 64 charts at a fill
        // of 0.925 and 116 at 0.948, 9 pages each (teeth split off included); per-triangle
        // charts needed 49 pages for each, at fills of 0.247 and 0.255, and merged charts with
        // one-texel gutters 16 pages at 0.639 and 0.670.
        for (name, mesh, charts, fill, pages) in [
            ("lumpy", lumpy(), 80, 0.85, 9),
            ("icosphere", Mesh::icosphere(3), 140, 0.85, 9),
        ] {
            let atlas = Atlas::build(&mesh, &[], &options(32, 0.05, 16)).unwrap();
            assert_masks_disjoint(&atlas);
            let (n, f) = (atlas.chart_count(), atlas.fill());
            assert!(n <= charts, "{name}: {n} charts");
            assert!(f >= fill, "{name}: fill {f:.3}");
            assert!(
                atlas.page_count() <= pages,
                "{name}: {} pages",
                atlas.page_count()
            );
            // Every triangle keeps at least the asked density.
            let a = f64::from(atlas.resolution());
            for (t, tri) in mesh.triangles.iter().enumerate() {
                let uv = 0.5 * signed_area2(&tri_uv(&atlas, t)).abs();
                let asked = area3(&corners3(&mesh, tri)) / 0.05f64.powi(2);
                assert!(
                    uv >= asked * 0.999,
                    "{name}: triangle {t}: {uv} < {asked} ({a})"
                );
            }
        }
    }

    #[test]
    fn a_box_gets_one_chart_per_face() {
        let mut mesh = Mesh::new();
        for i in 0..8u32 {
            mesh.positions.push(Vec3::new(
                (i & 1) as f32,
                ((i >> 1) & 1) as f32,
                (i >> 2) as f32,
            ));
            mesh.normals.push(Vec3::Z);
        }
        for q in [
            [0, 2, 3, 1],
            [4, 5, 7, 6],
            [0, 1, 5, 4],
            [2, 6, 7, 3],
            [0, 4, 6, 2],
            [1, 3, 7, 5],
        ] {
            mesh.triangles.push([q[0], q[1], q[2]]);
            mesh.triangles.push([q[0], q[2], q[3]]);
        }
        let atlas = Atlas::build(&mesh, &[], &options(32, 0.05, 16)).unwrap();
        assert_eq!(atlas.chart_count(), 6);
        for face in 0..6 {
            assert_eq!(atlas.chart_of[2 * face], atlas.chart_of[2 * face + 1]);
        }
        assert_masks_disjoint(&atlas);
        // Six equal squares fill at most six of a square's nine cells (0.586 measured).
        assert!(atlas.fill() >= 0.55, "fill {}", atlas.fill());
    }

    #[test]
    fn a_uv_rounded_off_its_triangle_stays_in_its_chart() {
        // Charts have no gutter: the runtime's nearest-texel lookup of a uv pushed off its
        // triangle (f32 rounding) must still find a texel of the triangle's own chart.
        let mesh = lumpy();
        let atlas = Atlas::build(&mesh, &[], &options(32, 0.05, 16)).unwrap();
        let a = f64::from(atlas.resolution());
        let push = FOOTPRINT_MARGIN * 0.9;
        let mut checked = 0;
        for t in 0..atlas.mesh.triangle_count() {
            let p = tri_uv(&atlas, t);
            let centroid = (p[0] + p[1] + p[2]) / 3.0;
            for e in 0..3 {
                let (u, v) = (p[e], p[(e + 1) % 3]);
                let Some(out) = (u - v).perp().try_normalize() else {
                    continue;
                };
                let out = if out.dot(centroid - u) > 0.0 {
                    -out
                } else {
                    out
                };
                for k in 0..=8 {
                    let q = u + (v - u) * (f64::from(k) / 8.0) + out * push;
                    let (x, y) = (q.x.floor(), q.y.floor());
                    if x < 0.0 || y < 0.0 || x >= a || y >= a {
                        continue;
                    }
                    let s = atlas.atlas_texel(x as u32, y as u32);
                    let chart = s.map(|s| atlas.chart_of[s.triangle as usize]);
                    assert_eq!(
                        chart,
                        Some(atlas.chart_of[t]),
                        "triangle {t}, edge {e}: {q}"
                    );
                    checked += 1;
                }
            }
        }
        assert!(checked > 10_000, "{checked}");
    }

    #[test]
    fn a_surface_that_turns_over_itself_is_cut_where_it_would_overlap() {
        // A spiral ramp of two turns, rising slowly: its normals stay within a few degrees of
        // +z, so only the overlap test keeps a chart from covering itself.
        let mut mesh = Mesh::new();
        let (steps, turns) = (96u32, 2.0f32);
        for i in 0..=steps {
            let a = std::f32::consts::TAU * turns * i as f32 / steps as f32;
            for r in [0.5f32, 1.0] {
                mesh.positions
                    .push(Vec3::new(r * a.cos(), r * a.sin(), 0.02 * a));
                mesh.normals.push(Vec3::Z);
            }
        }
        for i in 0..steps {
            let v = 2 * i;
            mesh.triangles.push([v, v + 2, v + 3]);
            mesh.triangles.push([v, v + 3, v + 1]);
        }
        let atlas = Atlas::build(&mesh, &[], &options(64, 0.02, 16)).unwrap();
        assert!(atlas.chart_count() >= 2, "{} charts", atlas.chart_count());
        assert_masks_disjoint(&atlas);
    }

    #[test]
    fn chart_density_is_uniform() {
        // Triangles of very different sizes and shapes, far apart.
        let shapes = [
            (1.0, [Vec3::ZERO, Vec3::X, Vec3::Y]),
            (
                4.0,
                [
                    Vec3::ZERO,
                    Vec3::new(1.0, 0.2, 0.0),
                    Vec3::new(0.3, 0.9, 0.5),
                ],
            ),
            (16.0, [Vec3::ZERO, Vec3::X, Vec3::new(0.5, 0.05, 0.0)]),
            (30.0, [Vec3::ZERO, Vec3::Z, Vec3::new(0.0, 0.7, 0.4)]),
        ];
        let mut mesh = Mesh::new();
        for (i, (scale, corners)) in shapes.iter().enumerate() {
            for c in corners {
                mesh.positions
                    .push(*c * *scale + Vec3::splat(100.0 * i as f32));
                mesh.normals.push(Vec3::Y);
            }
            let v = 3 * i as u32;
            mesh.triangles.push([v, v + 1, v + 2]);
        }
        let ts = 0.1;
        let atlas = Atlas::build(&mesh, &[], &options(128, ts, 64)).unwrap();
        let mut centres_inside = vec![0usize; mesh.triangle_count()];
        for y in 0..atlas.resolution() {
            for x in 0..atlas.resolution() {
                let q = DVec2::new(f64::from(x) + 0.5, f64::from(y) + 0.5);
                for (t, count) in centres_inside.iter_mut().enumerate() {
                    if closest_bary(&tri_uv(&atlas, t), q).1 == 0.0 {
                        *count += 1;
                    }
                }
            }
        }
        for (t, count) in centres_inside.iter().enumerate() {
            let area = area3(&corners3(&mesh, &mesh.triangles[t]));
            let expected = area / f64::from(ts * ts);
            // uv area × A² per unit area is at least 1/texel_size² (more where the charts
            // were grown to fill the grid).
            let uv_area = 0.5 * signed_area2(&tri_uv(&atlas, t)).abs();
            assert!(
                uv_area / expected > 1.0 - 1e-3,
                "triangle {t}: {uv_area} vs {expected}"
            );
            let ratio = *count as f64 / uv_area;
            assert!(
                (0.5..=2.0).contains(&ratio),
                "triangle {t}: {count} texels, expected {expected}"
            );
        }
    }

    #[test]
    fn user_uvs_used_as_is() {
        let mesh = plane(4);
        let uvs = mesh.uvs.clone();
        let atlas = Atlas::build(
            &mesh,
            &[(UvSource::Lightmap, &uvs)],
            &options(64, 1.0 / 60.0, 8),
        )
        .unwrap();
        assert_eq!(atlas.source, UvSource::Lightmap);
        assert!(atlas.rejected.is_empty());
        assert_eq!(atlas.mesh, mesh);
        assert_eq!(atlas.grid, 1);
        assert_table_valid(&atlas);
        // The plane covers the whole atlas: every texel is filled, with the triangle under its
        // centre.
        let a = atlas.resolution();
        for y in 0..a {
            for x in 0..a {
                let s = atlas.atlas_texel(x, y).unwrap();
                let q = DVec2::new(f64::from(x) + 0.5, f64::from(y) + 0.5);
                assert_eq!(closest_bary(&tri_uv(&atlas, s.triangle as usize), q).1, 0.0);
            }
        }
        let mut rng = Rng(7);
        for t in 0..mesh.triangle_count() as u32 {
            for _ in 0..20 {
                let b = rng.bary();
                let s = texel_of(&atlas, t, b).unwrap();
                // The texel's point is on the same surface, within a texel.
                let (p, _) = atlas.sample_surface(t, b);
                let (q, n) = atlas.sample_surface(s.triangle, s.bary);
                assert!(p.distance(q) <= 1.5 / a as f32, "{p} vs {q}");
                assert_eq!(n, Vec3::Z);
            }
        }
        // Mirrored uvs (orientation reversed) are just as usable.
        let mirrored: Vec<Vec2> = uvs.iter().map(|uv| Vec2::new(1.0 - uv.x, uv.y)).collect();
        let atlas = Atlas::build(
            &mesh,
            &[(UvSource::Texture, &mirrored)],
            &options(64, 0.02, 8),
        )
        .unwrap();
        assert_eq!(atlas.source, UvSource::Texture);
        assert_eq!(atlas.mesh.uvs, mirrored);
    }

    #[test]
    fn bad_user_uvs_fall_back() {
        let mesh = plane(4);
        let good = mesh.uvs.clone();
        let o = options(64, 0.02, 8);
        // Two triangles mapped onto the same uvs.
        let mut overlapping = good.clone();
        let [a, b, c] = mesh.triangles[0];
        let [d, e, f] = mesh.triangles[30];
        overlapping[d as usize] = good[a as usize];
        overlapping[e as usize] = good[b as usize];
        overlapping[f as usize] = good[c as usize];
        let atlas = Atlas::build(
            &mesh,
            &[
                (UvSource::Lightmap, &overlapping),
                (UvSource::Texture, &good),
            ],
            &o,
        )
        .unwrap();
        assert_eq!(atlas.source, UvSource::Texture);
        assert_eq!(atlas.rejected.len(), 1);
        assert_eq!(atlas.rejected[0].0, UvSource::Lightmap);
        assert!(
            atlas.rejected[0].1.contains("overlap"),
            "{}",
            atlas.rejected[0].1
        );
        // Out of range, non-finite, wrong length: our own charts.
        let mut outside = good.clone();
        outside[3].x = 1.01;
        let mut nan = good.clone();
        nan[0].y = f32::NAN;
        let short = &good[1..];
        let atlas = Atlas::build(
            &mesh,
            &[
                (UvSource::Lightmap, &outside),
                (UvSource::Texture, &nan),
                (UvSource::Texture, short),
            ],
            &o,
        )
        .unwrap();
        assert_eq!(atlas.source, UvSource::Charts);
        assert_eq!(atlas.rejected.len(), 3);
        assert!(
            atlas.rejected[0].1.contains("vertex 3"),
            "{}",
            atlas.rejected[0].1
        );
        assert_eq!(atlas.mesh.positions.len(), 3 * mesh.triangle_count());
        // Zero uv area with non-zero 3D area.
        let mut collapsed = good.clone();
        let [a, b, c] = mesh.triangles[5];
        collapsed[b as usize] = collapsed[a as usize];
        collapsed[c as usize] = collapsed[a as usize];
        let atlas = Atlas::build(&mesh, &[(UvSource::Texture, &collapsed)], &o).unwrap();
        assert_eq!(atlas.source, UvSource::Charts);
        assert!(
            atlas.rejected[0].1.contains("zero uv area"),
            "{}",
            atlas.rejected[0].1
        );
    }

    #[test]
    fn user_grid_follows_texel_size_and_is_capped() {
        let mesh = plane(2);
        let uvs = mesh.uvs.clone();
        let set = [(UvSource::Texture, uvs.as_slice())];
        // Area 1, uv area 1: side 1/texel_size texels.
        assert_eq!(
            Atlas::build(&mesh, &set, &options(16, 1.0 / 40.0, 8))
                .unwrap()
                .grid,
            3
        );
        assert_eq!(
            Atlas::build(&mesh, &set, &options(16, 1.0 / 16.0, 8))
                .unwrap()
                .grid,
            1
        );
        assert_eq!(
            Atlas::build(&mesh, &set, &options(16, 1e-6, 5))
                .unwrap()
                .grid,
            5
        );
        // Half the uv square: twice the texels per side... times √2.
        let half: Vec<Vec2> = uvs.iter().map(|uv| *uv * Vec2::new(0.5, 1.0)).collect();
        let set = [(UvSource::Texture, half.as_slice())];
        assert_eq!(
            Atlas::build(&mesh, &set, &options(16, 1.0 / 40.0, 8))
                .unwrap()
                .grid,
            4
        );
    }

    #[test]
    fn bad_options_and_meshes_are_errors() {
        let mesh = plane(2);
        for ts in [0.0, -1.0, f32::NAN, f32::INFINITY] {
            let e = Atlas::build(&mesh, &[], &options(16, ts, 4)).unwrap_err();
            assert!(e.to_string().contains("texel_size"), "{e}");
        }
        assert!(Atlas::build(&mesh, &[], &options(0, 0.1, 4)).is_err());
        assert!(Atlas::build(&mesh, &[], &options(MAX_ATLAS_RESOLUTION + 1, 0.1, 4)).is_err());
        assert!(Atlas::build(&mesh, &[], &options(16, 0.1, 0)).is_err());
        let e = Atlas::build(&Mesh::new(), &[], &options(16, 0.1, 4)).unwrap_err();
        assert!(e.to_string().contains("without triangles"), "{e}");
        let mut nan = mesh.clone();
        nan.positions[4].y = f32::NAN;
        let e = Atlas::build(&nan, &[], &options(16, 0.1, 4)).unwrap_err();
        assert!(e.to_string().contains("vertex 4"), "{e}");
        let mut out_of_range = mesh.clone();
        out_of_range.triangles[3][1] = 99;
        let e = Atlas::build(&out_of_range, &[], &options(16, 0.1, 4)).unwrap_err();
        assert!(e.to_string().contains("triangle 3"), "{e}");
        let mut no_normals = mesh.clone();
        no_normals.normals.clear();
        assert!(Atlas::build(&no_normals, &[], &options(16, 0.1, 4)).is_err());
        // Charts that do not fit: named grid, area and texel size.
        let e = Atlas::build(&mesh, &[], &options(16, 0.01, 2)).unwrap_err();
        let GeometryError::AtlasTooLarge { needed, .. } = e else {
            panic!("{e}");
        };
        assert!(needed > 2);
        assert!(e.to_string().contains("texel size 0.01"), "{e}");
        // One triangle larger than the largest atlas.
        let e = Atlas::build(&mesh, &[], &options(16, 1e-30, 1000)).unwrap_err();
        assert!(matches!(e, GeometryError::AtlasTooLarge { .. }), "{e}");
        // Many triangles, small limit: an error, quickly.
        let big = plane(300);
        let e = Atlas::build(&big, &[], &options(4, 1.0, 2)).unwrap_err();
        assert!(matches!(e, GeometryError::AtlasTooLarge { .. }), "{e}");
        // A user set is never too large: capped.
        let uvs = big.uvs.clone();
        let atlas =
            Atlas::build(&big, &[(UvSource::Texture, &uvs)], &options(16, 1e-9, 2)).unwrap();
        assert_eq!((atlas.grid, atlas.source), (2, UvSource::Texture));
    }

    #[test]
    fn degenerate_triangles_get_a_chart() {
        let mut mesh = Mesh::new();
        let tris = [
            [Vec3::ZERO, Vec3::X, Vec3::Y],               // ordinary
            [Vec3::ONE, Vec3::ONE, Vec3::ONE],            // a point
            [Vec3::ZERO, Vec3::X, Vec3::X * 2.0],         // a needle
            [Vec3::ZERO, Vec3::X * 1e-9, Vec3::Y * 1e-9], // tiny
        ];
        for (i, corners) in tris.iter().enumerate() {
            mesh.positions.extend_from_slice(corners);
            mesh.normals.extend_from_slice(&[Vec3::Z; 3]);
            let v = 3 * i as u32;
            mesh.triangles.push([v, v + 1, v + 2]);
        }
        let atlas = Atlas::build(&mesh, &[], &options(16, 0.1, 4)).unwrap();
        assert_table_valid(&atlas);
        let mut rng = Rng(3);
        for t in 0..mesh.triangle_count() {
            assert!(!footprint(&atlas, t).is_empty());
            for _ in 0..10 {
                let s = texel_of(&atlas, t as u32, rng.bary()).unwrap();
                assert_eq!(s.triangle, t as u32);
                let (p, n) = atlas.sample_surface(s.triangle, s.bary);
                assert!(p.is_finite() && (n.length() - 1.0).abs() < 1e-6);
            }
        }
    }

    #[test]
    fn build_is_deterministic() {
        let mesh = blob(2);
        let o = options(32, 0.05, 16);
        let (a, b) = (
            Atlas::build(&mesh, &[], &o).unwrap(),
            Atlas::build(&mesh, &[], &o).unwrap(),
        );
        assert_eq!(a.mesh, b.mesh);
        assert_eq!(a.texels, b.texels);
    }

    #[test]
    fn page_arithmetic() {
        // k = 1.
        assert_eq!(Atlas::page_of(1, Vec2::new(1.0, 1.0)), (0, [1.0, 1.0]));
        assert_eq!(Atlas::page_of(1, Vec2::new(0.25, 0.0)), (0, [0.25, 0.0]));
        // k = 3.
        assert_eq!(Atlas::page_of(3, Vec2::new(1.0, 0.0)), (2, [1.0, 0.0]));
        assert_eq!(Atlas::page_of(3, Vec2::new(1.0, 1.0)), (8, [1.0, 1.0]));
        assert_eq!(Atlas::page_of(3, Vec2::new(0.5, 0.5)), (4, [0.5, 0.5]));
        let (page, local) = Atlas::page_of(3, Vec2::new(0.5, 5.0 / 6.0));
        assert_eq!(page, 7);
        assert!((local[0] - 0.5).abs() < 1e-6 && (local[1] - 0.5).abs() < 1e-6);
        // Page texels against atlas texels, and uv exactly 1.0 through locate.
        let mesh = plane(3);
        let uvs = mesh.uvs.clone();
        for (k_expected, ts) in [(1, 1.0 / 16.0), (3, 1.0 / 40.0)] {
            let atlas =
                Atlas::build(&mesh, &[(UvSource::Lightmap, &uvs)], &options(16, ts, 8)).unwrap();
            let (k, m) = (atlas.grid, atlas.page_resolution);
            assert_eq!(k, k_expected);
            for page in 0..k * k {
                for (x, y) in [(0, 0), (m - 1, 0), (3, m - 1), (m - 1, m - 1)] {
                    let (px, py) = (page % k, page / k);
                    assert_eq!(
                        atlas.texel(page, x, y),
                        atlas.atlas_texel(px * m + x, py * m + y)
                    );
                }
            }
            assert_eq!(atlas.texel(k * k, 0, 0), None);
            assert_eq!(atlas.texel(0, m, 0), None);
            // Vertex 15 of the 3×3 plane is (1, 1).
            let (t, c) = atlas
                .mesh
                .triangles
                .iter()
                .enumerate()
                .find_map(|(t, v)| v.iter().position(|&v| v == 15).map(|c| (t, c)))
                .unwrap();
            let mut b = [0.0; 3];
            b[c] = 1.0;
            let (page, local) = atlas.locate(t as u32, b);
            assert_eq!((page, local), (k * k - 1, [1.0, 1.0]));
            assert_eq!(atlas.page_texel(local), (m - 1, m - 1));
            assert_eq!(texel_of(&atlas, t as u32, b).unwrap().triangle, t as u32);
        }
    }

    #[test]
    fn sample_surface_normals() {
        let mut mesh = plane(1);
        mesh.normals[0] = Vec3::new(0.0, 0.0, 2.0);
        mesh.normals[1] = Vec3::new(0.0, 0.0, -1.0);
        let atlas = Atlas::build(
            &mesh,
            &[(UvSource::Texture, &mesh.uvs.clone())],
            &options(8, 0.1, 4),
        )
        .unwrap();
        // Interpolated and renormalized.
        let (p, n) = atlas.sample_surface(0, [1.0, 0.0, 0.0]);
        assert_eq!((p, n), (Vec3::ZERO, Vec3::Z));
        // Interpolated normal vanishes: geometric normal.
        let (p, n) = atlas.sample_surface(0, [1.0 / 3.0, 2.0 / 3.0, 0.0]);
        assert!((p - Vec3::new(2.0 / 3.0, 0.0, 0.0)).length() < 1e-6);
        assert_eq!(n, Vec3::Z);
    }

    #[test]
    fn closest_bary_and_touches() {
        let p = [DVec2::ZERO, DVec2::new(4.0, 0.0), DVec2::new(0.0, 4.0)];
        assert_eq!(
            closest_bary(&p, DVec2::new(1.0, 1.0)),
            ([0.5, 0.25, 0.25], 0.0)
        );
        let (b, d2) = closest_bary(&p, DVec2::new(-1.0, 2.0));
        assert_eq!((b, d2), ([0.5, 0.0, 0.5], 1.0));
        let point = [DVec2::ONE; 3];
        assert_eq!(closest_bary(&point, DVec2::ZERO).1, 2.0);
        assert!(touches(&p, 1.0, 2.0));
        assert!(touches(&p, 2.0, 2.0)); // corner (2, 2) on the hypotenuse
        assert!(!touches(&p, 2.5, 2.5));
        assert!(touches(&point, 0.0, 0.0) && touches(&point, 1.0, 1.0));
        assert!(!touches(&point, 2.0, 0.0));
        let needle = [DVec2::ZERO, DVec2::new(4.0, 4.0), DVec2::new(2.0, 2.0)];
        assert!(touches(&needle, 1.0, 1.0) && !touches(&needle, 2.0, 0.5));
    }
}
