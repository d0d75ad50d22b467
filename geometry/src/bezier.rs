//! Bicubic tensor-product Bézier patches (thesis §3.1, Eq. 3.1–3.4), the Newell teapot, a
//! parser for patch files and adaptive tessellation.
//!
//! Conventions: control point `CP_ij` is stored at index `4 * i + j`; `i` runs along `u`, `j`
//! along `v`. Normals are `∂x/∂v × ∂x/∂u` (normalized), which makes all 32 patches of the
//! Newell teapot face outward. Parameters outside `[0, 1]` are clamped and NaN parameters are
//! treated as 0, so no function here ever returns NaN for finite control points.

use std::ops::Range;
use std::path::Path;

use glam::{Affine3A, DVec3, Vec2, Vec3};

use crate::mesh::Mesh;
use crate::{GeometryError, Result};

/// The thesis's 28 teapot patches (rim, body, handle, spout, lid) without the 4 bottom patches.
pub const TEAPOT_BODY_PATCHES: Range<usize> = 0..28;

/// Largest grid resolution [`BezierPatch::tessellation_level`] returns.
pub const MAX_TESSELLATION_LEVEL: u32 = 256;

/// The tessellation error allowed for an OSLF object's patches, as a fraction of ε: the bake
/// and the ground truth trace triangles within ε/50 of the surface, and the runtime's G-buffer
/// rasterizes the same tessellation, so that the three agree on the object's outline.
pub const TESSELLATION_ERROR: f32 = 1.0 / 50.0;

/// How far [`BezierPatch::refine_hit`] may move a hit of a tessellation from its triangle, in
/// the tessellation's tolerances: a chord lies within one tolerance of the patch along the
/// normal, and a ray at 1/16 of grazing meets the patch within 16 of it along the ray.
pub const REFINE_REACH: f32 = 16.0;

/// A bicubic Bézier patch: 4×4 control points, `CP_ij` at index `4 * i + j`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BezierPatch {
    /// Control points, row-major: `cp[4 * i + j] = CP_ij`, `i` along `u`, `j` along `v`.
    pub cp: [Vec3; 16],
}

/// Cubic Bernstein polynomials `B_i^3(t)`, i = 0..3.
fn bernstein3(t: f64) -> [f64; 4] {
    // Eq. 3.4
    let s = 1.0 - t;
    [s * s * s, 3.0 * t * s * s, 3.0 * t * t * s, t * t * t]
}

/// Quadratic Bernstein polynomials `B_i^2(t)`, i = 0..2 (for the hodograph).
fn bernstein2(t: f64) -> [f64; 3] {
    let s = 1.0 - t;
    [s * s, 2.0 * t * s, t * t]
}

/// Clamps a patch parameter to `[0, 1]`, NaN to 0.
fn param(t: f32) -> f64 {
    if t.is_nan() {
        0.0
    } else {
        f64::from(t).clamp(0.0, 1.0)
    }
}

/// Position and derivatives at one parameter point, in double precision.
struct Jet {
    du: DVec3,
    dv: DVec3,
    duv: DVec3,
}

impl BezierPatch {
    /// A patch from its 16 control points (`CP_ij` at `4 * i + j`).
    pub fn new(cp: [Vec3; 16]) -> Self {
        Self { cp }
    }

    fn p(&self, i: usize, j: usize) -> DVec3 {
        self.cp[4 * i + j].as_dvec3()
    }

    /// The surface point `x(u, v)`.
    #[allow(clippy::needless_range_loop)] // i, j are the CP_ij indices of Eq. 3.1
    pub fn eval(&self, u: f32, v: f32) -> Vec3 {
        self.point(param(u), param(v)).as_vec3()
    }

    #[allow(clippy::needless_range_loop)] // i, j are the CP_ij indices of Eq. 3.1
    fn point(&self, u: f64, v: f64) -> DVec3 {
        // Eq. 3.1, 3.3: x(u,v) = Σ_i Σ_j CP_ij B_i^3(u) B_j^3(v)
        let (bu, bv) = (bernstein3(u), bernstein3(v));
        let mut x = DVec3::ZERO;
        for i in 0..4 {
            for j in 0..4 {
                x += self.p(i, j) * (bu[i] * bv[j]);
            }
        }
        x
    }

