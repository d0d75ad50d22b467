//! Problems said once: an object whose store is missing or damaged, a camera the object cannot
//! be drawn for, a transform the light field cannot follow. Each is logged once and kept in
//! [`OslfMessages`], so an app (or a test) can show what was not drawn and why.

use std::sync::{Arc, Mutex};

use bevy::ecs::prelude::*;

/// Every problem said so far, shared by the main and render worlds; each distinct message is
/// logged (as an error) and kept once.
#[derive(Resource, Clone, Default)]
pub struct OslfMessages(Arc<Mutex<Vec<String>>>);

impl OslfMessages {
    /// Logs `message` and keeps it, unless it was said before. Returns whether it was new.
    pub fn say(&self, message: String) -> bool {
        let Ok(mut said) = self.0.lock() else {
            return false;
        };
        if said.contains(&message) {
            return false;
        }
        bevy::log::error!("{message}");
        said.push(message);
        true
    }

    /// Every message said so far, oldest first.
    pub fn all(&self) -> Vec<String> {
        self.0.lock().map(|m| m.clone()).unwrap_or_default()
    }
}
