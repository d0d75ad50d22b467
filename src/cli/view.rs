//! `oslf view STORE`: an interactive viewer.
//!
//! Drag with the left mouse button to orbit, scroll to zoom. Keys:
//!
//! | key | does |
//! | --- | --- |
//! | 1 … 6 | mode: recon, mirror, recon + mirror, glossy, recon + glossy, pbr |
//! | B | next blend: distance, angle, avg, r, n |
//! | E | next source: OSLF, environment-map baseline, parallax-corrected baseline (when the store has a proxy box to fit) |
//! | D | depth-corrected lookups on ↔ off (off, an order that reads distances gives way to per point) |
//! | F | glossy filter: mip ↔ point |
//! | G | next background: env, none (and the `--background` colour, if one was given) |
//! | O | integration order: per point → per direction → per point visible → per point searched (without depth correction or a store with distances, per point ↔ per direction) |
//! | Up / Down | blend power N × 2 / ÷ 2 |
//! | U / J, I / K | n_u, n_v × 2 / ÷ 2 |
//! | ] / [ | M × 2 / ÷ 2 |
//! | R / T | pbr roughness + 0.05 / − 0.05 (within [0, 1]) |
//! | M | pbr metallic 1 ↔ 0 |
//! | + / - | exposure × 1.25 / ÷ 1.25 |
//! | Esc | quit |
//!
//! `--background` sets what pixels off the object show at start, as for `oslf render` (the
//! store's environment cube by default).
//!
//! The window title shows the mode, its parameters, the frame time and the cache statistics of
//! the last frame; a line per second goes to stdout. Frames stream: a cube map that is not
//! resident falls back for one frame and is loaded for the next.

use std::path::PathBuf;
use std::sync::Arc;
use std::time::Instant;

use anyhow::{anyhow, Context};
use glam::Vec3;
use oslf_runtime::Camera;
use oslf_runtime::{
    Background, Blend, CacheConfig, Frame, Gpu, Lookup, Mode, MonteCarlo, Order, PbrIntegration,
    RenderOptions, Renderer, SampleFilter, ShadingParams, Source,
};
use winit::application::ApplicationHandler;
use winit::event::{ElementState, MouseButton, MouseScrollDelta, WindowEvent};
use winit::event_loop::{ActiveEventLoop, EventLoop};
use winit::keyboard::{Key, NamedKey};
use winit::window::{Window, WindowId};

use super::args::BackgroundArgs;

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct BlitUniform {
    exposure: f32,
    encode_srgb: u32,
    pad: [u32; 2],
}

struct Orbit {
    target: Vec3,
    distance: f32,
    yaw: f32,
    pitch: f32,
    up: Vec3,
    vfov: f32,
}

impl Orbit {
    fn from_camera(c: &Camera) -> Self {
        let d = c.position - c.target;
        let distance = d.length().max(1e-3);
        Self {
            target: c.target,
            distance,
            yaw: d.y.atan2(d.x),
            pitch: (d.z / distance).clamp(-1.0, 1.0).asin(),
            up: Vec3::Z,
            vfov: c.vfov_deg,
        }
    }

    fn camera(&self) -> Camera {
        let dir = Vec3::new(
            self.pitch.cos() * self.yaw.cos(),
            self.pitch.cos() * self.yaw.sin(),
            self.pitch.sin(),
        );
        Camera {
            position: self.target + dir * self.distance,
            target: self.target,
            up: self.up,
            vfov_deg: self.vfov,
        }
    }
}

struct State {
    window: Arc<Window>,
    surface: wgpu::Surface<'static>,
    config: wgpu::SurfaceConfiguration,
    renderer: Renderer,
    blit_layout: wgpu::BindGroupLayout,
    blit_pipeline: wgpu::RenderPipeline,
    blit_uniform: wgpu::Buffer,
}

struct App {
    store: PathBuf,
    access: super::args::StoreAccessArgs,
    state: Option<State>,
    /// Each mode's parameters, in [`Mode::ALL`] order: a mode keeps its own while another is
    /// shown.
    params: [ShadingParams; 6],
    /// The mode shown, an index into `params`.
    mode: usize,
    background_flag: BackgroundArgs,
    /// The backgrounds key G cycles through; the first is the one shown at start.
    backgrounds: Vec<Background>,
    /// The index of the current background in `backgrounds`.
    background: usize,
    orbit: Option<Orbit>,
    exposure: f32,
    dragging: bool,
    cursor: Option<(f64, f64)>,
    last_report: Instant,
    error: Option<anyhow::Error>,
}

