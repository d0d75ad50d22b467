//! Bake settings chosen from the scene where its file leaves them unset: ε, each object's
//! sample spacing, the cube resolution and the samples per texel, from the objects' sizes,
//! their distance to the surfaces around them and the lobes of their materials. Every rule is
//! relative to the object's size, so the same scene at any scale gets the same relative
//! placement ([`choose`]), and each choice says why ([`BakeChoice`]).

use crate::material::Material;
pub use crate::object_measure::{object_size, ObjectMeasure, CLEARANCE_QUANTILE};
pub use crate::scene::BakeChoice;
use crate::scene::{
    epsilon_problem, BakeSettings, NearSurface, OslfObject, PointPlacement, SampleDensity, Shape,
};

/// ε as a fraction of the diagonal of the object's bounding box. The thesis's teapot has ε at
/// 1/77 of it; on examples/can.toml with every other setting chosen, 1/128 gave RMSE L* 2.88 in
/// the pbr mode against 3.09 at 1/64 (docs/measurements.md, "Settings chosen from the scene"):
/// points nearer the surface see it with less parallax, and the cone of Eq. 3.10 still holds
/// the spacing of [`SPACING_PER_SIZE`] (up to 7.6 ε at φ = 85°).
pub const EPSILON_PER_SIZE: f32 = 1.0 / 128.0;

/// ε at most this fraction of the gap in front of the nearest twentieth of the object's
/// surface (along its normals to another surface; contacts aside): sample points there stay
/// clear of it.
pub const EPSILON_PER_CLEARANCE: f32 = 0.5;

/// A mirror's sample spacing as a fraction of the object's diagonal; a lobe of GGX width α
/// spaces points `1 + SPACING_PER_ALPHA · α` times as far (a rough lobe blurs the parallax
/// between points that a mirror shows).
pub const SPACING_PER_SIZE: f32 = 1.0 / 24.0;

/// See [`SPACING_PER_SIZE`].
pub const SPACING_PER_ALPHA: f32 = 4.0;

/// How far, in spacings, the cone of Eq. 3.10 must reach for a texel to find four points
/// ([`cone_epsilon`]). In a Poisson-disk set the four nearest points lie within about one
/// spacing: examples/can.toml at ε = h/5.7 on a radius of 4.9 h, and the orb at ε = h/5.4 on a
/// radius of 6.9 h found four for every texel away from the table they stand on.
pub const SPACINGS_PER_CONE: f32 = 1.0;

/// The cube resolutions chosen by default: a power of two between these. The largest is what a
/// mirror gets (sharper cubes cost 4× the rays per doubling: set `cube_resolution` for them).
pub const CUBE_RESOLUTION_RANGE: (u32, u32) = (16, 64);

/// Rays per cube map chosen by default: 16 samples per texel at 32² (noise falls as the
/// resolution falls, at the same cost per cube).
pub const RAYS_PER_CUBE: u32 = 6 * 32 * 32 * 16;

/// The samples per texel chosen by default lie within these.
pub const SAMPLES_PER_TEXEL_RANGE: (u32, u32) = (4, 16);

/// Which of the derivable settings the scene file left unset, and the store budget the
/// choices must fit (`store_budget_mb`).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Unset {
    pub epsilon: bool,
    /// Neither `sample_count` nor `sample_spacing` (objects with a `sample_spacing` of their
    /// own keep it).
    pub density: bool,
    /// No `placement`: chosen with the density (parallax), else the thesis's uniform.
    pub placement: bool,
    /// No `near_surface`: chosen with ε (lower), else the thesis's remove.
    pub near_surface: bool,
    pub cube_resolution: bool,
    pub samples_per_texel: bool,
    /// The store's size the chosen cube resolution and spacings must fit, in bytes
    /// ([`fit_store_budget`]).
    pub store_budget: Option<f64>,
}

impl Unset {
    /// Whether anything is left to choose (or a budget to report on).
    pub fn any(&self) -> bool {
        self.epsilon
            || self.density
            || self.cube_resolution
            || self.samples_per_texel
            || self.store_budget.is_some()
    }
}

/// Decimal places that print lengths down to `smallest` with two significant digits (at
/// most 12): ε, coordinates and spacings in the scene's units at any scale.
pub fn length_decimals(smallest: f32) -> usize {
    if !(smallest.is_finite() && smallest > 0.0) {
        return 3;
    }
    ((-smallest.log10()).ceil() + 1.0).clamp(0.0, 12.0) as usize
}

