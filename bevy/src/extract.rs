//! What the render world needs of the main world each frame: every OSLF object (its store,
//! transform, visibility and shading) and the stores they use.

use bevy::asset::{AssetId, Assets};
use bevy::camera::visibility::InheritedVisibility;
use bevy::ecs::prelude::*;
use bevy::math::Mat4;
use bevy::render::Extract;
use bevy::transform::components::GlobalTransform;
use oslf_runtime::ShadingParams;

use crate::asset::OslfStore;
use crate::object::OslfObject;

/// One object as extracted for this frame.
#[derive(Clone, Debug)]
pub(crate) struct ExtractedObject {
    /// Its main-world entity (for messages).
    pub entity: Entity,
    pub store: AssetId<OslfStore>,
    /// Bevy's world from the object's (the bake's) space.
    pub world_from_local: Mat4,
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

pub(crate) fn extract_oslf(
    mut out: ResMut<ExtractedOslf>,
    objects: Extract<Query<(Entity, &OslfObject, &GlobalTransform, &InheritedVisibility)>>,
    stores: Extract<Res<Assets<OslfStore>>>,
) {
    out.objects.clear();
    out.stores.clear();
    out.sheared.clear();
    for (entity, object, transform, visibility) in &objects {
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
        out.objects.push(ExtractedObject {
            entity,
            store: id,
            world_from_local: transform.to_matrix(),
            params: object.params,
            radiance_scale: object.radiance_scale,
        });
    }
}