    /// The patch's own intersection with the ray `origin + t·dir` near a hit of its
    /// tessellation at parameters `(u, v)`, point `near`: Newton's method on
    /// `x(u, v) − near − s·dir = 0` from there, in double precision. Returns the refined
    /// parameters and surface point, or `None` where it does not converge, leaves the patch's
    /// domain `[0, 1]²` (the ray meets a neighbouring patch, or misses this one) or moves
    /// farther than `max_move` from `near` (another sheet of the surface). The renderer's
    /// G-buffer and the ground truth tessellate the patches to different tolerances; both
    /// shade the surface point this finds, so that neither carries its chords' error into the
    /// reflected ray (docs/measurements.md, "The exact surface under each pixel").
    #[allow(clippy::neg_cmp_op_on_partial_ord)] // NaN fails the test, as it must
    pub fn refine_hit(
        &self,
        near: Vec3,
        dir: Vec3,
        (u, v): (f32, f32),
        max_move: f32,
    ) -> Option<(f32, f32, Vec3)> {
        const SLACK: f64 = 1e-4;
        let (near, dir) = (near.as_dvec3(), dir.as_dvec3().normalize_or_zero());
        let (mut u, mut v, mut s) = (param(u), param(v), 0.0);
        let tol = 1e-9 * self.scale();
        for _ in 0..16 {
            let j = self.jet(u, v);
            let f = self.point(u, v) - near - dir * s;
            let (a, b, c) = (j.du, j.dv, -dir);
            let det = a.dot(b.cross(c));
            if !(det.abs() > 1e-300) {
                return None;
            }
            // Cramer's rule for [∂x/∂u ∂x/∂v −dir]·(Δu, Δv, Δs) = −f.
            let du = -f.dot(b.cross(c)) / det;
            let dv = -a.dot(f.cross(c)) / det;
            let ds = -a.dot(b.cross(f)) / det;
            if !(du.is_finite() && dv.is_finite() && ds.is_finite()) {
                return None;
            }
            u += du;
            v += dv;
            s += ds;
            if !((-SLACK..=1.0 + SLACK).contains(&u) && (-SLACK..=1.0 + SLACK).contains(&v)) {
                return None;
            }
            if (a * du + b * dv).length() <= tol && ds.abs() <= tol {
                let (u, v) = (u.clamp(0.0, 1.0), v.clamp(0.0, 1.0));
                let x = self.point(u, v);
                return ((x - near).length() <= f64::from(max_move))
                    .then(|| (u as f32, v as f32, x.as_vec3()));
            }
        }
        None
    }

    #[allow(clippy::needless_range_loop)] // i, j are the CP_ij indices
    fn jet(&self, u: f64, v: f64) -> Jet {
        // Derivatives of Eq. 3.1 through the hodograph: differences of control points, so a
        // collapsed row of identical points gives an exactly zero derivative (no cancellation).
        let (bu3, bv3) = (bernstein3(u), bernstein3(v));
        let (bu2, bv2) = (bernstein2(u), bernstein2(v));
        let mut du = DVec3::ZERO;
        let mut dv = DVec3::ZERO;
        let mut duv = DVec3::ZERO;
        for i in 0..3 {
            for j in 0..4 {
                du += (self.p(i + 1, j) - self.p(i, j)) * (bu2[i] * bv3[j]);
            }
        }
        for i in 0..4 {
            for j in 0..3 {
                dv += (self.p(i, j + 1) - self.p(i, j)) * (bu3[i] * bv2[j]);
            }
        }
        for i in 0..3 {
            for j in 0..3 {
                let d =
                    (self.p(i + 1, j + 1) - self.p(i + 1, j)) - (self.p(i, j + 1) - self.p(i, j));
                duv += d * (bu2[i] * bv2[j]);
            }
        }
        Jet {
            du: du * 3.0,
            dv: dv * 3.0,
            duv: duv * 9.0,
        }
    }

    /// The partial derivatives `(∂x/∂u, ∂x/∂v)`.
    pub fn partials(&self, u: f32, v: f32) -> (Vec3, Vec3) {
        let j = self.jet(param(u), param(v));
        (j.du.as_vec3(), j.dv.as_vec3())
    }

