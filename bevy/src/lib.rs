//! Offset surface light fields in Bevy: objects baked by `oslf bake` drawn inside a Bevy
//! scene, with position-dependent mirror reflections and Monte Carlo glossy shading from the
//! store's cube maps, where a Bevy user would otherwise reach for a reflection probe.
//!
//! ```no_run
//! use bevy::prelude::*;
//! use oslf_bevy::{OslfObject, OslfPlugin};
//!
//! fn setup(mut commands: Commands, assets: Res<AssetServer>) {
//!     // Where the bake put it; move it with the entity's Transform.
//!     commands.spawn(OslfObject::new(assets.load("teapot.oslf")));
//! }
//!
//! App::new()
//!     .add_plugins((DefaultPlugins, OslfPlugin::default()))
//!     .add_systems(Startup, setup)
//!     .run();
//! ```
//!
//! What the plugin does:
//! - **Assets.** `.oslf` files load as [`OslfStore`] assets, validated by the format crate;
//!   a damaged store is an asset load error carrying the store's own message (section, byte
//!   offset) and the app keeps running.
//! - **Objects.** [`OslfObject`] (requires `Transform` and `Visibility`) places a store's
//!   object in the world and carries its [`oslf_runtime::ShadingParams`].
//! - **Drawing.** Every 3D camera draws every visible object between Bevy's opaque and
//!   transparent passes, with Bevy's view and (reversed-depth) projection, into the camera's
//!   own colour and depth targets: Bevy's meshes in front hide it, it hides what lies behind
//!   it, and it writes its depth. Its radiance is scaled by the camera's exposure and goes
//!   through Bevy's tonemapping like a mesh's (HDR cameras). MSAA cameras get the object in
//!   every sample it covers.
//! - **Bevy's prepass.** A camera with a prepass (`DepthPrepass`, `NormalPrepass`,
//!   `MotionVectorPrepass`; SSAO and TAA add them) gets each object written into it right
//!   after Bevy's own: its depth (so Bevy's main pass tests its meshes against the object),
//!   its world normals and its motion vectors, so SSAO, TAA and Bevy's other screen-space
//!   effects see the object. That pass rasterises the object into the runtime's G-buffer,
//!   and the drawing above shades that G-buffer: the object is rasterised once per camera.
//!   Under TAA it is rasterised with the frame's jitter, as Bevy's meshes are.
//!   Bevy's deferred G-buffer (`DeferredPrepass`) does not get the object's material; the
//!   object is drawn over Bevy's deferred lighting like a forward mesh.
//! - **Shadows.** With Bevy's `PbrPlugin`, each object has a child ([`OslfProxy`]), a mesh
//!   drawn only in Bevy's shadow passes: a coarser tessellation (within the bake's ε) that
//!   casts shadows on Bevy's meshes under Bevy's lights (unless the object has
//!   `NotShadowCaster`). The object itself is lit by its baked light field only: Bevy's
//!   lights and shadows do not fall on it.
//! - **Streaming.** Each store has one runtime renderer with an LRU cube-map cache. Its
//!   feedback is read back asynchronously after Bevy submits the frame: a frame never waits
//!   for the GPU; cube maps not yet resident fall back as in `oslf view` and arrive a few
//!   frames later. The counters are the resource [`OslfCacheStats`] and diagnostics
//!   ([`stats::CACHE_MISSES`], …).
//! - **Problems** (a missing or damaged store, a camera or transform the object cannot be
//!   drawn for) are logged once and kept in [`OslfMessages`]; nothing panics.
//!
//! Add the plugin after Bevy's `DefaultPlugins` (it needs the asset server and the 3D core
//! pipeline).

mod asset;
mod draw;
mod error;
mod extract;
mod messages;
mod object;
mod proxy;
mod report;
pub mod stats;

pub use asset::{OslfStore, OslfStoreLoader};
pub use error::OslfBevyError;
pub use messages::OslfMessages;
pub use object::OslfObject;
pub use oslf_runtime::{
    AshikhminShirley, Blend, CacheConfig, Glossy, Lookup, Mirror, Mode, MonteCarlo, Order, Pbr,
    PbrIntegration, PbrMaterial, Probe, Recon, ReconGlossy, ReconMirror, SampleFilter,
    ShadingParams, Source,
};
pub use proxy::OslfProxy;
pub use stats::OslfCacheStats;

use bevy::app::{App, Plugin, Update};
use bevy::asset::AssetApp;
use bevy::core_pipeline::core_3d::{main_opaque_pass_3d, main_transparent_pass_3d};
use bevy::core_pipeline::deferred::node::late_deferred_prepass;
use bevy::core_pipeline::prepass::node::late_prepass;
use bevy::core_pipeline::schedule::{Core3d, Core3dSystems};
use bevy::ecs::prelude::*;
use bevy::render::renderer::{RenderGraph, RenderGraphSystems};
use bevy::render::{ExtractSchedule, Render, RenderApp, RenderSystems};

/// Draws [`OslfObject`]s: add it after `DefaultPlugins`.
#[derive(Clone, Copy, Debug, Default)]
pub struct OslfPlugin {
    /// The cube-map cache of each store's renderer (GPU slots, RAM budget, granularity).
    pub cache: CacheConfig,
}

impl Plugin for OslfPlugin {
    fn build(&self, app: &mut App) {
        let messages = OslfMessages::default();
        let sink = stats::StatsSink::default();
        app.init_asset::<OslfStore>()
            .init_asset_loader::<OslfStoreLoader>()
            .insert_resource(messages.clone())
            .insert_resource(sink.clone())
            .add_systems(Update, (stats::publish_stats, report::report_stores));
        stats::register(app);
        proxy::register(app);
        if let Some(render_app) = app.get_sub_app_mut(RenderApp) {
            render_app
                .insert_resource(messages)
                .insert_resource(sink)
                .insert_resource(draw::OslfSettings { cache: self.cache })
                .init_resource::<extract::ExtractedOslf>()
                .init_resource::<draw::OslfRenderers>();
        }
    }

    // The render world's systems are added once every plugin is built: Bevy's core pipeline
    // replaces the `Core3d` schedule when it builds, dropping systems added to it earlier.
    fn finish(&self, app: &mut App) {
        let Some(render_app) = app.get_sub_app_mut(RenderApp) else {
            return;
        };
        render_app
            .add_systems(ExtractSchedule, extract::extract_oslf)
            .add_systems(Render, draw::prepare_oslf.in_set(RenderSystems::Prepare))
            .add_systems(
                Core3d,
                // Inside Bevy's prepass set, after its passes: what reads the prepass (SSAO,
                // the deferred lighting-id copy) runs after the set, the object in it.
                draw::prepass_oslf
                    .after(late_prepass)
                    .after(late_deferred_prepass)
                    .in_set(Core3dSystems::Prepass),
            )
            .add_systems(
                Core3d,
                draw::draw_oslf
                    .after(main_opaque_pass_3d)
                    .before(main_transparent_pass_3d)
                    .in_set(Core3dSystems::MainPass),
            )
            .add_systems(
                RenderGraph,
                draw::after_submit_oslf.after(RenderGraphSystems::Submit),
            );
    }
}