/// `x` with `decimals` places.
fn length(x: f32, decimals: usize) -> String {
    format!("{x:.decimals$}")
}

/// What the rules read of `object` among `shapes` ([`crate::object_measure::measure`]):
/// gaps narrower than the size-based ε ([`EPSILON_PER_SIZE`]) are contacts.
pub fn measure(object: &OslfObject, shapes: &[Shape], materials: &[Material]) -> ObjectMeasure {
    crate::object_measure::measure(object, shapes, materials, EPSILON_PER_SIZE)
}

/// Chooses the `unset` settings of `settings` for `objects` among `shapes`, sets them (and the
/// objects' own spacings), and returns the choices. Settings the file sets are kept.
pub fn choose(
    objects: &mut [OslfObject],
    shapes: &[Shape],
    materials: &[Material],
    settings: &mut BakeSettings,
    unset: Unset,
) -> Vec<BakeChoice> {
    if !unset.any() || objects.is_empty() {
        return Vec::new();
    }
    let measures: Vec<ObjectMeasure> = objects
        .iter()
        .map(|o| measure(o, shapes, materials))
        .collect();
    let mut choices = Vec::new();
    if unset.epsilon {
        choices.push(choose_epsilon(objects, &measures, settings, !unset.density));
        if unset.near_surface {
            settings.near_surface = NearSurface::Lower;
            choices.push(near_surface_choice());
        }
    }
    let decimals = length_decimals(settings.epsilon);
    if unset.density {
        for (object, m) in objects.iter_mut().zip(&measures) {
            if object.sample_spacing.is_some() {
                continue;
            }
            let by_lobe = lobe_spacing(m);
            let cone_spacing = cone_spacing(settings.epsilon, m.curvature, settings);
            let h = by_lobe.min(cone_spacing);
            object.sample_spacing = Some(h);
            let capped = if h < by_lobe {
                format!(
                    "; at most {}, so that a texel finds four points within phi_samplemap ({}°) of its normal at ε = {} where the surface curves as it typically does (Eq. 3.10)",
                    length(cone_spacing, decimals),
                    settings.phi_samplemap_deg,
                    length(settings.epsilon, decimals)
                )
            } else {
                String::new()
            };
            let points = (m.area / (0.866_025_4 * h * h)).ceil();
            choices.push(BakeChoice {
                key: "sample_spacing",
                object: Some(object.name.clone()),
                value: length(h, decimals),
                why: format!(
                    "about {points} points over its area {}: 1/{} of its size {} × (1 + {SPACING_PER_ALPHA}·α) for {}{capped}",
                    area(m.area),
                    (1.0 / SPACING_PER_SIZE).round(),
                    length(m.size, decimals),
                    lobe(m)
                ),
            });
        }
        settings.sample_count = finest_spacing(objects);
        if unset.placement {
            settings.placement = PointPlacement::Parallax;
            choices.push(placement_choice());
        }
    }
    if unset.cube_resolution {
        choices.push(choose_cube_resolution(objects, &measures, settings));
    }
    if unset.samples_per_texel {
        let n = settings.cube_resolution;
        settings.samples_per_texel = samples_per_texel(n);
        choices.push(samples_choice(n));
    }
    if let Some(budget) = unset.store_budget {
        fit_store_budget(objects, &measures, settings, unset, budget, &mut choices);
    }
    choices
}

/// The placement chosen with the density: parallax, the points closer together where what
/// they see is near (docs/measurements.md, "Parallax placement chosen with the density": on the
/// can over three seeds 0.58–0.62 of the better split sum against uniform's 0.60–0.68).
fn placement_choice() -> BakeChoice {
    BakeChoice {
        key: "placement",
        object: None,
        value: "\"parallax\"".into(),
        why: "the points crowd where what they see is near, where reflections change fastest \
              as the viewpoint moves, and thin out where it is far (placement = \"uniform\" \
              spreads them evenly, as the thesis did)"
            .into(),
    }
}

/// The rule chosen with ε: points near another surface lowered, not removed
/// (docs/measurements.md, "Points lowered near a contact": on the can over three seeds
/// 0.56–0.57 of the better split sum against 0.58–0.62 with the points removed).
fn near_surface_choice() -> BakeChoice {
    BakeChoice {
        key: "near_surface",
        object: None,
        value: "\"lower\"".into(),
        why: "a point that ε brings near another surface (the table an object stands on) is \
              lowered towards its own, down to ε/8, until what it faces lies three times its \
              height away, where reflections of the contact need it (near_surface = \"remove\" \
              removes it, as the thesis did)"
            .into(),
    }
}

