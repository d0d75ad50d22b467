//! The frame's two pipelines and their bind groups: the G-buffer pass over the tessellated
//! patches ([`GBufferPipeline`], gbuffer.wgsl) and the shading compute pass
//! ([`ShadePipelines`], shade.wgsl), specialized per mode through shade.wgsl's override
//! constants. Bind-group layout entries are listed in the order of the WGSL bindings.

use std::collections::HashMap;

use crate::uniform::ShadeUniform;

/// The G-buffer's colour targets: position and patch id; octahedral normal and (u, v).
pub(crate) const GBUFFER_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba32Float;
/// The G-buffer's material target of a store with textured objects (gbuffer.wgsl
/// `fs_textured`): 16-bit unorm pairs, and the object's texture flags.
pub(crate) const MATERIAL_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba32Uint;
/// The G-buffer pass's depth buffer.
pub(crate) const DEPTH_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;
/// The depth the G-buffer pass clears to: a pixel is covered where its depth is below it
/// (shade.wgsl `gb_depth`; the colour targets are not cleared).
pub(crate) const DEPTH_CLEAR: f32 = 1.0;
/// The shaded image (`out_image` in shade.wgsl).
pub(crate) const OUTPUT_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba32Float;
/// shade.wgsl's `@workgroup_size` on each side.
pub(crate) const WORKGROUP: u32 = 8;

/// shade.wgsl, the shading pass, as embedded: assembled from the WGSL modules of shade/ (root
/// `shade::pixel`), oslf-shading's modules and the structs generated from Rust
/// ([`shade_modules`]); the tests check that it is what they assemble to.
pub(crate) fn shade_wgsl() -> &'static str {
    include_str!("../generated/shade.wgsl")
}

/// composite.wgsl, a host frame's composite and prepass passes, as embedded: assembled from
/// renderer/composite.wgsl (root `composite`) and the modules it imports
/// ([`composite_modules`]).
pub(crate) fn composite_wgsl() -> &'static str {
    include_str!("../generated/composite.wgsl")
}

/// gbuffer.wgsl, the G-buffer pass, as embedded: assembled from gbuffer.wgsl (root `gbuffer`),
/// oslf-shading's modules and the structs generated from Rust ([`gbuffer_modules`]).
pub(crate) fn gbuffer_wgsl() -> &'static str {
    include_str!("../generated/gbuffer.wgsl")
}

/// The module of the structs generated from Rust: the uniform, the vertex, the texture
/// parameters, the host prepass's uniform.
#[cfg(test)]
fn layouts_module() -> (String, String) {
    let src = [
        crate::uniform::ShadeUniform::wgsl(),
        crate::geometry::GVertex::wgsl(),
        crate::textures::TextureParams::wgsl(),
        crate::renderer::PrepassUniform::wgsl(),
    ]
    .concat();
    ("layouts".into(), src)
}

/// The modules of shade.wgsl as (path under `package::`, source): shade/'s files by concept,
/// in the order of their CPU twins (the files of the same names under reference/).
#[cfg(test)]
pub(crate) fn shade_modules() -> Vec<(String, String)> {
    let files = [
        ("bindings", include_str!("shade/bindings.wgsl")),
        ("random", include_str!("shade/random.wgsl")),
        ("feedback", include_str!("shade/feedback.wgsl")),
        ("cube", include_str!("shade/cube.wgsl")),
        ("depth", include_str!("shade/depth.wgsl")),
        ("patch", include_str!("shade/patch.wgsl")),
        ("blend", include_str!("shade/blend.wgsl")),
        ("reconstruct", include_str!("shade/reconstruct.wgsl")),
        ("mirror", include_str!("shade/mirror.wgsl")),
        ("glossy", include_str!("shade/glossy.wgsl")),
        ("seams", include_str!("shade/seams.wgsl")),
        ("split_sum", include_str!("shade/split_sum.wgsl")),
        ("background", include_str!("shade/background.wgsl")),
        ("pixel", include_str!("shade/pixel.wgsl")),
    ];
    let mut modules = oslf_shading::wgsl::modules();
    modules.push(layouts_module());
    modules.push(octahedral_module());
    modules.extend(
        files
            .into_iter()
            .map(|(name, src)| (format!("shade::{name}"), src.to_string())),
    );
    modules
}

