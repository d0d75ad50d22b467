//! The component that places a baked object in the world.

use bevy::asset::Handle;
use bevy::camera::visibility::Visibility;
use bevy::ecs::component::Component;
use bevy::transform::components::Transform;
use oslf_runtime::ShadingParams;

use crate::asset::OslfStore;

/// A baked object drawn from its store: with its entity's `Transform` (the identity, the
/// default, puts it where the bake put it; translations, rotations and uniform scales move the
/// object and the light field baked around it together) and its shading settings, the same
/// [`ShadingParams`] as `oslf render` (mode, blend, source, M, lobe, depth correction).
///
/// Drawn by every 3D camera that sees it, depth-tested against Bevy's meshes both ways.
#[derive(Component, Clone, Debug)]
#[require(Transform, Visibility)]
pub struct OslfObject {
    /// The store (`asset_server.load("teapot.oslf")`).
    pub store: Handle<OslfStore>,
    /// How it is shaded.
    pub params: ShadingParams,
    /// Bevy's luminance (cd/m², what its lights and exposure work in) per unit of the store's
    /// radiance: 1 for a scene baked in Bevy's units; 683 (lumens per watt) for a glTF scene
    /// whose lights the bake turned into watts at its default `watts_per_lumen` of 1/683.
    pub radiance_scale: f32,
}

impl OslfObject {
    /// The object of `store` with the library's default shading (OSLF mirror and glossy terms).
    pub fn new(store: Handle<OslfStore>) -> Self {
        Self {
            store,
            params: ShadingParams::default(),
            radiance_scale: 1.0,
        }
    }

    /// The same object with `radiance_scale` ([`OslfObject::radiance_scale`]).
    pub fn with_radiance_scale(mut self, radiance_scale: f32) -> Self {
        self.radiance_scale = radiance_scale;
        self
    }

    /// The same object with `params`.
    pub fn with_params(mut self, params: ShadingParams) -> Self {
        self.params = params;
        self
    }
}
