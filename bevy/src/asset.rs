//! The `.oslf` store as a Bevy asset: loaded whole, validated by the format crate (its
//! checksums, sizes and table of contents), so a damaged store is an asset load error that
//! carries the store's own message and the app keeps running.

use std::sync::Arc;

use bevy::asset::{io::Reader, Asset, AssetLoader, LoadContext};
use bevy::reflect::TypePath;
use oslf_format::Store;

use crate::error::OslfBevyError;

/// A validated store in memory. Cheap to clone (the bytes are shared); the render world opens
/// its own [`Store`] over them for each renderer.
#[derive(Asset, TypePath, Clone, Debug)]
pub struct OslfStore {
    bytes: Arc<[u8]>,
    /// Cube maps in the store (sample points plus the environment cube, if baked).
    pub cubes: u32,
    /// Texels along a cube face's edge.
    pub cube_resolution: u32,
    /// Sample points.
    pub sample_points: usize,
}

impl OslfStore {
    /// Validates `bytes` as a store ([`Store::from_bytes`]); `name` says which in the error.
    pub fn from_bytes(name: &str, bytes: Vec<u8>) -> Result<Self, OslfBevyError> {
        let store = Store::from_bytes(&bytes).map_err(|source| OslfBevyError::Store {
            path: name.to_string(),
            source,
        })?;
        Ok(Self {
            cubes: store.cube_count(),
            cube_resolution: store.cube_resolution(),
            sample_points: store.sample_points().len(),
            bytes: bytes.into(),
        })
    }

    /// Opens the store again over the same bytes (for a renderer, which owns its store).
    pub fn open(&self) -> Result<Store, oslf_format::Error> {
        Store::from_bytes(&self.bytes)
    }

    /// Whether both are the same loaded bytes (not a reload).
    pub fn same_bytes(&self, other: &OslfStore) -> bool {
        Arc::ptr_eq(&self.bytes, &other.bytes)
    }

    /// Its size in bytes.
    pub fn len(&self) -> usize {
        self.bytes.len()
    }

    /// Whether it holds no bytes (never, once loaded: an empty file is refused).
    pub fn is_empty(&self) -> bool {
        self.bytes.is_empty()
    }
}

/// Loads `.oslf` files as [`OslfStore`] assets.
#[derive(Default, TypePath)]
pub struct OslfStoreLoader;

impl AssetLoader for OslfStoreLoader {
    type Asset = OslfStore;
    type Settings = ();
    type Error = OslfBevyError;

    async fn load(
        &self,
        reader: &mut dyn Reader,
        _settings: &(),
        load_context: &mut LoadContext<'_>,
    ) -> Result<OslfStore, OslfBevyError> {
        let name = load_context.path().to_string();
        let mut bytes = Vec::new();
        reader
            .read_to_end(&mut bytes)
            .await
            .map_err(|source| OslfBevyError::Read {
                path: name.clone(),
                source,
            })?;
        OslfStore::from_bytes(&name, bytes)
    }

    fn extensions(&self) -> &[&str] {
        &["oslf"]
    }
}
