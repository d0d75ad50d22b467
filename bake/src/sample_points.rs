//! OSLF sample points: spread over the objects' surfaces (Bézier patches and mesh triangles,
//! [`crate::surface`]) with controlled coverage, offset by ε along the geometric normal of the
//! face each lies on (thesis §3.1; a mesh's smooth shading normal would tilt points near a hard
//! edge towards the neighbouring face and closer than ε to it),
//! and culled where the free-space condition fails (§3.3), or, with `near_surface = "lower"`,
//! lowered towards their own surface where another surface is near ([`NEAR_CLEARANCE`]).
//!
//! Placement is *weighted sample elimination* (Yuksel 2015, "Sample Elimination for Generating
//! Poisson Disk Sample Sets"): many candidates are drawn uniformly by area over all surfaces, then
//! the one most crowded by its neighbours is removed until the requested count remains. The
//! result is a Poisson-disk set of exactly the requested size, deterministic for a seed.

use std::cmp::Ordering;
use std::collections::BinaryHeap;
use std::num::NonZero;

use glam::Vec3;
use kiddo::{ImmutableKdTree, SquaredEuclidean};
use oslf_format::SamplePoint;
use rayon::prelude::*;

use crate::pilot::{pilot_count, prediction_errors, Pilot, PilotCapture};
use crate::sample_map::{enclosed, VISIBILITY_LIFT};
pub use crate::surface::Surfaces;
use crate::surface::{MapDomain, SurfacePoint};
use oslf_scene::error::{BakeError, Result};
use oslf_scene::scene::{BakeSettings, NearSurface, PointPlacement, SampleDensity, Scene};
use oslf_shading::random::Rng;
use oslf_trace::bvh::TriangleScene;
use oslf_trace::capture::{capture_cube_with_noise, CaptureSettings};
use oslf_trace::integrator::Integrator;
use oslf_trace::ray::{Intersector, Ray};
/// Candidates drawn per requested point.
const CANDIDATES_PER_POINT: usize = 6;
/// Directions probed around each sample point by the free-space tests.
const PROBE_DIRECTIONS: usize = 64;
/// A point is "closer than ε to another surface" when a probe hits within this fraction of ε.
/// The margin below 1 absorbs the tessellation error (at most ε/50) of the point's own patch.
pub const FREE_SPACE_TOLERANCE: f32 = 0.95;

/// How many times [`NearSurface::Lower`] halves a point's height at most (to ε/8).
pub const NEAR_LOWERINGS: u32 = 3;

/// [`NearSurface::Lower`] lowers a point until every other surface in the half-space it faces
/// lies at least this many times its height away (docs/measurements.md, "Points lowered near a
/// contact": 3 against 2 on the can, over three seeds).
pub const NEAR_CLEARANCE: f32 = 3.0;

/// Rounds of [`refine`] the bake runs at most.
pub const REFINE_ROUNDS: usize = 3;

/// The outcome of [`place`].
#[derive(Clone, Debug, Default)]
pub struct Placement {
    /// The kept points, in a deterministic order (patch, then elimination order).
    pub points: Vec<SamplePoint>,
    /// Points placed before the free-space tests.
    pub placed: usize,
    /// Removed: closer than ε to some surface.
    pub removed_close: usize,
    /// Removed: inside geometry.
    pub removed_inside: usize,
    /// Kept nearer their surface than ε, near another ([`NearSurface::Lower`]).
    pub lowered: usize,
    /// Total surface area of the OSLF objects.
    pub area: f32,
    /// Poisson-disk radius of the placement (about half the typical spacing).
    pub radius: f32,
    /// Points added by [`refine`] where sample-map texels found fewer than four.
    pub added: usize,
    /// Pilot cubes captured by [`PointPlacement::Adaptive`] ([`crate::pilot`]).
    pub pilot_cubes: usize,
    /// Rays cast by the free-space tests and the pilot cubes.
    pub rays: u64,
}