/// Open a window on a store.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// The store (written by `oslf bake`).
    store: super::paths::InputPath,
    #[command(flatten)]
    access: super::args::StoreAccessArgs,
    #[command(flatten)]
    background: BackgroundArgs,
}

pub fn run(args: Args) -> anyhow::Result<()> {
    oslf_util::door::Door::new()
        .input("STORE", &args.store)
        .check()?;
    let store = args.store.0;
    let event_loop = EventLoop::new().context("cannot open a window (no display?)")?;
    let mut app = App {
        store,
        access: args.access,
        state: None,
        params: Mode::ALL.map(ShadingParams::of_mode),
        mode: Mode::ALL
            .iter()
            .position(|m| *m == ShadingParams::default().mode())
            .unwrap_or(0),
        background_flag: args.background,
        backgrounds: vec![Background::None],
        background: 0,
        orbit: None,
        exposure: 1.0,
        dragging: false,
        cursor: None,
        last_report: Instant::now(),
        error: None,
    };
    event_loop.run_app(&mut app)?;
    match app.error {
        Some(e) => Err(e),
        None => Ok(()),
    }
}

impl App {
    fn init(&mut self, event_loop: &ActiveEventLoop) -> anyhow::Result<()> {
        let store = self.access.open(&self.store)?;
        let (background, note) = self.background_flag.resolve(&store, &self.store)?;
        if let Some(note) = note {
            eprintln!("note: {note}");
        }
        self.backgrounds = background_cycle(background, store.env_cube_index().is_some());
        self.background = 0;
        let window = Arc::new(
            event_loop.create_window(
                Window::default_attributes()
                    .with_title("oslf viewer")
                    .with_inner_size(winit::dpi::PhysicalSize::new(655, 460)),
            )?,
        );
        let instance =
            wgpu::Instance::new(wgpu::InstanceDescriptor::new_without_display_handle_from_env());
        let surface = instance.create_surface(Arc::clone(&window))?;
        let adapter = pollster::block_on(instance.request_adapter(&wgpu::RequestAdapterOptions {
            power_preference: wgpu::PowerPreference::HighPerformance,
            force_fallback_adapter: false,
            compatible_surface: Some(&surface),
            apply_limit_buckets: false,
        }))?;
        let gpu = Gpu::on_adapter(&adapter)?;
        let size = window.inner_size();
        let mut config = surface
            .get_default_config(&adapter, size.width.max(1), size.height.max(1))
            .ok_or_else(|| anyhow!("the adapter cannot present to this window"))?;
        let caps = surface.get_capabilities(&adapter);
        if let Some(f) = caps.formats.iter().find(|f| !f.is_srgb()) {
            config.format = *f;
        }
        surface.configure(&gpu.device, &config);
        let device = &gpu.device;
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("viewer_blit.wgsl"),
            source: wgpu::ShaderSource::Wgsl(blit_wgsl().into()),
        });
        let blit_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("blit"),
            entries: &[
                wgpu::BindGroupLayoutEntry {
                    binding: 0,
                    visibility: wgpu::ShaderStages::FRAGMENT,
                    ty: wgpu::BindingType::Buffer {
                        ty: wgpu::BufferBindingType::Uniform,
                        has_dynamic_offset: false,
                        min_binding_size: None,
                    },
                    count: None,
                },
                wgpu::BindGroupLayoutEntry {
                    binding: 1,
                    visibility: wgpu::ShaderStages::FRAGMENT,
                    ty: wgpu::BindingType::Texture {
                        sample_type: wgpu::TextureSampleType::Float { filterable: false },
                        view_dimension: wgpu::TextureViewDimension::D2,
                        multisampled: false,
                    },
                    count: None,
                },
            ],
        });
        let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("blit"),
            bind_group_layouts: &[Some(&blit_layout)],
            immediate_size: 0,
        });
        let blit_pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("blit"),
            layout: Some(&layout),
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
                targets: &[Some(config.format.into())],
            }),
            multiview_mask: None,
            cache: None,
        });
        let blit_uniform = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("blit"),
            size: std::mem::size_of::<BlitUniform>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let renderer = Renderer::new(gpu, store, CacheConfig::default())?;
        self.orbit = Some(Orbit::from_camera(&renderer.default_view()));
        println!("adapter {}", renderer.gpu().adapter_name);
        self.state = Some(State {
            window,
            surface,
            config,
            renderer,
            blit_layout,
            blit_pipeline,
            blit_uniform,
        });
        Ok(())
    }

    fn draw(&mut self) -> anyhow::Result<()> {
        let (Some(s), Some(orbit)) = (self.state.as_mut(), self.orbit.as_ref()) else {
            return Ok(());
        };
        let t = Instant::now();
        let opts = RenderOptions {
            width: s.config.width,
            height: s.config.height,
            resolve_misses: false,
            max_passes: 1,
            read_pixels: false,
            background: self.backgrounds[self.background],
        };
        let frame: Frame = s
            .renderer
            .render(&orbit.camera(), &self.params[self.mode], &opts)?;
        let texture = match s.surface.get_current_texture() {
            wgpu::CurrentSurfaceTexture::Success(t)
            | wgpu::CurrentSurfaceTexture::Suboptimal(t) => t,
            wgpu::CurrentSurfaceTexture::Outdated | wgpu::CurrentSurfaceTexture::Lost => {
                s.surface.configure(&s.renderer.gpu().device, &s.config);
                return Ok(());
            }
            _ => return Ok(()),
        };
        let gpu = s.renderer.gpu();
        let image = s
            .renderer
            .output_texture()
            .ok_or_else(|| anyhow!("no image rendered"))?
            .create_view(&Default::default());
        let u = BlitUniform {
            exposure: self.exposure,
            encode_srgb: u32::from(!s.config.format.is_srgb()),
            pad: [0; 2],
        };
        gpu.queue
            .write_buffer(&s.blit_uniform, 0, bytemuck::bytes_of(&u));
        let group = gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("blit"),
            layout: &s.blit_layout,
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: s.blit_uniform.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: wgpu::BindingResource::TextureView(&image),
                },
            ],
        });
        let view = texture.texture.create_view(&Default::default());
        let mut encoder = gpu.device.create_command_encoder(&Default::default());
        {
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("blit"),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view: &view,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Clear(wgpu::Color::BLACK),
                        store: wgpu::StoreOp::Store,
                    },
                })],
                depth_stencil_attachment: None,
                timestamp_writes: None,
                occlusion_query_set: None,
                multiview_mask: None,
            });
            pass.set_pipeline(&s.blit_pipeline);
            pass.set_bind_group(0, &group, &[]);
            pass.draw(0..3, 0..1);
        }
        gpu.queue.submit([encoder.finish()]);
        gpu.queue.present(texture);
        gpu.take_errors()?;
        let ms = t.elapsed().as_secs_f64() * 1e3;
        let p = &self.params[self.mode];
        let st = &frame.stats;
        let lookup = match p.lookup() {
            Some(Lookup::Oslf { blend, blend_n }) => format!(" {} N={blend_n}", blend.name()),
            Some(l) => format!(" {}", l.source().name()),
            None => String::new(),
        };
        let plain = if p.depth() { "" } else { " plain" };
        let lobe = match (p.lobe(), p.material()) {
            (Some(l), _) => format!(" n_u={} n_v={}", l.nu, l.nv),
            (_, Some(m)) if m.object_material => format!(
                " object materials (else metallic={} roughness={:.2})",
                m.metallic, m.roughness
            ),
            (_, Some(m)) => format!(" metallic={} roughness={:.2}", m.metallic, m.roughness),
            _ => String::new(),
        };
        let integration = match (p.monte_carlo(), p.split_sum()) {
            (Some(mc), _) => format!(" M={} {:?} {:?}", mc.m, mc.order, mc.filter),
            (None, true) => " split-sum".into(),
            _ => String::new(),
        };
        let title = format!(
            "oslf — {}{lookup}{plain}{lobe}{integration} background {} — {ms:.0} ms — cache {} req, {} miss ({:.0}%), {} loaded, {} evicted, {} over budget",
            p.mode().name(),
            background_name(opts.background),
            st.requests,
            st.misses,
            100.0 * st.miss_rate,
            st.loads,
            st.evictions,
            st.unresolved
        );
        s.window.set_title(&title);
        if self.last_report.elapsed().as_secs_f64() >= 1.0 {
            println!("{title}");
            self.last_report = Instant::now();
        }
        s.window.request_redraw();
        Ok(())
    }

    fn key(&mut self, key: &Key) -> bool {
        let parallax = self.state.as_ref().is_some_and(|s| {
            s.renderer
                .proxy_box(&ShadingParams::of_mode(Mode::Recon))
                .is_some()
        });
        let distances = self
            .state
            .as_ref()
            .is_some_and(|s| s.renderer.constants().has_depth);
        let p = &mut self.params[self.mode];
        // A key for what the mode does not have changes nothing (the setters refuse it).
        match key {
            Key::Named(NamedKey::Escape) => return false,
            Key::Named(NamedKey::ArrowUp) => set_blend(p, |b, n| (b, (n * 2.0).clamp(1.0, 1e6))),
            Key::Named(NamedKey::ArrowDown) => set_blend(p, |b, n| (b, (n / 2.0).max(0.0))),
            Key::Character(c) => match c.as_str() {
                "1" | "2" | "3" | "4" | "5" | "6" => {
                    self.mode = c.parse::<usize>().unwrap_or(1) - 1;
                }
                "b" => set_blend(p, |b, n| {
                    let i = Blend::ALL.iter().position(|x| *x == b).unwrap_or(0);
                    (Blend::ALL[(i + 1) % Blend::ALL.len()], n)
                }),
                "e" => next_source(p, parallax),
                "d" => toggle_depth(p),
                "f" => next_filter(p),
                "g" => self.background = (self.background + 1) % self.backgrounds.len(),
                "o" => next_order(p, distances),
                "u" | "j" | "i" | "k" => {
                    if let Ok(l) = p.lobe_mut() {
                        match c.as_str() {
                            "u" => l.nu = (l.nu * 2.0).clamp(1.0, 1e7),
                            "j" => l.nu /= 2.0,
                            "i" => l.nv = (l.nv * 2.0).clamp(1.0, 1e7),
                            _ => l.nv /= 2.0,
                        }
                    }
                }
                "]" | "[" => {
                    if let Ok(mc) = p.monte_carlo_mut() {
                        mc.m = if c == "]" {
                            (mc.m * 2).min(65536)
                        } else {
                            (mc.m / 2).max(1)
                        };
                    }
                }
                // The keys set the factors for every object, as the flags do.
                "r" | "t" | "m" => {
                    if let Ok(m) = p.material_mut() {
                        match c.as_str() {
                            "r" => m.roughness = (m.roughness + 0.05).min(1.0),
                            "t" => m.roughness = (m.roughness - 0.05).max(0.0),
                            _ => m.metallic = if m.metallic < 1.0 { 1.0 } else { 0.0 },
                        }
                        m.object_material = false;
                    }
                }
                "+" | "=" => self.exposure *= 1.25,
                "-" => self.exposure /= 1.25,
                _ => {}
            },
            _ => {}
        }
        true
    }
}

