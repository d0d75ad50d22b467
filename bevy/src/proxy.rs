//! The object in Bevy's shadow passes: a proxy mesh, a child entity of each [`OslfObject`],
//! whose material draws nothing in the main pass or the prepass (the plugin's own passes
//! write the object there, `draw.rs`). In Bevy's shadow passes (the object casts shadows on
//! Bevy's meshes under Bevy's lights) it is a coarser tessellation than the runtime's, within
//! the bake's ε of the surface: every shadow map of every light draws it, and a shadow map
//! cannot tell ε (docs/measurements.md, "The Bevy plugin").
//!
//! Only with Bevy's `PbrPlugin` (shadows are its); without it there is no proxy. An object
//! with `NotShadowCaster` gives its proxy the same.

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

/// Marks a child entity that stands in for its parent [`OslfObject`] in Bevy's passes, and
/// in which.
#[derive(Component, Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum OslfProxy {
    /// In Bevy's shadow passes: the object's Bézier patches tessellated within the bake's ε
    /// (mesh objects as they are); it has `NotShadowCaster` where the object has.
    Shadow,
}

impl OslfProxy {
    const ALL: [OslfProxy; 1] = [OslfProxy::Shadow];
}

/// The shadow proxy's material: Bevy's default shadow shaders, no prepass; in the main pass
/// shaders that draw nothing (proxy.wgsl: every vertex outside the clip volume); both sides
/// drawn, as the runtime's G-buffer draws them.
#[derive(Asset, TypePath, AsBindGroup, Clone, Debug, Default)]
pub(crate) struct ShadowProxyMaterial {}

impl Material for ShadowProxyMaterial {
    fn vertex_shader() -> ShaderRef {
        "embedded://oslf_bevy/proxy.wgsl".into()
    }

    fn fragment_shader() -> ShaderRef {
        "embedded://oslf_bevy/proxy.wgsl".into()
    }

    fn enable_prepass() -> bool {
        false
    }

    fn enable_shadows() -> bool {
        true
    }

    fn specialize(
        _: &MaterialPipeline,
        descriptor: &mut RenderPipelineDescriptor,
        _: &MeshVertexBufferLayoutRef,
        _: MaterialPipelineKey<Self>,
    ) -> Result<(), SpecializedMeshPipelineError> {
        descriptor.primitive.cull_mode = None;
        Ok(())
    }
}

/// The one material every shadow proxy shares.
#[derive(Resource)]
pub(crate) struct ProxyMaterialHandles {
    shadow: Handle<ShadowProxyMaterial>,
}

/// Adds the proxy's material and systems where Bevy's PBR is there to use it.
pub(crate) fn register(app: &mut bevy::app::App) {
    if !app.is_plugin_added::<bevy::pbr::PbrPlugin>() {
        return;
    }
    embedded_asset!(app, "proxy.wgsl");
    app.add_plugins(MaterialPlugin::<ShadowProxyMaterial>::default());
    let shadow = app
        .world_mut()
        .resource_mut::<Assets<ShadowProxyMaterial>>()
        .add(ShadowProxyMaterial::default());
    app.insert_resource(ProxyMaterialHandles { shadow })
        .init_resource::<ProxyMeshes>()
        .add_systems(bevy::app::PostUpdate, sync_proxies);
}

/// A proxy's mesh and the translation (its tessellation's origin) it is drawn at.
type ProxyMesh = (Handle<Mesh>, Vec3);

/// Each store's proxy meshes, one per kind ([`OslfProxy::ALL`]).
#[derive(Resource, Default)]
struct ProxyMeshes(HashMap<AssetId<OslfStore>, (OslfStore, [ProxyMesh; 1])>);

/// `store`'s triangles for each proxy kind ([`OslfProxy::ALL`]) as Bevy meshes, or why there
/// are none.
fn proxy_meshes(store: &OslfStore) -> Result<[(Mesh, Vec3); 1], String> {
    let store = store.open().map_err(|e| e.to_string())?;
    Ok(OslfProxy::ALL.map(|kind| {
        bevy_mesh(match kind {
            OslfProxy::Shadow => ObjectMesh::from_store(&store, store.meta().bake.epsilon),
        })
    }))
}

