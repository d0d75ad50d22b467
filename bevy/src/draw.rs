//! The render world's side: one runtime [`Renderer`] per store (its cube-map cache shared by
//! every object of that store), made on Bevy's own device; each 3D camera draws every visible
//! object into its colour and depth targets between Bevy's opaque and transparent passes; the
//! cache's feedback is booked after Bevy submits the frame, without waiting for the GPU.

use std::collections::HashMap;
use std::sync::Mutex;

use bevy::asset::AssetId;
use bevy::ecs::prelude::*;
use bevy::render::camera::ExtractedCamera;
use bevy::render::diagnostic::RecordDiagnostics;
use bevy::render::render_resource::RenderPassDescriptor;
use bevy::render::renderer::{
    RenderAdapterInfo, RenderContext, RenderDevice, RenderQueue, ViewQuery,
};
use bevy::render::view::{ExtractedView, Msaa, ViewDepthStencilTexture, ViewTarget};
use oslf_runtime::{CacheConfig, Gpu, HostTarget, HostView, Renderer, DEPTH_SLACK};

use crate::asset::OslfStore;
use crate::error::OslfBevyError;
use crate::extract::ExtractedOslf;
use crate::messages::OslfMessages;
use crate::stats::StatsSink;

/// The plugin's settings in the render world.
#[derive(Resource, Clone, Copy)]
pub(crate) struct OslfSettings {
    pub cache: CacheConfig,
    /// Whether objects have proxies in Bevy's depth (`proxy.rs`), which their own depth must
    /// win over.
    pub proxies: bool,
}

/// A store's renderer, or why it has none.
struct StoreSlot {
    /// The asset it was made from (a reloaded asset makes a new renderer).
    source: OslfStore,
    /// In a mutex only to be `Sync`, as a resource must be (the cache's decoder channel is
    /// not); the render world reaches it through `&mut`, never locking.
    renderer: Option<Mutex<Renderer>>,
    /// Whether a view drew it this frame (its feedback is then booked after submission).
    drew: bool,
}

/// The renderers of the stores in use, on Bevy's device.
#[derive(Resource, Default)]
pub(crate) struct OslfRenderers {
    gpu: Option<Gpu>,
    slots: HashMap<AssetId<OslfStore>, StoreSlot>,
}

/// Bevy's math (glam 0.33) to the runtime's (glam 0.34), column by column.
fn to_runtime(m: bevy::math::Mat4) -> glam::Mat4 {
    glam::Mat4::from_cols_array(&m.to_cols_array())
}

/// Makes a renderer for each store in use that has none (or whose asset changed) and drops
/// those no object uses any more.
pub(crate) fn prepare_oslf(
    mut renderers: ResMut<OslfRenderers>,
    frame: Res<ExtractedOslf>,
    settings: Res<OslfSettings>,
    messages: Res<OslfMessages>,
    device: Res<RenderDevice>,
    queue: Res<RenderQueue>,
    info: Res<RenderAdapterInfo>,
) {
    for entity in &frame.sheared {
        messages.say(format!(
            "OSLF object {entity}: its transform scales unevenly (or by zero), which the baked \
             light field cannot follow, so it is not drawn"
        ));
    }
    let renderers = &mut *renderers;
    renderers
        .slots
        .retain(|id, _| frame.stores.iter().any(|(s, _)| s == id));
    if frame.stores.is_empty() {
        return;
    }
    let gpu = renderers
        .gpu
        .get_or_insert_with(|| {
            let queue: &wgpu::Queue = &queue;
            Gpu::from_host_device(
                device.wgpu_device().clone(),
                queue.clone(),
                format!("{} ({:?})", info.name, info.backend),
            )
        })
        .clone();
    for (id, store) in &frame.stores {
        if renderers
            .slots
            .get(id)
            .is_some_and(|s| s.source.same_bytes(store))
        {
            continue;
        }
        let renderer = store
            .open()
            .map_err(|source| OslfBevyError::Store {
                path: format!("{id}"),
                source,
            })
            .and_then(|s| Ok(Renderer::new(gpu.clone(), s, settings.cache)?));
        let renderer = match renderer {
            Ok(r) => Some(Mutex::new(r)),
            Err(e) => {
                messages.say(format!(
                    "OSLF store {id}: cannot be drawn on this device: {e}"
                ));
                None
            }
        };
        renderers.slots.insert(
            *id,
            StoreSlot {
                source: store.clone(),
                renderer,
                drew: false,
            },
        );
    }
}

