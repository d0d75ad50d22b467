//! The CPU reference of shade.wgsl: the same shading in Rust `f32`, function for function and
//! in the same operation order, so that GPU images can be checked against it (the parity
//! tests) and so that users without a GPU can still evaluate a G-buffer.
//!
//! Residency and feedback work as on the GPU: a [`CubeTexels`] says which faces are available,
//! and every face a lookup *would* read with everything resident is marked in the feedback
//! masks (bit `f` of entry `cube` = face `f` needed).

use std::f32::consts::PI;
use std::sync::atomic::{AtomicU32, Ordering};

use glam::Vec3;
use oslf_format::{SampleMapView, INVALID_INDEX};
use oslf_geometry::BezierPatch;

use crate::face::{FaceLayout, FAR_DISTANCE};
use crate::params::ShadeUniform;

/// Bisection steps of a depth-corrected lookup (DEPTH_REFINE in shade.wgsl).
const DEPTH_REFINE: u32 = 6;
/// Steps of a glossy sample's depth correction (DEPTH_ITERATIONS in shade.wgsl).
const DEPTH_ITERATIONS: u32 = 2;
/// Depth-thicknesses within which a texel of a depth-corrected lookup agrees with the hit, at
/// most half its distance (LOOKUP_AGREE in shade.wgsl).
const LOOKUP_AGREE: f32 = 1.0;
/// Depth-thicknesses within which a candidate sees the blend's common hit (HIT_AGREE in
/// shade.wgsl).
const HIT_AGREE: f32 = 0.25;

/// Where the reference reads cube-map texels.
pub trait CubeTexels: Sync {
    /// Texel `(x, y)` of mip `level` of `face` of cube `cube`, or `None` when that face is not
    /// available (not resident, the GPU's fallback case).
    fn texel(&self, cube: u32, face: usize, level: u32, x: u32, y: u32) -> Option<Vec3>;
    /// Distance texel `(x, y)` of `face` of cube `cube` (as the GPU's binary16 plane holds it),
    /// or `None` when that face is not available or has no distance plane.
    fn depth(&self, cube: u32, face: usize, x: u32, y: u32) -> Option<f32>;
    /// Whether any face of `cube` is available.
    fn resident(&self, cube: u32) -> bool;
}

/// One pixel of the G-buffer, as gbuffer.wgsl writes it.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct GTexel {
    /// World position and sample-map id + 1 (0 = background): a Bézier patch's, or the atlas
    /// page's that gbuffer.wgsl picked from a mesh's atlas uv.
    pub position_patch: [f32; 4],
    /// Octahedral normal, u, v (on the patch, or local to the atlas page).
    pub normal_uv: [f32; 4],
}

/// Everything the shader reads besides the G-buffer.
pub struct Shader<'a, C: CubeTexels> {
    pub uniform: ShadeUniform,
    /// Sample-point positions (world space).
    pub samples: &'a [Vec3],
    /// Per sample map: the world-space patch (zero control points for a mesh's atlas page,
    /// whose tangent frame then comes from the normal alone) and its object's base colour C_s.
    pub patches: &'a [BezierPatch],
    pub colors: &'a [Vec3],
    /// One sample map per map index (Bézier patch or atlas page).
    pub maps: &'a [SampleMapView<'a>],
    pub cubes: &'a C,
    /// Feedback masks, one per cube (sample points, then the environment cube).
    pub feedback: &'a [AtomicU32],
}

/// PCG hash (Jarzynski & Olano 2020), as `pcg` in shade.wgsl.
pub fn pcg(v: u32) -> u32 {
    let state = v.wrapping_mul(747796405).wrapping_add(2891336453);
    let word = ((state >> ((state >> 28) + 4)) ^ state).wrapping_mul(277803737);
    (word >> 22) ^ word
}

fn rand(pixel: u32, i: u32, j: u32, k: u32) -> f32 {
    let h = pcg(pixel.wrapping_add(pcg(i.wrapping_add(pcg(j.wrapping_mul(8).wrapping_add(k))))));
    (h >> 8) as f32 * (1.0 / 16777216.0)
}

/// (ξ1, ξ2) of filtered glossy sample `i` of `m` (as `filter_xi`): for m = n² the centres of
/// an n × n grid of strata through Shirley & Chiu's concentric map to the disc, as polar
/// coordinates (ξ1 = φ/2π, ξ2 = r²), so that each sample's cell is compact; else the
/// Hammersley set.
pub fn filter_xi(i: u32, m: u32) -> [f32; 2] {
    let n = (m as f32).sqrt().round() as u32;
    if n * n != m {
        return [
            (i as f32 + 0.5) / m as f32,
            i.reverse_bits() as f32 * 2.328_306_4e-10,
        ];
    }
    let a = 2.0 * ((i % n) as f32 + 0.5) / n as f32 - 1.0;
    let b = 2.0 * ((i / n) as f32 + 0.5) / n as f32 - 1.0;
    if a == 0.0 && b == 0.0 {
        return [0.0, 0.0]; // the centre cell of an odd n
    }
    let (mut r, mut phi) = if a.abs() > b.abs() {
        (a, 0.25 * PI * (b / a))
    } else {
        (b, 0.5 * PI - 0.25 * PI * (a / b))
    };
    if r < 0.0 {
        r = -r;
        phi += PI;
    }
    let x1 = phi * (0.5 / PI);
    [x1 - x1.floor(), r * r]
}

/// Samples per row of the filtered set of `m` (as `filter_rows`): n for m = n² when
/// `filtered`, else 1.
pub fn filter_rows(m: u32, filtered: bool) -> u32 {
    let n = (m as f32).sqrt().round() as u32;
    if filtered && n > 0 && n * n == m {
        n
    } else {
        1
    }
}

/// Face and face coordinates of a direction: [`oslf_format::cube::direction_to_face_st`].
pub fn face_st(d: Vec3) -> (usize, f32, f32) {
    oslf_format::cube::direction_to_face_st(d.to_array())
}

/// The point of `face`'s plane (major axis ±1) at face coordinates `(s, t)`, which may lie
/// outside `[0, 1]`: the inverse of [`face_st`] ([`oslf_format::cube::face_st_to_direction`],
/// not normalized).
pub fn face_point(face: usize, s: f32, t: f32) -> Vec3 {
    let sc = 2.0 * s - 1.0;
    let tc = 2.0 * t - 1.0;
    match face {
        0 => Vec3::new(1.0, -tc, -sc),
        1 => Vec3::new(-1.0, -tc, sc),
        2 => Vec3::new(sc, 1.0, tc),
        3 => Vec3::new(sc, -1.0, -tc),
        4 => Vec3::new(sc, -tc, 1.0),
        _ => Vec3::new(-sc, -tc, -1.0),
    }
}

/// Face and texel of a level `n` texels wide that texel `(x, y)` of `face` stands for, where
/// `(x, y)` may lie one texel off the face: then the texel of the adjacent face that the
/// direction through that texel's centre, extended on `face`'s plane, lands in (nearest
/// texel). shade.wgsl's `seam_texel` reads the same texel from a table (SEAM_LO, SEAM_HI).
pub fn seam_coords(face: usize, (x, y): (i32, i32), n: i32) -> (usize, (i32, i32)) {
    if x >= 0 && y >= 0 && x < n && y < n {
        return (face, (x, y));
    }
    let nf = n as f32;
    let (f, s, t) = face_st(face_point(
        face,
        (x as f32 + 0.5) / nf,
        (y as f32 + 0.5) / nf,
    ));
    (
        f,
        (((s * nf) as i32).min(n - 1), ((t * nf) as i32).min(n - 1)),
    )
}

/// Candidates of a texel: the sample map's four entries with their directions from x.
#[derive(Clone, Copy, Debug)]
struct Candidates {
    idx: [u32; 4],
    s: [Vec3; 4],
    count: u32,
}

// f32 twins of shade.wgsl's Bernstein polynomials; `oslf_bake::bezier` evaluates in f64, which
// the GPU cannot match.
fn bern3(t: f32) -> [f32; 4] {
    let s = 1.0 - t;
    [s * s * s, 3.0 * t * s * s, 3.0 * t * t * s, t * t * t]
}

fn bern2(t: f32) -> [f32; 3] {
    let s = 1.0 - t;
    [s * s, 2.0 * t * s, t * t]
}

/// ∂x/∂u through the hodograph, in `f32` (as `patch_du` in shade.wgsl).
pub fn patch_du(p: &BezierPatch, u: f32, v: f32) -> Vec3 {
    let (bu, bv) = (bern2(u), bern3(v));
    let mut du = Vec3::ZERO;
    for (i, bui) in bu.iter().enumerate() {
        for (j, bvj) in bv.iter().enumerate() {
            let d = p.cp[4 * (i + 1) + j] - p.cp[4 * i + j];
            du += d * (bui * bvj);
        }
    }
    du * 3.0
}

/// Where face coordinates `(s, t)` land on a face of side `n`: the four texels around them,
/// clamped at the face's edges, and the bilinear weights (as `Tap` in shade.wgsl).
struct Tap {
    x0: u32,
    y0: u32,
    x1: u32,
    y1: u32,
    wx: f32,
    wy: f32,
}