/// The bake's density where every object has a spacing of its own: the finest of them.
fn finest_spacing(objects: &[OslfObject]) -> SampleDensity {
    SampleDensity::Spacing(
        objects
            .iter()
            .filter_map(|o| o.sample_spacing)
            .fold(f32::INFINITY, f32::min),
    )
}

/// The samples per texel chosen at cube resolution `n`: [`RAYS_PER_CUBE`] per cube.
fn samples_per_texel(n: u32) -> u32 {
    (RAYS_PER_CUBE / (6 * n * n).max(1)).clamp(SAMPLES_PER_TEXEL_RANGE.0, SAMPLES_PER_TEXEL_RANGE.1)
}

/// The choice of [`samples_per_texel`] at `n`.
fn samples_choice(n: u32) -> BakeChoice {
    let spp = samples_per_texel(n);
    BakeChoice {
        key: "samples_per_texel",
        object: None,
        value: spp.to_string(),
        why: format!(
            "{} rays per cube map at {n}² (the choice aims at {RAYS_PER_CUBE}, 16 per texel at 32², within {}..={} per texel)",
            6 * n * n * spp,
            SAMPLES_PER_TEXEL_RANGE.0,
            SAMPLES_PER_TEXEL_RANGE.1
        ),
    }
}

/// The store's typical size at these settings: the placed points of every object (at its
/// spacing, or its share of `sample_count`) × six faces of `cube_resolution`² texels at the
/// encoding's typical compressed size ([`oslf_format::encoding::compressed_texel_bytes`]).
/// Points added where texels find fewer than four come on top.
pub fn store_estimate(objects: &[OslfObject], measures: &[ObjectMeasure], s: &BakeSettings) -> f64 {
    let shared_area: f64 = objects
        .iter()
        .zip(measures)
        .filter(|(o, _)| o.sample_spacing.is_none())
        .map(|(_, m)| f64::from(m.area))
        .sum();
    let points = |area: f64, h: f32| area / (0.866_025_4 * f64::from(h).powi(2));
    let mut n: f64 = objects
        .iter()
        .zip(measures)
        .filter_map(|(o, m)| o.sample_spacing.map(|h| points(f64::from(m.area), h)))
        .sum();
    if shared_area > 0.0 {
        n += match s.sample_count {
            SampleDensity::Count(c) => f64::from(c),
            SampleDensity::Spacing(h) => points(shared_area, h),
        };
    }
    let texel = oslf_format::encoding::compressed_texel_bytes(s.encoding, s.mantissa_bits)
        + if s.distance_channel {
            oslf_format::encoding::DISTANCE_COMPRESSED_BYTES
        } else {
            0.0
        };
    n.ceil() * 6.0 * f64::from(s.cube_resolution).powi(2) * texel
}

