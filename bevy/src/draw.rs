//! The render world's side: one runtime [`Renderer`] per store (its cube-map cache shared by
//! every object of that store), made on Bevy's own device; each 3D camera with a prepass
//! writes every visible object into it after Bevy's prepass (the object's G-buffer, rasterised
//! once: depth, normals, motion vectors), and each 3D camera draws every visible object into
//! its colour and depth targets between Bevy's opaque and transparent passes, from that
//! G-buffer where the prepass made one; the cache's feedback is booked after Bevy submits the
//! frame, without waiting for the GPU.

use std::collections::HashMap;
use std::sync::Mutex;

use bevy::asset::AssetId;
use bevy::core_pipeline::prepass::{PreviousViewData, ViewPrepassTextures};
use bevy::ecs::prelude::*;
use bevy::render::camera::{ExtractedCamera, TemporalJitter};
use bevy::render::diagnostic::RecordDiagnostics;
use bevy::render::render_resource::RenderPassDescriptor;
use bevy::render::renderer::{
    RenderAdapterInfo, RenderContext, RenderDevice, RenderQueue, ViewQuery,
};
use bevy::render::view::{ExtractedView, Msaa, ViewDepthStencilTexture, ViewTarget};
use oslf_runtime::{CacheConfig, Gpu, HostPrepass, HostTarget, HostView, PrepassTarget, Renderer};

use crate::asset::OslfStore;
use crate::error::OslfBevyError;
use crate::extract::ExtractedOslf;
use crate::messages::OslfMessages;
use crate::stats::StatsSink;