impl Tap {
    fn new(n: u32, s: f32, t: f32) -> Self {
        let nf = n as f32;
        let fx = (s * nf - 0.5).clamp(0.0, nf - 1.0);
        let fy = (t * nf - 0.5).clamp(0.0, nf - 1.0);
        let (x0, y0) = (fx.floor() as u32, fy.floor() as u32);
        Tap {
            x0,
            y0,
            x1: (x0 + 1).min(n - 1),
            y1: (y0 + 1).min(n - 1),
            wx: fx - fx.floor(),
            wy: fy - fy.floor(),
        }
    }
}

/// ∂x/∂v through the hodograph, in `f32` (as `patch_dv` in shade.wgsl).
pub fn patch_dv(p: &BezierPatch, u: f32, v: f32) -> Vec3 {
    let (bu, bv) = (bern3(u), bern2(v));
    let mut dv = Vec3::ZERO;
    for (i, bui) in bu.iter().enumerate() {
        for (j, bvj) in bv.iter().enumerate() {
            let d = p.cp[4 * i + j + 1] - p.cp[4 * i + j];
            dv += d * (bui * bvj);
        }
    }
    dv * 3.0
}

/// The shading normal at `(u, v)`: the patch's ∂x/∂u × ∂x/∂v facing as the interpolated
/// vertex normal `ni`, or `ni` where that degenerates or turns more than 25° from it (as
/// `patch_normal` in shade.wgsl).
#[allow(clippy::neg_cmp_op_on_partial_ord)]
pub fn patch_normal(p: &BezierPatch, u: f32, v: f32, ni: Vec3) -> Vec3 {
    let (du, dv) = (patch_du(p, u, v), patch_dv(p, u, v));
    let e = du.cross(dv);
    let len = e.length();
    if !(len > 1e-6 * du.length() * dv.length()) {
        return ni;
    }
    let ne = (if e.dot(ni) < 0.0 { -e } else { e }) / len;
    if !(ne.dot(ni) > 0.9) {
        return ni;
    }
    ne
}

/// Unit tangent orthogonal to `n` from ∂x/∂u, or the frame of Duff et al. (2017) where ∂x/∂u
/// vanishes or is parallel to `n` (as `tangent_frame` in shade.wgsl).
pub fn tangent_frame(n: Vec3, du: Vec3) -> Vec3 {
    let t = du - n * n.dot(du);
    let l2 = t.dot(t);
    if l2 > 1e-12 * du.dot(du).max(1e-30) {
        return t / l2.sqrt();
    }
    let sgn = if n.z >= 0.0 { 1.0 } else { -1.0 };
    let a = -1.0 / (sgn + n.z);
    let b = n.x * n.y * a;
    Vec3::new(1.0 + sgn * n.x * n.x * a, sgn * b, -sgn * n.x)
}

struct AsSample {
    l: Vec3,
    weight: f32,
    /// log2(M p(l)).
    lpdf: f32,
}

fn fresnel(rs: f32, c: f32) -> f32 {
    // Eq. 5.7 (Schlick)
    let k = (1.0 - c).clamp(0.0, 1.0);
    let k2 = k * k;
    rs + (1.0 - rs) * k2 * k2 * k
}

/// Replaces NaN and infinities by 0 (as `finite3`).
fn finite3(c: Vec3) -> Vec3 {
    Vec3::from_array(c.to_array().map(|x| if x.is_finite() { x } else { 0.0 }))
}