/// Draws every visible object into this camera's targets, after Bevy's opaque pass: depth-
/// tested against Bevy's meshes (reversed depth), its own depth written, its radiance scaled
/// by the camera's exposure (Bevy's tonemapping follows, as for its meshes).
pub(crate) fn draw_oslf(
    view: ViewQuery<(
        &ExtractedCamera,
        &ExtractedView,
        &ViewTarget,
        &ViewDepthStencilTexture,
        &Msaa,
    )>,
    frame: Res<ExtractedOslf>,
    mut renderers: ResMut<OslfRenderers>,
    messages: Res<OslfMessages>,
    settings: Res<OslfSettings>,
    mut ctx: RenderContext,
) {
    if frame.objects.is_empty() {
        return;
    }
    let view_entity = view.entity();
    let (camera, extracted, target, depth, msaa) = view.into_inner();
    if camera.viewport.is_some() {
        messages.say(format!(
            "OSLF: camera {view_entity} draws into a viewport, which OSLF objects do not \
             support yet; they are not drawn by it"
        ));
        return;
    }
    if !camera.hdr {
        messages.say(format!(
            "OSLF: camera {view_entity} is not HDR: Bevy tonemaps its meshes in their shaders \
             then, and OSLF objects are written untonemapped (add `Hdr` to the camera)"
        ));
    }
    let samples = msaa.samples();
    let color = if samples > 1 {
        target.sampled_main_texture_view()
    } else {
        Some(target.main_texture_view())
    };
    let Some(color) = color else {
        return;
    };
    let size = target.main_texture().size();
    let host_target = HostTarget {
        color,
        color_format: target.main_texture_format(),
        depth: depth.attachment.depth_stencil_views().attachment_view(),
        depth_format: depth.texture().format(),
        // Bevy's depth is reversed (1 near, 0 far); its meshes pass GreaterEqual.
        depth_compare: wgpu::CompareFunction::GreaterEqual,
        sample_count: samples,
        width: size.width,
        height: size.height,
        depth_slack: if settings.proxies { DEPTH_SLACK } else { 0.0 },
    };
    let view_from_world = extracted.world_from_view.to_matrix().inverse();
    // The plugin's share of the frame, CPU and GPU, as Bevy's RenderDiagnosticsPlugin shows
    // its own passes' (`render/oslf/elapsed_gpu`, where the adapter has timestamp queries).
    let diagnostics = ctx.diagnostic_recorder();
    let diagnostics = diagnostics.as_deref();
    let span = diagnostics.time_span(ctx.command_encoder(), "oslf");
    let mut drew = false;
    for object in &frame.objects {
        let Some(slot) = renderers.slots.get_mut(&object.store) else {
            continue;
        };
        let Some(Ok(renderer)) = slot.renderer.as_mut().map(Mutex::get_mut) else {
            continue;
        };
        let host_view = HostView {
            view: to_runtime(view_from_world * object.world_from_local),
            projection: to_runtime(extracted.clip_from_view),
            exposure: camera.exposure * object.radiance_scale,
        };
        match renderer.encode_into(
            ctx.command_encoder(),
            &host_view,
            &host_target,
            &object.params,
        ) {
            Ok(()) => {
                slot.drew = true;
                drew = true;
            }
            Err(e) => {
                messages.say(format!(
                    "OSLF object {}: not drawn by camera {view_entity}: {e}",
                    object.entity
                ));
            }
        }
    }
    if drew && samples > 1 {
        // Bevy resolved its multisampled colour at the end of the opaque pass, and its
        // transparent pass resolves only when it has something to draw: resolve again so the
        // object reaches the single-sample texture that post-processing reads.
        drop(
            ctx.command_encoder()
                .begin_render_pass(&RenderPassDescriptor {
                    label: Some("oslf msaa resolve"),
                    color_attachments: &[Some(target.get_color_attachment())],
                    depth_stencil_attachment: None,
                    timestamp_writes: None,
                    occlusion_query_set: None,
                    multiview_mask: None,
                }),
        );
    }
    span.end(ctx.command_encoder());
}

/// After Bevy submitted the frame: each renderer that drew maps its feedback and books what
/// earlier frames' feedback asked for (loads, uploads), never waiting for the GPU.
pub(crate) fn after_submit_oslf(
    mut renderers: ResMut<OslfRenderers>,
    sink: Res<StatsSink>,
    messages: Res<OslfMessages>,
) {
    for (id, slot) in &mut renderers.slots {
        if !std::mem::take(&mut slot.drew) {
            continue;
        }
        let Some(Ok(renderer)) = slot.renderer.as_mut().map(Mutex::get_mut) else {
            continue;
        };
        match renderer.after_submit() {
            Ok(Some(stats)) => {
                sink.add(&stats);
                if let Some(seconds) = renderer.host_pass_seconds() {
                    sink.passes(*id, seconds);
                }
            }
            Ok(None) => {}
            Err(e) => {
                messages.say(format!(
                    "OSLF store {id}: booking the cache's feedback: {e}"
                ));
            }
        }
    }
}
