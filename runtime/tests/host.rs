//! Drawing into a host's frame (`Renderer::encode_into`, `after_submit`): the host's matrices,
//! colour and depth targets and encoder, depth tested both ways against the host's meshes,
//! with depth growing away from the camera and reversed (as Bevy draws), single-sampled and
//! 4× multisampled; the cache's feedback read back asynchronously until nothing falls back.
//! The object's pixels equal the CPU reference of the same G-buffer, as for
//! `Renderer::render`. With a host prepass (`Renderer::encode_prepass_into`), the object's depth,
//! normals and motion vectors are in the host's prepass targets before its main pass, and the
//! frame shades them alike.

use crate::common;
use crate::common::knobs::Knobs;

use std::sync::{Arc, Mutex};

use common::{compare, open_store};
use glam::camera::rh::proj::directx;
use glam::camera::rh::view::look_at_mat4;
use glam::{Mat4, Vec3};
use oslf_runtime::reference::{prepass_motion, prepass_normal, GTexel, StoreCubes};
use oslf_runtime::renderer::normal_from_local;
use oslf_runtime::{
    CacheConfig, Gpu, HostPrepass, HostTarget, HostView, Mode, PrepassTarget, Renderer,
};

const W: u32 = 160;
const H: u32 = 120;
const COLOR: wgpu::TextureFormat = wgpu::TextureFormat::Rgba32Float;
const COLOR_MSAA: wgpu::TextureFormat = wgpu::TextureFormat::Rgba16Float;
const DEPTH: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;
/// Bevy's prepass formats: normals, motion vectors.
const NORMAL: wgpu::TextureFormat = wgpu::TextureFormat::Rgb10a2Unorm;
const MOTION: wgpu::TextureFormat = wgpu::TextureFormat::Rg16Float;
/// The clip-space shift of the host's previous frame in the prepass test: the object moved
/// 0.1 in normalised x since (a tenth of the half-width).
const PREVIOUS_SHIFT: f32 = 0.1;

/// The object's world transform in the prepass test: scaled unevenly, so that its world
/// normals need the inverse transpose (the shading itself does not use it).
fn world_from_local() -> Mat4 {
    Mat4::from_scale_rotation_translation(
        Vec3::new(2.0, 1.0, 0.25),
        glam::Quat::from_rotation_z(0.5),
        Vec3::new(1.0, -2.0, 3.0),
    )
}

/// The host's previous clip space in the prepass test: PREVIOUS_SHIFT further right.
fn previous_clip_from_clip() -> Mat4 {
    Mat4::from_translation(Vec3::new(PREVIOUS_SHIFT, 0.0, 0.0))
}
/// The host's clear colour, its mesh in front of the object (left half) and its mesh behind
/// the object (everywhere, drawn after it).
const CLEAR: [f32; 4] = [0.1, 0.2, 0.3, 1.0];
const FRONT: [f32; 4] = [1.0, 0.0, 0.0, 1.0];
const BEHIND: [f32; 4] = [0.0, 1.0, 0.0, 1.0];

struct Host {
    /// The colour target (multisampled with `samples` > 1, then resolved into `resolved`).
    color: wgpu::Texture,
    resolved: Option<wgpu::Texture>,
    format: wgpu::TextureFormat,
    depth: wgpu::Texture,
    reversed: bool,
    samples: u32,
    /// The prepass's normal and motion targets, where the host has a prepass.
    prepass: Option<(wgpu::Texture, wgpu::Texture)>,
}

impl Host {
    /// Single-sampled targets (`Rgba32Float`), or `samples` per pixel (`Rgba16Float`, which
    /// every adapter multisamples).
    fn new(gpu: &Gpu, reversed: bool, samples: u32, prepass: bool) -> Self {
        let make = |format, samples| {
            gpu.device.create_texture(&wgpu::TextureDescriptor {
                label: None,
                size: wgpu::Extent3d {
                    width: W,
                    height: H,
                    depth_or_array_layers: 1,
                },
                mip_level_count: 1,
                sample_count: samples,
                dimension: wgpu::TextureDimension::D2,
                format,
                usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
                view_formats: &[],
            })
        };
        let format = if samples == 1 { COLOR } else { COLOR_MSAA };
        Self {
            color: make(format, samples),
            resolved: (samples > 1).then(|| make(format, 1)),
            format,
            depth: make(DEPTH, samples),
            reversed,
            samples,
            prepass: prepass.then(|| (make(NORMAL, samples), make(MOTION, samples))),
        }
    }