// `j` indexes the four candidates' parallel arrays (indices, directions, weights), as in
// shade.wgsl; `!(x > 0.0)` is shade.wgsl's NaN-aware test, kept word for word.
#[allow(clippy::needless_range_loop, clippy::neg_cmp_op_on_partial_ord)]
impl<C: CubeTexels> Shader<'_, C> {
    /// Radiance of `cube` towards `dir`, marking the face as needed (as `lookup`/`fetch`).
    fn lookup(&self, cube: u32, dir: Vec3) -> Option<Vec3> {
        let (face, s, t) = face_st(dir);
        self.mark(cube, face);
        self.read_tap(cube, face, s, t, 0)
    }

    /// Marks `face` of `cube` as needed in the feedback.
    fn mark(&self, cube: u32, face: usize) {
        if let Some(f) = self.feedback.get(cube as usize) {
            f.fetch_or(1 << face, Ordering::Relaxed);
        }
    }

    /// `lookup` on mip `level`, without the feedback mark (as `read_tap`): bilinear
    /// within the face.
    fn read_tap(&self, cube: u32, face: usize, s: f32, t: f32, level: u32) -> Option<Vec3> {
        let Tap {
            x0,
            y0,
            x1,
            y1,
            wx,
            wy,
        } = Tap::new((self.uniform.cube_res >> level).max(1), s, t);
        let t00 = self.cubes.texel(cube, face, level, x0, y0)?;
        let t10 = self.cubes.texel(cube, face, level, x1, y0)?;
        let t01 = self.cubes.texel(cube, face, level, x0, y1)?;
        let t11 = self.cubes.texel(cube, face, level, x1, y1)?;
        let top = t00 + (t10 - t00) * wx;
        let bottom = t01 + (t11 - t01) * wx;
        Some(top + (bottom - top) * wy)
    }

    /// Radiance of `cube` towards `dir` at fractional mip level `lod`, marking the face (as
    /// `lookup_lod`).
    fn lookup_lod(&self, cube: u32, dir: Vec3, lod: f32) -> Option<Vec3> {
        if !(lod > 0.0) {
            return self.lookup(cube, dir);
        }
        self.lookup_levels(cube, dir, lod)
    }

    /// Radiance of `cube` towards `dir` at mip level `lod` ≥ 0 across face edges, the two
    /// nearest levels blended (as `lookup_levels`).
    fn lookup_levels(&self, cube: u32, dir: Vec3, lod: f32) -> Option<Vec3> {
        let top = self.uniform.mip_levels - 1;
        let l = lod.clamp(0.0, top as f32);
        let l0 = l.floor() as u32;
        let f = l - l0 as f32;
        let fst = face_st(dir);
        let a = self.seamless_level(cube, fst, l0, true);
        if !(f > 0.0) {
            return a;
        }
        let b = self.seamless_level(cube, fst, (l0 + 1).min(top), true);
        Some(a? + (b? - a?) * f)
    }

    /// (ξ1, ξ2) of sample `i` of integration `j`, numbers `k` and `k + 1` (as `sample_xi`):
    /// random with ξ1 stratified, or when filtering the fixed set [`filter_xi`].
    fn sample_xi(&self, pixel: u32, i: u32, j: u32, k: u32) -> [f32; 2] {
        let m = self.uniform.m;
        if self.uniform.mip_levels > 1 {
            return filter_xi(i, m);
        }
        [
            (i as f32 + rand(pixel, i, j, k)) / m as f32,
            rand(pixel, i, j, k + 1),
        ]
    }

    /// The mip level of a sample towards `dir` with log2(M p) = `lpdf` (as `sample_lod`).
    fn sample_lod(&self, dir: Vec3, lpdf: f32) -> f32 {
        if self.uniform.mip_levels <= 1 {
            return 0.0;
        }
        let (_, s, t) = face_st(dir);
        let (sc, tc) = (2.0 * s - 1.0, 2.0 * t - 1.0);
        let log_texel = 2.0 * (2.0 / self.uniform.cube_res as f32).log2()
            - 1.5 * (1.0 + sc * sc + tc * tc).log2();
        (0.5 * (-lpdf - log_texel)).max(0.0)
    }

    /// Distance from sample point `cube` to the first hit towards `d` (nearest texel), marking
    /// the face (every face when it is not available and `walk`); sets `missing` then (as
    /// `depth_toward`).
    fn depth_toward(&self, cube: u32, d: Vec3, walk: bool, missing: &mut bool) -> f32 {
        let (face, s, t) = face_st(d);
        self.mark(cube, face);
        let n = self.uniform.cube_res;
        let x = ((s * n as f32) as u32).min(n - 1);
        let y = ((t * n as f32) as u32).min(n - 1);
        self.cubes.depth(cube, face, x, y).unwrap_or_else(|| {
            if let Some(f) = self.feedback.get(cube as usize).filter(|_| walk) {
                f.fetch_or(63, Ordering::Relaxed);
            }
            *missing = true;
            FAR_DISTANCE
        })
    }

    /// The ray point at inverse distance `w` seen from `p`: its offset from `p` and
    /// |q − p| − D_p (as `depth_probe`).
    #[allow(clippy::too_many_arguments)]
    fn depth_probe(
        &self,
        cube: u32,
        p: Vec3,
        x: Vec3,
        r: Vec3,
        w: f32,
        missing: &mut bool,
    ) -> (Vec3, f32) {
        if !(w > 0.0) {
            return (r, 1.0);
        }
        let d = x + r * (1.0 / w) - p;
        (d, d.length() - self.depth_toward(cube, d, true, missing))
    }

    /// The depth-corrected lookup direction of sample point `cube` for the ray from `x` along
    /// `r`, and its status: 1 hit, 0 none (plain), −1 hidden (as `depth_search`).
    fn depth_search(&self, cube: u32, x: Vec3, r: Vec3) -> (Vec3, f32) {
        let u = &self.uniform;
        let p = self.samples[cube as usize];
        let lo = (x - p).length();
        if !(lo > 0.0) {
            return (r, 0.0);
        }
        let mut missing = false;
        let w0 = 1.0 / lo;
        let mut a = self.depth_probe(cube, p, x, r, w0, &mut missing);
        if missing {
            return (r, 0.0);
        }
        if a.1 >= 0.0 {
            return (r, -1.0);
        }
        let span = a.0.normalize().dot(r).clamp(-1.0, 1.0).acos();
        let steps = ((span * u.cube_res as f32 / (0.5 * PI)).ceil() as u32).clamp(1, u.depth_steps);
        let (mut wa, mut wb, mut b) = (w0, 0.0f32, (r, 1.0f32));
        for k in 1..steps {
            let w = w0 * (1.0 - k as f32 / steps as f32);
            let q = self.depth_probe(cube, p, x, r, w, &mut missing);
            if q.1 >= 0.0 {
                wb = w;
                b = q;
                break;
            }
            wa = w;
            a = q;
        }
        for _ in 0..DEPTH_REFINE {
            let wm = 0.5 * (wa + wb);
            let q = self.depth_probe(cube, p, x, r, wm, &mut missing);
            if q.1 >= 0.0 {
                wb = wm;
                b = q;
            } else {
                wa = wm;
                a = q;
            }
        }
        if missing || !(wb > 0.0) {
            return (r, 0.0);
        }
        if b.1 > u.depth_thickness * b.0.length() {
            return (r, -1.0);
        }
        if b.1 - a.1 > 0.0 {
            let ws = wa + (wb - wa) * (-a.1 / (b.1 - a.1));
            if ws > 0.0 {
                return (x + r * (1.0 / ws) - p, 1.0);
            }
        }
        (b.0, 1.0)
    }

    /// The depth-corrected lookup direction of sample point `cube` for a glossy sample from
    /// `x` along `l` (as `depth_iterate`): for a `fresh` sample DEPTH_ITERATIONS fixed-point
    /// steps on the spheres of the stored distances from `l`, `l` where a step finds nothing
    /// or `x` lies outside, and `seed` set to the distance it converged to (0 for none); for
    /// the others of its row, the sphere of radius `seed`, reading nothing.
    fn depth_iterate(&self, cube: u32, x: Vec3, l: Vec3, fresh: bool, seed: &mut f32) -> Vec3 {
        let o = x - self.samples[cube as usize];
        let (ol, oo) = (o.dot(l), o.dot(o));
        let step = |dist: f32| o + l * ((ol * ol - (oo - dist * dist)).sqrt() - ol);
        if !fresh {
            return if *seed * *seed > oo { step(*seed) } else { l };
        }
        let mut missing = false;
        let mut q = l;
        *seed = 0.0;
        for _ in 0..DEPTH_ITERATIONS {
            let dist = self.depth_toward(cube, q, true, &mut missing);
            if !(dist < FAR_DISTANCE) || !(dist * dist > oo) {
                *seed = 0.0;
                return l;
            }
            q = step(dist);
            *seed = dist;
        }
        q
    }

    /// Radiance of `cube` for the `depth_search` result `h` at level `lod`: on level 0 the
    /// bilinear tap over the texels whose distance agrees with the hit's (as `depth_lookup`).
    fn depth_lookup(&self, cube: u32, h: (Vec3, f32), lod: f32) -> Option<Vec3> {
        if lod > 0.0 || h.1 < 0.0 {
            return self.lookup_lod(cube, h.0, lod);
        }
        let (face, s, t) = face_st(h.0);
        self.mark(cube, face);
        let Tap {
            x0,
            y0,
            x1,
            y1,
            wx,
            wy,
        } = Tap::new(self.uniform.cube_res, s, t);
        let dist = if h.1 > 0.0 {
            h.0.length()
        } else {
            FAR_DISTANCE
        };
        let tol = (LOOKUP_AGREE * self.uniform.depth_thickness).min(0.5) * dist;
        let taps = [(x0, y0), (x1, y0), (x0, y1), (x1, y1)];
        let mut w = [
            (1.0 - wx) * (1.0 - wy),
            wx * (1.0 - wy),
            (1.0 - wx) * wy,
            wx * wy,
        ];
        let mut agree = [0.0f32; 4];
        for k in 0..4 {
            let d = self.cubes.depth(cube, face, taps[k].0, taps[k].1)?;
            if (d - dist).abs() <= tol {
                agree[k] = w[k];
            }
        }
        let sum = agree[0] + agree[1] + agree[2] + agree[3];
        if sum > 0.0 {
            w = agree.map(|a| a / sum);
        }
        let mut c = Vec3::ZERO;
        for k in 0..4 {
            c += self.cubes.texel(cube, face, 0, taps[k].0, taps[k].1)? * w[k];
        }
        Some(c)
    }

    /// Texel `(x, y)` of mip `level` of `face` of `cube`, where `(x, y)` may lie one texel off
    /// the face: then the texel of the adjacent face it stands for ([`seam_coords`]). `None`
    /// when that face is not available. Marks the face it reads when `mark` (as `seam_texel`).
    fn seam_texel(
        &self,
        cube: u32,
        face: usize,
        (x, y): (i32, i32),
        level: u32,
        mark: bool,
    ) -> Option<Vec3> {
        let n = (self.uniform.cube_res >> level).max(1) as i32;
        let (f, c) = seam_coords(face, (x, y), n);
        if mark {
            self.mark(cube, f);
        }
        self.cubes.texel(cube, f, level, c.0 as u32, c.1 as u32)
    }

    /// Radiance of mip `level` of `cube` at `face_st` of a direction, bilinear *across* face
    /// edges: the four
    /// texel centres around the direction on its face, those off the face read from the
    /// adjacent face ([`Self::seam_texel`]), with the usual bilinear weights. At a corner of
    /// the cube, where three faces meet, the texel off the face in both directions does not
    /// exist: it is the mean of the other three. `None` when a face it reads is not available.
    /// Marks the faces it reads when `mark` (as `seamless_level`).
    fn seamless_level(
        &self,
        cube: u32,
        (face, s, t): (usize, f32, f32),
        level: u32,
        mark: bool,
    ) -> Option<Vec3> {
        let n = (self.uniform.cube_res >> level).max(1) as i32;
        let nf = n as f32;
        let fx = s * nf - 0.5;
        let fy = t * nf - 0.5;
        let (x0, y0) = (fx.floor() as i32, fy.floor() as i32);
        let (wx, wy) = (fx - fx.floor(), fy - fy.floor());
        // The texel off the face in both directions, as k = column + 2 * row; 4 = none.
        let mut corner = 4;
        if (x0 < 0 || x0 + 1 >= n) && (y0 < 0 || y0 + 1 >= n) {
            corner = usize::from(x0 >= 0) + 2 * usize::from(y0 >= 0);
        }
        // Every texel is read (and its face marked) before any is missed, as on the GPU.
        let read: [Option<Vec3>; 4] = std::array::from_fn(|k| {
            if k == corner {
                Some(Vec3::ZERO)
            } else {
                let at = (x0 + (k & 1) as i32, y0 + (k >> 1) as i32);
                self.seam_texel(cube, face, at, level, mark)
            }
        });
        let mut t = [read[0]?, read[1]?, read[2]?, read[3]?];
        if corner < 4 {
            t[corner] = (t[0] + t[1] + t[2] + t[3]) * (1.0 / 3.0);
        }
        let top = t[0] + (t[1] - t[0]) * wx;
        let bottom = t[2] + (t[3] - t[2]) * wx;
        Some(top + (bottom - top) * wy)
    }

    /// `seamless_level` at level 0 without feedback marks: for the background only (as
    /// `seamless_read`). `lookup` (reflections, reconstruction) clamps at face edges.
    fn seamless_read(&self, cube: u32, dir: Vec3) -> Option<Vec3> {
        self.seamless_level(cube, face_st(dir), 0, false)
    }

    fn candidates(&self, patch: u32, u: f32, v: f32, x: Vec3, n: Vec3) -> Candidates {
        let m = self.uniform.map_res;
        let tx = ((u.clamp(0.0, 1.0) * m as f32) as u32).min(m - 1);
        let ty = ((v.clamp(0.0, 1.0) * m as f32) as u32).min(m - 1);
        let raw = self
            .maps
            .get(patch as usize)
            .and_then(|map| map.get(tx, ty))
            .unwrap_or([INVALID_INDEX; 4]);
        let mut c = Candidates {
            idx: [INVALID_INDEX; 4],
            s: [n; 4],
            count: 0,
        };
        for j in 0..4 {
            let idx = raw[j];
            if idx != INVALID_INDEX && idx < self.uniform.sample_count {
                c.idx[j] = idx;
                let d = self.samples[idx as usize] - x;
                let l2 = d.dot(d);
                if l2 > 0.0 {
                    c.s[j] = d / l2.sqrt();
                }
                c.count += 1;
            }
        }
        c
    }

    fn is_resident(&self, cube: u32) -> bool {
        self.cubes.resident(cube)
    }

    fn blend_weights(&self, c: &Candidates, a: Vec3) -> [f32; 4] {
        let u = &self.uniform;
        let mut w = [0.0f32; 4];
        let (mut best, mut best_dot, mut first) = (0usize, -2.0f32, 4usize);
        for j in 0..4 {
            if c.idx[j] == INVALID_INDEX {
                continue;
            }
            if first == 4 {
                first = j;
            }
            let d = a.dot(c.s[j]);
            if d > best_dot {
                best_dot = d;
                best = j;
            }
        }
        if first == 4 {
            return w;
        }
        match u.blend {
            0 => w[first] = 1.0, // Eq. 4.3
            1 => w[best] = 1.0,  // Eq. 4.4-4.5
            _ => {
                for j in 0..4 {
                    if c.idx[j] == INVALID_INDEX {
                        continue;
                    }
                    if u.blend == 2 || u.blend_n == 0.0 {
                        w[j] = 1.0; // Eq. 4.9
                    } else if best_dot > 0.0 {
                        let r = a.dot(c.s[j]).max(0.0) / best_dot;
                        if r > 0.0 {
                            w[j] = r.powf(u.blend_n); // Eq. 4.10, 4.11
                        }
                    }
                }
                if best_dot <= 0.0 && u.blend != 2 && u.blend_n != 0.0 {
                    w[best] = 1.0;
                }
            }
        }
        w
    }

    /// Blended radiance towards `dir` for the ray from `x` at mip level `lod`, each candidate
    /// depth-corrected when the uniform asks (as `blend_read`).
    fn blend_read(
        &self,
        c: &Candidates,
        w: [f32; 4],
        x: Vec3,
        dir: Vec3,
        lod: f32,
    ) -> Option<Vec3> {
        let depth = self.uniform.depth_steps > 0;
        let (mut acc, mut wsum, mut hidden, mut hsum) = (Vec3::ZERO, 0.0, Vec3::ZERO, 0.0);
        let mut near = 3.4e38f32;
        for j in 0..4 {
            if w[j] > 0.0 {
                let (l, status) = if depth {
                    let h = self.depth_search(c.idx[j], x, dir);
                    if h.1 > 0.0 {
                        near = near.min((h.0 + self.samples[c.idx[j] as usize] - x).dot(dir));
                    }
                    (self.depth_lookup(c.idx[j], h, lod), h.1)
                } else {
                    (self.lookup_lod(c.idx[j], dir, lod), 1.0)
                };
                if let Some(l) = l {
                    if status >= 0.0 {
                        acc += l * w[j];
                        wsum += w[j];
                    } else {
                        hidden += l * w[j];
                        hsum += w[j];
                    }
                }
            }
        }
        if depth && near < 3.4e38 {
            // The candidates' common hit (as `blend_read`).
            let hit = x + dir * near;
            let (mut cacc, mut csum) = (Vec3::ZERO, 0.0);
            for j in 0..4 {
                if w[j] > 0.0 {
                    let d = hit - self.samples[c.idx[j] as usize];
                    let dl = d.length();
                    let mut missing = false;
                    let seen = self.depth_toward(c.idx[j], d, false, &mut missing);
                    if !missing
                        && (dl - seen).abs() <= HIT_AGREE * self.uniform.depth_thickness * dl
                    {
                        if let Some(l) = self.depth_lookup(c.idx[j], (d, 1.0), lod) {
                            cacc += l * w[j];
                            csum += w[j];
                        }
                    }
                }
            }
            if csum > 0.0 {
                return Some(cacc / csum);
            }
        }
        if wsum > 0.0 {
            return Some(acc / wsum);
        }
        (hsum > 0.0).then(|| hidden / hsum)
    }

    /// The environment cube's lookup direction for the ray from `x` along `dir` (as `env_dir`).
    fn env_dir(&self, x: Vec3, dir: Vec3) -> Vec3 {
        let u = &self.uniform;
        if u.source != 2 {
            return dir;
        }
        let v = |a: [f32; 4]| Vec3::from_slice(&a[..3]);
        crate::probe::parallax_dir(x, dir, v(u.probe_pos), v(u.box_min), v(u.box_max))
    }

    /// The environment cube for the ray from `x` along `dir` at `lod` (as `env_read`).
    fn env_read(&self, x: Vec3, dir: Vec3, lod: f32) -> Vec3 {
        if self.uniform.env_cube == INVALID_INDEX {
            return Vec3::ZERO;
        }
        self.lookup_lod(self.uniform.env_cube, self.env_dir(x, dir), lod)
            .unwrap_or(Vec3::ZERO)
    }

    fn recon_choice(&self, c: &Candidates, n: Vec3, resident_only: bool) -> usize {
        let (mut best, mut best_dot) = (4usize, -2.0f32);
        for j in 0..4 {
            if c.idx[j] == INVALID_INDEX {
                continue;
            }
            if resident_only && !self.is_resident(c.idx[j]) {
                continue;
            }
            let d = n.dot(c.s[j]);
            if d >= self.uniform.cos_phi_shader {
                return j;
            }
            if d > best_dot {
                best_dot = d;
                best = j;
            }
        }
        best
    }

    /// The mean, weighted by ⟨n, s_j⟩, over the candidates in front of `x` that see it (as
    /// `recon_visible`).
    fn recon_visible(&self, c: &Candidates, x: Vec3, n: Vec3) -> Option<Vec3> {
        let (mut acc, mut count) = (Vec3::ZERO, 0.0f32);
        for j in 0..4 {
            let i = c.idx[j];
            let cos_j = n.dot(c.s[j]);
            if i == INVALID_INDEX || cos_j <= 0.0 {
                continue;
            }
            let d = x - self.samples[i as usize];
            let mut missing = false;
            let seen = self.depth_toward(i, d, false, &mut missing);
            if missing || d.length() > seen * (1.0 + self.uniform.depth_thickness) {
                continue;
            }
            if let Some(l) = self.depth_lookup(i, (d, 1.0), 0.0) {
                acc += l * cos_j;
                count += cos_j;
            }
        }
        (count > 0.0).then(|| acc / count)
    }

    fn recon(&self, c: &Candidates, x: Vec3, n: Vec3) -> Vec3 {
        if self.uniform.depth_steps > 0 {
            if let Some(m) = self.recon_visible(c, x, n) {
                return m;
            }
        }
        let ideal = self.recon_choice(c, n, false);
        if ideal == 4 {
            return Vec3::ZERO;
        }
        let i = c.idx[ideal];
        if let Some(l) = self.lookup(i, x - self.samples[i as usize]) {
            return l;
        }
        let j = self.recon_choice(c, n, true);
        if j == 4 {
            return Vec3::ZERO;
        }
        let i = c.idx[j];
        self.lookup(i, x - self.samples[i as usize])
            .unwrap_or(Vec3::ZERO)
    }

    fn mirror(&self, c: &Candidates, x: Vec3, n: Vec3, r: Vec3) -> Vec3 {
        if self.uniform.source != 0 || c.count == 0 {
            return self.env_read(x, r, 0.0);
        }
        let axis = if self.uniform.blend == 4 { n } else { r };
        self.blend_read(c, self.blend_weights(c, axis), x, r, 0.0)
            .unwrap_or_else(|| self.env_read(x, r, 0.0))
    }

    #[allow(clippy::too_many_arguments)]
    fn sample_as(
        &self,
        xi1: f32,
        xi2: f32,
        n: Vec3,
        t: Vec3,
        b: Vec3,
        v: Vec3,
        nv: f32,
    ) -> AsSample {
        let u = &self.uniform;
        let q = ((xi1 * 4.0) as u32).min(3);
        let xq = xi1 * 4.0 - q as f32;
        let half_angle = 0.5 * PI * xq;
        let mut phi =
            ((u.nu + 1.0).sqrt() * half_angle.sin()).atan2((u.nv + 1.0).sqrt() * half_angle.cos());
        phi = match q {
            1 => PI - phi,
            2 => PI + phi,
            3 => 2.0 * PI - phi,
            _ => phi,
        };
        let (cp, sp) = (phi.cos(), phi.sin());
        let e = u.nu * cp * cp + u.nv * sp * sp;
        let cos_theta = (1.0 - xi2).powf(1.0 / (e + 1.0));
        let sin_theta = (1.0 - cos_theta * cos_theta).max(0.0).sqrt();
        let h = t * (sin_theta * cp) + b * (sin_theta * sp) + n * cos_theta;
        let vh = v.dot(h);
        let l = 2.0 * vh * h - v;
        // Eq. 5.8 and 5.11 as in shade.wgsl.
        let lpdf = (u.m as f32).log2() + 0.5 * ((u.nu + 1.0) * (u.nv + 1.0)).log2()
            - (2.0 * PI).log2()
            + e / (e + 1.0) * (1.0 - xi2).log2()
            - (4.0 * vh.max(1e-30)).log2();
        let nl = n.dot(l);
        let weight = if vh > 0.0 && nl > 0.0 {
            fresnel(u.rs, vh) * nl / nv.max(nl)
        } else {
            0.0
        };
        AsSample { l, weight, lpdf }
    }

    #[allow(clippy::too_many_arguments)]
    fn sample_diffuse(&self, xi1: f32, r2: f32, n: Vec3, t: Vec3, b: Vec3, nv: f32) -> AsSample {
        let u = &self.uniform;
        let phi = 2.0 * PI * xi1;
        let rad = r2.sqrt();
        let z = (1.0 - r2).max(0.0).sqrt();
        let l = t * (rad * phi.cos()) + b * (rad * phi.sin()) + n * z;
        let nl = n.dot(l);
        let lpdf = (u.m as f32).log2() + (nl.max(1e-30) / PI).log2();
        let fv = 1.0 - (1.0 - 0.5 * nv.max(0.0)).powf(5.0);
        let fl = 1.0 - (1.0 - 0.5 * nl.max(0.0)).powf(5.0);
        let weight = if nl > 0.0 {
            28.0 / 23.0 * u.rd * (1.0 - u.rs) * fv * fl // Eq. 5.4 × π
        } else {
            0.0
        };
        AsSample { l, weight, lpdf }
    }

    /// The radiance of sample `s` for the shaded point `x` from `cube` (or, per direction,
    /// `cube` = INVALID, the blend), as `sample_radiance`; `fresh` and `seed` as
    /// `depth_iterate`. `None` when a face was not available.
    #[allow(clippy::too_many_arguments)]
    fn sample_radiance(
        &self,
        c: &Candidates,
        cube: u32,
        wn: [f32; 4],
        x: Vec3,
        s: &AsSample,
        fresh: bool,
        seed: &mut f32,
    ) -> Option<Vec3> {
        let u = &self.uniform;
        let lod = self.sample_lod(s.l, s.lpdf);
        if u.order == 1 && cube == INVALID_INDEX {
            let w = if u.blend != 4 {
                self.blend_weights(c, s.l)
            } else {
                wn
            };
            return Some(
                self.blend_read(c, w, x, s.l, lod)
                    .unwrap_or_else(|| self.env_read(x, s.l, lod)),
            );
        }
        let d = if cube == u.env_cube {
            self.env_dir(x, s.l)
        } else if u.depth_steps > 0 {
            self.depth_iterate(cube, x, s.l, fresh, seed)
        } else {
            s.l
        };
        if u.mip_levels > 1 {
            self.lookup_levels(cube, d, lod)
        } else {
            self.lookup(cube, d)
        }
    }

    #[allow(clippy::too_many_arguments)]
    fn integrate(
        &self,
        c: &Candidates,
        cube: u32,
        j: u32,
        pixel: u32,
        x: Vec3,
        n: Vec3,
        t: Vec3,
        b: Vec3,
        v: Vec3,
        nv: f32,
    ) -> (Vec3, bool) {
        let u = &self.uniform;
        let mut acc = Vec3::ZERO;
        let mut ok = true;
        let wn = self.blend_weights(c, n);
        // Per kind of sample (specular, diffuse): `depth_iterate`'s seed, and whether the row
        // has had its fresh sample (its first one above the surface).
        let mut seed = [0.0f32; 2];
        let mut fresh = [true; 2];
        let rows = filter_rows(u.m, u.mip_levels > 1);
        for i in 0..u.m {
            if i % rows == 0 {
                fresh = [true; 2];
            }
            for k in 0..2 {
                if k == 1 && u.rd <= 0.0 {
                    continue;
                }
                let [x1, x2] = self.sample_xi(pixel, i, j, 2 * k);
                let s = if k == 0 {
                    self.sample_as(x1, x2, n, t, b, v, nv)
                } else {
                    self.sample_diffuse(x1, x2, n, t, b, nv)
                };
                if s.weight <= 0.0 {
                    continue;
                }
                let li = self
                    .sample_radiance(c, cube, wn, x, &s, fresh[k as usize], &mut seed[k as usize])
                    .unwrap_or_else(|| {
                        ok = false;
                        Vec3::ZERO
                    });
                fresh[k as usize] = false;
                acc += li * s.weight;
            }
        }
        (acc / u.m.max(1) as f32, ok)
    }

    #[allow(clippy::too_many_arguments)]
    fn glossy(
        &self,
        c: &Candidates,
        pixel: u32,
        x: Vec3,
        n: Vec3,
        t: Vec3,
        v: Vec3,
        r: Vec3,
    ) -> Vec3 {
        let u = &self.uniform;
        let b = n.cross(t);
        let nv = n.dot(v);
        if u.source != 0 || c.count == 0 {
            if u.env_cube == INVALID_INDEX {
                return Vec3::ZERO;
            }
            return self.integrate(c, u.env_cube, 4, pixel, x, n, t, b, v, nv).0;
        }
        if u.order == 1 {
            return self
                .integrate(c, INVALID_INDEX, 4, pixel, x, n, t, b, v, nv)
                .0;
        }
        let axis = if u.blend == 4 { n } else { r };
        let w = self.blend_weights(c, axis);
        let mut acc = Vec3::ZERO;
        let mut wsum = 0.0;
        for j in 0..4 {
            if w[j] > 0.0 {
                let (est, ok) = self.integrate(c, c.idx[j], j as u32, pixel, x, n, t, b, v, nv);
                if ok {
                    acc += est * w[j];
                    wsum += w[j];
                }
            }
        }
        if wsum > 0.0 {
            return acc / wsum;
        }
        if u.env_cube == INVALID_INDEX {
            return Vec3::ZERO;
        }
        self.integrate(c, u.env_cube, 4, pixel, x, n, t, b, v, nv).0
    }

    /// The unit direction of the camera ray through the centre of pixel `(px, py)`, as
    /// [`oslf_geometry::Camera::direction`] computes it (as `camera_ray`).
    pub fn camera_ray(&self, px: u32, py: u32) -> Vec3 {
        let u = &self.uniform;
        let (w, h) = (u.size[0] as f32, u.size[1] as f32);
        let aspect = w / h;
        let tan_half = u.cam_right[3];
        let sx = (2.0 * (px as f32 + 0.5) / w - 1.0) * aspect * tan_half;
        let sy = (1.0 - 2.0 * (py as f32 + 0.5) / h) * tan_half;
        let forward = Vec3::from_slice(&u.cam_forward[..3]);
        let d = forward
            + Vec3::from_slice(&u.cam_right[..3]) * sx
            + Vec3::from_slice(&u.cam_up[..3]) * sy;
        let l2 = d.dot(d);
        if l2 > 0.0 && l2 <= 3.0e38 {
            return d / l2.sqrt();
        }
        forward
    }

    /// What background pixel `(px, py)` shows, alpha 0 (as `background`): the environment
    /// cube is read without a feedback mark, as it is pinned resident, and filtered across
    /// face edges ([`Self::seamless_read`]).
    fn background(&self, px: u32, py: u32) -> [f32; 4] {
        let u = &self.uniform;
        let c = match u.background {
            0 => return [0.0; 4],
            1 if u.env_cube == INVALID_INDEX => Vec3::ZERO,
            1 => self
                .seamless_read(u.env_cube, self.camera_ray(px, py))
                .unwrap_or(Vec3::ZERO),
            _ => Vec3::from_slice(&u.bg_color[..3]),
        };
        let c = finite3(c);
        [c.x, c.y, c.z, 0.0]
    }

    /// Shades pixel `(px, py)` with G-buffer texel `g`: the background with alpha 0 off the
    /// object, else the colour with alpha 1 (as `shade` in shade.wgsl).
    pub fn shade(&self, px: u32, py: u32, g: &GTexel) -> [f32; 4] {
        let u = &self.uniform;
        if g.position_patch[3] < 0.5 {
            return self.background(px, py);
        }
        let patch = (g.position_patch[3] - 0.5) as u32;
        let x = Vec3::new(
            g.position_patch[0],
            g.position_patch[1],
            g.position_patch[2],
        );
        let (pu, pv) = (g.normal_uv[2], g.normal_uv[3]);
        let ni = crate::geometry::oct_decode([g.normal_uv[0], g.normal_uv[1]]);
        let n = self
            .patches
            .get(patch as usize)
            .map_or(ni, |p| patch_normal(p, pu, pv, ni));
        let c = self.candidates(patch, pu, pv, x, n);
        let v = (Vec3::from_slice(&u.camera_pos[..3]) - x).normalize();
        let r = 2.0 * n.dot(v) * n - v; // Eq. 2.4
        let pixel = pcg(px.wrapping_add(pcg(py.wrapping_add(pcg(u.seed)))));
        let mut spec = Vec3::ZERO;
        if u.terms & 2 != 0 {
            spec = self.mirror(&c, x, n, r);
        } else if u.terms & 4 != 0 {
            let du = self
                .patches
                .get(patch as usize)
                .map_or(Vec3::ZERO, |p| patch_du(p, pu, pv));
            let t = tangent_frame(n, du);
            spec = self.glossy(&c, pixel, x, n, t, v, r);
        }
        if u.terms & 8 != 0 {
            spec *= self
                .colors
                .get(patch as usize)
                .copied()
                .unwrap_or(Vec3::ONE);
        }
        let mut color = spec;
        if u.terms & 1 != 0 {
            color += self.recon(&c, x, n); // Eq. 3.12, 4.12
        }
        let c = finite3(color);
        [c.x, c.y, c.z, 1.0]
    }
}