/// Changes the OSLF lookup's blend and N by `f`, where the mode looks the OSLF up.
fn set_blend(p: &mut ShadingParams, f: impl Fn(Blend, f32) -> (Blend, f32)) {
    if let Some((blend, n)) = p.blend() {
        let (blend, n) = f(blend, n);
        let _ = p.set_lookup(Lookup::oslf(blend, n));
    }
}

/// Key E: the OSLF, then the environment cube, then (with a proxy box) that cube
/// parallax-corrected, then the OSLF again. The pbr mode's split-sum baseline goes through the
/// two probes and then back to Monte Carlo over the OSLF.
fn next_source(p: &mut ShadingParams, parallax: bool) {
    let next = match p.source() {
        Source::Oslf => Source::EnvMap,
        Source::EnvMap if parallax => Source::Parallax,
        Source::EnvMap | Source::Parallax => Source::Oslf,
    };
    let (blend, n) = p.blend().unwrap_or(Lookup::DEFAULT_BLEND);
    let lookup = Lookup::of_source(next, blend, n, None);
    if let ShadingParams::Pbr(pbr) = p {
        if let PbrIntegration::SplitSum(_) = pbr.integration {
            pbr.integration = match lookup {
                Lookup::Probe(probe) => PbrIntegration::SplitSum(probe),
                Lookup::Oslf { .. } => PbrIntegration::default(),
            };
            return;
        }
    }
    let _ = p.set_lookup(lookup);
}

