//! Why sample-map texels are short: each texel that found fewer than four sample
//! points ([`crate::sample_map`]) is given a cause and a place, per object, in words a user
//! can act on.
//!
//! Causes, tested in this order at the texel's surface point `x`:
//! - **contact**: the sample point that would serve the texel, ε out along its face's normal,
//!   fails the free-space test of placement (§3.3): a surface lies closer than ε
//!   ([`FREE_SPACE_TOLERANCE`]) or encloses it. The object rests on or touches that surface
//!   (a box on a table: its bottom), or folds onto itself. Harmless where the side cannot be
//!   seen; the surface is named as the scene names it.
//! - **unseen**: contact, and no view reaches the texel: every probe direction within
//!   [`UNSEEN_CONE_DEG`] of its normal meets a surface within the object's size (a can's base
//!   on a table). Its empty texels lose nothing, so they are neither warned about nor refused
//!   under `--strict` ([`ObjectCoverage::unseen_empty`]).
//! - **hidden**: four or more of the texel's nearest points lie within φ_samplemap of its
//!   normal, but geometry hides enough of them (a crevice, a nearby surface).
//! - **sparse**: fewer than four of its nearest points
//!   ([`MAX_CANDIDATES`](crate::sample_map::MAX_CANDIDATES)) lie within φ_samplemap of its
//!   normal: the points are too far apart there.
//!
//! Texels of one cause are grouped by the surface they touch and the axis they face, and each
//! group located by the box its texels span. Only short texels are examined (64 probe rays, at
//! most 64 more for the unseen test of contact texels, and at most
//! [`MAX_CANDIDATES`](crate::sample_map::MAX_CANDIDATES) visibility rays each: about twice what
//! the map build cast for them; examples/meshes.toml: 0.06 s beside the maps'
//! 1.4 s), and the maps are only read: the store does not change.

use std::collections::BTreeMap;

use glam::Vec3;
use oslf_format::{SampleMaps, SamplePoint, INVALID_INDEX};
use rayon::prelude::*;

pub use crate::sample_map::UNSEEN_CONE_DEG;
use crate::sample_map::{self, enclosed, PointIndex, VISIBILITY_LIFT};
use crate::sample_points::{fibonacci_sphere, through_point, FREE_SPACE_TOLERANCE};
use crate::surface::MapDomain;
use oslf_trace::bvh::Instance;
use oslf_trace::ray::{Intersector, Ray};

/// Places shown per object, largest first; the others are summed in
/// [`ObjectCoverage::other_short`].
pub const PLACES_SHOWN: usize = 3;

/// Directions probed around a texel's would-be sample point by the contact test (as many as
/// placement's free-space test probes).
const PROBE_DIRECTIONS: usize = 64;

/// Why a texel found fewer than four sample points.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Cause {
    /// Its sample point would lie closer than ε to a surface, or inside one.
    Contact,
    /// In contact, and enclosed: no view reaches its surface ([`UNSEEN_CONE_DEG`]).
    Unseen,
    /// Enough points in its cone, but hidden behind geometry.
    Hidden,
    /// Too few points within φ_samplemap of its normal.
    Sparse,
}

impl Cause {
    /// What to do about it.
    pub fn remedy(self) -> &'static str {
        match self {
            Cause::Contact => {
                "harmless where unseen (the object rests on or touches it), otherwise move them \
                 more than epsilon apart or lower epsilon"
            }
            Cause::Unseen => "no view reaches them: nothing is lost",
            Cause::Hidden => {
                "lower epsilon, or raise sample_count (or lower sample_spacing) so points land \
                 in the gap"
            }
            Cause::Sparse => "raise sample_count (or lower sample_spacing)",
        }
    }
}

/// The names of the scene's triangles: which instance a global triangle index
/// ([`oslf_trace::ray::SurfaceHit::triangle`]) belongs to, as the scene names it.
#[derive(Clone, Debug, Default)]
pub struct SurfaceNames {
    /// Per instance: one past its last global triangle index, and its name.
    ends: Vec<(u64, String)>,
}