/// Fits the chosen settings into a store of `budget` bytes ([`store_estimate`]): halves a
/// chosen cube resolution down to the smallest of [`CUBE_RESOLUTION_RANGE`] (the samples per
/// texel follow where chosen), then widens the chosen spacings; a chosen ε rises with them to
/// what the cone of Eq. 3.10 needs, a given ε caps them. The choices say what the budget
/// changed; a choice line `store_budget_mb` says what is left (and that it cannot be met, when
/// it cannot).
fn fit_store_budget(
    objects: &mut [OslfObject],
    measures: &[ObjectMeasure],
    settings: &mut BakeSettings,
    unset: Unset,
    budget: f64,
    choices: &mut Vec<BakeChoice>,
) {
    let before = store_estimate(objects, measures, settings);
    let mb = |bytes: f64| {
        let d = length_decimals((bytes / 1e6) as f32);
        format!("{:.d$} MB", bytes / 1e6)
    };
    let note = format!("; lowered to fit the store budget of {}", mb(budget));
    while unset.cube_resolution
        && settings.cube_resolution > CUBE_RESOLUTION_RANGE.0
        && store_estimate(objects, measures, settings) > budget
    {
        settings.cube_resolution /= 2;
        let n = settings.cube_resolution;
        let texel_deg = 90.0 / n as f32;
        if let Some(c) = choices.iter_mut().find(|c| c.key == "cube_resolution") {
            c.value = n.to_string();
            c.why = format!("texels of {texel_deg:.2}°{note}");
        }
        if unset.samples_per_texel {
            settings.samples_per_texel = samples_per_texel(n);
            if let Some(c) = choices.iter_mut().find(|c| c.key == "samples_per_texel") {
                *c = samples_choice(n);
            }
        }
    }
    let estimate = store_estimate(objects, measures, settings);
    let chosen: Vec<String> = choices
        .iter()
        .filter(|c| c.key == "sample_spacing")
        .filter_map(|c| c.object.clone())
        .collect();
    if estimate > budget && !chosen.is_empty() {
        // Store size goes as 1/h²: widen every chosen spacing alike. A chosen ε rises with
        // them to what the cone of Eq. 3.10 needs; a given one caps them.
        // 1 % over: the point counts round up.
        let widen = 1.01 * (estimate / budget).sqrt() as f32;
        let epsilon_before = settings.epsilon;
        let mut epsilon = settings.epsilon;
        for (object, m) in objects.iter_mut().zip(measures) {
            let Some(h) = object
                .sample_spacing
                .filter(|_| chosen.contains(&object.name))
            else {
                continue;
            };
            let wide = if unset.epsilon {
                epsilon = epsilon.max(cone_epsilon(h * widen, m.curvature, settings));
                h * widen
            } else {
                (h * widen)
                    .min(cone_spacing(epsilon, m.curvature, settings))
                    .max(h)
            };
            object.sample_spacing = Some(wide);
        }
        settings.epsilon = epsilon;
        let decimals = length_decimals(epsilon);
        let budget_note = format!("the store budget of {}", mb(budget));
        for c in choices.iter_mut() {
            if c.key == "epsilon" && epsilon > epsilon_before {
                c.value = length(epsilon, decimals);
                c.why = format!(
                    "{}; raised with the spacings widened for {budget_note}, to what the cone of Eq. 3.10 needs",
                    c.why
                );
            }
            let spacing = objects
                .iter()
                .zip(measures)
                .find(|(o, _)| c.key == "sample_spacing" && c.object.as_ref() == Some(&o.name))
                .and_then(|(o, m)| o.sample_spacing.map(|h| (h, m.area)));
            if let Some((h, area)) = spacing {
                c.value = length(h, decimals);
                let points = (area / (0.866_025_4 * h * h)).ceil();
                c.why = format!(
                    "{}; × {widen:.2} for {budget_note}: about {points} points",
                    c.why
                );
            }
        }
        settings.sample_count = finest_spacing(objects);
    }
    let after = store_estimate(objects, measures, settings);
    let met = if after <= budget * 1.0001 {
        "met".to_string()
    } else {
        "not met: what the file sets (or the widest spacing the cone of Eq. 3.10 allows at its epsilon) keeps the store above it; leave those keys to the bake, or lower them".to_string()
    };
    choices.push(BakeChoice {
        key: "store_budget_mb",
        object: None,
        value: mb(budget).trim_end_matches(" MB").to_string(),
        why: format!(
            "{met}: the chosen settings' store is about {} (before the budget: {}; points added where texels find fewer than four come on top)",
            mb(after),
            mb(before)
        ),
    });
}

/// An object's spacing by its size and lobe: [`SPACING_PER_SIZE`] × size × (1 +
/// [`SPACING_PER_ALPHA`] · α).
fn lobe_spacing(m: &ObjectMeasure) -> f32 {
    m.size * SPACING_PER_SIZE * (1.0 + SPACING_PER_ALPHA * m.alpha)
}

/// The ε at which a texel finds four points at spacing `h` within the cone of Eq. 3.10 on a
/// surface of curvature `curvature`: a point ε above the surface at distance d lies within φ
/// of the texel's normal where ε − κd²/2 ≥ d · tan(90° − φ) (a convex surface curves away
/// below the tangent plane by κd²/2), with d up to [`SPACINGS_PER_CONE`] spacings.
fn cone_epsilon(h: f32, curvature: f32, settings: &BakeSettings) -> f32 {
    let t = (90.0 - settings.phi_samplemap_deg).to_radians().tan();
    let d = SPACINGS_PER_CONE * h;
    d * t + 0.5 * curvature * d * d
}

/// The largest spacing [`cone_epsilon`] allows at `epsilon`: the root of κd²/2 + t·d = ε,
/// over [`SPACINGS_PER_CONE`].
fn cone_spacing(epsilon: f32, curvature: f32, settings: &BakeSettings) -> f32 {
    let t = (90.0 - settings.phi_samplemap_deg).to_radians().tan();
    let d = if curvature > 0.0 {
        ((t * t + 2.0 * curvature * epsilon).sqrt() - t) / curvature
    } else {
        epsilon / t
    };
    d / SPACINGS_PER_CONE
}