/// The modules of gbuffer.wgsl, as [`shade_modules`].
#[cfg(test)]
pub(crate) fn gbuffer_modules() -> Vec<(String, String)> {
    let mut modules = oslf_shading::wgsl::modules();
    modules.push(layouts_module());
    modules.push(octahedral_module());
    modules.push(("gbuffer".into(), include_str!("gbuffer.wgsl").into()));
    modules
}

/// The modules of composite.wgsl (the host frame's composite and prepass passes), as
/// [`shade_modules`].
#[cfg(test)]
pub(crate) fn composite_modules() -> Vec<(String, String)> {
    let mut modules = oslf_shading::wgsl::modules();
    modules.push(layouts_module());
    modules.push(octahedral_module());
    modules.push((
        "composite".into(),
        include_str!("renderer/composite.wgsl").into(),
    ));
    modules
}

/// The octahedral normal encoding the G-buffer writes and the passes after it read.
#[cfg(test)]
fn octahedral_module() -> (String, String) {
    ("octahedral".into(), include_str!("octahedral.wgsl").into())
}

/// A read-only or read-write storage buffer at `binding`.
fn storage_entry(
    binding: u32,
    read_only: bool,
    stages: wgpu::ShaderStages,
) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: stages,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Storage { read_only },
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    }
}

/// A texture the compute stage loads from, at `binding`.
fn texture_entry(
    binding: u32,
    sample_type: wgpu::TextureSampleType,
    dim: wgpu::TextureViewDimension,
) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::Texture {
            sample_type,
            view_dimension: dim,
            multisampled: false,
        },
        count: None,
    }
}

/// The uniform block `Params` at binding 0.
fn uniform_entry(stages: wgpu::ShaderStages) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding: 0,
        visibility: stages,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Uniform,
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    }
}

/// The G-buffer pass: its render pipeline and its one bind group (uniform, vertices).
pub(crate) struct GBufferPipeline {
    /// Rasterizes the patches' triangles into the two G-buffer targets and depth.
    pub pipeline: wgpu::RenderPipeline,
    /// gbuffer.wgsl's group 0.
    pub group: wgpu::BindGroup,
}

impl GBufferPipeline {
    /// Creates the pipeline and binds `uniform` (the [`ShadeUniform`] buffer) and `vertices`;
    /// with `textures` (the layout of the objects' texture groups) it draws with
    /// `fs_textured` into a third target, [`MATERIAL_FORMAT`].
    pub fn new(
        device: &wgpu::Device,
        uniform: &wgpu::Buffer,
        vertices: &wgpu::Buffer,
        textures: Option<&wgpu::BindGroupLayout>,
    ) -> Self {
        let layout = Self::bind_group_layout(device);
        let group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("gbuffer"),
            layout: &layout,
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: uniform.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: vertices.as_entire_binding(),
                },
            ],
        });
        let pipeline = Self::render_pipeline(device, &layout, textures);
        Self { pipeline, group }
    }

    /// gbuffer.wgsl's bindings: the uniform, the vertices.
    fn bind_group_layout(device: &wgpu::Device) -> wgpu::BindGroupLayout {
        device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("gbuffer"),
            entries: &[
                uniform_entry(wgpu::ShaderStages::VERTEX | wgpu::ShaderStages::FRAGMENT),
                storage_entry(1, true, wgpu::ShaderStages::VERTEX),
            ],
        })
    }

    /// Triangle lists without culling, depth test `Less`, two [`GBUFFER_FORMAT`] targets (and
    /// the [`MATERIAL_FORMAT`] one with `textures`).
    fn render_pipeline(
        device: &wgpu::Device,
        layout: &wgpu::BindGroupLayout,
        textures: Option<&wgpu::BindGroupLayout>,
    ) -> wgpu::RenderPipeline {
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("gbuffer.wgsl"),
            source: wgpu::ShaderSource::Wgsl(gbuffer_wgsl().into()),
        });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("gbuffer"),
            bind_group_layouts: &[Some(layout), textures][..1 + usize::from(textures.is_some())],
            immediate_size: 0,
        });
        let target = |format| {
            Some(wgpu::ColorTargetState {
                format,
                blend: None,
                write_mask: wgpu::ColorWrites::ALL,
            })
        };
        let targets = [
            target(GBUFFER_FORMAT),
            target(GBUFFER_FORMAT),
            target(MATERIAL_FORMAT),
        ];
        let (entry, targets) = match textures {
            Some(_) => ("fs_textured", &targets[..]),
            None => ("fs_main", &targets[..2]),
        };
        device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("gbuffer"),
            layout: Some(&pipeline_layout),
            vertex: wgpu::VertexState {
                module: &module,
                entry_point: Some("vs_main"),
                compilation_options: Default::default(),
                buffers: &[],
            },
            primitive: wgpu::PrimitiveState {
                topology: wgpu::PrimitiveTopology::TriangleList,
                cull_mode: None,
                ..Default::default()
            },
            depth_stencil: Some(wgpu::DepthStencilState {
                format: DEPTH_FORMAT,
                depth_write_enabled: Some(true),
                depth_compare: Some(wgpu::CompareFunction::Less),
                stencil: Default::default(),
                bias: Default::default(),
            }),
            multisample: Default::default(),
            fragment: Some(wgpu::FragmentState {
                module: &module,
                entry_point: Some(entry),
                compilation_options: Default::default(),
                targets,
            }),
            multiview_mask: None,
            cache: None,
        })
    }
}