    /// Size of the control net (largest distance from `CP_00`), the length scale for tolerances.
    fn scale(&self) -> f64 {
        let o = self.p(0, 0);
        self.cp
            .iter()
            .map(|c| (c.as_dvec3() - o).length())
            .fold(0.0, f64::max)
    }

    /// Unnormalized normal `∂x/∂v × ∂x/∂u` at a point, or `None` when it vanishes.
    fn raw_normal(&self, u: f64, v: f64, tol2: f64) -> Option<DVec3> {
        let j = self.jet(u, v);
        let n = j.dv.cross(j.du);
        (n.length_squared() > tol2).then_some(n)
    }

    /// The unit outward normal at `(u, v)`; never NaN.
    ///
    /// Regular points use `∂x/∂v × ∂x/∂u`. Where one partial vanishes (a patch edge collapsed
    /// to a point, as on the teapot's lid top and bottom) the normal is the limit taken along
    /// the parameter line through `(u, v)`: if `∂x/∂v → 0` at the edge `u = u₀`, then
    /// `∂x/∂v(u, v) = (u - u₀) ∂²x/∂u∂v(u₀, v) + O((u - u₀)²)`, so
    /// `n ∝ sign(u - u₀) · ∂²x/∂u∂v × ∂x/∂u`, with `u - u₀` taken towards the patch interior
    /// (positive for `u < ½`). Symmetrically for `∂x/∂u → 0`. If that also vanishes (higher
    /// order degeneracy) the normal of the nearest regular point on the segment towards the
    /// patch centre is used; a patch with no regular point at all yields `+z`.
    pub fn normal(&self, u: f32, v: f32) -> Vec3 {
        let (u, v) = (param(u), param(v));
        let s = self.scale();
        if !(s > 0.0 && s.is_finite()) {
            return Vec3::Z;
        }
        let tol = 1e-12 * s * s;
        let tol2 = tol * tol;
        if let Some(n) = self.raw_normal(u, v, tol2) {
            return finish(n);
        }
        let j = self.jet(u, v);
        let small = 1e-9 * s;
        let (du_small, dv_small) = (j.du.length() <= small, j.dv.length() <= small);
        if dv_small && !du_small {
            let sign = if u < 0.5 { 1.0 } else { -1.0 };
            let n = j.duv.cross(j.du) * sign;
            if n.length_squared() > tol2 {
                return finish(n);
            }
        } else if du_small && !dv_small {
            let sign = if v < 0.5 { 1.0 } else { -1.0 };
            let n = j.dv.cross(j.duv) * sign;
            if n.length_squared() > tol2 {
                return finish(n);
            }
        }
        // Higher-order degeneracy: walk towards the centre until the surface is regular.
        let mut step = 1e-6;
        while step <= 0.5 {
            let (uu, vv) = (u + (0.5 - u) * step, v + (0.5 - v) * step);
            if let Some(n) = self.raw_normal(uu, vv, tol2) {
                return finish(n);
            }
            step *= 4.0;
        }
        Vec3::Z
    }

    /// The patch mapped by an affine transform (Bézier evaluation commutes with affine maps,
    /// so transforming the control points transforms the surface).
    pub fn transformed(&self, m: &Affine3A) -> BezierPatch {
        BezierPatch {
            cp: self.cp.map(|c| m.transform_point3(c)),
        }
    }

    /// Tessellates into an `n × n` grid of quads (two triangles each, `2n²` triangles,
    /// `(n+1)²` vertices). uv = patch parameters `(u, v)`; normals from [`Self::normal`];
    /// triangles wound counter-clockwise around the normal. `n` is clamped to at least 1.
    ///
    /// Triangles touching a collapsed edge have zero area; the BVH drops them.
    pub fn tessellate(&self, n: u32) -> Mesh {
        let n = n.max(1);
        let side = n as usize + 1;
        let mut mesh = Mesh {
            positions: Vec::with_capacity(side * side),
            normals: Vec::with_capacity(side * side),
            uvs: Vec::with_capacity(side * side),
            triangles: Vec::with_capacity(2 * (n as usize) * (n as usize)),
        };
        for i in 0..side {
            let u = i as f32 / n as f32;
            for j in 0..side {
                let v = j as f32 / n as f32;
                mesh.positions.push(self.eval(u, v));
                mesh.normals.push(self.normal(u, v));
                mesh.uvs.push(Vec2::new(u, v));
            }
        }
        let idx = |i: usize, j: usize| (i * side + j) as u32;
        for i in 0..n as usize {
            for j in 0..n as usize {
                // (p(i,j+1) - p(i,j)) × (p(i+1,j) - p(i,j)) ≈ ∂v × ∂u: the outward normal.
                mesh.triangles
                    .push([idx(i, j), idx(i, j + 1), idx(i + 1, j)]);
                mesh.triangles
                    .push([idx(i + 1, j), idx(i, j + 1), idx(i + 1, j + 1)]);
            }
        }
        mesh
    }