/// Every cube of a store as the GPU pool holds it, decoded to linear RGB: every mip level
/// and the distance planes ([`FaceLayout`]). The reference's view of "everything resident".
pub struct StoreCubes {
    layout: FaceLayout,
    /// Per cube, per level: six faces of `side(level)²` texels.
    levels: Vec<Vec<Vec<Vec3>>>,
    /// Per cube: six distance planes of `res²` (empty without a distance channel).
    depth: Vec<Vec<f32>>,
    /// Optional residency masks (the GPU cache's indirection table): a face is available
    /// only where its bit is set.
    pub masks: Option<Vec<u32>>,
}

impl StoreCubes {
    /// Decodes every cube of `store` (in parallel) as a renderer on an adapter with BC texture
    /// compression uploads them (BC6H stores as their blocks; the other encodings do not
    /// depend on it). To match a given renderer, use [`StoreCubes::decode_as`] with its
    /// [`crate::Renderer::face_layout`]. Errors name the cube.
    pub fn decode(store: &oslf_format::Store) -> crate::Result<Self> {
        Self::decode_as(store, FaceLayout::for_store(store, true))
    }

    /// Decodes every cube of `store` built as `layout` says (the GPU's payloads: for BC6H the
    /// specification's decoder, what the hardware returns). Errors name the cube.
    pub fn decode_as(store: &oslf_format::Store, layout: FaceLayout) -> crate::Result<Self> {
        use rayon::prelude::*;
        type Cube = (Vec<Vec<Vec3>>, Vec<f32>);
        let cubes = (0..store.cube_count())
            .into_par_iter()
            .map(|cube| -> crate::Result<Cube> {
                let err = |source| crate::RuntimeError::Cube { cube, source };
                let mut levels = vec![Vec::new(); layout.levels as usize];
                let mut depth = Vec::new();
                for face in 0..6u8 {
                    let payload = layout.build(store, cube, face).map_err(err)?;
                    for (l, level) in levels.iter_mut().enumerate() {
                        let rgb = layout.decode_level(&payload, l as u32).map_err(err)?;
                        level.extend(rgb.into_iter().map(Vec3::from_array));
                    }
                    depth.extend(layout.decode_depth(&payload));
                }
                Ok((levels, depth))
            })
            .collect::<crate::Result<Vec<Cube>>>()?;
        let (levels, depth) = cubes.into_iter().unzip();
        Ok(Self {
            layout,
            levels,
            depth,
            masks: None,
        })
    }

