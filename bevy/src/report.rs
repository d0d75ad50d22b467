//! The main world's check of each object's store: a store that failed to load (missing,
//! damaged) or a handle that loads nothing is said once, and the object draws nothing.

use bevy::asset::{AssetLoadError, AssetServer, Assets, LoadState};
use bevy::ecs::prelude::*;

use crate::asset::OslfStore;
use crate::error::OslfBevyError;
use crate::messages::OslfMessages;
use crate::object::OslfObject;

pub(crate) fn report_stores(
    objects: Query<(Entity, &OslfObject)>,
    server: Res<AssetServer>,
    stores: Res<Assets<OslfStore>>,
    messages: Res<OslfMessages>,
) {
    for (entity, object) in &objects {
        let id = object.store.id();
        if stores.contains(id) {
            continue;
        }
        let name = object
            .store
            .path()
            .map(|p| p.to_string())
            .unwrap_or_else(|| format!("{id}"));
        match server.get_load_state(id) {
            Some(LoadState::Loading) => {}
            Some(LoadState::Failed(e)) => {
                messages.say(format!(
                    "OSLF object {entity}: its store {name} failed to load, so it draws nothing: {}",
                    load_error_message(&e)
                ));
            }
            Some(LoadState::NotLoaded) | Some(LoadState::Loaded) | None => {
                messages.say(format!(
                    "OSLF object {entity}: its store {name} is not loaded nor loading (load it \
                     with the AssetServer), so it draws nothing"
                ));
            }
        }
    }
}

/// The loader's own message for a store it refused (Bevy's wrapper would add a backtrace),
/// else Bevy's (a missing file, say).
fn load_error_message(e: &AssetLoadError) -> String {
    if let AssetLoadError::AssetLoaderError(loader) = e {
        if let Some(ours) = loader.error().downcast_ref::<OslfBevyError>() {
            return ours.to_string();
        }
    }
    e.to_string()
}