/// Key F: filtered importance sampling, point sampling, and for the pbr mode over a probe the
/// split-sum baseline.
/// The O key: the next integration order of `Order::ALL`; without depth correction or a store
/// with `distances`, past the orders that read distances (the renderer refuses them there).
fn next_order(p: &mut ShadingParams, distances: bool) {
    let depth = p.depth() && distances;
    if let Ok(mc) = p.monte_carlo_mut() {
        let i = Order::ALL.iter().position(|&o| o == mc.order).unwrap_or(0);
        mc.order = (1..=Order::ALL.len())
            .map(|k| Order::ALL[(i + k) % Order::ALL.len()])
            .find(|o| depth || !o.reads_distances())
            .unwrap_or(Order::PerPoint);
    }
}

/// The D key: depth-corrected lookups on or off; turned off, an order that reads distances
/// (refused without them) gives way to per point.
fn toggle_depth(p: &mut ShadingParams) {
    let on = !p.depth();
    if p.set_depth(on).is_err() || on {
        return;
    }
    if let Ok(mc) = p.monte_carlo_mut() {
        if mc.order.reads_distances() {
            mc.order = Order::PerPoint;
        }
    }
}

fn next_filter(p: &mut ShadingParams) {
    if let ShadingParams::Pbr(pbr) = p {
        match pbr.integration {
            PbrIntegration::SplitSum(probe) => {
                pbr.integration = PbrIntegration::MonteCarlo {
                    lookup: Lookup::Probe(probe),
                    depth: true,
                    integration: MonteCarlo::default(),
                };
                return;
            }
            PbrIntegration::MonteCarlo {
                lookup: Lookup::Probe(probe),
                integration:
                    MonteCarlo {
                        filter: SampleFilter::Point,
                        ..
                    },
                ..
            } => {
                pbr.integration = PbrIntegration::SplitSum(probe);
                return;
            }
            _ => {}
        }
    }
    if let Ok(mc) = p.monte_carlo_mut() {
        mc.filter = match mc.filter {
            SampleFilter::Mip => SampleFilter::Point,
            SampleFilter::Point => SampleFilter::Mip,
        };
    }
}