    fn available(&self, cube: u32, face: usize) -> bool {
        match &self.masks {
            Some(m) => m.get(cube as usize).copied().unwrap_or(0) & (1 << face) != 0,
            None => true,
        }
    }
}

impl CubeTexels for StoreCubes {
    fn texel(&self, cube: u32, face: usize, level: u32, x: u32, y: u32) -> Option<Vec3> {
        if !self.available(cube, face) {
            return None;
        }
        let n = self.layout.side(level) as usize;
        self.levels
            .get(cube as usize)?
            .get(level as usize)?
            .get(face * n * n + y as usize * n + x as usize)
            .copied()
    }

    fn depth(&self, cube: u32, face: usize, x: u32, y: u32) -> Option<f32> {
        if !self.available(cube, face) {
            return None;
        }
        let n = self.layout.res as usize;
        self.depth
            .get(cube as usize)?
            .get(face * n * n + y as usize * n + x as usize)
            .copied()
    }

    fn resident(&self, cube: u32) -> bool {
        match &self.masks {
            Some(m) => m.get(cube as usize).copied().unwrap_or(0) & 63 != 0,
            None => (cube as usize) < self.levels.len(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The constants of a store without sample points, maps or distances: environment cube
    /// `env_cube`, faces of `cube_res`².
    fn store_constants(env_cube: u32, cube_res: u32) -> crate::params::StoreConstants {
        crate::params::StoreConstants {
            sample_count: 0,
            env_cube,
            map_res: 1,
            index16: true,
            cube_res,
            slots_per_texture: 1,
            mip_levels: 1,
            has_depth: false,
            origin: [0.0; 3],
            fitted_box: None,
        }
    }

    #[test]
    fn tangent_frames_are_unit_and_orthogonal_even_where_du_vanishes() {
        for n in [
            Vec3::Z,
            -Vec3::Z,
            Vec3::new(0.6, 0.0, -0.8),
            Vec3::new(-1e-8, 1.0, 0.0).normalize(),
        ] {
            for du in [Vec3::ZERO, n * 3.0, Vec3::X, Vec3::new(1e-30, 0.0, 0.0)] {
                let t = tangent_frame(n, du);
                assert!(t.is_finite(), "{n} {du}");
                assert!((t.length() - 1.0).abs() < 1e-5, "{n} {du} {t}");
                assert!(t.dot(n).abs() < 1e-5, "{n} {du} {t}");
            }
        }
    }

    /// No cube is ever available.
    struct NoCubes;

    impl CubeTexels for NoCubes {
        fn texel(&self, _: u32, _: usize, _: u32, _: u32, _: u32) -> Option<Vec3> {
            None
        }
        fn depth(&self, _: u32, _: usize, _: u32, _: u32) -> Option<f32> {
            None
        }
        fn resident(&self, _: u32) -> bool {
            false
        }
    }

    #[test]
    fn camera_rays_are_the_cameras_directions_through_pixel_centres() {
        use crate::params::{Background, ShadeUniform, ShadingParams};
        use oslf_geometry::Camera;
        let k = store_constants(u32::MAX, 1);
        for (camera, (w, h)) in [
            (
                Camera {
                    position: Vec3::new(5.5, -6.5, 4.5),
                    target: Vec3::new(0.0, 0.0, 1.0),
                    up: Vec3::Z,
                    vfov_deg: 36.0,
                },
                (96, 72),
            ),
            (
                Camera {
                    position: Vec3::new(0.0, 0.0, 3.0),
                    target: Vec3::ZERO,
                    up: Vec3::Y,
                    vfov_deg: 150.0,
                },
                (7, 300),
            ),
        ] {
            let uniform = ShadeUniform::new(
                &ShadingParams::default(),
                glam::Mat4::IDENTITY,
                &camera,
                [w, h],
                &k,
                Background::Env,
            );
            let shader = bare_shader(uniform, &[], &NoCubes);
            for (i, j) in [
                (0, 0),
                (w - 1, 0),
                (w / 2, h / 2),
                (0, h - 1),
                (w - 1, h - 1),
            ] {
                let want = camera.direction(i as f32 + 0.5, j as f32 + 0.5, w, h);
                let got = shader.camera_ray(i, j);
                assert!((got - want).length() < 1e-6, "{i},{j}: {got} vs {want}");
            }
        }
    }

    #[test]
    fn background_pixels_have_alpha_zero_and_no_non_finite_colour() {
        use crate::params::{Background, ShadeUniform, ShadingParams};
        let k = store_constants(0, 1);
        let camera = oslf_geometry::Camera {
            position: Vec3::new(0.0, -3.0, 0.0),
            target: Vec3::ZERO,
            up: Vec3::Z,
            vfov_deg: 40.0,
        };
        for (bg, want) in [
            (Background::None, [0.0; 4]),
            (Background::Color([0.5, 1.0, 3.0]), [0.5, 1.0, 3.0, 0.0]),
            // Not resident: black, never a stale or non-finite value.
            (Background::Env, [0.0; 4]),
        ] {
            let shader = Shader {
                uniform: ShadeUniform::new(
                    &ShadingParams::default(),
                    glam::Mat4::IDENTITY,
                    &camera,
                    [4, 3],
                    &k,
                    bg,
                ),
                samples: &[],
                patches: &[],
                colors: &[],
                maps: &[],
                cubes: &NoCubes,
                feedback: &[],
            };
            assert_eq!(shader.shade(1, 2, &GTexel::default()), want, "{bg:?}");
        }
    }

    /// shade.wgsl's seam table (SEAM_LO, SEAM_HI, read from its source and decoded as its
    /// `seam_texel` does) gives the texel `seam_coords` finds by projection, for every texel
    /// one off a face's edge (corners aside), on faces of 1 to 1024 texels.
    #[test]
    fn shader_seam_table_matches_the_projection() {
        let src = include_str!("shade.wgsl");
        let table = |name: &str| -> [u32; 4] {
            let head = format!("const {name} = vec4<u32>(");
            let at = src.find(&head).expect(name) + head.len();
            let body = &src[at..at + src[at..].find(')').unwrap()];
            let v: Vec<u32> = body
                .split(',')
                .map(|w| {
                    let w = w.trim().trim_end_matches('u');
                    u32::from_str_radix(w.trim_start_matches("0x"), 16).unwrap()
                })
                .collect();
            v.try_into().unwrap()
        };
        let (lo, hi) = (table("SEAM_LO"), table("SEAM_HI"));
        let shader = |face: usize, x: i32, y: i32, n: i32| -> (usize, (i32, i32)) {
            let in_x = x >= 0 && x < n;
            let (e, a) = if in_x {
                (if y >= n { 3 } else { 2 }, x)
            } else {
                (if x >= n { 1 } else { 0 }, y.clamp(0, n - 1))
            };
            let code = if face == 5 {
                hi[e]
            } else {
                lo[e] >> (6 * face)
            } & 63;
            let along = if code & 16 != 0 { n - 1 - a } else { a };
            let fixed = if code & 32 != 0 { n - 1 } else { 0 };
            let c = if code & 8 != 0 {
                (along, fixed)
            } else {
                (fixed, along)
            };
            ((code & 7) as usize, c)
        };
        for n in [1, 2, 3, 4, 6, 8, 16, 48, 64, 256, 1024] {
            for face in 0..6 {
                for a in 0..n {
                    for (x, y) in [(-1, a), (n, a), (a, -1), (a, n)] {
                        assert_eq!(
                            shader(face, x, y, n),
                            seam_coords(face, (x, y), n),
                            "face {face}, texel ({x}, {y}) of {n}"
                        );
                    }
                }
            }
        }
    }

    #[test]
    fn face_points_invert_face_st() {
        for face in 0..6 {
            for (s, t) in [(0.5, 0.5), (0.1, 0.8), (0.97, 0.03), (0.02, 0.99)] {
                let p = face_point(face, s, t);
                let (f, s2, t2) = face_st(p);
                assert_eq!(f, face, "{face} {s} {t}");
                assert!(
                    (s2 - s).abs() < 1e-6 && (t2 - t).abs() < 1e-6,
                    "{face} {s} {t}"
                );
                let want = Vec3::from_array(oslf_format::cube::face_st_to_direction(face, s, t));
                assert!((p.normalize() - want).length() < 1e-6, "{face} {s} {t}");
            }
        }
    }

    /// A resident cube of resolution `n` whose texels are a smooth (linear) function of the
    /// directions through their centres.
    struct SmoothCube(u32);

    impl CubeTexels for SmoothCube {
        fn depth(&self, _: u32, _: usize, _: u32, _: u32) -> Option<f32> {
            None
        }
        fn texel(&self, _: u32, face: usize, _: u32, x: u32, y: u32) -> Option<Vec3> {
            assert!(face < 6 && x < self.0 && y < self.0, "{face} {x} {y}");
            let d = Vec3::from_array(oslf_format::cube::texel_direction(face, x, y, self.0));
            Some(Vec3::splat(0.5) + d * Vec3::new(0.4, 0.3, 0.2))
        }
        fn resident(&self, _: u32) -> bool {
            true
        }
    }

    /// The default shading (depth-corrected) of a store of `res`² cubes with distances and no
    /// environment cube.
    fn depth_uniform(res: u32) -> crate::params::ShadeUniform {
        use crate::params::{Background, ShadeUniform, ShadingParams};
        let mut k = store_constants(INVALID_INDEX, res);
        k.has_depth = true;
        let camera = oslf_geometry::Camera {
            position: Vec3::new(0.0, -5.0, 1.0),
            target: Vec3::ZERO,
            up: Vec3::Z,
            vfov_deg: 40.0,
        };
        let u = ShadeUniform::new(
            &ShadingParams::default(),
            glam::Mat4::IDENTITY,
            &camera,
            [4, 4],
            &k,
            Background::Env,
        );
        assert!(u.depth_steps > 0);
        u
    }

    /// A shader with no patches or sample maps: for the parts that need only cubes.
    fn bare_shader<'a, C: CubeTexels>(
        uniform: ShadeUniform,
        samples: &'a [Vec3],
        cubes: &'a C,
    ) -> Shader<'a, C> {
        Shader {
            uniform,
            samples,
            patches: &[],
            colors: &[],
            maps: &[],
            cubes,
            feedback: &[],
        }
    }

    /// A cube whose every face holds a near surface (distance 2, red) on its left half and
    /// nothing (blue) on its right: a silhouette down the middle of each face.
    struct Silhouette(u32);

    impl CubeTexels for Silhouette {
        fn depth(&self, _: u32, _: usize, x: u32, _: u32) -> Option<f32> {
            Some(if x < self.0 / 2 { 2.0 } else { FAR_DISTANCE })
        }
        fn texel(&self, _: u32, _: usize, _: u32, x: u32, _: u32) -> Option<Vec3> {
            Some(if x < self.0 / 2 { Vec3::X } else { Vec3::Z })
        }
        fn resident(&self, _: u32) -> bool {
            true
        }
    }

    /// A depth-corrected lookup at a silhouette takes the radiance of the surface its hit lies
    /// on, not the bilinear blend across the silhouette that a plain lookup gives: a hit at the
    /// near surface's distance reads red, a ray that meets nothing blue; a hit whose distance
    /// agrees with no texel, and a hidden one, the plain blend.
    #[test]
    fn depth_lookups_keep_the_hits_surface_at_a_silhouette() {
        let res = 8;
        let cubes = Silhouette(res);
        let shader = bare_shader(depth_uniform(res), &[Vec3::ZERO], &cubes);
        // Face +x at s = ½: halfway between texel columns 3 (near) and 4 (nothing).
        let dir = face_point(0, 0.5, 3.5 / res as f32).normalize();
        let (face, s, _) = face_st(dir);
        assert!(face == 0 && (s - 0.5).abs() < 1e-6, "{face} {s}");
        let plain = shader.lookup(0, dir).unwrap();
        assert!(
            (plain - Vec3::new(0.5, 0.0, 0.5)).length() < 1e-5,
            "{plain}"
        );
        let near = shader.depth_lookup(0, (dir * 2.0, 1.0), 0.0).unwrap();
        assert_eq!(near, Vec3::X);
        let none = shader.depth_lookup(0, (dir, 0.0), 0.0).unwrap();
        assert_eq!(none, Vec3::Z);
        let between = shader.depth_lookup(0, (dir * 50.0, 1.0), 0.0).unwrap();
        assert!((between - plain).length() < 1e-6, "{between}");
        let hidden = shader.depth_lookup(0, (dir, -1.0), 0.0).unwrap();
        assert!((hidden - plain).length() < 1e-6, "{hidden}");
    }

    /// A sample point's view of a ceiling at z = 10 (nothing below the horizon), or of a
    /// sphere of radius 3 around it (`sphere`).
    struct Ceiling {
        res: u32,
        p: Vec3,
        sphere: bool,
    }

    impl CubeTexels for Ceiling {
        fn depth(&self, _: u32, face: usize, x: u32, y: u32) -> Option<f32> {
            if self.sphere {
                return Some(3.0);
            }
            let d = Vec3::from_array(oslf_format::cube::texel_direction(face, x, y, self.res));
            Some(if d.z > 0.0 {
                (10.0 - self.p.z) / d.z * d.length()
            } else {
                FAR_DISTANCE
            })
        }
        fn texel(&self, _: u32, _: usize, _: u32, _: u32, _: u32) -> Option<Vec3> {
            Some(Vec3::ONE)
        }
        fn resident(&self, _: u32) -> bool {
            true
        }
    }

    /// A glossy sample's depth correction (`depth_iterate`) turns the direction from the
    /// shaded point into the one from the sample point to where the ray meets what the sample
    /// point sees: exactly on a sphere of equal distances, within a few texels' angle on a
    /// ceiling where the plain direction is off by ten times more; the plain direction for a
    /// ray that meets nothing, and for a shaded point outside the sphere.
    #[test]
    fn glossy_depth_correction_finds_where_the_ray_meets_the_stored_distances() {
        let res = 64;
        let p = Vec3::new(0.0, 0.0, 0.1);
        let x = Vec3::new(0.8, 0.3, 0.0);
        let l = Vec3::new(-0.6, 0.2, 1.0).normalize();
        let angle = |a: Vec3, b: Vec3| a.normalize().dot(b.normalize()).clamp(-1.0, 1.0).acos();
        let sphere = Ceiling {
            res,
            p,
            sphere: true,
        };
        let shader = bare_shader(depth_uniform(res), std::slice::from_ref(&p), &sphere);
        let mut seed = 0.0;
        let q = shader.depth_iterate(0, x, l, true, &mut seed);
        let along = q - (x - p);
        assert!((q.length() - 3.0).abs() < 1e-5, "{q}");
        assert!(angle(along, l) < 1e-3 && along.dot(l) > 0.0, "{q}");
        assert!((seed - 3.0).abs() < 1e-3, "{seed}");
        // The next sample of the row takes the sphere of that distance, reading nothing:
        // exact on the sphere; the plain direction without a seed.
        let l2 = Vec3::new(-0.5, 0.3, 1.0).normalize();
        let q2 = shader.depth_iterate(0, x, l2, false, &mut seed);
        assert!((q2.length() - 3.0).abs() < 1e-3, "{q2}");
        assert!(angle(q2 - (x - p), l2) < 1e-3, "{q2}");
        assert!(
            (seed - 3.0).abs() < 1e-3,
            "a warm sample keeps the seed: {seed}"
        );
        assert_eq!(shader.depth_iterate(0, x, l2, false, &mut 0.0), l2);
        let far = Vec3::new(3.0, 0.0, 0.0);
        let mut seed = 1.0;
        assert_eq!(shader.depth_iterate(0, far, l, true, &mut seed), l);
        assert_eq!(seed, 0.0, "no hit leaves no seed");

        let ceiling = Ceiling {
            res,
            p,
            sphere: false,
        };
        let shader = bare_shader(depth_uniform(res), std::slice::from_ref(&p), &ceiling);
        let hit = x + l * (10.0 / l.z) - p;
        let q = shader.depth_iterate(0, x, l, true, &mut 0.0);
        let texel = std::f32::consts::FRAC_PI_2 / res as f32;
        assert!(
            angle(q, hit) < 3.0 * texel,
            "{} texels",
            angle(q, hit) / texel
        );
        assert!(
            angle(l, hit) > 10.0 * angle(q, hit),
            "{} {}",
            angle(l, hit),
            angle(q, hit)
        );
        let down = Vec3::new(0.3, 0.0, -1.0).normalize();
        assert_eq!(shader.depth_iterate(0, x, down, true, &mut 0.0), down);
    }

    /// Two sample points over a ceiling 10 away (blue), with a small plate halfway (red) that
    /// only the first one's cube holds (too thin for the second's texels, say).
    struct TwoViews {
        res: u32,
        points: [Vec3; 2],
    }

    impl TwoViews {
        fn trace(&self, cube: u32, face: usize, x: u32, y: u32) -> (f32, Vec3) {
            let d = Vec3::from_array(oslf_format::cube::texel_direction(face, x, y, self.res));
            let p = self.points[cube as usize];
            if d.z <= 0.0 {
                return (FAR_DISTANCE, Vec3::Y);
            }
            let t = (5.0 - p.z) / d.z;
            let q = p + d * t;
            if cube == 0 && q.x * q.x + q.y * q.y < 0.25 {
                return (t * d.length(), Vec3::X);
            }
            ((10.0 - p.z) / d.z * d.length(), Vec3::Z)
        }
    }

    impl CubeTexels for TwoViews {
        fn depth(&self, cube: u32, face: usize, x: u32, y: u32) -> Option<f32> {
            Some(self.trace(cube, face, x, y).0)
        }
        fn texel(&self, cube: u32, face: usize, _: u32, x: u32, y: u32) -> Option<Vec3> {
            Some(self.trace(cube, face, x, y).1)
        }
        fn resident(&self, _: u32) -> bool {
            true
        }
    }

    /// The candidates agree on the nearest hit their searches find: the plate that one
    /// candidate's cube resolves is what the blend shows, the other candidate (whose distances
    /// do not see the plate's point) left out, not a mix of plate and ceiling.
    #[test]
    fn depth_corrected_blends_agree_on_the_nearest_hit() {
        let res = 64;
        let uniform = depth_uniform(res);
        let points = [Vec3::new(0.1, 0.0, 0.1), Vec3::new(-0.1, 0.0, 0.1)];
        let cubes = TwoViews { res, points };
        let shader = bare_shader(uniform, &points, &cubes);
        let x = Vec3::ZERO;
        let c = Candidates {
            idx: [0, 1, INVALID_INDEX, INVALID_INDEX],
            s: [
                points[0].normalize(),
                points[1].normalize(),
                Vec3::Z,
                Vec3::Z,
            ],
            count: 2,
        };
        // Each candidate alone: the plate (the first), the ceiling (the second).
        let first = shader
            .blend_read(&c, [1.0, 0.0, 0.0, 0.0], x, Vec3::Z, 0.0)
            .unwrap();
        let second = shader
            .blend_read(&c, [0.0, 1.0, 0.0, 0.0], x, Vec3::Z, 0.0)
            .unwrap();
        assert!((first - Vec3::X).length() < 1e-5, "{first}");
        assert!((second - Vec3::Z).length() < 1e-5, "{second}");
        // Together, with the second weighted three times the first: the plate.
        let both = shader
            .blend_read(&c, [0.25, 0.75, 0.0, 0.0], x, Vec3::Z, 0.0)
            .unwrap();
        assert!((both - Vec3::X).length() < 1e-5, "{both}");
        // A ray past the plate's edge meets the ceiling for both.
        let past = Vec3::new(0.3, 0.0, 1.0).normalize();
        let both = shader
            .blend_read(&c, [0.25, 0.75, 0.0, 0.0], x, past, 0.0)
            .unwrap();
        assert!((both - Vec3::Z).length() < 1e-5, "{both}");
    }

    /// Filtered samples for M = n² are the grid's stratum centres through the concentric map:
    /// mapped back to the square (the map's inverse), sample i lands at the centre of cell i;
    /// every (ξ1, ξ2) lies in [0, 1)², and other M take the Hammersley set.
    #[test]
    fn filtered_samples_are_concentric_stratum_centres() {
        for n in [1u32, 2, 3, 4, 5, 8, 16] {
            let m = n * n;
            for i in 0..m {
                let [x1, x2] = filter_xi(i, m);
                assert!(
                    (0.0..1.0).contains(&x1) && (0.0..1.0).contains(&x2),
                    "{m} {i}"
                );
                // Polar (r, φ) on the disc back to the square [-1, 1]² (Shirley & Chiu).
                let (r, mut phi) = (x2.sqrt(), 2.0 * PI * x1);
                if phi > 1.75 * PI {
                    phi -= 2.0 * PI;
                }
                let (a, b) = if phi < 0.25 * PI {
                    (r, r * phi / (0.25 * PI))
                } else if phi < 0.75 * PI {
                    (-r * (phi - 0.5 * PI) / (0.25 * PI), r)
                } else if phi < 1.25 * PI {
                    (-r, -r * (phi - PI) / (0.25 * PI))
                } else {
                    (r * (phi - 1.5 * PI) / (0.25 * PI), -r)
                };
                let cell = |c: f32| (c + 1.0) * 0.5 * n as f32;
                let (ca, cb) = (cell(a), cell(b));
                assert!(
                    (ca - ((i % n) as f32 + 0.5)).abs() < 1e-4
                        && (cb - ((i / n) as f32 + 0.5)).abs() < 1e-4,
                    "m {m} sample {i}: cell ({ca}, {cb})"
                );
            }
        }
        assert_eq!(filter_xi(3, 12), [3.5 / 12.0, 0.75]);
    }

    /// The shading normal is the patch's own (as the geometry crate evaluates it, to f32
    /// rounding), facing as the interpolated normal it is given, and that normal where the
    /// patch's degenerates (an atlas page's zero control points) or turns more than 25° away.
    #[test]
    fn patch_normals_are_the_patchs_own_facing_as_the_vertex_normal() {
        let teapot = oslf_geometry::bezier::newell_teapot();
        let mut compared = 0;
        for p in &teapot {
            for (u, v) in [(0.3, 0.6), (0.5, 0.5), (0.9, 0.15), (0.05, 0.95)] {
                let exact = p.normal(u, v);
                let du = patch_du(p, u, v);
                let dv = patch_dv(p, u, v);
                if du.cross(dv).length() < 1e-3 * du.length() * dv.length() {
                    continue; // near a collapsed edge: f32 derivatives lose digits
                }
                let tilt = (exact + Vec3::new(0.05, -0.03, 0.02)).normalize();
                let n = patch_normal(p, u, v, tilt);
                assert!((n - exact).length() < 1e-4, "{n} {exact}");
                let flipped = patch_normal(p, u, v, -tilt);
                assert!((flipped + exact).length() < 1e-4, "{flipped} {exact}");
                let far = (exact + tilt.any_orthonormal_vector()).normalize();
                assert_eq!(patch_normal(p, u, v, far), far);
                compared += 1;
            }
        }
        assert!(compared > 100, "{compared}");
        let page = BezierPatch::new([Vec3::ZERO; 16]);
        assert_eq!(patch_normal(&page, 0.5, 0.5, Vec3::Y), Vec3::Y);
    }

    /// The environment background is as continuous across face edges as inside a face: the
    /// largest difference between adjacent pixels whose rays lie on different faces is at most
    /// `FACTOR` times the largest between adjacent pixels on one face. (Clamped bilinear
    /// filtering within each face, as `lookup` does, shows a seam 5-20 times larger.)
    #[test]
    fn the_env_background_is_continuous_across_face_edges() {
        use crate::params::{Background, ShadeUniform, ShadingParams};
        use oslf_geometry::Camera;
        const FACTOR: f32 = 1.5;
        let (w, h) = (160u32, 120u32);
        for res in [8, 32] {
            let k = store_constants(0, res);
            // Views across edges of every orientation, vertical and horizontal in the image,
            // and across a corner of the cube.
            for (target, up) in [
                (Vec3::new(1.0, 0.05, 1.0), Vec3::Y),
                (Vec3::new(1.0, 1.0, 0.1), Vec3::Z),
                (Vec3::new(-1.0, -1.0, -0.2), Vec3::Z),
                (Vec3::new(0.1, 1.0, 1.0), Vec3::X),
                (Vec3::new(0.2, -1.0, -1.0), Vec3::X),
                (Vec3::new(1.0, 1.0, 1.0), Vec3::Z),
            ] {
                let camera = Camera {
                    position: Vec3::ZERO,
                    target,
                    up,
                    vfov_deg: 50.0,
                };
                let shader = Shader {
                    uniform: ShadeUniform::new(
                        &ShadingParams::default(),
                        glam::Mat4::IDENTITY,
                        &camera,
                        [w, h],
                        &k,
                        Background::Env,
                    ),
                    samples: &[],
                    patches: &[],
                    colors: &[],
                    maps: &[],
                    cubes: &SmoothCube(res),
                    feedback: &[],
                };
                let px = |i: u32, j: u32| {
                    let c = shader.shade(i, j, &GTexel::default());
                    assert!(c.iter().all(|x| x.is_finite()) && c[3] == 0.0, "{c:?}");
                    (
                        face_st(shader.camera_ray(i, j)).0,
                        Vec3::new(c[0], c[1], c[2]),
                    )
                };
                let img: Vec<_> = (0..h).flat_map(|j| (0..w).map(move |i| (i, j))).collect();
                let img: Vec<_> = img.into_iter().map(|(i, j)| px(i, j)).collect();
                let (mut seam, mut inside, mut seam_pairs) = (0f32, 0f32, 0);
                for j in 0..h {
                    for i in 0..w {
                        let a = img[(j * w + i) as usize];
                        for (di, dj) in [(1, 0), (0, 1)] {
                            if i + di >= w || j + dj >= h {
                                continue;
                            }
                            let b = img[((j + dj) * w + i + di) as usize];
                            let d = (a.1 - b.1).abs().max_element();
                            if a.0 == b.0 {
                                inside = inside.max(d);
                            } else {
                                seam = seam.max(d);
                                seam_pairs += 1;
                            }
                        }
                    }
                }
                println!("res {res} {target}: across edges {seam:.2e}, inside {inside:.2e}");
                assert!(
                    seam_pairs > w.min(h) as usize / 2,
                    "{target}: no face edge in view"
                );
                assert!(
                    inside > 0.0 && seam <= FACTOR * inside,
                    "res {res} {target}: a seam of {seam} where one face varies by {inside}"
                );
            }
        }
    }

    #[test]
    fn fresnel_is_schlick_at_both_ends() {
        assert_eq!(fresnel(0.04, 1.0), 0.04);
        assert!((fresnel(0.04, 0.0) - 1.0).abs() < 1e-6);
        assert!((fresnel(0.04, -0.5) - 1.0).abs() < 1e-6);
    }
}
