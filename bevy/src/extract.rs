//! What the render world needs of the main world: every OSLF object (its store, transform,
//! visibility and shading) and the stores they use. Extracted again only in a frame where
//! something of it changed (an object's component, transform or visibility; an object
//! removed; a store loaded, reloaded or dropped): the render world keeps the last extraction
//! otherwise, as Bevy's own extraction of visibility ranges does.

use bevy::asset::{AssetEvent, AssetId, Assets};
use bevy::camera::visibility::InheritedVisibility;
use bevy::ecs::lifecycle::RemovedComponents;
use bevy::ecs::message::MessageReader;
use bevy::ecs::prelude::*;
use bevy::math::Mat4;
use bevy::render::Extract;
use bevy::transform::components::GlobalTransform;
use oslf_runtime::ShadingParams;

use crate::asset::OslfStore;
use crate::object::OslfObject;
use crate::stats::StatsSink;

/// One object as extracted for this frame.
#[derive(Clone, Debug)]
pub(crate) struct ExtractedObject {
    /// Its main-world entity (for messages).
    pub entity: Entity,
    pub store: AssetId<OslfStore>,
    /// Bevy's world from the object's (the bake's) space.
    pub world_from_local: Mat4,
    /// The same at the previous frame (where its motion vectors start).
    pub previous_world_from_local: Mat4,
    pub params: ShadingParams,
    pub radiance_scale: f32,
}

/// This frame's objects and the loaded stores they use.
#[derive(Resource, Default)]
pub(crate) struct ExtractedOslf {
    /// Visible objects with a uniform scale.
    pub objects: Vec<ExtractedObject>,
    /// Every loaded store an object uses, visible or not (its renderer and cache are kept).
    pub stores: Vec<(AssetId<OslfStore>, OslfStore)>,
    /// Objects not drawn because their transform is not a uniform scale, rotation and
    /// translation (the light field cannot be sheared).
    pub sheared: Vec<Entity>,
}

/// Whether a transform's scale is uniform enough for the light field to follow it.
pub(crate) fn uniform_scale(t: &GlobalTransform) -> bool {
    let s = t.scale().abs();
    let (lo, hi) = (s.min_element(), s.max_element());
    lo > 0.0 && hi.is_finite() && (hi - lo) <= 1e-4 * hi
}

/// The objects whose component, transform or visibility changed since the last extraction.
type ChangedObjects = (
    With<OslfObject>,
    Or<(
        Changed<OslfObject>,
        Changed<GlobalTransform>,
        Changed<InheritedVisibility>,
    )>,
);

pub(crate) fn extract_oslf(
    mut out: ResMut<ExtractedOslf>,
    objects: Extract<Query<(Entity, &OslfObject, &GlobalTransform, &InheritedVisibility)>>,
    changed: Extract<Query<(), ChangedObjects>>,
    mut removed: Extract<RemovedComponents<OslfObject>>,
    mut store_events: Extract<MessageReader<AssetEvent<OslfStore>>>,
    stores: Extract<Res<Assets<OslfStore>>>,
    sink: Res<StatsSink>,
) {
    // Both readers are drained every frame, so that what they held is not seen again.
    let removed_any = removed.read().count() > 0;
    let stores_changed = store_events.read().count() > 0;
    if changed.is_empty() && !removed_any && !stores_changed {
        // Nothing moved since the last frame.
        for o in &mut out.objects {
            o.previous_world_from_local = o.world_from_local;
        }
        return;
    }
    // Where each object was at the last extraction, which no change followed until now.
    let before: std::collections::HashMap<Entity, Mat4> = out
        .objects
        .iter()
        .map(|o| (o.entity, o.world_from_local))
        .collect();
    out.objects.clear();
    out.stores.clear();
    out.sheared.clear();
    let mut extracted = 0;
    for (entity, object, transform, visibility) in &objects {
        extracted += 1;
        let id = object.store.id();
        let Some(store) = stores.get(id) else {
            continue;
        };
        if !out.stores.iter().any(|(s, _)| *s == id) {
            out.stores.push((id, store.clone()));
        }
        if !visibility.get() {
            continue;
        }
        if !uniform_scale(transform) {
            out.sheared.push(entity);
            continue;
        }
        let world_from_local = transform.to_matrix();
        out.objects.push(ExtractedObject {
            entity,
            store: id,
            world_from_local,
            previous_world_from_local: before.get(&entity).copied().unwrap_or(world_from_local),
            params: object.params,
            radiance_scale: object.radiance_scale,
        });
    }
    sink.extracted(extracted);
}