/// The override constants of shade.wgsl that change from frame to frame (the rest, POOLS,
/// FACE_SHIFT and TEXTURED, are fixed per renderer): one compute pipeline per distinct key.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub(crate) struct ShadeKey {
    /// TERMS: the uniform's `terms`.
    pub terms: u32,
    /// BLEND: the uniform's `blend`.
    pub blend: u32,
    /// SOURCE: the uniform's `source`.
    pub source: u32,
    /// ORDER: the uniform's `order`.
    pub order: u32,
    /// DIFFUSE: the glossy term has a diffuse part (R_d > 0, or a pbr material not wholly
    /// metallic).
    pub diffuse: bool,
    /// IRRADIANCE: the diffuse part is read from the store's irradiance section (the uniform's
    /// `irradiance` is an index).
    pub irradiance: bool,
    /// BACKGROUND: the uniform's `background`.
    pub background: u32,
    /// DEPTH: depth-corrected lookups (the uniform's `depth_steps` > 0).
    pub depth: bool,
    /// FILTER: filtered importance sampling for the glossy term (the uniform's `mip_levels` > 1).
    pub filter: bool,
    /// SPLIT_SUM: the pbr mode's split-sum baseline (the uniform's `split_sum`).
    pub split_sum: bool,
}

impl ShadeKey {
    /// The key a frame with uniform `u` needs.
    pub fn of(u: &ShadeUniform) -> Self {
        Self {
            terms: u.terms,
            blend: u.blend,
            source: u.source,
            order: u.order,
            diffuse: u.has_diffuse(),
            irradiance: u.reads_irradiance(),
            background: u.background,
            depth: u.depth_steps > 0,
            filter: u.mip_levels > 1,
            split_sum: u.split_sum != 0,
        }
    }

    /// The override constants by name.
    pub(crate) fn constants(
        &self,
        pools: u32,
        face_shift: u32,
        textured: bool,
    ) -> Vec<(&'static str, f64)> {
        vec![
            ("TERMS", f64::from(self.terms)),
            ("BLEND", f64::from(self.blend)),
            ("SOURCE", f64::from(self.source)),
            ("ORDER", f64::from(self.order)),
            ("POOLS", f64::from(pools)),
            ("FACE_SHIFT", f64::from(face_shift)),
            ("DIFFUSE", f64::from(u32::from(self.diffuse))),
            ("IRRADIANCE", f64::from(u32::from(self.irradiance))),
            ("BACKGROUND", f64::from(self.background)),
            ("DEPTH", f64::from(u32::from(self.depth))),
            ("FILTER", f64::from(u32::from(self.filter))),
            ("SPLIT_SUM", f64::from(u32::from(self.split_sum))),
            ("TEXTURED", f64::from(u32::from(textured))),
        ]
    }
}