/// Places sample points over every map domain of `surfaces` (patches and mesh triangles),
/// offsets them and removes invalid ones. [`PointPlacement::Adaptive`] needs the scene's
/// light, [`place_lit`]'s: here it is an error.
pub fn place(
    surfaces: &Surfaces,
    settings: &BakeSettings,
    geometry: &impl Intersector,
) -> Result<Placement> {
    place_lit(surfaces, settings, geometry, None)
}

/// [`place`], with `pilot` capturing the pilot cubes of [`PointPlacement::Adaptive`]
/// ([`crate::pilot`]; the bake's own CPU path tracer over the same scene).
pub fn place_lit(
    surfaces: &Surfaces,
    settings: &BakeSettings,
    geometry: &impl Intersector,
    pilot: Option<&PilotCapture>,
) -> Result<Placement> {
    let area = surfaces.area();
    if area.is_nan() || area <= 0.0 {
        return Err(BakeError::Invalid(
            "the OSLF objects have zero surface area: no sample points can be placed".into(),
        ));
    }
    let mut rng = Rng::new(settings.seed, PLACEMENT_STREAM);
    let mut radius = f32::INFINITY;
    let mut chosen: Vec<SurfacePoint> = Vec::new();
    let (mut pilot_cubes, mut pilot_rays) = (0usize, 0u64);
    for group in groups(surfaces, settings)? {
        let draw = |rng: &mut Rng| match group.objects.as_slice() {
            [] => surfaces.sample(rng),
            [o] => surfaces.sample_object(*o, rng),
            several => {
                // An object by area, then a point on it.
                let mut target = rng.next_f32() * group.area;
                let o = several
                    .iter()
                    .copied()
                    .find(|&o| {
                        target -= surfaces.object_area(o);
                        target < 0.0
                    })
                    .unwrap_or(several[several.len() - 1]);
                surfaces.sample_object(o, rng)
            }
        };
        let (kept, candidates, area) = match settings.placement {
            PointPlacement::Uniform => {
                let candidates: Vec<SurfacePoint> = (0..group.count * CANDIDATES_PER_POINT)
                    .map(|_| draw(&mut rng))
                    .collect();
                let kept = eliminate(&candidates, None, group.count, group.area);
                (kept, candidates, group.area)
            }
            PointPlacement::Parallax | PointPlacement::Adaptive => {
                // Uniform draws thinned to a density ∝ 1/scale² (scale 0.5 always kept).
                let draws: Vec<SurfacePoint> =
                    (0..group.count * CANDIDATES_PER_POINT * PARALLAX_DRAWS)
                        .map(|_| draw(&mut rng))
                        .collect();
                let scales = if settings.placement == PointPlacement::Parallax {
                    parallax_scales(&draws, geometry, settings.epsilon, group.area)
                } else {
                    let Some(pilot) = pilot else {
                        return Err(BakeError::Invalid(
                            "placement \"adaptive\" captures pilot cubes: it needs the scene's \
                             light (sample_points::place_lit)"
                                .into(),
                        ));
                    };
                    let (scales, pilots, rays) =
                        adaptive_scales(&draws, group.count, group.area, settings, geometry, pilot);
                    pilot_cubes += pilots;
                    pilot_rays += rays;
                    scales
                };
                // The area the points cover at unit scale: ∫ 1/scale² dA.
                let area = group.area * scales.iter().map(|s| 1.0 / (s * s)).sum::<f32>()
                    / scales.len().max(1) as f32;
                let keep_all = PARALLAX_SCALE.0 * PARALLAX_SCALE.0;
                let (candidates, kept_scales): (Vec<SurfacePoint>, Vec<f32>) = draws
                    .iter()
                    .zip(&scales)
                    .filter(|(_, s)| rng.next_f32() * s.powi(2) < keep_all)
                    .map(|(c, s)| (*c, *s))
                    .unzip();
                let kept = eliminate(&candidates, Some(&kept_scales), group.count, area);
                (kept, candidates, area)
            }
        };
        chosen.extend(kept.iter().map(|&i| candidates[i]));
        radius = radius.min(poisson_radius(area, group.count));
    }

    let mut placement = Placement {
        placed: chosen.len(),
        area,
        radius,
        pilot_cubes,
        ..Default::default()
    };
    let directions = fibonacci_sphere(PROBE_DIRECTIONS);
    for c in &chosen {
        let (outcome, kept) = offset_draw(geometry, c, settings, &directions);
        match (outcome, kept) {
            (_, Some(kept)) => {
                placement.lowered += usize::from(kept.lowered);
                placement.points.push(SamplePoint {
                    position: kept.position.to_array(),
                    normal: c.offset.to_array(),
                    uv: c.uv.to_array(),
                    patch: c.map,
                    object: c.object,
                });
            }
            (FreeSpace::Inside, None) => placement.removed_inside += 1,
            _ => placement.removed_close += 1,
        }
    }
    placement.rays = (chosen.len() * PROBE_DIRECTIONS * 2) as u64 + pilot_rays;
    if placement.points.is_empty() {
        return Err(BakeError::Invalid(format!(
            "all {} sample points were removed ({} closer than ε = {} to a surface, {} inside geometry)",
            chosen.len(),
            placement.removed_close,
            settings.epsilon,
            placement.removed_inside
        )));
    }
    Ok(placement)
}