impl SurfaceNames {
    /// The names of `instances`, in the order [`oslf_trace::bvh::TriangleScene::build`] numbers
    /// their triangles.
    pub fn of(instances: &[Instance]) -> Self {
        let mut end = 0u64;
        let ends = instances
            .iter()
            .map(|i| {
                end += i.mesh.triangles.len() as u64;
                (end, i.name.clone())
            })
            .collect();
        SurfaceNames { ends }
    }

    /// The name of the instance holding global triangle `triangle` (`None`: unknown or
    /// unnamed).
    pub fn name(&self, triangle: u32) -> Option<&str> {
        self.instance_name(self.instance(triangle)?)
    }

    /// The index of the instance holding global triangle `triangle`.
    fn instance(&self, triangle: u32) -> Option<u32> {
        let k = self
            .ends
            .partition_point(|(end, _)| *end <= u64::from(triangle));
        (k < self.ends.len()).then_some(k as u32)
    }

    /// The name of instance `k` (`None`: unknown or unnamed).
    fn instance_name(&self, k: u32) -> Option<&str> {
        self.ends
            .get(k as usize)
            .map(|(_, name)| name.as_str())
            .filter(|n| !n.is_empty())
    }
}

/// One place where an object's texels are short for one cause.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct ShortPlace {
    pub cause: Cause,
    /// The surface closer than ε (contact only), as the scene names it: a shape
    /// (`[[box]] 0`, `room.glb: nodes[3] "Table": …`) or `object "NAME"` (itself or another
    /// OSLF object). `None`: not contact, or the surface has no name.
    pub surface: Option<String>,
    /// The axis the texels' surface faces most: `+x`, `-x`, `+y`, `-y`, `+z` (up), `-z` (down).
    pub facing: &'static str,
    /// Short texels here (fewer than four points), of which `empty` have none.
    pub short: u64,
    pub empty: u64,
    /// World-space box of the texels' surface points.
    pub min: [f32; 3],
    pub max: [f32; 3],
    /// What to do about it ([`Cause::remedy`]).
    pub remedy: &'static str,
}

/// One object's short texels: how many, and where and why.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct ObjectCoverage {
    pub object: String,
    /// Used sample-map texels of the object.
    pub texels: u64,
    /// Of them, with fewer than four points, and with none.
    pub short: u64,
    pub empty: u64,
    /// Of the empty texels, those no view reaches ([`Cause::Unseen`]).
    pub unseen_empty: u64,
    /// The largest places ([`PLACES_SHOWN`] at most), most short texels first.
    pub places: Vec<ShortPlace>,
    /// Short texels in places not shown.
    pub other_short: u64,
    /// Decimal places that print the object's coordinates: enough for ε and for a hundredth
    /// of the object's size ([`decimals_for`]).
    pub decimals: usize,
}

/// What [`diagnose`] needs besides the maps.
pub struct Probe<'a, G: Intersector> {
    pub geometry: &'a G,
    pub names: &'a SurfaceNames,
    pub epsilon: f32,
    pub phi_samplemap_deg: f32,
    /// The diagonal of each object's bounding box, in object order (for the decimals of its
    /// coordinates).
    pub object_sizes: &'a [f32],
}

/// Group of short texels: object, cause, instance touched (contact), facing axis (0..6).
type Key = (u32, Cause, Option<u32>, u8);

/// Groups of short texels, in key order.
type Groups = BTreeMap<Key, Group>;