    /// The grid resolution `n` for [`Self::tessellate`] whose flat triangles deviate from the
    /// patch by less than `max_error` (distance between `x(u, v)` and the triangle point with
    /// the same parameters, which bounds the chordal deviation).
    ///
    /// Bound: for linear interpolation on a triangle of parameter size `h = 1/n`,
    /// `|x - L| ≤ h²/8 (M_uu + 2 M_uv + M_vv)` where the `M` bound the second derivatives;
    /// from the control net `M_uu = 6 max|Δ²_u CP|`, `M_uv = 9 max|Δ_u Δ_v CP|`,
    /// `M_vv = 6 max|Δ²_v CP|`. The result is clamped to `1..=MAX_TESSELLATION_LEVEL`; a
    /// non-positive or NaN `max_error` gives `MAX_TESSELLATION_LEVEL`.
    pub fn tessellation_level(&self, max_error: f32) -> u32 {
        if max_error.is_nan() || max_error <= 0.0 {
            return MAX_TESSELLATION_LEVEL;
        }
        let n = (self.interpolation_bound() / f64::from(max_error))
            .sqrt()
            .ceil();
        if n.is_nan() {
            return MAX_TESSELLATION_LEVEL;
        }
        (n as u32).clamp(1, MAX_TESSELLATION_LEVEL)
    }

    /// The bound of [`Self::tessellation_level`] at its largest grid,
    /// `MAX_TESSELLATION_LEVEL²` quads: the smallest tessellation error this patch is
    /// guaranteed to reach. Anything asking for less (an ε too small for the patch) gets
    /// this much instead.
    pub fn min_tessellation_error(&self) -> f32 {
        let n = f64::from(MAX_TESSELLATION_LEVEL);
        (self.interpolation_bound() / (n * n)) as f32
    }

    /// `(M_uu + 2 M_uv + M_vv) / 8` of [`Self::tessellation_level`]: the linear-interpolation
    /// error on a grid of parameter spacing `h` is at most `h²` times this.
    fn interpolation_bound(&self) -> f64 {
        let (mut muu, mut muv, mut mvv) = (0.0f64, 0.0f64, 0.0f64);
        for i in 0..4 {
            for j in 0..4 {
                if i < 2 {
                    let d = self.p(i + 2, j) - 2.0 * self.p(i + 1, j) + self.p(i, j);
                    muu = muu.max(d.length());
                }
                if j < 2 {
                    let d = self.p(i, j + 2) - 2.0 * self.p(i, j + 1) + self.p(i, j);
                    mvv = mvv.max(d.length());
                }
                if i < 3 && j < 3 {
                    let d =
                        self.p(i + 1, j + 1) - self.p(i + 1, j) - self.p(i, j + 1) + self.p(i, j);
                    muv = muv.max(d.length());
                }
            }
        }
        (6.0 * muu + 2.0 * 9.0 * muv + 6.0 * mvv) / 8.0
    }
}

/// Normalizes a non-zero double-precision normal to a unit `Vec3`.
fn finish(n: DVec3) -> Vec3 {
    n.normalize().as_vec3().try_normalize().unwrap_or(Vec3::Z)
}

/// The 32 patches of Newell's teapot (z up, rim diameter ≈ 3): 1–12 rim/body, 13–16 handle,
/// 17–20 spout, 21–28 lid, 29–32 bottom (zero-based 0..12, 12..16, 16..20, 20..28, 28..32).
pub fn newell_teapot() -> Vec<BezierPatch> {
    const TEXT: &str = include_str!("../data/newell-teapot.txt");
    match parse_patch_file(TEXT, Path::new("geometry/data/newell-teapot.txt")) {
        Ok(p) => p,
        // The data is compiled in and covered by tests; this cannot happen.
        Err(e) => unreachable!("built-in teapot data is invalid: {e}"),
    }
}