/// What the shading pass binds, named as in shade.wgsl.
pub(crate) struct ShadeBindings<'a> {
    /// `P`: the [`ShadeUniform`].
    pub uniform: &'a wgpu::Buffer,
    /// `gb_position`.
    pub gb_position: &'a wgpu::TextureView,
    /// `gb_normal`.
    pub gb_normal: &'a wgpu::TextureView,
    /// `sample_maps`.
    pub sample_maps: &'a wgpu::TextureView,
    /// `samples`.
    pub samples: &'a wgpu::Buffer,
    /// `patches`.
    pub patches: &'a wgpu::Buffer,
    /// `slots`: the cache's indirection table.
    pub slots: &'a wgpu::Buffer,
    /// `feedback`.
    pub feedback: &'a wgpu::Buffer,
    /// `pool0` … `pool3`.
    pub pool: &'a [wgpu::TextureView],
    /// `dpool0` … `dpool3`.
    pub depth_pool: &'a [wgpu::TextureView],
    /// `out_image`.
    pub output: &'a wgpu::TextureView,
    /// `gb_depth`: the G-buffer pass's depth.
    pub gb_depth: &'a wgpu::TextureView,
    /// `prefiltered`: the prefiltered environment ([`crate::prefilter`]).
    pub prefiltered: &'a wgpu::TextureView,
    /// `gb_material`: the G-buffer's material target (1×1 unless the store has textures).
    pub gb_material: &'a wgpu::TextureView,
}

/// Binding of `pool0`; the pool arrays follow it.
const POOL_BINDING: u32 = 8;
/// Binding of `dpool0`; the distance arrays follow it.
const DEPTH_POOL_BINDING: u32 = 12;
/// Binding of `out_image`.
const OUTPUT_BINDING: u32 = 16;
/// Binding of `gb_depth`.
const GB_DEPTH_BINDING: u32 = 17;
/// Binding of `prefiltered`.
const PREFILTERED_BINDING: u32 = 18;
/// Binding of `gb_material`.
const GB_MATERIAL_BINDING: u32 = 19;

/// The shading pass: its bind-group layout, shader module, and the compute pipelines built so
/// far, one per [`ShadeKey`].
pub(crate) struct ShadePipelines {
    layout: wgpu::BindGroupLayout,
    module: wgpu::ShaderModule,
    pipeline_layout: wgpu::PipelineLayout,
    /// POOLS: pool textures in use.
    pools: u32,
    /// FACE_SHIFT: 2^face_shift faces side by side in each pool layer.
    face_shift: u32,
    /// TEXTURED: the store has textured objects (the G-buffer has its material target).
    textured: bool,
    pipelines: HashMap<ShadeKey, wgpu::ComputePipeline>,
}