/// Why ε is what it is.
enum EpsilonRule {
    /// [`EPSILON_PER_SIZE`] × the size of object `.0`.
    Size(usize),
    /// [`EPSILON_PER_CLEARANCE`] × the clearance of object `.0`.
    Clearance(usize),
    /// The cone of Eq. 3.10 at the spacing `.1` of object `.0`'s points (the file's, or its
    /// lobe's), at its typical curvature.
    Cone(usize, f32),
    /// Twice the smallest ε object `.0`'s coordinates and tessellation allow.
    Floor(usize),
}

/// ε: the smallest over the objects of [`EPSILON_PER_SIZE`] × the size, bounded by
/// [`EPSILON_PER_CLEARANCE`] × the clearance; raised to what the cone of Eq. 3.10 needs at
/// each object's spacing at its typical curvature ([`cone_epsilon`]; the spacing the file gives,
/// `density_given`: `sample_count` or `sample_spacing`, or an object's own, else its lobe's),
/// and to twice the smallest ε each object's f32 coordinates and tessellation allow
/// ([`epsilon_problem`]).
fn choose_epsilon(
    objects: &[OslfObject],
    measures: &[ObjectMeasure],
    settings: &mut BakeSettings,
    density_given: bool,
) -> BakeChoice {
    let (mut eps, mut rule) = (f32::INFINITY, EpsilonRule::Size(0));
    for (i, m) in measures.iter().enumerate() {
        let by_size = m.size * EPSILON_PER_SIZE;
        let by_gap = m
            .clearance
            .map_or(f32::INFINITY, |c| EPSILON_PER_CLEARANCE * c);
        if by_size.min(by_gap) < eps {
            eps = by_size.min(by_gap);
            rule = if by_gap < by_size {
                EpsilonRule::Clearance(i)
            } else {
                EpsilonRule::Size(i)
            };
        }
    }
    for (i, h) in spacings(objects, measures, settings, density_given) {
        let need = cone_epsilon(h, measures[i].curvature, settings);
        if need > eps {
            (eps, rule) = (need, EpsilonRule::Cone(i, h));
        }
    }
    for (i, object) in objects.iter().enumerate() {
        let floor = lowest_epsilon(object, eps);
        if floor > eps {
            (eps, rule) = (floor, EpsilonRule::Floor(i));
        }
    }
    settings.epsilon = eps;
    let d = length_decimals(eps);
    let which = if objects.len() > 1 {
        format!(" (the smallest of {} objects')", objects.len())
    } else {
        String::new()
    };
    let name = |i: usize| &objects[i].name;
    let why = match rule {
        EpsilonRule::Size(i) => format!(
            "1/{} of object {:?}'s size {}{which}",
            (1.0 / EPSILON_PER_SIZE).round(),
            name(i),
            length(measures[i].size, d)
        ),
        EpsilonRule::Clearance(i) => format!(
            "{EPSILON_PER_CLEARANCE} × the gap of {} in front of the nearest {:.0}% of object {:?}'s surface (1/{} of its size {} would come closer to the surface there){which}",
            length(measures[i].clearance.unwrap_or(0.0), d),
            100.0 * CLEARANCE_QUANTILE,
            name(i),
            (1.0 / EPSILON_PER_SIZE).round(),
            length(measures[i].size, d)
        ),
        EpsilonRule::Cone(i, h) => format!(
            "so that a texel of object {:?} finds four points within phi_samplemap ({}°) of its normal at a spacing of {} where its surface curves as it typically does (radius {}; Eq. 3.10: a smaller ε needs more points)",
            name(i),
            settings.phi_samplemap_deg,
            length(h, d),
            if measures[i].curvature > 0.0 { length(1.0 / measures[i].curvature, d) } else { "∞".to_string() }
        ),
        EpsilonRule::Floor(i) => format!(
            "twice the smallest ε object {:?}'s f32 coordinates and tessellation allow",
            name(i)
        ),
    };
    BakeChoice {
        key: "epsilon",
        object: None,
        value: length(eps, d),
        why,
    }
}

