//! The object as Bevy sees it: a proxy mesh (a child entity of each [`OslfObject`]) of the
//! very triangles the runtime rasterises, with a material that takes part in Bevy's shadow
//! passes (the object casts shadows on Bevy's meshes under Bevy's lights) and its depth and
//! normal prepass (what SSAO and Bevy's other screen-space effects read), but draws nothing in
//! the main pass: the plugin's own pass shades the object.
//!
//! Only with Bevy's `PbrPlugin` (shadows and the prepass are its); without it there is no
//! proxy. An object with `NotShadowCaster` gives its proxy the same.

use std::collections::HashMap;

use bevy::asset::RenderAssetUsages;
use bevy::asset::{embedded_asset, Asset, AssetId, Assets, Handle};
use bevy::camera::visibility::Visibility;
use bevy::ecs::prelude::*;
use bevy::light::NotShadowCaster;
use bevy::math::Vec3;
use bevy::mesh::{Indices, Mesh, Mesh3d, MeshVertexBufferLayoutRef, PrimitiveTopology};
use bevy::pbr::{Material, MaterialPipeline, MaterialPipelineKey, MaterialPlugin, MeshMaterial3d};
use bevy::reflect::TypePath;
use bevy::render::render_resource::{
    AsBindGroup, RenderPipelineDescriptor, SpecializedMeshPipelineError,
};
use bevy::shader::ShaderRef;
use bevy::transform::components::{GlobalTransform, Transform};
use oslf_runtime::geometry::ObjectMesh;

use crate::asset::OslfStore;
use crate::extract::uniform_scale;
use crate::messages::OslfMessages;
use crate::object::OslfObject;

/// Marks the child entity that stands in for its parent [`OslfObject`] in Bevy's shadow and
/// prepass passes.
#[derive(Component, Clone, Copy, Debug, Default)]
pub struct OslfProxy;

/// The proxy's material: Bevy's default prepass and shadow shaders; in the main pass shaders
/// that draw nothing (every vertex outside the clip volume).
#[derive(Asset, TypePath, AsBindGroup, Clone, Debug, Default)]
pub(crate) struct ProxyMaterial {}

impl Material for ProxyMaterial {
    fn vertex_shader() -> ShaderRef {
        "embedded://oslf_bevy/proxy.wgsl".into()
    }

    fn fragment_shader() -> ShaderRef {
        "embedded://oslf_bevy/proxy.wgsl".into()
    }

    fn specialize(
        _: &MaterialPipeline,
        descriptor: &mut RenderPipelineDescriptor,
        _: &MeshVertexBufferLayoutRef,
        _: MaterialPipelineKey<Self>,
    ) -> Result<(), SpecializedMeshPipelineError> {
        // The runtime's G-buffer draws both sides; so do the shadow maps and the prepass. (In
        // the main pass its vertex shader culls every triangle.)
        descriptor.primitive.cull_mode = None;
        Ok(())
    }
}

/// The one proxy material every proxy shares.
#[derive(Resource)]
pub(crate) struct ProxyMaterialHandle(Handle<ProxyMaterial>);

/// Adds the proxy's material and systems where Bevy's PBR is there to use it.
pub(crate) fn register(app: &mut bevy::app::App) -> bool {
    if !app.is_plugin_added::<bevy::pbr::PbrPlugin>() {
        return false;
    }
    embedded_asset!(app, "proxy.wgsl");
    app.add_plugins(MaterialPlugin::<ProxyMaterial>::default());
    let handle = app
        .world_mut()
        .resource_mut::<Assets<ProxyMaterial>>()
        .add(ProxyMaterial::default());
    app.insert_resource(ProxyMaterialHandle(handle))
        .init_resource::<ProxyMeshes>()
        .add_systems(bevy::app::PostUpdate, sync_proxies);
    true
}

/// Each store's proxy mesh and the translation (the tessellation's origin) it is drawn at.
#[derive(Resource, Default)]
struct ProxyMeshes(HashMap<AssetId<OslfStore>, (OslfStore, Handle<Mesh>, Vec3)>);

/// The runtime's triangles of `store` as a Bevy mesh (positions relative to the returned
/// origin, vertex normals), or why there is none.
fn proxy_mesh(store: &OslfStore) -> Result<(Mesh, Vec3), String> {
    let store = store.open().map_err(|e| e.to_string())?;
    let mesh = ObjectMesh::of_store(&store);
    let positions: Vec<[f32; 3]> = mesh
        .vertices
        .iter()
        .map(|v| {
            [
                v.position_patch[0],
                v.position_patch[1],
                v.position_patch[2],
            ]
        })
        .collect();
    let normals: Vec<[f32; 3]> = mesh
        .vertices
        .iter()
        .map(|v| {
            let n = glam::Vec3::from_slice(&v.normal_u[..3]);
            n.try_normalize().unwrap_or(glam::Vec3::Z).to_array()
        })
        .collect();
    let origin = Vec3::from_array(mesh.origin.to_array());
    let bevy_mesh = Mesh::new(
        PrimitiveTopology::TriangleList,
        RenderAssetUsages::RENDER_WORLD,
    )
    .with_inserted_attribute(Mesh::ATTRIBUTE_POSITION, positions)
    .with_inserted_attribute(Mesh::ATTRIBUTE_NORMAL, normals)
    .with_inserted_indices(Indices::U32(mesh.indices));
    Ok((bevy_mesh, origin))
}