/// `mesh` as a Bevy mesh (positions relative to the returned origin, vertex normals).
fn bevy_mesh(mesh: ObjectMesh) -> (Mesh, Vec3) {
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
    (bevy_mesh, origin)
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

/// What [`sync_proxies`] reads of each proxy: its entity, kind, parent, mesh, shadow casting
/// and visibility.
type ProxyQuery<'w, 's> = Query<
    'w,
    's,
    (
        Entity,
        &'static OslfProxy,
        &'static ChildOf,
        &'static Mesh3d,
        Has<NotShadowCaster>,
        &'static Visibility,
    ),
>;

/// Keeps the two proxies of each object in step with it: the meshes of its store (new ones when
/// the store is reloaded), hidden while the store is not loaded or the object's scale is uneven
/// (the plugin does not draw it then), the shadow proxy's shadow casting as the object's; a
/// proxy whose parent is no longer an object is despawned.
#[allow(clippy::too_many_arguments)]
fn sync_proxies(
    mut commands: Commands,
    objects: ObjectQuery,
    proxies: ProxyQuery,
    stores: Res<Assets<OslfStore>>,
    mut meshes: ResMut<Assets<Mesh>>,
    mut cache: ResMut<ProxyMeshes>,
    materials: Res<ProxyMaterialHandles>,
    messages: Res<OslfMessages>,
) {
    cache
        .0
        .retain(|id, (s, _)| stores.get(*id).is_some_and(|now| now.same_bytes(s)));
    // What each object's proxies should be: their meshes and translations (none while the
    // store is not loaded), their visibility and whether the shadow proxy casts no shadow.
    let mut wanted = HashMap::new();
    for (entity, object, transform, no_shadow) in &objects {
        let id = object.store.id();
        let proxy_meshes = match stores.get(id) {
            None => None,
            Some(store) => {
                if let std::collections::hash_map::Entry::Vacant(slot) = cache.0.entry(id) {
                    match proxy_meshes(store) {
                        Ok(made) => {
                            let handles = made.map(|(mesh, origin)| (meshes.add(mesh), origin));
                            slot.insert((store.clone(), handles));
                        }
                        Err(e) => {
                            messages.say(format!("OSLF store {id}: no shadow proxy: {e}"));
                        }
                    }
                }
                cache.0.get(&id).map(|(_, m)| m.clone())
            }
        };
        let visible = proxy_meshes.is_some() && uniform_scale(transform);
        let visibility = if visible {
            Visibility::Inherited
        } else {
            Visibility::Hidden
        };
        for (i, kind) in OslfProxy::ALL.into_iter().enumerate() {
            let mesh = proxy_meshes.as_ref().map(|m| m[i].clone());
            wanted.insert((entity, kind), (mesh, visibility, no_shadow));
        }
    }
    let mut has_proxy = std::collections::HashSet::new();
    for (proxy, kind, parent, mesh, proxy_no_shadow, proxy_visibility) in &proxies {
        let key = (parent.parent(), *kind);
        let Some((want_mesh, visibility, no_shadow)) = wanted.get(&key) else {
            commands.entity(proxy).despawn();
            continue;
        };
        if !has_proxy.insert(key) {
            commands.entity(proxy).despawn(); // one proxy of each kind per object
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
    for ((entity, kind), (mesh, visibility, no_shadow)) in wanted {
        let Some((mesh, origin)) = mesh else {
            continue;
        };
        if has_proxy.contains(&(entity, kind)) {
            continue;
        }
        let mut proxy = commands.spawn((
            kind,
            Mesh3d(mesh),
            Transform::from_translation(origin),
            visibility,
            ChildOf(entity),
        ));
        match kind {
            OslfProxy::Shadow => proxy.insert(MeshMaterial3d(materials.shadow.clone())),
        };
        if no_shadow {
            proxy.insert(NotShadowCaster);
        }
    }
}