    /// Depth as the host's convention has it: `near` 0 is the camera, 1 the far end.
    fn depth_of(&self, near: f32) -> f32 {
        if self.reversed {
            1.0 - near
        } else {
            near
        }
    }

    fn compare(&self) -> wgpu::CompareFunction {
        if self.reversed {
            wgpu::CompareFunction::Greater
        } else {
            wgpu::CompareFunction::Less
        }
    }

    /// Clears colour and depth, then draws the host's mesh in front of everything over the
    /// left half.
    fn begin(&self, gpu: &Gpu, encoder: &mut wgpu::CommandEncoder) {
        let cv = self.color.create_view(&Default::default());
        let dv = self.depth.create_view(&Default::default());
        let [r, g, b, a] = CLEAR.map(f64::from);
        encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("host clear"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: &cv,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Clear(wgpu::Color { r, g, b, a }),
                    store: wgpu::StoreOp::Store,
                },
            })],
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: &dv,
                depth_ops: Some(wgpu::Operations {
                    load: wgpu::LoadOp::Clear(self.depth_of(1.0)),
                    store: wgpu::StoreOp::Store,
                }),
                stencil_ops: None,
            }),
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        self.mesh(
            gpu,
            encoder,
            self.depth_of(0.0),
            FRONT,
            (0, W / 2),
            wgpu::CompareFunction::Always,
        );
        for t in self.prepass.iter().flat_map(|(n, m)| [n, m]) {
            let v = t.create_view(&Default::default());
            encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("host prepass clear"),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view: &v,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT),
                        store: wgpu::StoreOp::Store,
                    },
                })],
                depth_stencil_attachment: None,
                timestamp_writes: None,
                occlusion_query_set: None,
                multiview_mask: None,
            });
        }
    }

    /// A full-height quad over columns `x0..x1` at depth `z`, colour `c`, tested by `compare`.
    fn mesh(
        &self,
        gpu: &Gpu,
        encoder: &mut wgpu::CommandEncoder,
        z: f32,
        c: [f32; 4],
        (x0, x1): (u32, u32),
        compare: wgpu::CompareFunction,
    ) {
        let source = format!(
            "@vertex fn vs(@builtin(vertex_index) i: u32) -> @builtin(position) vec4<f32> {{
                let p = vec2<f32>(f32((i << 1u) & 2u), f32(i & 2u)) * 2.0 - 1.0;
                return vec4<f32>(p, {z:?}, 1.0);
            }}
            @fragment fn fs() -> @location(0) vec4<f32> {{
                return vec4<f32>({:?}, {:?}, {:?}, {:?});
            }}",
            c[0], c[1], c[2], c[3]
        );
        let module = gpu
            .device
            .create_shader_module(wgpu::ShaderModuleDescriptor {
                label: None,
                source: wgpu::ShaderSource::Wgsl(source.into()),
            });
        let pipeline = gpu
            .device
            .create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                label: Some("host mesh"),
                layout: None,
                vertex: wgpu::VertexState {
                    module: &module,
                    entry_point: Some("vs"),
                    compilation_options: Default::default(),
                    buffers: &[],
                },
                primitive: Default::default(),
                depth_stencil: Some(wgpu::DepthStencilState {
                    format: DEPTH,
                    depth_write_enabled: Some(true),
                    depth_compare: Some(compare),
                    stencil: Default::default(),
                    bias: Default::default(),
                }),
                multisample: wgpu::MultisampleState {
                    count: self.samples,
                    ..Default::default()
                },
                fragment: Some(wgpu::FragmentState {
                    module: &module,
                    entry_point: Some("fs"),
                    compilation_options: Default::default(),
                    targets: &[Some(self.format.into())],
                }),
                multiview_mask: None,
                cache: None,
            });
        let cv = self.color.create_view(&Default::default());
        let dv = self.depth.create_view(&Default::default());
        fn keep<V>() -> wgpu::Operations<V> {
            wgpu::Operations {
                load: wgpu::LoadOp::Load,
                store: wgpu::StoreOp::Store,
            }
        }
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("host mesh"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: &cv,
                depth_slice: None,
                resolve_target: None,
                ops: keep(),
            })],
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: &dv,
                depth_ops: Some(keep()),
                stencil_ops: None,
            }),
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        pass.set_viewport(x0 as f32, 0.0, (x1 - x0) as f32, H as f32, 0.0, 1.0);
        pass.set_pipeline(&pipeline);
        pass.draw(0..3, 0..1);
    }

    /// One host frame: its front mesh, the object, then its mesh behind the object drawn over
    /// everything; submitted, then the renderer's `after_submit`.
    fn frame(
        &self,
        gpu: &Gpu,
        r: &mut Renderer,
        view: &HostView,
        params: &Knobs,
    ) -> Option<oslf_runtime::CacheStats> {
        let mut encoder = gpu.device.create_command_encoder(&Default::default());
        self.begin(gpu, &mut encoder);
        let cv = self.color.create_view(&Default::default());
        let dv = self.depth.create_view(&Default::default());
        if let Some((normal, motion)) = &self.prepass {
            let (nv, mv) = (
                normal.create_view(&Default::default()),
                motion.create_view(&Default::default()),
            );
            let prepass = HostPrepass {
                depth: &dv,
                depth_format: DEPTH,
                depth_compare: self.compare(),
                sample_count: self.samples,
                width: W,
                height: H,
                normal: Some(PrepassTarget {
                    view: &nv,
                    format: NORMAL,
                }),
                motion: Some(PrepassTarget {
                    view: &mv,
                    format: MOTION,
                }),
                world_from_local: world_from_local(),
                // The previous frame saw the object PREVIOUS_SHIFT further right in clip space.
                previous_clip_from_local: previous_clip_from_clip() * view.projection * view.view,
            };
            r.encode_prepass_into(&mut encoder, view, &prepass, &params.params())
                .unwrap();
        }
        let target = HostTarget {
            color: &cv,
            color_format: self.format,
            depth: &dv,
            depth_format: DEPTH,
            depth_compare: self.compare(),
            sample_count: self.samples,
            width: W,
            height: H,
            depth_slack: 0.0,
        };
        r.encode_into(&mut encoder, view, &target, &params.params())
            .unwrap();
        self.mesh(
            gpu,
            &mut encoder,
            self.depth_of(0.9999),
            BEHIND,
            (0, W),
            self.compare(),
        );
        if let Some(resolved) = &self.resolved {
            // The host resolves its multisampled colour: an empty pass does.
            let rv = resolved.create_view(&Default::default());
            encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("host resolve"),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view: &cv,
                    depth_slice: None,
                    resolve_target: Some(&rv),
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Load,
                        store: wgpu::StoreOp::Store,
                    },
                })],
                depth_stencil_attachment: None,
                timestamp_writes: None,
                occlusion_query_set: None,
                multiview_mask: None,
            });
        }
        gpu.queue.submit([encoder.finish()]);
        r.after_submit().unwrap()
    }

    /// The colour target (resolved), as f32.
    fn colors(&self, gpu: &Gpu) -> Vec<[f32; 4]> {
        if self.format == COLOR {
            return self.read(gpu, false);
        }
        self.read::<[u16; 4]>(gpu, false)
            .into_iter()
            .map(|p| p.map(f16_to_f32))
            .collect()
    }

    fn read<T: bytemuck::Pod>(&self, gpu: &Gpu, depth: bool) -> Vec<T> {
        let texture = match (depth, &self.resolved) {
            (true, _) => &self.depth,
            (false, Some(resolved)) => resolved,
            (false, None) => &self.color,
        };
        self.read_texture(gpu, texture, depth)
    }

    /// A single-sampled `texture`'s texels as `T`, row-major (its depth aspect with `depth`).
    fn read_texture<T: bytemuck::Pod>(
        &self,
        gpu: &Gpu,
        texture: &wgpu::Texture,
        depth: bool,
    ) -> Vec<T> {
        let texel = std::mem::size_of::<T>() as u32;
        let row = (W * texel).next_multiple_of(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT);
        let buffer = gpu.device.create_buffer(&wgpu::BufferDescriptor {
            label: None,
            size: u64::from(row * H),
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let mut encoder = gpu.device.create_command_encoder(&Default::default());
        encoder.copy_texture_to_buffer(
            wgpu::TexelCopyTextureInfo {
                texture,
                mip_level: 0,
                origin: wgpu::Origin3d::ZERO,
                aspect: if depth {
                    wgpu::TextureAspect::DepthOnly
                } else {
                    wgpu::TextureAspect::All
                },
            },
            wgpu::TexelCopyBufferInfo {
                buffer: &buffer,
                layout: wgpu::TexelCopyBufferLayout {
                    offset: 0,
                    bytes_per_row: Some(row),
                    rows_per_image: Some(H),
                },
            },
            wgpu::Extent3d {
                width: W,
                height: H,
                depth_or_array_layers: 1,
            },
        );
        gpu.queue.submit([encoder.finish()]);
        let bytes = gpu.read_buffer(&buffer).unwrap();
        (0..H as usize)
            .flat_map(|y| {
                let line = &bytes[y * row as usize..][..(W * texel) as usize];
                bytemuck::pod_collect_to_vec::<u8, T>(line)
            })
            .collect()
    }
}

/// An IEEE half-precision value as f32 (finite values; the targets hold no others).
fn f16_to_f32(h: u16) -> f32 {
    let sign = if h >> 15 == 1 { -1.0 } else { 1.0 };
    let exponent = i32::from((h >> 10) & 0x1f);
    let mantissa = f32::from(h & 0x3ff);
    match exponent {
        0 => sign * mantissa * 2f32.powi(-24),
        31 => f32::NAN,
        e => sign * (1.0 + mantissa / 1024.0) * 2f32.powi(e - 15),
    }
}

/// The store's camera as a host's matrices: a right-handed look-at and a perspective projection with
/// depth growing away from the camera, or reversed and infinite (Bevy's).
fn host_view(r: &Renderer, reversed: bool) -> HostView {
    let cam = r.default_view();
    let aspect = W as f32 / H as f32;
    let near = (cam.target - cam.position).length() * 1e-3;
    let projection = if reversed {
        directx::perspective_infinite_reverse(cam.vfov_deg.to_radians(), aspect, near)
    } else {
        directx::perspective(cam.vfov_deg.to_radians(), aspect, near, near * 1e6)
    };
    HostView {
        view: look_at_mat4(cam.position, cam.target, cam.up),
        projection,
        exposure: 1.0,
        jitter: [0.0; 2],
    }
}

fn draws_into_a_host_frame(reversed: bool, samples: u32, exposure: f32, prepass: bool) {
    let label = format!(
        "{}, {samples} sample(s) per pixel, exposure {exposure}{}",
        if reversed { "reversed depth" } else { "depth" },
        if prepass { ", a prepass" } else { "" }
    );
    let store = open_store();
    let cubes = StoreCubes::decode(&store).unwrap();
    let gpu = Gpu::headless().unwrap();
    let mut r = Renderer::new(gpu.clone(), store, CacheConfig::default()).unwrap();
    let view = HostView {
        exposure,
        ..host_view(&r, reversed)
    };
    let params = Knobs {
        mode: Mode::ReconMirror,
        ..Default::default()
    };
    let host = Host::new(&gpu, reversed, samples, prepass);
    // Streaming: the first frame finds the cube maps missing and falls back; their loads
    // arrive over the next frames, read back without waiting.
    let mut booked = Vec::new();
    for _ in 0..40 {
        booked.extend(host.frame(&gpu, &mut r, &view, &params));
        gpu.wait().unwrap();
        if booked.last().is_some_and(|s| s.misses == 0) {
            break;
        }
    }
    assert!(
        booked.first().is_some_and(|s| s.misses > 0),
        "{label}: the first frame should miss: {booked:?}"
    );
    assert!(
        booked.last().is_some_and(|s| s.misses == 0),
        "{label}: the frames never stopped missing: {booked:?}"
    );
    // The indirection table goes to the GPU in the frames that loaded faces.
    assert!(
        booked.iter().all(|s| s.loads == 0 || s.table_writes > 0),
        "{label}: a frame loaded faces without writing the table: {booked:?}"
    );
    // One more frame, everything resident: the image to check. It uploads nothing: no faces,
    // and not the unchanged table.
    let mut steady: Vec<_> = host
        .frame(&gpu, &mut r, &view, &params)
        .into_iter()
        .collect();
    gpu.wait().unwrap();
    steady.extend(r.after_submit().unwrap());
    assert!(!steady.is_empty(), "{label}: the last frame booked nothing");
    assert!(
        steady
            .iter()
            .all(|s| s.loads == 0 && s.bytes_uploaded == 0 && s.table_writes == 0),
        "{label}: the steady frame uploaded: {steady:?}"
    );
    // The booked frames' passes were timed inside the host's encoder (lavapipe has
    // timestamp queries).
    let times = r.host_pass_seconds();
    assert!(
        times.is_some_and(|t| [t.gbuffer, t.shade, t.composite]
            .iter()
            .chain(prepass.then_some(&t.prepass))
            .all(|s| s.is_some_and(|s| s > 0.0 && s < 60.0))),
        "{label}: host pass times {times:?}"
    );
    assert!(
        times.is_some_and(|t| prepass || t.prepass.is_none()),
        "{label}: a prepass timed without one: {times:?}"
    );
    let color = host.colors(&gpu);
    // A multisampled depth target cannot be copied out: its samples are judged by the colours.
    let depth: Vec<Option<f32>> = if samples == 1 {
        host.read::<f32>(&gpu, true).into_iter().map(Some).collect()
    } else {
        vec![None; color.len()]
    };
    let camera = view.camera().unwrap();
    let (cpu, _) = r
        .reference_image(&camera, &params.params(), &cubes)
        .unwrap();
    let behind = host.depth_of(0.9999);
    let (mut hidden, mut shown) = (0, 0);
    let mut object_gpu = Vec::new();
    let mut object_cpu = Vec::new();
    for (i, ((c, d), reference)) in color.iter().zip(&depth).zip(&cpu).enumerate() {
        let left = (i as u32 % W) < W / 2;
        let on_object = reference[3] == 1.0;
        if left {
            // The host's mesh in front hides the object.
            assert_eq!(*c, FRONT, "{label}: pixel {i}");
            hidden += usize::from(on_object);
        } else if on_object {
            // The object hides the host's mesh behind it, and wrote its depth.
            shown += 1;
            object_gpu.push(*c);
            let [x, y, z, _] = reference.map(|v| v * exposure);
            object_cpu.push([x, y, z, 1.0]);
            if let Some(d) = *d {
                let nearer = if reversed { d > behind } else { d < behind };
                assert!(
                    nearer,
                    "{label}: pixel {i}: object depth {d} against {behind}"
                );
            }
        } else {
            assert_eq!(*c, BEHIND, "{label}: pixel {i}");
            assert!(d.is_none_or(|d| d == behind), "{label}: pixel {i}: {d:?}");
        }
    }
    assert!(
        hidden > 100 && shown > 100,
        "{label}: {hidden} hidden, {shown} shown"
    );
    if let (Some((normal, motion)), 1) = (&host.prepass, samples) {
        let gbuffer = r.read_gbuffer().unwrap();
        let clip_from_patch = view.projection * view.view * Mat4::from_translation(r.mesh().origin);
        let twin = |g: &GTexel| {
            let [x, y, z, _] = g.position_patch;
            let [e0, e1, _, _] = g.normal_uv;
            let normal = prepass_normal([e0, e1], normal_from_local(world_from_local()));
            let before = previous_clip_from_clip() * clip_from_patch;
            let motion = prepass_motion(Vec3::new(x, y, z), clip_from_patch, before);
            (normal.truncate() * 2.0 - Vec3::ONE, motion)
        };
        let expected: Vec<_> = gbuffer.iter().map(twin).collect();
        check_prepass(
            &gpu, &host, normal, motion, &cpu, &expected, &camera, &label,
        );
    }
    let (n, share, mae) = compare(&object_gpu, &object_cpu, 2e-3);
    println!("{label}: {n} object pixels, {:.3}% within 2e-3 of the CPU reference, mean |gpu-cpu| {mae:.2e}", share * 100.0);
    assert!(share >= 0.995 && mae < 2e-3, "{label}: {share} {mae}");
}

/// The prepass's targets after the frame: on the object's visible pixels a unit normal, most
/// of them facing the camera, and the motion of the shifted previous frame, both as the CPU
/// twin gives them from the frame's G-buffer (`expected`: world normal, motion); elsewhere
/// (hidden by the host's front mesh, or off the object) as the host cleared them.
#[allow(clippy::too_many_arguments)]
fn check_prepass(
    gpu: &Gpu,
    host: &Host,
    normal: &wgpu::Texture,
    motion: &wgpu::Texture,
    reference: &[[f32; 4]],
    expected: &[(Vec3, glam::Vec2)],
    camera: &oslf_runtime::Camera,
    label: &str,
) {
    let normals: Vec<u32> = host.read_texture(gpu, normal, false);
    let motions: Vec<[u16; 2]> = host.read_texture(gpu, motion, false);
    // The camera looks at the object's space; its normals are judged in it.
    let to_camera = (camera.position - camera.target).normalize();
    let local_from_normal = normal_from_local(world_from_local()).inverse();
    let (mut shown, mut facing) = (0, 0);
    for (i, (((n, m), c), (want_n, want_m))) in normals
        .iter()
        .zip(&motions)
        .zip(reference)
        .zip(expected)
        .enumerate()
    {
        let left = (i as u32 % W) < W / 2;
        if left || c[3] != 1.0 {
            assert_eq!((*n, *m), (0, [0, 0]), "{label}: pixel {i} written");
            continue;
        }
        shown += 1;
        let unorm = |shift: u32| f32::from((*n >> shift & 1023) as u16) / 1023.0 * 2.0 - 1.0;
        let n = Vec3::new(unorm(0), unorm(10), unorm(20));
        // The CPU twin's normal, within the 10-bit target's rounding: Vulkan converts to either
        // of the two nearest codes, a code's width (1/1023 of n·½ + ½) apart at most.
        assert!(
            (n - *want_n).abs().max_element() <= 2.01 / 1023.0,
            "{label}: pixel {i}: normal {n}, the CPU twin's {want_n}"
        );
        assert!(
            (n.length() - 1.0).abs() < 0.01,
            "{label}: pixel {i}: normal {n}"
        );
        let local = local_from_normal.transform_vector3(n);
        facing += usize::from(local.dot(to_camera) > 0.0);
        let m = m.map(f16_to_f32);
        let want = [-0.5 * PREVIOUS_SHIFT, 0.0];
        assert!(
            (m[0] - want[0]).abs() < 1e-3 && m[1].abs() < 1e-3,
            "{label}: pixel {i}: motion {m:?}, not {want:?}"
        );
        // The CPU twin's motion, within the half-float target's rounding.
        assert!(
            (glam::Vec2::from(m) - *want_m).abs().max_element() <= 1e-4,
            "{label}: pixel {i}: motion {m:?}, the CPU twin's {want_m}"
        );
    }
    assert!(
        facing * 10 >= shown * 9,
        "{label}: {facing} of {shown} normals face the camera"
    );
}

#[test]
fn the_object_is_drawn_into_a_host_frame_depth_tested_both_ways() {
    draws_into_a_host_frame(false, 1, 1.0, false);
}

#[test]
fn the_object_is_drawn_into_a_host_frame_with_reversed_depth() {
    draws_into_a_host_frame(true, 1, 1.0, false);
}

#[test]
fn the_object_is_drawn_into_a_multisampled_host_frame_at_the_hosts_exposure() {
    draws_into_a_host_frame(true, 4, 0.5, false);
}

#[test]
fn the_object_is_written_into_a_host_prepass_and_shaded_from_it_depth_tested_both_ways() {
    draws_into_a_host_frame(false, 1, 1.0, true);
    draws_into_a_host_frame(true, 1, 1.0, true);
}

#[test]
fn the_object_is_written_into_a_multisampled_host_prepass_and_shaded_from_it() {
    draws_into_a_host_frame(true, 4, 0.5, true);
}

#[test]
fn a_jittered_host_view_moves_the_object_by_its_jitter() {
    let gpu = Gpu::headless().unwrap();
    let mut r = Renderer::new(gpu.clone(), open_store(), CacheConfig::default()).unwrap();
    let view = host_view(&r, true);
    let params = Knobs {
        mode: Mode::ReconMirror,
        ..Default::default()
    };
    let host = Host::new(&gpu, true, 1, false);
    // Streams until nothing falls back, then one frame more: the image.
    let mut settled = |view: &HostView| {
        for _ in 0..40 {
            let booked = host.frame(&gpu, &mut r, view, &params);
            gpu.wait().unwrap();
            if booked.is_some_and(|s| s.misses == 0) {
                break;
            }
        }
        host.frame(&gpu, &mut r, view, &params);
        gpu.wait().unwrap();
        host.colors(&gpu)
    };
    let plain = settled(&view);
    // One pixel to the right: 2 / W in normalised x.
    let jittered = settled(&HostView {
        jitter: [2.0 / W as f32, 0.0],
        ..view
    });
    // Right of the host's front mesh, each object pixel is its left neighbour's unjittered
    // one (the same surface point, seen along the same ray from the eye).
    let (mut object, mut same) = (0, 0);
    for y in 0..H {
        for x in W / 2 + 1..W - 1 {
            let (before, after) = (
                plain[(y * W + x) as usize],
                jittered[(y * W + x + 1) as usize],
            );
            if before == BEHIND {
                continue;
            }
            object += 1;
            let close = (0..3).all(|k| (before[k] - after[k]).abs() <= 1e-3 * before[k].max(1.0));
            same += usize::from(close);
        }
    }
    println!("{same} of {object} object pixels equal their neighbours unjittered");
    assert!(object > 100, "{object} object pixels");
    assert!(same * 100 >= object * 98, "{same} of {object}");
    // Jitter is sub-pixel: more than the whole screen is refused.
    let mut encoder = gpu.device.create_command_encoder(&Default::default());
    let cv = host.color.create_view(&Default::default());
    let dv = host.depth.create_view(&Default::default());
    let target = HostTarget {
        color: &cv,
        color_format: host.format,
        depth: &dv,
        depth_format: DEPTH,
        depth_compare: host.compare(),
        sample_count: 1,
        width: W,
        height: H,
        depth_slack: 0.0,
    };
    for jitter in [[1.5, 0.0], [0.0, f32::NAN]] {
        let e = r
            .encode_into(
                &mut encoder,
                &HostView { jitter, ..view },
                &target,
                &params.params(),
            )
            .unwrap_err()
            .to_string();
        assert!(e.contains("HostView::jitter"), "{e}");
    }
}

#[test]
fn a_host_target_or_view_the_renderer_cannot_draw_into_is_refused() {
    let gpu = Gpu::headless().unwrap();
    let mut r = Renderer::new(gpu.clone(), open_store(), CacheConfig::default()).unwrap();
    let host = Host::new(&gpu, false, 1, false);
    let (cv, dv) = (
        host.color.create_view(&Default::default()),
        host.depth.create_view(&Default::default()),
    );
    let good = HostTarget {
        color: &cv,
        color_format: COLOR,
        depth: &dv,
        depth_format: DEPTH,
        depth_compare: wgpu::CompareFunction::Less,
        sample_count: 1,
        width: W,
        height: H,
        depth_slack: 0.0,
    };
    let view = host_view(&r, false);
    let params = Knobs::default();
    let mut refuse = |view: &HostView, target: &HostTarget, expect: &str| {
        let mut encoder = gpu.device.create_command_encoder(&Default::default());
        let e = r
            .encode_into(&mut encoder, view, target, &params.params())
            .unwrap_err()
            .to_string();
        assert!(e.contains(expect), "{e}");
    };
    refuse(
        &view,
        &HostTarget {
            sample_count: 3,
            ..good
        },
        "sample_count 3: must be 1, 2, 4 or 8",
    );
    refuse(
        &view,
        &HostTarget {
            depth_compare: wgpu::CompareFunction::Always,
            ..good
        },
        "depth_compare Always",
    );
    refuse(
        &view,
        &HostTarget {
            depth_format: COLOR,
            ..good
        },
        "has no depth aspect",
    );
    for slack in [f32::NAN, -1e-6, 0.5] {
        refuse(
            &view,
            &HostTarget {
                depth_slack: slack,
                ..good
            },
            "depth_slack",
        );
    }
    let ortho = HostView {
        projection: directx::orthographic(-1.0, 1.0, -1.0, 1.0, 0.1, 10.0),
        ..view
    };
    refuse(&ortho, &good, "only right-handed perspective projections");
    let nan = HostView {
        view: Mat4::from_translation(Vec3::NAN),
        ..view
    };
    refuse(&nan, &good, "must be finite");
    let dark = HostView {
        exposure: -1.0,
        ..view
    };
    refuse(
        &dark,
        &good,
        "HostView::exposure -1: must be finite and ≥ 0",
    );
    // A prepass is refused alike, and for its own matrices and formats.
    let prepass = HostPrepass {
        depth: &dv,
        depth_format: DEPTH,
        depth_compare: wgpu::CompareFunction::Less,
        sample_count: 1,
        width: W,
        height: H,
        normal: None,
        motion: None,
        world_from_local: Mat4::IDENTITY,
        previous_clip_from_local: view.projection * view.view,
    };
    let mut refuse_prepass = |prepass: &HostPrepass, expect: &str| {
        let mut encoder = gpu.device.create_command_encoder(&Default::default());
        let e = r
            .encode_prepass_into(&mut encoder, &view, prepass, &params.params())
            .unwrap_err()
            .to_string();
        assert!(e.contains(expect), "{e}");
    };
    refuse_prepass(
        &HostPrepass {
            sample_count: 0,
            ..prepass
        },
        "HostPrepass::sample_count 0",
    );
    refuse_prepass(
        &HostPrepass {
            depth_compare: wgpu::CompareFunction::Equal,
            ..prepass
        },
        "HostPrepass::depth_compare Equal",
    );
    refuse_prepass(
        &HostPrepass {
            normal: Some(PrepassTarget {
                view: &dv,
                format: DEPTH,
            }),
            ..prepass
        },
        "HostPrepass::normal.format Depth32Float is not a colour format",
    );
    refuse_prepass(
        &HostPrepass {
            world_from_local: Mat4::ZERO,
            ..prepass
        },
        "HostPrepass::world_from_local: must be finite and invertible",
    );
    refuse_prepass(
        &HostPrepass {
            previous_clip_from_local: Mat4::from_translation(Vec3::INFINITY),
            ..prepass
        },
        "HostPrepass::previous_clip_from_local: must be finite",
    );
    // Nothing was recorded for the refused frames: a good one still draws.
    let mut encoder = gpu.device.create_command_encoder(&Default::default());
    r.encode_into(&mut encoder, &view, &good, &params.params())
        .unwrap();
    gpu.queue.submit([encoder.finish()]);
    r.after_submit().unwrap();
}

#[test]
fn on_a_hosts_device_the_renderer_keeps_its_errors_and_the_host_its_handler() {
    let own = Gpu::headless().unwrap();
    let heard = Arc::new(Mutex::new(Vec::<String>::new()));
    let sink = Arc::clone(&heard);
    own.device
        .on_uncaptured_error(Arc::new(move |e: wgpu::Error| {
            sink.lock().unwrap().push(e.to_string());
        }));
    let gpu = Gpu::from_host_device(own.device.clone(), own.queue.clone(), "host".into());
    let mut r = Renderer::new(gpu.clone(), open_store(), CacheConfig::default()).unwrap();
    let host = Host::new(&gpu, false, 1, false);
    let view = host_view(&r, false);
    let params = Knobs::default();
    host.frame(&gpu, &mut r, &view, &params);
    gpu.wait().unwrap();
    // A colour format no render pass writes: the renderer's error, and nothing recorded.
    let (cv, dv) = (
        host.color.create_view(&Default::default()),
        host.depth.create_view(&Default::default()),
    );
    let bad = HostTarget {
        color: &cv,
        color_format: wgpu::TextureFormat::Rgb9e5Ufloat,
        depth: &dv,
        depth_format: DEPTH,
        depth_compare: wgpu::CompareFunction::Less,
        sample_count: 1,
        width: W,
        height: H,
        depth_slack: 0.0,
    };
    for _ in 0..2 {
        let mut encoder = gpu.device.create_command_encoder(&Default::default());
        let e = r
            .encode_into(&mut encoder, &view, &bad, &params.params())
            .unwrap_err();
        assert!(matches!(e, oslf_runtime::RuntimeError::Gpu(_)), "{e}");
        println!("refused: {e}");
        gpu.queue.submit([encoder.finish()]);
    }
    host.frame(&gpu, &mut r, &view, &params);
    gpu.wait().unwrap();
    assert!(
        heard.lock().unwrap().is_empty(),
        "the host heard {:?}",
        heard.lock().unwrap()
    );
}
