//! The object in Bevy's prepass, written there by the plugin (src/draw.rs, `prepass_oslf`), in
//! a real headless Bevy app: a camera with depth, normal and motion-vector prepasses sees the
//! moving object's unit world normals and its motion (the screen motion of its centre from one
//! frame to the next), while Bevy's still table beside it has none. Bevy's prepass textures
//! cannot be copied, so a test pass loads them into a texture that can be.
//!
//! On lavapipe in CI; this test fails, never skips, without an adapter.

#[path = "../../runtime/tests/common/mod.rs"]
mod common;
#[path = "../examples/shared/headless.rs"]
mod headless;

use std::sync::{Arc, Mutex};

use bevy::app::{App, Startup, Update};
use bevy::asset::{AssetServer, Assets};
use bevy::core_pipeline::prepass::{
    DepthPrepass, MotionVectorPrepass, NormalPrepass, ViewPrepassTextures,
};
use bevy::core_pipeline::schedule::{Core3d, Core3dSystems};
use bevy::ecs::prelude::*;
use bevy::image::Image;
use bevy::math::Vec3;
use bevy::mesh::{Mesh, Mesh3d};
use bevy::pbr::{MeshMaterial3d, StandardMaterial};
use bevy::render::renderer::{
    RenderContext, RenderDevice, RenderGraph, RenderGraphSystems, ViewQuery,
};
use bevy::render::view::Msaa;
use bevy::render::RenderApp;
use bevy::shape::Cuboid;
use bevy::transform::components::Transform;
use glam::camera::rh::proj::directx;
use glam::camera::rh::view::look_at_mat4;
use oslf_bevy::{Mode, OslfMessages, OslfObject, ShadingParams};
use oslf_runtime::{CacheConfig, Camera, Gpu, Renderer};

const W: u32 = 160;
const H: u32 = 120;

/// The store's camera, the centre of the object's bounds and how far the object moves per
/// frame (world units).
#[derive(Resource, Clone, Copy)]
struct Setup {
    camera: Camera,
    centre: glam::Vec3,
    floor: f32,
    step: glam::Vec3,
}

/// Moves its entity by this much every update.
#[derive(Component)]
struct Mover(Vec3);

fn setup(
    mut commands: Commands,
    setup: Res<Setup>,
    assets: Res<AssetServer>,
    mut images: ResMut<Assets<Image>>,
    mut meshes: ResMut<Assets<Mesh>>,
    mut materials: ResMut<Assets<StandardMaterial>>,
) {
    let s = *setup;
    headless::spawn_linear_camera(&mut commands, &mut images, &s.camera, (W, H), Msaa::Off)
        .insert((DepthPrepass, NormalPrepass, MotionVectorPrepass));
    commands.spawn((
        OslfObject::new(assets.load("teapot.oslf"))
            .with_params(ShadingParams::of_mode(Mode::ReconMirror)),
        Mover(Vec3::from_array(s.step.to_array())),
    ));
    // A still table under the object.
    commands.spawn((
        Mesh3d(meshes.add(Cuboid::new(40.0, 40.0, 0.2))),
        MeshMaterial3d(materials.add(StandardMaterial::default())),
        Transform::from_translation(Vec3::new(s.centre.x, s.centre.y, s.floor - 0.1)),
    ));
}

fn move_objects(mut movers: Query<(&mut Transform, &Mover)>) {
    for (mut t, m) in &mut movers {
        t.translation += m.0;
    }
}

/// The latest frame's prepass as the test pass read it, per pixel: motion (x, y), the length
/// of the decoded normal, and the normal's alpha (1 where written).
#[derive(Resource, Clone, Default)]
struct PrepassPixels(Arc<Mutex<Option<Vec<[f32; 4]>>>>);

/// The read-back buffer the current frame's test pass copied into.
#[derive(Resource, Default)]
struct Pending(Option<wgpu::Buffer>);

const READ_WGSL: &str = "
@group(0) @binding(0) var normals: texture_2d<f32>;
@group(0) @binding(1) var motion: texture_2d<f32>;
@vertex fn vs(@builtin(vertex_index) i: u32) -> @builtin(position) vec4<f32> {
    let p = vec2<f32>(f32((i << 1u) & 2u), f32(i & 2u)) * 2.0 - 1.0;
    return vec4<f32>(p, 0.0, 1.0);
}
@fragment fn fs(@builtin(position) p: vec4<f32>) -> @location(0) vec4<f32> {
    let xy = vec2<i32>(p.xy);
    let n = textureLoad(normals, xy, 0);
    return vec4<f32>(textureLoad(motion, xy, 0).xy, length(n.xyz * 2.0 - 1.0), n.w);
}";