/// One field of a line: 1-based column and text.
struct Field<'a> {
    column: usize,
    text: &'a str,
}

/// One significant line: 1-based line number and fields.
struct Line<'a> {
    number: usize,
    fields: Vec<Field<'a>>,
    /// Column just past the last character (for "missing field" errors).
    end_column: usize,
}

/// Parses a Bézier patch file.
///
/// Format (see `geometry/data/newell-teapot.txt`): `#` starts a comment; blank lines are ignored;
/// fields are separated by commas and/or whitespace. Line 1: the patch count. Then one line of
/// 16 one-based control-point indices per patch (row-major 4×4, `CP_ij` at `4i + j`). Then the
/// point count, then one `x, y, z` line per point. Errors are [`GeometryError::Parse`] naming
/// `path`, the line and the column.
pub fn parse_patch_file(text: &str, path: &Path) -> Result<Vec<BezierPatch>> {
    let err =
        |line: usize, column: usize, message: String| parse_error(path, line, column, message);
    let last_line = text.lines().count().max(1);
    let mut it = significant_lines(text, path)?.into_iter();

    let (patch_count, _, _) = count_line(it.next(), "patch", path, last_line)?;
    // (line, column) of every index, to locate out-of-range errors after the point count.
    let mut patch_indices: Vec<[(usize, usize, usize); 16]> =
        Vec::with_capacity(patch_count.min(1 << 16));
    for k in 0..patch_count {
        let line = it.next().ok_or_else(|| {
            err(
                last_line,
                1,
                format!("file ends after {k} of {patch_count} patches"),
            )
        })?;
        check_fields(&line, 16, "a patch line", path)?;
        let mut idx = [(0usize, 0usize, 0usize); 16];
        for (slot, f) in idx.iter_mut().zip(&line.fields) {
            let i: usize = f.text.parse().map_err(|_| {
                err(
                    line.number,
                    f.column,
                    format!("invalid control-point index {:?}", f.text),
                )
            })?;
            *slot = (i, line.number, f.column);
        }
        patch_indices.push(idx);
    }
    let (point_count, _, _) = count_line(it.next(), "point", path, last_line)?;
    let mut points = Vec::with_capacity(point_count.min(1 << 20));
    for k in 0..point_count {
        let line = it.next().ok_or_else(|| {
            err(
                last_line,
                1,
                format!("file ends after {k} of {point_count} points"),
            )
        })?;
        check_fields(&line, 3, "a point line", path)?;
        let mut xyz = [0.0f32; 3];
        for (c, f) in xyz.iter_mut().zip(&line.fields) {
            let x: f32 = f.text.parse().map_err(|_| {
                err(
                    line.number,
                    f.column,
                    format!("invalid coordinate {:?}", f.text),
                )
            })?;
            if !x.is_finite() {
                return Err(err(
                    line.number,
                    f.column,
                    format!("coordinate {:?} is not finite", f.text),
                ));
            }
            *c = x;
        }
        points.push(Vec3::from_array(xyz));
    }
    if let Some(extra) = it.next() {
        return Err(err(
            extra.number,
            extra.fields[0].column,
            format!("unexpected data after {point_count} points"),
        ));
    }
    patch_indices
        .iter()
        .map(|idx| {
            let mut cp = [Vec3::ZERO; 16];
            for (c, &(i, line, column)) in cp.iter_mut().zip(idx) {
                if i == 0 || i > points.len() {
                    return Err(err(
                        line,
                        column,
                        format!("control-point index {i} out of range 1..={}", points.len()),
                    ));
                }
                *c = points[i - 1];
            }
            Ok(BezierPatch { cp })
        })
        .collect()
}

/// A [`GeometryError::Parse`] of the patch file `path` at `line`, `column`.
fn parse_error(path: &Path, line: usize, column: usize, message: String) -> GeometryError {
    GeometryError::Parse {
        path: path.to_path_buf(),
        line,
        column,
        message,
    }
}