/// The backgrounds key G cycles through, `first` first: then the environment cube (when the
/// store has one), then none.
fn background_cycle(first: Background, has_env: bool) -> Vec<Background> {
    let mut cycle = vec![first];
    for b in [Background::Env, Background::None] {
        if (b != Background::Env || has_env) && !cycle.contains(&b) {
            cycle.push(b);
        }
    }
    cycle
}

/// The background as the title shows it.
fn background_name(b: Background) -> String {
    match b {
        Background::None => "none".into(),
        Background::Env => "env".into(),
        Background::Color([r, g, b]) => format!("{r},{g},{b}"),
    }
}

impl ApplicationHandler for App {
    fn resumed(&mut self, event_loop: &ActiveEventLoop) {
        if self.state.is_none() {
            if let Err(e) = self.init(event_loop) {
                self.error = Some(e);
                event_loop.exit();
            }
        }
    }

    fn window_event(&mut self, event_loop: &ActiveEventLoop, _: WindowId, event: WindowEvent) {
        match event {
            WindowEvent::CloseRequested => event_loop.exit(),
            WindowEvent::Resized(size) => {
                if let Some(s) = self.state.as_mut() {
                    s.config.width = size.width.max(1);
                    s.config.height = size.height.max(1);
                    s.surface.configure(&s.renderer.gpu().device, &s.config);
                }
            }
            WindowEvent::RedrawRequested => {
                if let Err(e) = self.draw() {
                    self.error = Some(e);
                    event_loop.exit();
                }
            }
            WindowEvent::KeyboardInput { event, .. }
                if event.state == ElementState::Pressed && !self.key(&event.logical_key) =>
            {
                event_loop.exit();
            }
            WindowEvent::MouseInput {
                button: MouseButton::Left,
                state,
                ..
            } => self.dragging = state == ElementState::Pressed,
            WindowEvent::CursorMoved { position, .. } => {
                if let (true, Some((x, y)), Some(o)) =
                    (self.dragging, self.cursor, self.orbit.as_mut())
                {
                    o.yaw -= (position.x - x) as f32 * 0.01;
                    o.pitch = (o.pitch + (position.y - y) as f32 * 0.01).clamp(-1.5, 1.5);
                }
                self.cursor = Some((position.x, position.y));
            }
            WindowEvent::MouseWheel { delta, .. } => {
                if let Some(o) = self.orbit.as_mut() {
                    let steps = match delta {
                        MouseScrollDelta::LineDelta(_, y) => y,
                        MouseScrollDelta::PixelDelta(p) => p.y as f32 / 40.0,
                    };
                    o.distance *= 0.9f32.powf(steps);
                }
            }
            _ => {}
        }
    }
}