/// [`place_lit`] for `scene` (whose objects `surfaces` are, traced in `geometry`), the pilot
/// cubes of an adaptive placement captured by the bake's CPU path tracer whatever the bake's
/// capture device, so that the points are the same on every device.
pub fn place_in(scene: &Scene, surfaces: &Surfaces, geometry: &TriangleScene) -> Result<Placement> {
    if scene.bake.placement != PointPlacement::Adaptive {
        return place(surfaces, &scene.bake, geometry);
    }
    let integrator = Integrator::for_scene(scene, geometry);
    let settings = crate::pilot::capture_settings(&CaptureSettings::from_bake(&scene.bake));
    let pilot = |position: Vec3, index: u32| {
        let (cube, rays, noise) = capture_cube_with_noise(&integrator, position, index, &settings);
        let noise = noise.relative_error().unwrap_or(0.0) as f32;
        (cube, noise, rays.closest + rays.shadow)
    };
    place_lit(surfaces, &scene.bake, geometry, Some(&pilot))
}

/// Points placed together by one weighted sample elimination, drawn over `objects` (all of
/// them where it is empty): the objects at the bake's density, or one object at its own
/// `sample_spacing`.
struct Group {
    objects: Vec<usize>,
    count: usize,
    area: f32,
}

/// Points for `area` at spacing `h` (hexagonal packing: each point covers (√3/2)·h²), within
/// 1 to 16 million; `what` names the key in the error.
fn spacing_count(area: f32, h: f32, what: &str) -> Result<usize> {
    let n = (area / (0.866_025_4 * h * h)).ceil();
    if !(1.0..=16e6).contains(&n) {
        return Err(BakeError::Invalid(format!(
            "{what} {h} gives {n} points over an area of {area} (allowed: 1 to 16 million)"
        )));
    }
    Ok(n as usize)
}

/// The placement groups: one for the bake's density, then one per object with a
/// `sample_spacing` of its own, in object order. Without such objects, one group over all
/// of them (the placement is then what it was before per-object spacings existed).
fn groups(surfaces: &Surfaces, settings: &BakeSettings) -> Result<Vec<Group>> {
    let objects = surfaces.objects();
    let own: Vec<usize> = (0..objects.len())
        .filter(|&o| objects[o].sample_spacing.is_some())
        .collect();
    let shared_area = if own.is_empty() {
        surfaces.area()
    } else {
        (0..objects.len())
            .filter(|o| !own.contains(o))
            .map(|o| surfaces.object_area(o))
            .sum()
    };
    let mut groups = Vec::new();
    if own.len() < objects.len() {
        let count = match settings.sample_count {
            SampleDensity::Count(n) => n as usize,
            SampleDensity::Spacing(h) => spacing_count(shared_area, h, "sample_spacing")?,
        };
        let shared = if own.is_empty() {
            Vec::new()
        } else {
            (0..objects.len()).filter(|o| !own.contains(o)).collect()
        };
        groups.push(Group {
            objects: shared,
            count,
            area: shared_area,
        });
    }
    for o in own {
        let area = surfaces.object_area(o);
        let what = format!("object {:?}: sample_spacing", objects[o].name);
        let count = spacing_count(area, surfaces.spacing(o), &what)?;
        groups.push(Group {
            objects: vec![o],
            count,
            area,
        });
    }
    Ok(groups)
}