/// The lines of the patch file `text` (at `path`) that hold fields, split into their fields:
/// comments dropped, fields separated by commas and/or whitespace (a comma must sit between
/// two fields).
fn significant_lines<'a>(text: &'a str, path: &Path) -> Result<Vec<Line<'a>>> {
    let err =
        |line: usize, column: usize, message: String| parse_error(path, line, column, message);
    let mut lines = Vec::new();
    for (k, raw) in text.lines().enumerate() {
        let number = k + 1;
        let content = raw.split('#').next().unwrap_or("");
        let mut fields = Vec::new();
        let col_of = |byte: usize| content[..byte].chars().count() + 1;
        let mut start: Option<usize> = None; // byte offset of the current field
                                             // Column of a comma not yet followed by a field (a comma must sit between two fields).
        let mut pending_comma: Option<usize> = None;
        for (b, ch) in content.char_indices() {
            let sep = ch == ',' || ch.is_whitespace();
            if !sep {
                if start.is_none() {
                    start = Some(b);
                    pending_comma = None;
                }
                continue;
            }
            if let Some(s) = start.take() {
                fields.push(Field {
                    column: col_of(s),
                    text: &content[s..b],
                });
            }
            if ch == ',' {
                if pending_comma.is_some() || fields.is_empty() {
                    return Err(err(number, col_of(b), "empty field before ','".into()));
                }
                pending_comma = Some(col_of(b));
            }
        }
        if let Some(s) = start {
            fields.push(Field {
                column: col_of(s),
                text: &content[s..],
            });
        } else if let Some(c) = pending_comma {
            return Err(err(number, c, "trailing ','".into()));
        }
        if !fields.is_empty() {
            lines.push(Line {
                number,
                fields,
                end_column: content.chars().count() + 1,
            });
        }
    }
    Ok(lines)
}

/// The count (of patches or points, `what`) on `line`, with the line number and column where
/// it stands; `last_line` locates a missing count.
fn count_line(
    line: Option<Line>,
    what: &str,
    path: &Path,
    last_line: usize,
) -> Result<(usize, usize, usize)> {
    let err =
        |line: usize, column: usize, message: String| parse_error(path, line, column, message);
    let line = line.ok_or_else(|| err(last_line, 1, format!("missing {what} count")))?;
    if line.fields.len() != 1 {
        let f = &line.fields[1];
        return Err(err(
            line.number,
            f.column,
            format!(
                "expected a single {what} count, found {} fields",
                line.fields.len()
            ),
        ));
    }
    let f = &line.fields[0];
    let n: usize = f.text.parse().map_err(|_| {
        err(
            line.number,
            f.column,
            format!("invalid {what} count {:?}", f.text),
        )
    })?;
    if n == 0 {
        return Err(err(line.number, f.column, format!("{what} count is 0")));
    }
    Ok((n, line.number, f.column))
}