/// The blit shader as embedded: view_blit.wgsl with what it imports of oslf-shading's modules
/// (its tone curve and sRGB encoding), assembled ([`blit_modules`]; the tests check it).
fn blit_wgsl() -> &'static str {
    include_str!("../../generated/view_blit.wgsl")
}

/// The modules of the blit shader, as (path under `package::`, source).
#[cfg(test)]
fn blit_modules() -> Vec<(String, String)> {
    let mut modules = oslf_shading::wgsl::modules();
    modules.push(("view_blit".into(), include_str!("view_blit.wgsl").into()));
    modules
}

#[cfg(test)]
mod tests {
    use oslf_runtime::{Mode, Order, ShadingParams};

    /// O cycles every order with depth-corrected lookups on a store with distances, and only
    /// per point and per direction without either.
    #[test]
    fn the_o_key_skips_orders_that_read_distances_without_depth() {
        let cycle = |depth: bool, distances: bool| {
            let mut p = ShadingParams::of_mode(Mode::Glossy);
            p.set_depth(depth).unwrap();
            (0..4)
                .map(|_| {
                    super::next_order(&mut p, distances);
                    assert!(p.validate().is_ok() || !depth, "{p:?}");
                    p.monte_carlo_mut().unwrap().order
                })
                .collect::<Vec<_>>()
        };
        assert_eq!(
            cycle(true, true),
            [
                Order::PerDirection,
                Order::PerPointVisible,
                Order::PerPointSearched,
                Order::PerPoint
            ]
        );
        for (depth, distances) in [(false, true), (true, false), (false, false)] {
            assert_eq!(
                cycle(depth, distances),
                [
                    Order::PerDirection,
                    Order::PerPoint,
                    Order::PerDirection,
                    Order::PerPoint
                ]
            );
        }
    }

    /// D turned off gives an order that reads distances up for per point (it would be
    /// refused), and leaves the others; turned on, the order stays.
    #[test]
    fn the_d_key_leaves_no_order_that_needs_depth() {
        for order in Order::ALL {
            let mut p = ShadingParams::of_mode(Mode::Pbr);
            p.monte_carlo_mut().unwrap().order = order;
            super::toggle_depth(&mut p);
            assert!(!p.depth());
            assert!(p.validate().is_ok(), "{order:?}");
            let want = if order.reads_distances() {
                Order::PerPoint
            } else {
                order
            };
            assert_eq!(p.monte_carlo().unwrap().order, want);
            super::toggle_depth(&mut p);
            assert!(p.depth());
            assert_eq!(p.monte_carlo().unwrap().order, want);
        }
    }

    /// The embedded blit shader is what its modules assemble to (`OSLF_BLESS=1` writes it).
    #[test]
    fn blit_shader_is_its_modules_assembled() {
        let file =
            std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("generated/view_blit.wgsl");
        oslf_shading::wgsl::check_assembled(&file, "view_blit", &super::blit_modules())
            .unwrap_or_else(|e| panic!("{e}"));
    }

    /// The blit shader, as assembled, parses and validates.
    #[test]
    fn blit_shader_validates() {
        use wgpu::naga;
        let src = super::blit_wgsl();
        let module = naga::front::wgsl::parse_str(src)
            .unwrap_or_else(|e| panic!("{}", e.emit_to_string(src)));
        naga::valid::Validator::new(
            naga::valid::ValidationFlags::all(),
            naga::valid::Capabilities::default(),
        )
        .validate(&module)
        .unwrap();
    }
}