/// After Bevy's main pass: loads the view's normal and motion prepass into a copyable
/// `Rgba32Float` texture, and copies that into a buffer to map after submission.
fn read_prepass(
    view: ViewQuery<&ViewPrepassTextures>,
    device: Res<RenderDevice>,
    mut pending: ResMut<Pending>,
    mut ctx: RenderContext,
) {
    let textures = view.into_inner();
    let (Some(normal), Some(motion)) = (&textures.normal, &textures.motion_vectors) else {
        return;
    };
    let device: &wgpu::Device = device.wgpu_device();
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("read prepass"),
        source: wgpu::ShaderSource::Wgsl(READ_WGSL.into()),
    });
    let format = wgpu::TextureFormat::Rgba32Float;
    let pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some("read prepass"),
        layout: None,
        vertex: wgpu::VertexState {
            module: &module,
            entry_point: Some("vs"),
            compilation_options: Default::default(),
            buffers: &[],
        },
        primitive: Default::default(),
        depth_stencil: None,
        multisample: Default::default(),
        fragment: Some(wgpu::FragmentState {
            module: &module,
            entry_point: Some("fs"),
            compilation_options: Default::default(),
            targets: &[Some(format.into())],
        }),
        multiview_mask: None,
        cache: None,
    });
    let group = device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("read prepass"),
        layout: &pipeline.get_bind_group_layout(0),
        entries: &[
            wgpu::BindGroupEntry {
                binding: 0,
                resource: wgpu::BindingResource::TextureView(&normal.texture.default_view),
            },
            wgpu::BindGroupEntry {
                binding: 1,
                resource: wgpu::BindingResource::TextureView(&motion.texture.default_view),
            },
        ],
    });
    let size = wgpu::Extent3d {
        width: W,
        height: H,
        depth_or_array_layers: 1,
    };
    let out = device.create_texture(&wgpu::TextureDescriptor {
        label: Some("read prepass"),
        size,
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format,
        usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
        view_formats: &[],
    });
    let row = W * 16; // 2560 bytes, a multiple of 256
    let buffer = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("read prepass"),
        size: u64::from(row * H),
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let encoder = ctx.command_encoder();
    {
        let view = out.create_view(&Default::default());
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("read prepass"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: &view,
                depth_slice: None,
                resolve_target: None,
                ops: Default::default(),
            })],
            depth_stencil_attachment: None,
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        pass.set_pipeline(&pipeline);
        pass.set_bind_group(0, &group, &[]);
        pass.draw(0..3, 0..1);
    }
    encoder.copy_texture_to_buffer(
        out.as_image_copy(),
        wgpu::TexelCopyBufferInfo {
            buffer: &buffer,
            layout: wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(row),
                rows_per_image: Some(H),
            },
        },
        size,
    );
    pending.0 = Some(buffer);
}

/// After Bevy submitted the frame: maps the test pass's buffer (waiting) into
/// [`PrepassPixels`].
fn map_prepass(mut pending: ResMut<Pending>, device: Res<RenderDevice>, out: Res<PrepassPixels>) {
    let Some(buffer) = pending.0.take() else {
        return;
    };
    buffer.map_async(wgpu::MapMode::Read, .., |r| r.unwrap());
    device
        .wgpu_device()
        .poll(wgpu::PollType::wait_indefinitely())
        .unwrap();
    let bytes = buffer.get_mapped_range(..).unwrap().to_vec();
    let texels = bytes
        .chunks_exact(16)
        .map(|t| {
            std::array::from_fn(|k| f32::from_le_bytes(t[4 * k..4 * k + 4].try_into().unwrap()))
        })
        .collect();
    *out.0.lock().unwrap() = Some(texels);
}

/// The store's camera as Bevy's (the infinite reversed projection of `spawn_linear_camera`):
/// clip from world.
fn clip_from_world(camera: &Camera) -> glam::Mat4 {
    let projection = directx::perspective_infinite_reverse(
        camera.vfov_deg.to_radians(),
        W as f32 / H as f32,
        0.01,
    );
    projection * look_at_mat4(camera.position, camera.target, camera.up)
}