/// Checks that `line` (`what`, e.g. "a patch line") has `expected` fields.
fn check_fields(line: &Line, expected: usize, what: &str, path: &Path) -> Result<()> {
    let err =
        |line: usize, column: usize, message: String| parse_error(path, line, column, message);
    if line.fields.len() != expected {
        let column = line
            .fields
            .get(expected)
            .map_or(line.end_column, |f| f.column);
        return Err(err(
            line.number,
            column,
            format!(
                "{what} needs {expected} fields, found {}",
                line.fields.len()
            ),
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn teapot_parses() {
        let t = newell_teapot();
        assert_eq!(t.len(), 32);
        assert_eq!(t[0].cp[0], Vec3::new(1.4, 0.0, 2.4));
    }

    #[test]
    fn flat_bilinear_patch_exact() {
        // Control points on a regular grid: x(u,v) = (u, v, 0) exactly (linear precision).
        let mut cp = [Vec3::ZERO; 16];
        for i in 0..4 {
            for j in 0..4 {
                cp[4 * i + j] = Vec3::new(i as f32 / 3.0, j as f32 / 3.0, 0.0);
            }
        }
        let p = BezierPatch::new(cp);
        for &(u, v) in &[(0.0, 0.0), (0.25, 0.5), (1.0, 0.3), (0.7, 1.0)] {
            assert!((p.eval(u, v) - Vec3::new(u, v, 0.0)).length() < 1e-6);
            let (du, dv) = p.partials(u, v);
            assert!((du - Vec3::X).length() < 1e-6 && (dv - Vec3::Y).length() < 1e-6);
            // ∂v × ∂u = y × x = -z
            assert!((p.normal(u, v) + Vec3::Z).length() < 1e-6);
        }
    }

    /// Distance from `x` to the line `o + t·d` (`d` unit).
    fn off_line(x: Vec3, o: Vec3, d: Vec3) -> f32 {
        let w = x - o;
        (w - d * w.dot(d)).length()
    }

    #[test]
    fn a_chord_hit_refines_to_the_patch_on_the_same_ray() {
        // Points on the flat triangles of a coarse (level 2) tessellation of the teapot's body,
        // seen along tilted rays: the refined point lies on the ray and on the patch, far
        // closer than the chord did, and its normal is the patch's there.
        let mut refined = 0;
        for patch in newell_teapot().iter().take(12) {
            let mesh = patch.tessellate(2);
            for tri in &mesh.triangles {
                let [a, b, c] = tri.map(|i| i as usize);
                let w = Vec3::new(0.2, 0.5, 0.3);
                let at = |q: &[Vec3]| q[a] * w.x + q[b] * w.y + q[c] * w.z;
                let flat = at(&mesh.positions);
                let uv = mesh.uvs[a] * w.x + mesh.uvs[b] * w.y + mesh.uvs[c] * w.z;
                let n = at(&mesh.normals).normalize();
                let dir = (-n + n.any_orthonormal_vector() * 0.4).normalize();
                let chord = (patch.eval(uv.x, uv.y) - flat).length();
                let Some((u, v, x)) = patch.refine_hit(flat, dir, (uv.x, uv.y), 1.0) else {
                    continue;
                };
                refined += 1;
                assert!(
                    off_line(x, flat, dir) < 1e-5,
                    "off the ray by {}",
                    off_line(x, flat, dir)
                );
                assert!((patch.eval(u, v) - x).length() < 1e-5);
                assert!((0.0..=1.0).contains(&u) && (0.0..=1.0).contains(&v));
                assert!(
                    (x - flat).length() < 4.0 * chord + 1e-4,
                    "moved {}",
                    (x - flat).length()
                );
            }
        }
        // Rays near a patch's border may leave it for its neighbour; most stay.
        assert!(refined > 12 * 8 * 3 / 4, "{refined} of {} refined", 12 * 8);
    }

    #[test]
    fn a_hit_with_no_surface_near_it_is_not_refined() {
        let p = newell_teapot()[0];
        let x = p.eval(0.5, 0.5);
        let n = p.normal(0.5, 0.5);
        // The ray along the tangent plane, 0.5 above the surface: the patch is not near.
        let above = x + n * 0.5;
        let t = p.partials(0.5, 0.5).0.normalize();
        assert_eq!(p.refine_hit(above, t, (0.5, 0.5), 0.1), None);
        // Straight down onto the patch from 0.5 above: found, unless limited to 0.1.
        let (u, v, hit) = p.refine_hit(above, -n, (0.5, 0.5), 1.0).unwrap();
        assert!((hit - x).length() < 1e-5 && (u - 0.5).abs() < 1e-5 && (v - 0.5).abs() < 1e-5);
        assert_eq!(p.refine_hit(above, -n, (0.5, 0.5), 0.1), None);
        // A degenerate patch and a zero direction.
        assert_eq!(
            BezierPatch::new([Vec3::ONE; 16]).refine_hit(Vec3::ONE, Vec3::Z, (0.5, 0.5), 1.0),
            None
        );
        assert_eq!(p.refine_hit(x, Vec3::ZERO, (0.5, 0.5), 1.0), None);
    }

    #[test]
    fn fully_degenerate_patch_is_finite() {
        let p = BezierPatch::new([Vec3::ONE; 16]);
        assert_eq!(p.normal(0.5, 0.5), Vec3::Z);
        assert!(p.normal(f32::NAN, 2.0).is_finite());
        assert_eq!(p.tessellation_level(f32::NAN), MAX_TESSELLATION_LEVEL);
        assert_eq!(p.tessellation_level(0.1), 1);
    }
}