/// The placement RNG's stream id (cube-map texels use hashed streams of their own).
const PLACEMENT_STREAM: u64 = 0x0051_a3c1_e5ee_d000;

/// Uniform draws per candidate of a parallax placement, thinned by their spacing scale.
const PARALLAX_DRAWS: usize = 4;
/// Probe rays per draw of a parallax placement (the directions of a Fibonacci sphere of twice
/// as many above its surface).
const PARALLAX_RAYS: usize = 16;
/// The limits of a parallax placement's spacing, relative to its typical spacing.
pub const PARALLAX_SCALE: (f32, f32) = (0.5, 2.0);

/// Each draw's spacing scale in a parallax placement: the harmonic mean distance to what it
/// sees over the hemisphere of its offset (probe rays from ε above it; a ray that escapes counts
/// as 4 × √`area`, far for these objects), over the geometric mean of all draws, within
/// [`PARALLAX_SCALE`]. A mirror reflection's parallax between two points is their spacing over
/// that distance: spacing ∝ distance keeps it even.
fn parallax_scales(
    draws: &[SurfacePoint],
    geometry: &impl Intersector,
    epsilon: f32,
    area: f32,
) -> Vec<f32> {
    let far = 4.0 * area.sqrt();
    let directions = fibonacci_sphere(2 * PARALLAX_RAYS);
    let distance: Vec<f32> = draws
        .iter()
        .map(|c| {
            let origin = c.position + c.offset * epsilon;
            let (mut inverse, mut n) = (0.0f32, 0u32);
            for &dir in directions.iter().filter(|d| d.dot(c.offset) > 0.0) {
                let t = geometry
                    .intersect(&Ray::new(origin, dir), far)
                    .map_or(far, |h| h.t.max(epsilon));
                inverse += 1.0 / t;
                n += 1;
            }
            if n == 0 {
                far
            } else {
                n as f32 / inverse
            }
        })
        .collect();
    let log_mean = distance.iter().map(|d| d.ln()).sum::<f32>() / distance.len().max(1) as f32;
    let typical = log_mean.exp();
    distance
        .iter()
        .map(|d| (d / typical).clamp(PARALLAX_SCALE.0, PARALLAX_SCALE.1))
        .collect()
}