/// What [`sync_proxies`] reads of each object: its entity, component, transform and whether
/// it casts no shadow.
type ObjectQuery<'w, 's> = Query<
    'w,
    's,
    (
        Entity,
        &'static OslfObject,
        &'static GlobalTransform,
        Has<NotShadowCaster>,
    ),
>;

/// What [`sync_proxies`] reads of each proxy: its entity, parent, mesh, shadow casting and
/// visibility.
type ProxyQuery<'w, 's> = Query<
    'w,
    's,
    (
        Entity,
        &'static ChildOf,
        &'static Mesh3d,
        Has<NotShadowCaster>,
        &'static Visibility,
    ),
    With<OslfProxy>,
>;

/// Keeps one proxy per object in step with it: the mesh of its store (a new one when the store
/// is reloaded), hidden while the store is not loaded or the object's scale is uneven (the
/// plugin does not draw it then), its shadow casting as the object's; a proxy whose parent is
/// no longer an object is despawned.
#[allow(clippy::too_many_arguments)]
fn sync_proxies(
    mut commands: Commands,
    objects: ObjectQuery,
    proxies: ProxyQuery,
    stores: Res<Assets<OslfStore>>,
    mut meshes: ResMut<Assets<Mesh>>,
    mut cache: ResMut<ProxyMeshes>,
    material: Res<ProxyMaterialHandle>,
    messages: Res<OslfMessages>,
) {
    cache
        .0
        .retain(|id, (s, _, _)| stores.get(*id).is_some_and(|now| now.same_bytes(s)));
    // What each object's proxy should be: its mesh and translation (none while the store is
    // not loaded), its visibility and whether it casts no shadow.
    let mut wanted = HashMap::new();
    for (entity, object, transform, no_shadow) in &objects {
        let id = object.store.id();
        let mesh = match stores.get(id) {
            None => None,
            Some(store) => {
                if let std::collections::hash_map::Entry::Vacant(slot) = cache.0.entry(id) {
                    match proxy_mesh(store) {
                        Ok((mesh, origin)) => {
                            slot.insert((store.clone(), meshes.add(mesh), origin));
                        }
                        Err(e) => {
                            messages
                                .say(format!("OSLF store {id}: no shadow or prepass proxy: {e}"));
                        }
                    }
                }
                cache.0.get(&id).map(|(_, m, o)| (m.clone(), *o))
            }
        };
        let visible = mesh.is_some() && uniform_scale(transform);
        let visibility = if visible {
            Visibility::Inherited
        } else {
            Visibility::Hidden
        };
        wanted.insert(entity, (mesh, visibility, no_shadow));
    }
    let mut has_proxy = std::collections::HashSet::new();
    for (proxy, parent, mesh, proxy_no_shadow, proxy_visibility) in &proxies {
        let Some((want_mesh, visibility, no_shadow)) = wanted.get(&parent.parent()) else {
            commands.entity(proxy).despawn();
            continue;
        };
        if !has_proxy.insert(parent.parent()) {
            commands.entity(proxy).despawn(); // one proxy per object
            continue;
        }
        let mut c = commands.entity(proxy);
        if let Some((m, origin)) = want_mesh {
            if mesh.0 != *m {
                c.insert((Mesh3d(m.clone()), Transform::from_translation(*origin)));
            }
        }
        if proxy_no_shadow != *no_shadow {
            if *no_shadow {
                c.insert(NotShadowCaster);
            } else {
                c.remove::<NotShadowCaster>();
            }
        }
        if proxy_visibility != visibility {
            c.insert(*visibility);
        }
    }
    for (entity, (mesh, visibility, no_shadow)) in wanted {
        let Some((mesh, origin)) = mesh else {
            continue;
        };
        if has_proxy.contains(&entity) {
            continue;
        }
        let mut proxy = commands.spawn((
            OslfProxy,
            Mesh3d(mesh),
            MeshMaterial3d(material.0.clone()),
            Transform::from_translation(origin),
            visibility,
            ChildOf(entity),
        ));
        if no_shadow {
            proxy.insert(NotShadowCaster);
        }
    }
}