/// Per object (names from `object_names`, in object order), its used texels, short texels
/// and the places they lie, for the sample maps `maps` of `domains` built from `points`.
/// Objects without any used texel are left out.
pub fn diagnose<G: Intersector>(
    maps: &SampleMaps,
    domains: &[MapDomain],
    points: &[SamplePoint],
    object_names: &[String],
    probe: &Probe<G>,
) -> Vec<ObjectCoverage> {
    let res = maps.resolution;
    let page = (res as usize) * (res as usize);
    let mut texels = vec![0u64; object_names.len()];
    for d in domains {
        let used = (0..res)
            .flat_map(|y| (0..res).map(move |x| (x, y)))
            .filter(|&(x, y)| d.covers(x, y))
            .count() as u64;
        if let Some(t) = texels.get_mut(d.object() as usize) {
            *t += used;
        }
    }
    let short = sample_map::short_texels(maps, domains);
    let index = PointIndex::new(points);
    let directions = fibonacci_sphere(PROBE_DIRECTIONS);
    // Folded into groups as they come (memory per group, not per texel): counts and bounds
    // do not depend on the order.
    let groups = short
        .par_iter()
        .fold(Groups::new, |mut groups, &(map, x, y)| {
            let Some(domain) = domains.get(map as usize) else {
                return groups;
            };
            let Some((p, n, offset)) = domain.texel_offset(x, y, res) else {
                return groups;
            };
            let empty = maps
                .indices
                .get(map as usize * page + (y * res + x) as usize)
                .is_some_and(|t| t[0] == INVALID_INDEX);
            let object = domain.object();
            let (cause, instance) = classify(probe, &index, &directions, object, (p, n, offset));
            let key = (object, cause, instance, facing_axis(n));
            groups
                .entry(key)
                .or_insert_with(|| Group::at(p))
                .add(p, empty);
            groups
        })
        .reduce(Groups::new, |mut a, b| {
            for (key, g) in b {
                a.entry(key).or_insert_with(|| Group::at(g.min)).merge(&g);
            }
            a
        });
    let decimals: Vec<usize> = (0..object_names.len())
        .map(|o| decimals_for(probe.epsilon, probe.object_sizes.get(o).copied()))
        .collect();
    summarize(groups, &texels, object_names, probe.names, &decimals)
}

/// The cause of one short texel of `object` at `p` (unit normal `n`, offset direction
/// `offset`), and for contact the instance of the surface ([`SurfaceNames`]).
fn classify<G: Intersector>(
    probe: &Probe<G>,
    index: &PointIndex,
    directions: &[Vec3],
    object: u32,
    (p, n, offset): (Vec3, Vec3, Vec3),
) -> (Cause, Option<u32>) {
    let point = p + offset * probe.epsilon;
    let lift = probe.epsilon * VISIBILITY_LIFT;
    if let Some(triangle) = contact(probe.geometry, point, probe.epsilon, object, directions) {
        let reach = probe.object_sizes.get(object as usize).copied();
        let cause = match reach {
            Some(reach) if enclosed(probe.geometry, p + n * lift, n, reach, directions) => {
                Cause::Unseen
            }
            _ => Cause::Contact,
        };
        return (cause, probe.names.instance(triangle));
    }
    let cos_phi = probe.phi_samplemap_deg.to_radians().cos();
    let (in_cone, _) = sample_map::texel_candidates(index, probe.geometry, p, n, cos_phi, lift);
    if in_cone >= 4 {
        (Cause::Hidden, None)
    } else {
        (Cause::Sparse, None)
    }
}

/// Placement's free-space test at `point` (§3.3), naming what fails it: the triangle of the
/// nearest hit closer than ε × [`FREE_SPACE_TOLERANCE`], or, where most probes hit back faces
/// (the point is enclosed), the nearest back face hit. Surfaces of other objects and shapes
/// come before `object`'s own (a box resting on a table: the table, not the box's bottom in
/// the same plane). `None`: the point is free.
fn contact(
    geometry: &impl Intersector,
    point: Vec3,
    epsilon: f32,
    object: u32,
    directions: &[Vec3],
) -> Option<u32> {
    let near = epsilon * FREE_SPACE_TOLERANCE;
    let mut back_faces = 0;
    // (own object, distance, triangle): the smallest wins.
    let mut nearest: Option<(bool, f32, u32)> = None;
    let mut nearest_back: Option<(bool, f32, u32)> = None;
    let closer = |best: Option<(bool, f32, u32)>, candidate: (bool, f32, u32)| match best {
        Some(b) if (b.0, b.1) <= (candidate.0, candidate.1) => best,
        _ => Some(candidate),
    };
    for &dir in directions {
        // A surface through the point itself, as placement tests it.
        if let Some(hit) = through_point(geometry, point, dir, near) {
            nearest = closer(nearest, (hit.object == object, 0.0, hit.triangle));
        }
        let Some(hit) = geometry.intersect(&Ray::new(point, dir), f32::MAX) else {
            continue;
        };
        let candidate = (hit.object == object, hit.t, hit.triangle);
        if hit.t < near {
            nearest = closer(nearest, candidate);
        }
        if hit.geometric_normal.dot(dir) > 0.0 {
            back_faces += 1;
            nearest_back = closer(nearest_back, candidate);
        }
    }
    if let Some((_, _, triangle)) = nearest {
        return Some(triangle);
    }
    (back_faces * 2 > directions.len())
        .then_some(nearest_back)
        .flatten()
        .map(|(_, _, t)| t)
}