/// Each draw's spacing scale in an adaptive placement ([`crate::pilot`]): pilot cubes at a
/// coarse Poisson-disk subset of the draws ([`pilot_count`] of the `count` points, ε above
/// them as [`place`] puts points), each pilot's leave-one-out prediction error, and each draw
/// taking its nearest pilot's (of its object). The scale is the error's inverse square root
/// over the draws' geometric mean of it, within [`PARALLAX_SCALE`]: where interpolating between
/// points errs as the square of their spacing, that evens the error out. Returns the scales,
/// the pilot cubes captured and their rays.
fn adaptive_scales(
    draws: &[SurfacePoint],
    count: usize,
    area: f32,
    settings: &BakeSettings,
    geometry: &impl Intersector,
    capture: &PilotCapture,
) -> (Vec<f32>, usize, u64) {
    let wanted = pilot_count(count);
    let directions = fibonacci_sphere(PROBE_DIRECTIONS);
    // A uniform placement's elimination over as many draws per pilot as one of points: more
    // would break more near-ties of its weights differently at another scale.
    let pool = &draws[..(wanted * CANDIDATES_PER_POINT).min(draws.len())];
    let sites: Vec<(usize, Vec3)> = eliminate(pool, None, wanted, area)
        .into_par_iter()
        .filter_map(|i| {
            let (_, kept) = offset_draw(geometry, &draws[i], settings, &directions);
            kept.map(|k| (i, k.position))
        })
        .collect();
    let captured: Vec<(Pilot, u64)> = sites
        .par_iter()
        .map(|&(i, position)| {
            // The draw's index picks the random streams: a pilot removed by the free-space
            // tests at one scale and not another leaves the others' cubes the same.
            let (cube, noise, rays) = capture(position, i as u32);
            let c = &draws[i];
            let pilot = Pilot {
                position,
                normal: c.offset,
                object: c.object,
                cube,
                noise,
            };
            (pilot, rays)
        })
        .collect();
    let rays =
        captured.iter().map(|(_, r)| r).sum::<u64>() + (sites.len() * PROBE_DIRECTIONS * 2) as u64;
    let (pilots, _): (Vec<Pilot>, Vec<u64>) = captured.into_iter().unzip();
    if pilots.is_empty() {
        return (vec![1.0; draws.len()], 0, rays);
    }
    let errors = prediction_errors(&pilots);
    // Each draw's nearest pilot of its own object (else the nearest).
    let bases: Vec<[f32; 3]> = sites
        .iter()
        .map(|&(i, _)| draws[i].position.to_array())
        .collect();
    let tree: ImmutableKdTree<f32, 3> = ImmutableKdTree::new_from_slice(&bases);
    let nearest = NonZero::new(8.min(pilots.len())).expect("at least one pilot");
    let floor = 1e-4f32;
    let error: Vec<f32> = draws
        .par_iter()
        .map(|d| {
            let found = tree.nearest_n::<SquaredEuclidean>(&d.position.to_array(), nearest);
            let own = found
                .iter()
                .find(|nb| pilots[nb.item as usize].object == d.object)
                .unwrap_or(&found[0]);
            errors[own.item as usize].max(floor)
        })
        .collect();
    let log_mean = error.iter().map(|e| e.ln()).sum::<f32>() / error.len().max(1) as f32;
    let typical = log_mean.exp();
    // In steps of an eighth of an octave: the pilots' errors carry Monte Carlo noise, and the
    // same scene at another scale rounds its paths differently; steps keep the scales, and
    // so the points, the same unless an error crosses a step.
    let scales = error
        .iter()
        .map(|e| {
            let octaves = (0.5 * (typical / e).log2() * SCALE_STEPS).round() / SCALE_STEPS;
            octaves.exp2().clamp(PARALLAX_SCALE.0, PARALLAX_SCALE.1)
        })
        .collect();
    (scales, pilots.len(), rays)
}

/// Steps per octave of an adaptive placement's spacing scales.
const SCALE_STEPS: f32 = 8.0;