/// Each object's spacing: its own `sample_spacing` from the file, else (where
/// `density_given`) the bake's `sample_spacing`, or the spacing `sample_count` points give over
/// the objects without a spacing of their own (hexagonal packing, as the placement counts);
/// else the spacing its lobe will be given ([`lobe_spacing`]).
fn spacings(
    objects: &[OslfObject],
    measures: &[ObjectMeasure],
    settings: &BakeSettings,
    density_given: bool,
) -> Vec<(usize, f32)> {
    let shared_area: f32 = objects
        .iter()
        .zip(measures)
        .filter(|(o, _)| o.sample_spacing.is_none())
        .map(|(_, m)| m.area)
        .sum();
    let shared = match settings.sample_count {
        SampleDensity::Spacing(h) => h,
        SampleDensity::Count(n) => (shared_area / (0.866_025_4 * n.max(1) as f32)).sqrt(),
    };
    objects
        .iter()
        .enumerate()
        .map(|(i, o)| match o.sample_spacing {
            Some(h) => (i, h),
            None if density_given => (i, shared),
            None => (i, lobe_spacing(&measures[i])),
        })
        .collect()
}

/// Twice the smallest ε [`epsilon_problem`] accepts for `object`, found by doubling from a
/// millionth of `guess` (0 when the guess itself is far above it).
fn lowest_epsilon(object: &OslfObject, guess: f32) -> f32 {
    if epsilon_problem(guess * 0.5, object).is_none() {
        return 0.0;
    }
    let mut eps = guess * 0.5;
    for _ in 0..64 {
        if epsilon_problem(eps, object).is_none() {
            return 2.0 * eps;
        }
        eps *= 2.0;
    }
    2.0 * eps
}

/// The cube resolution that resolves the typical lobe (the area median of each object's
/// roughness; the sharpest over the objects): texels of at most α radians (a GGX lobe reflects
/// over about 2α) at the face's centre, a power of two within [`CUBE_RESOLUTION_RANGE`]. At the
/// same rays per cube, sharper cubes are noisier: examples/can.toml (label 0.35, metal 0.12)
/// gave RMSE L* 2.67 at 16² and 16 samples per texel, 2.55 at 32² and 16, 2.88 at 64² and 4
/// (docs/measurements.md, "Settings chosen from the scene").
fn choose_cube_resolution(
    objects: &[OslfObject],
    measures: &[ObjectMeasure],
    settings: &mut BakeSettings,
) -> BakeChoice {
    let (lo, hi) = CUBE_RESOLUTION_RANGE;
    let (i, m) = measures
        .iter()
        .enumerate()
        .min_by(|a, b| a.1.typical_alpha.total_cmp(&b.1.typical_alpha))
        .expect("choose is called with objects");
    let wanted = if m.typical_alpha > 0.0 {
        (std::f32::consts::FRAC_PI_2 / m.typical_alpha)
            .ceil()
            .min(1e6) as u32
    } else {
        u32::MAX
    };
    let n = wanted.clamp(lo, hi).next_power_of_two().min(hi);
    settings.cube_resolution = n;
    let texel_deg = 90.0 / n as f32;
    let capped = if wanted > hi {
        format!(" (it would take more than {hi}²: set cube_resolution for sharper cubes)")
    } else {
        String::new()
    };
    BakeChoice {
        key: "cube_resolution",
        object: None,
        value: n.to_string(),
        why: format!(
            "texels of {texel_deg:.2}° for object {:?}, {}{capped}",
            objects[i].name,
            typical_lobe(m)
        ),
    }
}

/// The lobe a measure describes, for messages.
fn lobe(m: &ObjectMeasure) -> String {
    match m.roughness {
        Some(r) => format!("its smoothest roughness {r:.3} (GGX α {:.4})", m.alpha),
        None => "a mirror (its material is Lambertian: the runtime's mirror and glossy modes reflect at any lobe)".to_string(),
    }
}

/// The typical lobe a measure describes, for messages.
fn typical_lobe(m: &ObjectMeasure) -> String {
    match m.typical_roughness {
        Some(r) => format!(
            "its typical roughness {r:.3} (GGX α {:.4}, the median over its area; sharper texels cost noise at the same rays per cube)",
            m.typical_alpha
        ),
        None => lobe(m),
    }
}

/// An area in the scene's units squared, to three significant digits.
fn area(a: f32) -> String {
    let d = (length_decimals(a) + 1).min(12);
    format!("{a:.d$}")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn decimals_follow_the_smallest_length() {
        assert_eq!(length_decimals(0.1), 2);
        assert_eq!(length_decimals(0.0029), 4);
        assert_eq!(length_decimals(2.9), 1);
        assert_eq!(length_decimals(2900.0), 0);
        assert_eq!(length_decimals(2.9e-6), 7);
        assert_eq!(length_decimals(f32::NAN), 3);
    }
}