/// The axis `n` is closest to: 0 `+x`, 1 `-x`, 2 `+y`, 3 `-y`, 4 `+z`, 5 `-z`.
fn facing_axis(n: Vec3) -> u8 {
    let a = n.abs();
    let axis = if a.x >= a.y && a.x >= a.z {
        0
    } else if a.y >= a.z {
        1
    } else {
        2
    };
    2 * axis + u8::from(n[axis as usize] < 0.0)
}

/// The name of [`facing_axis`]'s axis.
fn axis_name(axis: u8) -> &'static str {
    ["+x", "-x", "+y", "-y", "+z", "-z"]
        .get(axis as usize)
        .copied()
        .unwrap_or("?")
}

/// One group's totals while summing.
struct Group {
    short: u64,
    empty: u64,
    min: Vec3,
    max: Vec3,
}

impl Group {
    /// No texel yet, its box starting at `p`.
    fn at(p: Vec3) -> Self {
        Group {
            short: 0,
            empty: 0,
            min: p,
            max: p,
        }
    }

    /// Adds a texel at `p`.
    fn add(&mut self, p: Vec3, empty: bool) {
        self.short += 1;
        self.empty += u64::from(empty);
        self.min = self.min.min(p);
        self.max = self.max.max(p);
    }

    /// Adds `other`'s texels.
    fn merge(&mut self, other: &Group) {
        self.short += other.short;
        self.empty += other.empty;
        self.min = self.min.min(other.min);
        self.max = self.max.max(other.max);
    }
}

/// The report of `groups`, objects in order, surfaces named by `names`.
fn summarize(
    groups: Groups,
    texels: &[u64],
    object_names: &[String],
    names: &SurfaceNames,
    decimals: &[usize],
) -> Vec<ObjectCoverage> {
    let mut per_object: BTreeMap<u32, Vec<ShortPlace>> = BTreeMap::new();
    for ((object, cause, instance, axis), g) in groups {
        per_object.entry(object).or_default().push(ShortPlace {
            cause,
            surface: instance
                .and_then(|k| names.instance_name(k))
                .map(str::to_string),
            facing: axis_name(axis),
            short: g.short,
            empty: g.empty,
            min: g.min.to_array(),
            max: g.max.to_array(),
            remedy: cause.remedy(),
        });
    }
    object_names
        .iter()
        .enumerate()
        .filter(|(o, _)| texels.get(*o).is_some_and(|&t| t > 0))
        .map(|(o, name)| {
            let mut places = per_object.remove(&(o as u32)).unwrap_or_default();
            // Most short texels first; the sort is stable, so ties keep the key order.
            places.sort_by_key(|p| std::cmp::Reverse(p.short));
            let short: u64 = places.iter().map(|p| p.short).sum();
            let empty: u64 = places.iter().map(|p| p.empty).sum();
            let unseen_empty = places
                .iter()
                .filter(|p| p.cause == Cause::Unseen)
                .map(|p| p.empty)
                .sum();
            let other_short = places.iter().skip(PLACES_SHOWN).map(|p| p.short).sum();
            places.truncate(PLACES_SHOWN);
            ObjectCoverage {
                object: name.clone(),
                texels: texels[o],
                short,
                empty,
                unseen_empty,
                places,
                other_short,
                decimals: decimals[o],
            }
        })
        .collect()
}

