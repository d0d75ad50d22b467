//! What differs between the settings of two stores (a partial file and the bake that wants
//! to continue it, or two shards), named setting by setting with both values.

use crate::header::{Header, Section};
use crate::meta::{decode_meta, ObjectInfo, StoreMeta};

/// How a setting compared by [`setting_differences`] reads from a store's header and
/// metadata, as its messages print it.
type ReadSetting = fn(&Header, &StoreMeta) -> String;

/// The settings [`setting_differences`] compares, in the order it names them: the name its
/// messages use and how to read the value.
const SETTINGS: [(&str, ReadSetting); 18] = [
    ("scene hash (the scene file's text)", |_, m| {
        let s: String = m.bake.scene_hash[..8]
            .iter()
            .map(|v| format!("{v:02x}"))
            .collect();
        format!("{s}…")
    }),
    ("seed", |_, m| m.bake.seed.to_string()),
    ("cube_resolution", |_, m| m.bake.cube_resolution.to_string()),
    ("sample count", |h, _| h.sample_count.to_string()),
    ("sample_map_resolution", |_, m| {
        m.bake.sample_map_resolution.to_string()
    }),
    ("samples_per_texel", |_, m| {
        m.bake.samples_per_texel.to_string()
    }),
    ("target_noise", |_, m| {
        recorded(m.bake.sampling.map(|s| s.target_noise))
    }),
    ("denoise", |_, m| {
        recorded(m.bake.sampling.map(|s| s.denoised))
    }),
    ("bounces", |_, m| m.bake.bounces.to_string()),
    ("epsilon", |_, m| m.bake.epsilon.to_string()),
    ("phi_samplemap", |_, m| {
        format!("{}°", m.bake.phi_samplemap_deg)
    }),
    ("encoding", |_, m| m.bake.encoding.to_string()),
    ("mantissa_bits", |_, m| m.bake.mantissa_bits.to_string()),
    ("face filter", |h, _| h.filter.to_string()),
    ("distance_channel", |_, m| {
        m.bake.distance_channel.to_string()
    }),
    ("zstd_level", |_, m| m.bake.zstd_level.to_string()),
    ("env_cube", |_, m| m.has_env_cube.to_string()),
    ("camera", |_, m| match &m.camera {
        Some(c) => format!(
            "position {:?}, target {:?}, up {:?}, vfov {}°",
            c.position, c.target, c.up, c.vfov_deg
        ),
        None => "none".into(),
    }),
];

/// A setting of format 1.2's sampling record as the messages print it: "not recorded" in a
/// store of an earlier format.
fn recorded(value: Option<impl ToString>) -> String {
    value.map_or_else(|| "not recorded".into(), |v| v.to_string())
}

/// How a field compared by [`setting_differences`] reads from an object.
type ReadObjectField = fn(&ObjectInfo) -> String;

/// The fields of an object [`setting_differences`] compares, named as its messages name them
/// after the object.
const OBJECT_FIELDS: [(&str, ReadObjectField); 4] = [
    ("name", |o| format!("{:?}", o.name)),
    ("transform", |o| format!("{:?}", o.transform)),
    ("colour", |o| format!("{:?}", o.base_color)),
    ("patches", |o| {
        format!(
            "{}..{}",
            o.first_patch,
            u64::from(o.first_patch) + u64::from(o.patch_count)
        )
    }),
];

/// What an object is made of, as [`setting_differences`] names it.
fn object_kind(o: &ObjectInfo) -> String {
    match &o.mesh {
        None => "Bézier patches".to_string(),
        Some(m) => format!(
            "triangle mesh ({} vertices, {} triangles, {}×{} atlas pages)",
            m.positions.len(),
            m.triangles.len(),
            m.atlas_grid,
            m.atlas_grid
        ),
    }
}

/// What differs between the settings a partial file was started with (`old`) and those of
/// the bake that wants to continue it (`new`): one `"name old (this bake: new)"` per bake
/// parameter, count, camera, object or patch. Empty if they agree.
pub(crate) fn setting_differences(
    old_header: &Header,
    old: &StoreMeta,
    new_header: &Header,
    new: &StoreMeta,
    new_label: &str,
) -> Vec<String> {
    let mut d = Vec::new();
    let mut diff = |name: &str, a: String, b: String| {
        if a != b {
            d.push(format!("{name} {a} ({new_label}: {b})"));
        }
    };
    for (name, read) in SETTINGS {
        diff(name, read(old_header, old), read(new_header, new));
    }
    let mut mesh_note = None;
    if old.objects.len() != new.objects.len() {
        diff(
            "object count",
            old.objects.len().to_string(),
            new.objects.len().to_string(),
        );
    } else if let Some((i, (x, y))) = old
        .objects
        .iter()
        .zip(&new.objects)
        .enumerate()
        .find(|(_, (x, y))| x != y)
    {
        let object = format!("object {i} ({:?})", y.name);
        for (field, read) in OBJECT_FIELDS {
            diff(&format!("{object} {field}"), read(x), read(y));
        }
        let (a, b) = (object_kind(x), object_kind(y));
        if a != b {
            diff(&format!("{object} kind"), a, b);
        } else if x.mesh != y.mesh {
            mesh_note = Some(format!("the vertices or triangles of {object}"));
        }
    }
    if old.patches.len() != new.patches.len() {
        diff(
            "patch count",
            old.patches.len().to_string(),
            new.patches.len().to_string(),
        );
    } else if let Some(i) = old
        .patches
        .iter()
        .zip(&new.patches)
        .position(|(x, y)| x != y)
    {
        d.push(format!("the control points of patch {i}"));
    }
    d.extend(mesh_note);
    d
}

/// What differs between two store prefixes (`old`, and `new` of `new_label`): the settings
/// (as `StoreWriter::resume` names them), else the section that differs.
pub(crate) fn prefix_difference(old: &[u8], new: &[u8], new_label: &str) -> String {
    let parse = |b: &[u8]| -> Option<(Header, StoreMeta)> {
        let h = Header::parse(b).ok()?;
        let start = usize::try_from(h.meta.offset).ok()?;
        let end = usize::try_from(h.meta.end()).ok()?;
        let meta = decode_meta(b.get(start..end)?, h.meta.offset, h.version).ok()?;
        Some((h, meta))
    };
    let (Some((oh, om)), Some((nh, nm))) = (parse(old), parse(new)) else {
        return "its store header or metadata is damaged".into();
    };
    let d = setting_differences(&oh, &om, &nh, &nm, new_label);
    if !d.is_empty() {
        return format!("it was baked with different settings: {}", d.join(", "));
    }
    let differs = |s: Section, t: Section| {
        let get = |b: &[u8], s: Section| -> Option<Vec<u8>> {
            b.get(usize::try_from(s.offset).ok()?..usize::try_from(s.end()).ok()?)
                .map(<[u8]>::to_vec)
        };
        get(old, s) != get(new, t)
    };
    let section = if oh.points_checksum != nh.points_checksum || differs(oh.points, nh.points) {
        "sample points"
    } else if oh.maps_checksum != nh.maps_checksum || differs(oh.maps, nh.maps) {
        "sample maps"
    } else {
        "store headers"
    };
    format!(
        "its {section} differ from {new_label}'s although every setting is the same (baked by another version of oslf?)"
    )
}