/// Weighted sample elimination down to `target` points; returns kept candidate indices in
/// ascending order. With `scales`, each candidate's distances count in units of its spacing
/// scale (the mean of the pair's), and `area` is the area at unit scale: a point removes its
/// neighbours within a radius that grows with its scale.
fn eliminate(
    candidates: &[SurfacePoint],
    scales: Option<&[f32]>,
    target: usize,
    area: f32,
) -> Vec<usize> {
    let m = candidates.len();
    if m <= target {
        return (0..m).collect();
    }
    let r_max = poisson_radius(area, target);
    let r_min = r_max * (1.0 - (target as f32 / m as f32).powf(1.5)) * 0.65;
    let radius = 2.0 * r_max;
    let weight = |d: f32| {
        let d = d.max(r_min);
        (1.0 - d / radius).max(0.0).powi(8)
    };
    let scale = |i: usize| scales.map_or(1.0, |s| s[i]);
    let reach = radius * scales.map_or(1.0, |_| PARALLAX_SCALE.1);

    let positions: Vec<[f32; 3]> = candidates.iter().map(|c| c.position.to_array()).collect();
    let tree: ImmutableKdTree<f32, 3> = ImmutableKdTree::new_from_slice(&positions);
    let max_items = NonZero::new(m).expect("m > target >= 0 so m >= 1");
    let neighbours: Vec<Vec<(u32, f32)>> = positions
        .iter()
        .enumerate()
        .map(|(i, p)| {
            let mut list: Vec<(u32, f32)> = tree
                .nearest_n_within::<SquaredEuclidean>(p, reach * reach, max_items, false)
                .into_iter()
                .filter(|nb| nb.item as usize != i)
                .map(|nb| {
                    let s = 0.5 * (scale(i) + scale(nb.item as usize));
                    (nb.item as u32, weight(nb.distance.sqrt() / s))
                })
                .filter(|&(_, w)| scales.is_none() || w > 0.0)
                .collect();
            list.sort_unstable_by_key(|&(j, _)| j);
            list
        })
        .collect();

    let mut weights: Vec<f32> = neighbours
        .iter()
        .map(|list| list.iter().map(|&(_, w)| w).sum())
        .collect();
    let mut removed = vec![false; m];
    let mut heap: BinaryHeap<Entry> = weights
        .iter()
        .enumerate()
        .map(|(i, &w)| Entry {
            weight: w,
            index: i,
        })
        .collect();
    let mut remaining = m;
    while remaining > target {
        let Some(top) = heap.pop() else { break };
        if removed[top.index] || top.weight != weights[top.index] {
            continue; // stale entry
        }
        removed[top.index] = true;
        remaining -= 1;
        for &(j, w) in &neighbours[top.index] {
            let j = j as usize;
            if !removed[j] {
                weights[j] -= w;
                heap.push(Entry {
                    weight: weights[j],
                    index: j,
                });
            }
        }
    }
    (0..m).filter(|&i| !removed[i]).collect()
}

/// Yuksel 2015, Eq. 5 (surface, d = 2): the largest Poisson-disk radius of `n` points on an
/// area `a`, r_max = sqrt(A / (2√3 N)).
fn poisson_radius(area: f32, n: usize) -> f32 {
    (area / (2.0 * 3f32.sqrt() * n.max(1) as f32)).sqrt()
}