/// `3496 of 20976 texels (16.7%) short, 3496 empty` for an object.
impl std::fmt::Display for ObjectCoverage {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "object {:?}: {} of {} texels ({:.1}%) with fewer than four points, {} with none",
            self.object,
            self.short,
            self.texels,
            100.0 * self.short as f64 / self.texels.max(1) as f64,
            self.empty
        )?;
        match self.unseen_empty {
            0 => {}
            u if u == self.empty => write!(f, ", all where no view reaches")?,
            u => write!(f, " ({u} of them where no view reaches)")?,
        }
        if self.other_short > 0 {
            write!(f, " ({} in smaller places not listed)", self.other_short)?;
        }
        Ok(())
    }
}

impl ShortPlace {
    /// One line: how many, where, why, and what to do; coordinates to `decimals` places.
    /// `1983 texels facing down (−z) at x 1.00…2.00, y −0.50…0.50, z = 0.00, 1889 of them
    /// empty: within ε of [[box]] 0; harmless where …`.
    pub fn describe(&self, decimals: usize) -> String {
        let why = match (self.cause, &self.surface) {
            (Cause::Contact, Some(s)) => format!("within ε of {s}"),
            (Cause::Contact, None) => "within ε of another surface".to_string(),
            (Cause::Unseen, Some(s)) => format!("within ε of {s}, enclosed"),
            (Cause::Unseen, None) => "within ε of another surface, enclosed".to_string(),
            (Cause::Hidden, _) => "their nearest points are hidden behind geometry".to_string(),
            (Cause::Sparse, _) => "too few points within phi_samplemap of their normal".to_string(),
        };
        let facing = match self.facing {
            "+z" => "up (+z)",
            "-z" => "down (−z)",
            "-x" => "−x",
            "-y" => "−y",
            other => other,
        };
        let number = |v: f32| format!("{v:.*}", decimals).replace('-', "−");
        let tol = 0.5 * 10f32.powi(-(decimals as i32));
        let span = ["x", "y", "z"]
            .iter()
            .enumerate()
            .map(|(i, axis)| {
                let (lo, hi) = (self.min[i], self.max[i]);
                if hi - lo <= tol {
                    format!("{axis} = {}", number(0.5 * (lo + hi)))
                } else {
                    format!("{axis} {}…{}", number(lo), number(hi))
                }
            })
            .collect::<Vec<_>>()
            .join(", ");
        let empty = match self.empty {
            0 => String::new(),
            e if e == self.short => ", all empty".to_string(),
            e => format!(", {e} of them empty"),
        };
        format!(
            "{} texels facing {facing} at {span}{empty}: {why}; {}",
            self.short, self.remedy
        )
    }
}

/// Decimal places that print coordinates near an object to two significant digits of ε and
/// of a hundredth of the object's size `size` (the smaller), in the scene's units at any scale
/// ([`oslf_scene::bake_defaults::length_decimals`]).
pub fn decimals_for(epsilon: f32, size: Option<f32>) -> usize {
    let smallest = size.map_or(epsilon, |s| epsilon.min(0.01 * s));
    oslf_scene::bake_defaults::length_decimals(smallest)
}

#[cfg(test)]
mod tests {
    use super::*;
    use oslf_geometry::bezier::BezierPatch;
    use oslf_scene::shapes;
    use oslf_trace::bvh::TriangleScene;