#[test]
fn the_moving_object_is_in_bevys_normal_and_motion_vector_prepass() {
    let store = common::store_path();
    let (camera, lo, hi) = {
        let opened = oslf_format::Store::open(&store).unwrap();
        let r = Renderer::new(Gpu::headless().unwrap(), opened, CacheConfig::default()).unwrap();
        let (lo, hi) = r.mesh().bounds();
        (r.default_view(), lo, hi)
    };
    // Sideways on screen, a two-hundredth of the object's size per frame.
    let right = (camera.target - camera.position)
        .cross(camera.up)
        .normalize();
    let step = right * 0.005 * (hi - lo).length();
    let s = Setup {
        camera,
        centre: (lo + hi) * 0.5,
        floor: lo.z,
        step,
    };
    let mut app = headless::headless_app(store.parent().unwrap(), CacheConfig::default());
    app.insert_resource(s)
        .add_systems(Startup, setup)
        .add_systems(Update, move_objects);
    app.finish();
    app.cleanup();
    let pixels = PrepassPixels::default();
    app.sub_app_mut(RenderApp)
        .insert_resource(pixels.clone())
        .init_resource::<Pending>()
        .add_systems(Core3d, read_prepass.after(Core3dSystems::MainPass))
        .add_systems(RenderGraph, map_prepass.after(RenderGraphSystems::Submit));
    // Until the store is loaded and the object moves in the prepass, then a few frames more.
    // Bevy's still meshes move by rounding (1e-7); the object by a few thousandths.
    let moving = |p: &[f32; 4]| p[0].hypot(p[1]) > 1e-4;
    let start = std::time::Instant::now();
    let mut more = 5;
    while more > 0 && start.elapsed().as_secs() < 120 {
        app.update();
        let seen = pixels
            .0
            .lock()
            .unwrap()
            .as_ref()
            .is_some_and(|p| p.iter().any(moving));
        if seen {
            more -= 1;
        }
    }
    let messages = app.world().resource::<OslfMessages>().all();
    assert!(messages.is_empty(), "{messages:?}");
    let frame = pixels
        .0
        .lock()
        .unwrap()
        .clone()
        .expect("no prepass read back");
    // Where the object's centre is on screen now and was a frame ago (updates so far, each
    // moving it a step): its motion in UV units, as Bevy's prepass stores motion.
    let clip = clip_from_world(&camera);
    let centre = s.centre + step * start_frames(&app) as f32;
    let uv = |p: glam::Vec3| {
        let c = clip * p.extend(1.0);
        glam::Vec2::new(c.x / c.w, c.y / c.w)
    };
    let motion = |p: glam::Vec3| (uv(p) - uv(p - step)) * glam::Vec2::new(0.5, -0.5);
    let want = motion(centre);
    // Nearer points move faster on screen: the bounds' corners give the range.
    let corners: Vec<f32> = (0..8)
        .map(|k| {
            let pick = |bit: u32, a: f32, b: f32| if k >> bit & 1 == 1 { b } else { a };
            let corner = glam::Vec3::new(
                pick(0, lo.x, hi.x),
                pick(1, lo.y, hi.y),
                pick(2, lo.z, hi.z),
            );
            motion(corner + (centre - s.centre)).length()
        })
        .collect();
    let slowest = corners.iter().copied().fold(f32::INFINITY, f32::min);
    let fastest = corners.iter().copied().fold(0.0, f32::max);
    let moved: Vec<&[f32; 4]> = frame.iter().filter(|p| moving(p)).collect();
    let object: Vec<glam::Vec2> = moved.iter().map(|p| glam::Vec2::new(p[0], p[1])).collect();
    println!(
        "{} of {} pixels moving; the centre's motion {want}, the corners' {slowest}…{fastest}",
        object.len(),
        frame.len()
    );
    // The object covers a good part of the frame (the table the rest: still), and wrote unit
    // normals.
    assert!(
        (1000..frame.len() / 2).contains(&object.len()),
        "{} moving pixels",
        object.len()
    );
    assert!(
        moved.iter().all(|p| (p[2] - 1.0).abs() < 0.01),
        "the object wrote a normal that is not a unit one"
    );
    // Every moving pixel moves the way the object's centre does (within a degree), as fast
    // as a point within its bounds.
    let off: Vec<&glam::Vec2> = object
        .iter()
        .filter(|m| {
            let speed = m.length();
            m.angle_to(want).abs() > 1f32.to_radians()
                || speed < 0.95 * slowest
                || speed > 1.05 * fastest
        })
        .collect();
    assert!(
        off.is_empty(),
        "{} of {} moving pixels do not move as the object: {:?}",
        off.len(),
        object.len(),
        &off[..off.len().min(5)]
    );
}

/// Updates run so far: the object's position is its start plus this many steps.
fn start_frames(app: &App) -> u32 {
    app.world().resource::<bevy::diagnostic::FrameCount>().0
}