/// Adds sample points where sample-map texels found fewer than four (thesis §6.3: density must
/// let every texel find its points within φ_samplemap). A candidate sits ε above each short
/// texel's surface point (lower near another surface, as [`place`] puts it with
/// `near_surface`); texels are visited in order and a candidate is kept when it passes the
/// free-space tests and lies at least `min_distance` from every existing and newly kept
/// point; a candidate in contact, where no view reaches its texel (`sample_map::enclosed`
/// within its object's `reach`, its size), is not. At most `max_new` points are added. Returns how
/// many were added, and how many of them were lowered.
#[allow(clippy::too_many_arguments)]
pub fn refine(
    points: &mut Vec<SamplePoint>,
    short_texels: &[(u32, u32, u32)],
    maps: &[MapDomain],
    resolution: u32,
    epsilon: f32,
    near_surface: NearSurface,
    min_distance: f32,
    max_new: usize,
    reach: &[f32],
    geometry: &impl Intersector,
) -> (usize, usize) {
    let existing: Vec<[f32; 3]> = points.iter().map(|p| p.position).collect();
    let tree: ImmutableKdTree<f32, 3> = ImmutableKdTree::new_from_slice(&existing);
    let directions = fibonacci_sphere(PROBE_DIRECTIONS);
    let min_sq = min_distance * min_distance;
    // A point at any height lies within ε of the one at ε.
    let sure = min_distance - epsilon;
    // Whether an existing or newly `added` point lies within √`r_sq` of `p`.
    let crowded = |added: &[SamplePoint], p: Vec3, r_sq: f32| {
        (!existing.is_empty()
            && tree.nearest_one::<SquaredEuclidean>(&p.to_array()).distance < r_sq)
            || added
                .iter()
                .any(|a| Vec3::from_array(a.position).distance_squared(p) < r_sq)
    };
    let mut added: Vec<SamplePoint> = Vec::new();
    let mut lowered = 0;
    for &(patch_index, x, y) in short_texels {
        if added.len() >= max_new {
            break;
        }
        let Some(map) = maps.get(patch_index as usize) else {
            continue;
        };
        let Some((base, n, offset)) = map.texel_offset(x, y, resolution) else {
            continue;
        };
        let u = (x as f32 + 0.5) / resolution as f32;
        let v = (y as f32 + 0.5) / resolution as f32;
        // Cheap first: a point within `sure` of the one at ε rules out every height below it.
        if sure > 0.0 && crowded(&added, base + offset * epsilon, sure * sure) {
            continue;
        }
        let (_, Some(kept)) = offset_point(
            geometry,
            base,
            offset,
            map.object(),
            epsilon,
            near_surface,
            &directions,
        ) else {
            continue;
        };
        // A texel in contact (no point fits at ε) that no view reaches, under a base, is not
        // worth a point of the budget: the coverage report counts it as unseen.
        let reach = reach.get(map.object() as usize).copied().unwrap_or(0.0);
        let lift = base + n * epsilon * VISIBILITY_LIFT;
        if kept.contact && enclosed(geometry, lift, n, reach, &directions) {
            continue;
        }
        if crowded(&added, kept.position, min_sq) {
            continue;
        }
        let q = kept.position.to_array();
        lowered += usize::from(kept.lowered);
        added.push(SamplePoint {
            position: q,
            normal: offset.to_array(),
            uv: [u, v],
            patch: patch_index,
            object: map.object(),
        });
    }
    let n = added.len();
    points.extend(added);
    (n, lowered)
}

/// Max-heap entry: highest weight first, ties broken by the lower index (deterministic).
#[derive(PartialEq)]
struct Entry {
    weight: f32,
    index: usize,
}
impl Eq for Entry {}
impl PartialOrd for Entry {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}
impl Ord for Entry {
    fn cmp(&self, other: &Self) -> Ordering {
        self.weight
            .total_cmp(&other.weight)
            .then_with(|| other.index.cmp(&self.index))
    }
}

enum FreeSpace {
    Ok,
    TooClose,
    Inside,
}

/// Where [`offset_point`] put a point.
struct Offset {
    position: Vec3,
    /// Nearer its surface than ε.
    lowered: bool,
    /// At ε it failed the free-space test (another surface within ε): a contact.
    contact: bool,
}

/// [`offset_point`] for a drawn surface point with the bake's ε and `near_surface`: along the
/// face's own normal, so the point lies ε from its face (§3.1).
fn offset_draw(
    geometry: &impl Intersector,
    c: &SurfacePoint,
    settings: &BakeSettings,
    directions: &[Vec3],
) -> (FreeSpace, Option<Offset>) {
    offset_point(
        geometry,
        c.position,
        c.offset,
        c.object,
        settings.epsilon,
        settings.near_surface,
        directions,
    )
}