impl ShadePipelines {
    /// Compiles shade.wgsl for a pool of `pools` arrays with 2^`face_shift` faces per layer
    /// (and for a G-buffer with a material target where `textured`);
    /// pipelines are built on first use ([`ShadePipelines::prepare`]).
    pub fn new(device: &wgpu::Device, pools: u32, face_shift: u32, textured: bool) -> Self {
        let layout = Self::bind_group_layout(device);
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("shade.wgsl"),
            source: wgpu::ShaderSource::Wgsl(shade_wgsl().into()),
        });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("shade"),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        Self {
            layout,
            module,
            pipeline_layout,
            pools,
            face_shift,
            textured,
            pipelines: HashMap::new(),
        }
    }

    /// shade.wgsl's bindings, in its order.
    fn bind_group_layout(device: &wgpu::Device) -> wgpu::BindGroupLayout {
        let float = wgpu::TextureSampleType::Float { filterable: false };
        let d2 = wgpu::TextureViewDimension::D2;
        let d2a = wgpu::TextureViewDimension::D2Array;
        let cs = wgpu::ShaderStages::COMPUTE;
        let mut entries = vec![
            uniform_entry(cs),
            texture_entry(1, float, d2),
            texture_entry(2, float, d2),
            texture_entry(3, wgpu::TextureSampleType::Uint, d2a),
            storage_entry(4, true, cs),
            storage_entry(5, true, cs),
            storage_entry(6, true, cs),
            storage_entry(7, false, cs),
        ];
        for b in POOL_BINDING..OUTPUT_BINDING {
            entries.push(texture_entry(b, float, d2a));
        }
        debug_assert_eq!(DEPTH_POOL_BINDING - POOL_BINDING, 4);
        entries.push(wgpu::BindGroupLayoutEntry {
            binding: OUTPUT_BINDING,
            visibility: cs,
            ty: wgpu::BindingType::StorageTexture {
                access: wgpu::StorageTextureAccess::WriteOnly,
                format: OUTPUT_FORMAT,
                view_dimension: d2,
            },
            count: None,
        });
        entries.push(texture_entry(
            GB_DEPTH_BINDING,
            wgpu::TextureSampleType::Depth,
            d2,
        ));
        entries.push(texture_entry(PREFILTERED_BINDING, float, d2a));
        entries.push(texture_entry(
            GB_MATERIAL_BINDING,
            wgpu::TextureSampleType::Uint,
            d2,
        ));
        device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("shade"),
            entries: &entries,
        })
    }

    /// The bind group of `b`, in the order of [`ShadePipelines::bind_group_layout`].
    pub fn bind_group(&self, device: &wgpu::Device, b: &ShadeBindings) -> wgpu::BindGroup {
        let mut entries = vec![
            wgpu::BindGroupEntry {
                binding: 0,
                resource: b.uniform.as_entire_binding(),
            },
            wgpu::BindGroupEntry {
                binding: 1,
                resource: wgpu::BindingResource::TextureView(b.gb_position),
            },
            wgpu::BindGroupEntry {
                binding: 2,
                resource: wgpu::BindingResource::TextureView(b.gb_normal),
            },
            wgpu::BindGroupEntry {
                binding: 3,
                resource: wgpu::BindingResource::TextureView(b.sample_maps),
            },
            wgpu::BindGroupEntry {
                binding: 4,
                resource: b.samples.as_entire_binding(),
            },
            wgpu::BindGroupEntry {
                binding: 5,
                resource: b.patches.as_entire_binding(),
            },
            wgpu::BindGroupEntry {
                binding: 6,
                resource: b.slots.as_entire_binding(),
            },
            wgpu::BindGroupEntry {
                binding: 7,
                resource: b.feedback.as_entire_binding(),
            },
        ];
        for (i, v) in b.pool.iter().enumerate() {
            entries.push(wgpu::BindGroupEntry {
                binding: POOL_BINDING + i as u32,
                resource: wgpu::BindingResource::TextureView(v),
            });
        }
        for (i, v) in b.depth_pool.iter().enumerate() {
            entries.push(wgpu::BindGroupEntry {
                binding: DEPTH_POOL_BINDING + i as u32,
                resource: wgpu::BindingResource::TextureView(v),
            });
        }
        entries.push(wgpu::BindGroupEntry {
            binding: OUTPUT_BINDING,
            resource: wgpu::BindingResource::TextureView(b.output),
        });
        entries.push(wgpu::BindGroupEntry {
            binding: GB_DEPTH_BINDING,
            resource: wgpu::BindingResource::TextureView(b.gb_depth),
        });
        entries.push(wgpu::BindGroupEntry {
            binding: PREFILTERED_BINDING,
            resource: wgpu::BindingResource::TextureView(b.prefiltered),
        });
        entries.push(wgpu::BindGroupEntry {
            binding: GB_MATERIAL_BINDING,
            resource: wgpu::BindingResource::TextureView(b.gb_material),
        });
        device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("shade"),
            layout: &self.layout,
            entries: &entries,
        })
    }

    /// Builds the pipeline for `key` unless it exists.
    pub fn prepare(&mut self, device: &wgpu::Device, key: ShadeKey) {
        if self.pipelines.contains_key(&key) {
            return;
        }
        let constants = key.constants(self.pools, self.face_shift, self.textured);
        let pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label: Some("shade"),
            layout: Some(&self.pipeline_layout),
            module: &self.module,
            entry_point: Some("shade"),
            compilation_options: wgpu::PipelineCompilationOptions {
                constants: &constants,
                zero_initialize_workgroup_memory: true,
            },
            cache: None,
        });
        self.pipelines.insert(key, pipeline);
    }

    /// The pipeline for `key`, once [`ShadePipelines::prepare`]d.
    pub fn get(&self, key: &ShadeKey) -> Option<&wgpu::ComputePipeline> {
        self.pipelines.get(key)
    }
}