/// The plugin's settings in the render world.
#[derive(Resource, Clone, Copy)]
pub(crate) struct OslfSettings {
    pub cache: CacheConfig,
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

impl OslfRenderers {
    /// The renderer of `store`, if it has one, and its slot's flag saying a view drew it.
    fn renderer(&mut self, store: AssetId<OslfStore>) -> Option<(&mut Renderer, &mut bool)> {
        let slot = self.slots.get_mut(&store)?;
        let renderer = slot.renderer.as_mut()?.get_mut().ok()?;
        Some((renderer, &mut slot.drew))
    }
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

/// The runtime's view of `object` through Bevy's `view`, at the camera's exposure, jittered
/// as Bevy jitters its meshes this frame (TAA) for a target of `size`.
fn host_view(
    camera: &ExtractedCamera,
    view: &ExtractedView,
    jitter: Option<&TemporalJitter>,
    size: wgpu::Extent3d,
    object: &crate::extract::ExtractedObject,
) -> HostView {
    let view_from_world = view.world_from_view.to_matrix().inverse();
    let pixels = bevy::math::Vec2::new(size.width as f32, size.height as f32);
    let jitter = jitter.map_or([0.0; 2], |j| ndc_jitter(view.clip_from_view, j, pixels));
    HostView {
        view: to_runtime(view_from_world * object.world_from_local),
        projection: to_runtime(view.clip_from_view),
        exposure: camera.exposure * object.radiance_scale,
        jitter,
    }
}

/// How far `jitter` moves what the perspective `clip_from_view` projects this frame, in
/// normalised device coordinates, for a target of `size` pixels: Bevy jitters the projection's
/// third column, which with clip w = −z_view moves normalised x, y by minus what it added.
fn ndc_jitter(
    clip_from_view: bevy::math::Mat4,
    jitter: &TemporalJitter,
    size: bevy::math::Vec2,
) -> [f32; 2] {
    let mut jittered = clip_from_view;
    jitter.jitter_projection(&mut jittered, size);
    let moved = jittered.z_axis - clip_from_view.z_axis;
    [-moved.x, -moved.y]
}

/// What [`prepass_oslf`] reads of a view: its camera, matrices, depth target, samples per
/// pixel, prepass targets, previous matrices (where it has motion vectors) and jitter (with
/// TAA).
type PrepassView = (
    &'static ExtractedCamera,
    &'static ExtractedView,
    &'static ViewDepthStencilTexture,
    &'static Msaa,
    &'static ViewPrepassTextures,
    Option<&'static PreviousViewData>,
    Option<&'static TemporalJitter>,
);

/// Writes every visible object into this camera's prepass, after Bevy's: its depth into the
/// view's depth (which Bevy's main pass then tests its meshes against, and which is copied
/// again into the prepass depth texture SSAO and other effects read), its world normals and
/// motion vectors into the prepass's targets where the camera has them. Each object is
/// rasterised into its renderer's G-buffer here, which [`draw_oslf`] shades. A camera without
/// a prepass draws in [`draw_oslf`] alone.
pub(crate) fn prepass_oslf(
    view: ViewQuery<PrepassView>,
    frame: Res<ExtractedOslf>,
    mut renderers: ResMut<OslfRenderers>,
    messages: Res<OslfMessages>,
    mut ctx: RenderContext,
) {
    if frame.objects.is_empty() {
        return;
    }
    let view_entity = view.entity();
    let (camera, extracted, depth, msaa, textures, previous, jitter) = view.into_inner();
    let has_prepass = textures.depth.is_some()
        || textures.normal.is_some()
        || textures.motion_vectors.is_some()
        || textures.deferred.is_some();
    // A viewport is refused by `draw_oslf`, which says so.
    if !has_prepass || camera.viewport.is_some() {
        return;
    }
    let target = |a: &bevy::render::texture::ColorAttachment| {
        let texture = &a.texture;
        (texture.default_view.clone(), texture.texture.format())
    };
    let (normal, motion) = (
        textures.normal.as_ref().map(target),
        textures.motion_vectors.as_ref().map(target),
    );
    let size = depth.texture().size();
    let clip_from_world =
        extracted.clip_from_view * extracted.world_from_view.to_matrix().inverse();
    let previous_clip_from_world =
        previous.map_or(clip_from_world, |p| p.unjittered_clip_from_world);
    let diagnostics = ctx.diagnostic_recorder();
    let diagnostics = diagnostics.as_deref();
    let span = diagnostics.time_span(ctx.command_encoder(), "oslf_prepass");
    let mut wrote = false;
    for object in &frame.objects {
        let Some((renderer, _)) = renderers.renderer(object.store) else {
            continue;
        };
        let prepass = HostPrepass {
            depth: depth.attachment.depth_stencil_views().attachment_view(),
            depth_format: depth.texture().format(),
            // Bevy's depth is reversed (1 near, 0 far); its meshes pass GreaterEqual.
            depth_compare: wgpu::CompareFunction::GreaterEqual,
            sample_count: msaa.samples(),
            width: size.width,
            height: size.height,
            normal: normal.as_ref().map(|(view, format)| PrepassTarget {
                view,
                format: *format,
            }),
            motion: motion.as_ref().map(|(view, format)| PrepassTarget {
                view,
                format: *format,
            }),
            world_from_local: to_runtime(object.world_from_local),
            previous_clip_from_local: to_runtime(
                previous_clip_from_world * object.previous_world_from_local,
            ),
        };
        match renderer.encode_prepass_into(
            ctx.command_encoder(),
            &host_view(camera, extracted, jitter, size, object),
            &prepass,
            &object.params,
        ) {
            Ok(()) => wrote = true,
            Err(e) => {
                messages.say(format!(
                    "OSLF object {}: not in the prepass of camera {view_entity}: {e}",
                    object.entity
                ));
            }
        }
    }
    // Bevy copied the view's depth into the prepass depth texture at the end of its
    // prepass, before the objects were in it.
    if let (true, Some(prepass_depth)) = (wrote, &textures.depth) {
        ctx.command_encoder().copy_texture_to_texture(
            depth.texture().as_image_copy(),
            prepass_depth.texture.texture.as_image_copy(),
            textures.size,
        );
    }
    span.end(ctx.command_encoder());
}

/// What [`draw_oslf`] reads of a view: its camera, matrices, colour and depth targets,
/// samples per pixel and jitter (with TAA).
type DrawView = (
    &'static ExtractedCamera,
    &'static ExtractedView,
    &'static ViewTarget,
    &'static ViewDepthStencilTexture,
    &'static Msaa,
    Option<&'static TemporalJitter>,
);

/// Draws every visible object into this camera's targets, after Bevy's opaque pass: depth-
/// tested against Bevy's meshes (reversed depth), its own depth written, its radiance scaled
/// by the camera's exposure (Bevy's tonemapping follows, as for its meshes).
pub(crate) fn draw_oslf(
    view: ViewQuery<DrawView>,
    frame: Res<ExtractedOslf>,
    mut renderers: ResMut<OslfRenderers>,
    messages: Res<OslfMessages>,
    mut ctx: RenderContext,
) {
    if frame.objects.is_empty() {
        return;
    }
    let view_entity = view.entity();
    let (camera, extracted, target, depth, msaa, jitter) = view.into_inner();
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
        // Bevy's depth holds no proxy of the object (only its prepass's own depth, which the
        // runtime matches exactly).
        depth_slack: 0.0,
    };
    // The plugin's share of the frame, CPU and GPU, as Bevy's RenderDiagnosticsPlugin shows
    // its own passes' (`render/oslf/elapsed_gpu`, where the adapter has timestamp queries).
    let diagnostics = ctx.diagnostic_recorder();
    let diagnostics = diagnostics.as_deref();
    let span = diagnostics.time_span(ctx.command_encoder(), "oslf");
    let mut drew = false;
    for object in &frame.objects {
        let Some((renderer, slot_drew)) = renderers.renderer(object.store) else {
            continue;
        };
        match renderer.encode_into(
            ctx.command_encoder(),
            &host_view(camera, extracted, jitter, size, object),
            &host_target,
            &object.params,
        ) {
            Ok(()) => {
                *slot_drew = true;
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

#[cfg(test)]
mod tests {
    use super::*;
    use bevy::camera::CameraProjection;
    use bevy::math::{Mat4, Vec2, Vec3, Vec4Swizzles};

    /// The runtime's jitter moves a point's normalised coordinates as Bevy's jittered
    /// projection does, for Bevy's infinite reversed perspective.
    #[test]
    fn the_jitter_moves_points_as_bevys_jittered_projection() {
        // Bevy's own perspective projection (infinite, reversed depth).
        let projection = bevy::camera::PerspectiveProjection {
            fov: 0.8,
            aspect_ratio: 16.0 / 9.0,
            near: 0.1,
            ..Default::default()
        }
        .get_clip_from_view();
        let size = Vec2::new(1920.0, 1080.0);
        let jitter = TemporalJitter {
            offset: Vec2::new(0.3, -0.45),
        };
        let [jx, jy] = ndc_jitter(projection, &jitter, size);
        let mut jittered = projection;
        jitter.jitter_projection(&mut jittered, size);
        for p in [Vec3::new(0.5, -0.2, -3.0), Vec3::new(-4.0, 1.0, -40.0)] {
            let ndc = |m: Mat4| {
                let c = m * p.extend(1.0);
                c.xy() / c.w
            };
            let moved = ndc(jittered) - ndc(projection);
            assert!(
                (moved - Vec2::new(jx, jy)).length() < 1e-6,
                "{moved} {jx} {jy}"
            );
            // A sub-pixel offset: 0.3 and 0.45 of a pixel (2 / size in normalised units).
            assert!((moved.abs() * size / 2.0 - Vec2::new(0.3, 0.45)).length() < 1e-3);
        }
    }
}