/// Where the point over `base` (on object `own`, its face's normal `offset`) goes: ε along
/// `offset` where the free-space tests pass there, and with [`NearSurface::Lower`], nearer its
/// own surface where another lies within ε or within [`NEAR_CLEARANCE`] times the point's
/// height in the half-space it faces (halving the height at most [`NEAR_LOWERINGS`] times,
/// the lowest that passes the free-space tests kept). Returns the test's outcome and, where it
/// passed, the point.
fn offset_point(
    geometry: &impl Intersector,
    base: Vec3,
    offset: Vec3,
    own: u32,
    epsilon: f32,
    rule: NearSurface,
    directions: &[Vec3],
) -> (FreeSpace, Option<Offset>) {
    let lowerings = match rule {
        NearSurface::Remove => 0,
        NearSurface::Lower => NEAR_LOWERINGS,
    };
    // Another surface within `far` of `position`, in the half-space `offset` faces (or all).
    let other_within = |position: Vec3, far: f32, facing: bool| {
        directions
            .iter()
            .filter(|d| !facing || d.dot(offset) > 0.0)
            .any(|&d| {
                geometry
                    .intersect(&Ray::new(position, d), far)
                    .is_some_and(|h| h.object != own)
            })
    };
    let mut h = epsilon;
    let mut kept: Option<Offset> = None;
    let mut outcome = FreeSpace::TooClose;
    let mut contact = false;
    for k in 0..=lowerings {
        let position = base + offset * h;
        outcome = free_space(geometry, position, h, directions);
        contact |= k == 0 && matches!(outcome, FreeSpace::TooClose);
        match outcome {
            FreeSpace::Ok => {
                kept = Some(Offset {
                    position,
                    lowered: k > 0,
                    contact,
                });
                if k == lowerings || !other_within(position, h * NEAR_CLEARANCE, true) {
                    break;
                }
            }
            // Lowered as far as the gap allows; or a surface of its own object within ε
            // (a fold, a concave rim), which lowering would not leave.
            FreeSpace::TooClose
                if kept.is_some() || !other_within(position, h * FREE_SPACE_TOLERANCE, false) =>
            {
                break
            }
            FreeSpace::TooClose => {}
            FreeSpace::Inside => break,
        }
        h *= 0.5;
    }
    match kept {
        Some(p) => (FreeSpace::Ok, Some(p)),
        None => (outcome, None),
    }
}

/// Free-space tests of §3.3 at an offset point: no surface within ε (up to
/// [`FREE_SPACE_TOLERANCE`]), and not enclosed (most probes hitting back faces).
fn free_space(
    geometry: &impl Intersector,
    position: Vec3,
    epsilon: f32,
    directions: &[Vec3],
) -> FreeSpace {
    let near = epsilon * FREE_SPACE_TOLERANCE;
    let mut back_faces = 0;
    for &dir in directions {
        let ray = Ray::new(position, dir);
        if geometry.occluded(&ray, near) || through_point(geometry, position, dir, near).is_some() {
            return FreeSpace::TooClose;
        }
        if let Some(hit) = geometry.intersect(&ray, f32::MAX) {
            if hit.geometric_normal.dot(dir) > 0.0 {
                back_faces += 1;
            }
        }
    }
    if back_faces * 2 > directions.len() {
        FreeSpace::Inside
    } else {
        FreeSpace::Ok
    }
}

/// A surface passing through `position` (within [`THROUGH_POINT`] × `near` of it along `dir`),
/// which a ray from the point skips as a self-hit: its hit, from a segment through the point.
/// The distance is measured from the hit point, so the segment origin's rounding (far from
/// the scene's origin) does not move the threshold.
pub fn through_point(
    geometry: &impl Intersector,
    position: Vec3,
    dir: Vec3,
    near: f32,
) -> Option<oslf_trace::ray::SurfaceHit> {
    let origin = position - dir * near;
    geometry
        .intersect(&Ray::new(origin, dir), 2.0 * near)
        .filter(|hit| (origin + dir * hit.t - position).dot(dir).abs() <= near * THROUGH_POINT)
}

/// How close to a probed point (a fraction of the free-space distance) a surface counts as
/// passing through it.
pub const THROUGH_POINT: f32 = 1.0 / 64.0;

/// `n` directions spread evenly over the unit sphere (Fibonacci lattice).
pub fn fibonacci_sphere(n: usize) -> Vec<Vec3> {
    let golden = std::f32::consts::PI * (3.0 - 5f32.sqrt());
    (0..n)
        .map(|i| {
            let z = 1.0 - (2 * i + 1) as f32 / n as f32;
            let r = (1.0 - z * z).max(0.0).sqrt();
            let phi = golden * i as f32;
            Vec3::new(r * phi.cos(), r * phi.sin(), z)
        })
        .collect()
}