    /// A flat patch over [0, 1]² at z = 0 facing +z; a thin wall standing on it at x = 0.5;
    /// sample points ε above it only beyond the wall (x ≥ 0.52). Beside the wall, texels are in
    /// contact with it; a little farther, their nearest points in the cone are behind it
    /// (hidden); farther still, none are in reach (sparse).
    #[test]
    fn each_cause_is_found_where_it_holds() {
        let eps = 0.02;
        let mut cp = [Vec3::ZERO; 16];
        for i in 0..4 {
            for j in 0..4 {
                cp[4 * i + j] = Vec3::new(j as f32 / 3.0, i as f32 / 3.0, 0.0);
            }
        }
        let mut patch = BezierPatch::new(cp);
        if patch.normal(0.5, 0.5).z < 0.0 {
            for i in 0..4 {
                for j in 0..4 {
                    cp[4 * i + j] = Vec3::new(i as f32 / 3.0, j as f32 / 3.0, 0.0);
                }
            }
            patch = BezierPatch::new(cp);
        }
        assert!(patch.normal(0.5, 0.5).z > 0.99);
        let mut wall = shapes::cuboid(Vec3::new(0.01, 2.0, 0.2)).unwrap();
        for p in &mut wall.positions {
            *p += Vec3::new(0.5, 0.5, 0.1);
        }
        let instances = vec![
            Instance {
                name: "object \"flat\"".into(),
                mesh: patch.tessellate(8),
                material: 0,
                object: 0,
            },
            Instance {
                name: "wall".into(),
                mesh: wall,
                material: 0,
                object: oslf_trace::ray::ENVIRONMENT_OBJECT,
            },
        ];
        let names = SurfaceNames::of(&instances);
        let geometry = TriangleScene::build(instances).unwrap();
        let points: Vec<SamplePoint> = (0..49)
            .flat_map(|i| (0..=50).map(move |j| (0.52 + 0.01 * i as f32, 0.02 * j as f32)))
            .map(|(x, y)| SamplePoint {
                position: [x, y, eps],
                normal: [0.0, 0.0, 1.0],
                uv: [x, y],
                patch: 0,
                object: 0,
            })
            .collect();
        let domains = [MapDomain::Patch {
            object: 0,
            patch: &patch,
        }];
        let phi = 80.0;
        let silent = oslf_trace::progress::or_silent(&None);
        let (maps, stats) = sample_map::build(&domains, &points, &geometry, 64, phi, eps, silent);
        let probe = Probe {
            geometry: &geometry,
            names: &names,
            epsilon: eps,
            phi_samplemap_deg: phi,
            object_sizes: &[1.0],
        };
        let report = diagnose(&maps, &domains, &points, &["flat".into()], &probe);
        assert_eq!(report.len(), 1);
        let c = &report[0];
        assert_eq!(
            (c.texels, c.short, c.empty),
            (stats.texels, stats.short, stats.empty)
        );
        assert_eq!(c.other_short, 0, "{c:#?}");
        let place = |cause: Cause| {
            c.places
                .iter()
                .find(|p| p.cause == cause)
                .unwrap_or_else(|| panic!("no {cause:?} in {c:#?}"))
        };
        // Sparse: everything well short of the wall.
        let sparse = place(Cause::Sparse);
        assert!(sparse.min[0] < 0.05 && sparse.max[0] < 0.45, "{sparse:?}");
        assert_eq!(sparse.surface, None);
        // Hidden: the band between, within reach of the points behind the wall.
        let hidden = place(Cause::Hidden);
        assert!(hidden.min[0] > 0.38 && hidden.max[0] < 0.49, "{hidden:?}");
        // Contact: beside the wall (its would-be points are closer than ε to it), named.
        let contact = place(Cause::Contact);
        assert_eq!(contact.surface.as_deref(), Some("wall"), "{contact:?}");
        assert!(
            contact.min[0] > 0.45 && contact.max[0] < 0.55,
            "{contact:?}"
        );
        for p in &c.places {
            assert_eq!(p.facing, "+z", "{p:?}");
        }
    }

    #[test]
    fn a_triangle_is_named_by_the_instance_that_holds_it() {
        let mesh = |n: usize| oslf_geometry::mesh::Mesh {
            triangles: vec![[0, 1, 2]; n],
            ..Default::default()
        };
        let named = |name: &str, n| Instance {
            name: name.into(),
            mesh: mesh(n),
            material: 0,
            object: 0,
        };
        let names = SurfaceNames::of(&[named("a", 2), named("", 3), named("c", 1)]);
        let got: Vec<Option<&str>> = (0..7).map(|t| names.name(t)).collect();
        assert_eq!(
            got,
            [Some("a"), Some("a"), None, None, None, Some("c"), None]
        );
    }
}
