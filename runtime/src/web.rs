//! A store as a web page draws it: the same buffers, textures and cube-map payloads the
//! renderer uploads, as bytes a browser's WebGPU uploads, described by one [`WebManifest`].
//!
//! The page (`web/oslf-viewer.js` of the `oslf` crate, served by `oslf serve` and written by
//! `oslf export-web`) runs the runtime's own shaders, the embedded `gbuffer.wgsl` and
//! `shade.wgsl` ([`GBUFFER_WGSL`], [`SHADE_WGSL`]), with the bind groups, override constants,
//! uniform and pool layout that [`Renderer`](crate::Renderer) uses: all of them computed here,
//! in Rust, so that nothing of the shading is written a second time in the page. What the page
//! computes itself is the camera (orbit and zoom change it every frame: the view-projection
//! and ray frame of `renderer/camera.rs` and `uniform.rs`, written into the uniform at the
//! offsets of [`UniformFields`]) and the cube cache (which slot holds which cube).
//!
//! Resources, by the names [`WebStore::resource`] takes:
//!
//! | name | bytes |
//! |---|---|
//! | `vertices.bin` | the tessellated mesh's `GVertex` array (gbuffer.wgsl `vertices`) |
//! | `indices.bin` | its triangle indices, u32 |
//! | `samples.bin` | sample points, object-relative vec4, then each cube's nine spherical-harmonic coefficients (shade.wgsl `samples`) |
//! | `patches.bin` | per sample map 19 vec4 (shade.wgsl `patches`) |
//! | `maps.bin` | every sample map's texels, layer after layer (shade.wgsl `sample_maps`) |
//! | `texture-O-K.bin` | object O's texture of kind K (`base_color`, …), RGBA8 rows |
//!
//! and per cube, [`WebStore::cube`]: its six faces' payloads ([`FaceLayout`]) one after
//! another, in the encoding of the variant the page chose.

use std::sync::Arc;

use oslf_format::{Encoding, Store, TextureKind};
use serde::Serialize;

use crate::buffers::{patch_data, sample_map_bytes, sample_map_format, sample_point_data};
use crate::cache::{CacheConfig, NO_SLOT};
use crate::error::{Result, RuntimeError};
use crate::face::{upload_encoding, FaceLayout};
use crate::geometry::ObjectMesh;
use crate::params::{Background, Mode};
use crate::pipelines::{ShadeKey, WORKGROUP};
use crate::pool::PoolLayout;
use crate::renderer::{store_constants, store_view};
use crate::shading::ShadingParams;
use crate::textures::{object_textures, BOUND_KINDS};
use crate::uniform::ShadeUniform;

/// The G-buffer pass's shader, as the renderer compiles it.
pub const GBUFFER_WGSL: &str = include_str!("../generated/gbuffer.wgsl");
/// The shading pass's shader, as the renderer compiles it.
pub const SHADE_WGSL: &str = include_str!("../generated/shade.wgsl");

/// The version of [`WebManifest`]'s layout; a page refuses a manifest of another.
pub const WEB_FORMAT_VERSION: u32 = 1;

/// Byte offsets in the uniform of the fields a page writes for each frame.
#[derive(Clone, Debug, Serialize)]
pub struct UniformFields {
    /// Size of the uniform in bytes.
    pub bytes: usize,
    /// `view_proj`: 16 f32, column-major.
    pub view_proj: usize,
    /// `camera_pos`: vec4 f32 (w = 1).
    pub camera_pos: usize,
    /// `size`: two u32.
    pub size: usize,
    /// `m`: u32, the Monte Carlo samples per pixel.
    pub m: usize,
    /// `cam_right`: right and, in w, tan(vfov / 2).
    pub cam_right: usize,
    /// `cam_up`.
    pub cam_up: usize,
    /// `cam_forward`.
    pub cam_forward: usize,
    /// `background`: u32 tag (0 none, 1 environment cube).
    pub background: usize,
    /// `depth_steps`: u32, 0 for lookups without depth correction (override DEPTH off).
    pub depth_steps: usize,
    /// `mip_levels`: u32, 1 for point-sampled glossy lookups (override FILTER off).
    pub mip_levels: usize,
}

/// A camera in world space.
#[derive(Clone, Debug, Serialize)]
pub struct WebCamera {
    /// Eye position.
    pub position: [f32; 3],
    /// Point looked at.
    pub target: [f32; 3],
    /// Up vector.
    pub up: [f32; 3],
    /// Vertical field of view in degrees.
    pub vfov_deg: f32,
}

/// One mode as the page draws it.
#[derive(Clone, Debug, Serialize)]
pub struct WebMode {
    /// The CLI name (`pbr`, `recon-mirror`, …).
    pub name: String,
    /// The uniform of a frame in this mode with its default parameters, as u32 words (the
    /// camera fields are the page's to write).
    pub uniform: Vec<u32>,
    /// shade.wgsl's override constants for this mode, by name.
    pub constants: Vec<(String, f64)>,
}

/// One mip level of a face payload.
#[derive(Clone, Debug, Serialize)]
pub struct WebLevel {
    /// Side in texels.
    pub side: u32,
    /// Byte offset in the face payload.
    pub offset: usize,
    /// Bytes per row as the copy counts them (texels, or 4×4 blocks).
    pub row_bytes: u32,
    /// Rows.
    pub rows: u32,
}

/// One way the page can hold the cube maps: an encoding, its pool layout and its modes'
/// uniforms (which carry the pool's constants).
#[derive(Clone, Debug, Serialize)]
pub struct WebVariant {
    /// `bc6h`, `rgb9e5`, `rgba16f` or `rgba32f`: the cube URL's encoding.
    pub encoding: String,
    /// The WebGPU texture format of the pool.
    pub texture_format: String,
    /// The WebGPU feature the format needs (`texture-compression-bc`), if any.
    pub feature: Option<String>,
    /// GPU cache slots (cubes) in all.
    pub slots: u32,
    /// Cubes per pool texture.
    pub slots_per_texture: u32,
    /// 2^face_shift faces side by side per layer.
    pub face_shift: u32,
    /// Pool textures that hold slots (shade.wgsl's POOLS).
    pub pools: u32,
    /// Size of each of the four pool textures as [width, height, layers] (`None`: a one-texel,
    /// or one-block, placeholder).
    pub pool_sizes: Vec<Option<[u32; 3]>>,
    /// The face's side.
    pub cube_res: u32,
    /// The face payload's mip levels.
    pub levels: Vec<WebLevel>,
    /// Byte offset of the distance plane (R16Float, `cube_res` rows of `2·cube_res` bytes) in
    /// the face payload, when the store has distances.
    pub depth_offset: Option<usize>,
    /// Bytes of one face payload; a cube is six.
    pub face_bytes: usize,
    /// The modes.
    pub modes: Vec<WebMode>,
    /// For a block-compressed variant: one of the store's blocks and its 16 texels as the
    /// format's decoder reads them (RGB, row-major), so that a page can check that its adapter
    /// decodes the format before it uses it (a software adapter may read such textures as 0).
    pub probe: Option<BlockProbe>,
}

/// A block and what it decodes to.
#[derive(Clone, Debug, Serialize)]
pub struct BlockProbe {
    /// The block's bytes.
    pub block: Vec<u8>,
    /// Its 4×4 texels, linear RGB.
    pub texels: Vec<[f32; 3]>,
}

/// A texture of a textured object.
#[derive(Clone, Debug, Serialize)]
pub struct WebImage {
    /// Its kind's name; the resource is `texture-O-KIND.bin`.
    pub kind: String,
    /// Width in texels.
    pub width: u32,
    /// Height in texels.
    pub height: u32,
}

/// A textured object's group 1 of gbuffer.wgsl.
#[derive(Clone, Debug, Serialize)]
pub struct WebObjectTextures {
    /// Its `TextureParams` as u32 words.
    pub params: Vec<u32>,
    /// Its images in binding order (binding 1 + index); `None` binds a 1×1 texture.
    pub images: Vec<Option<WebImage>>,
}

/// Everything a page needs to know before it fetches the store's bytes.
#[derive(Clone, Debug, Serialize)]
pub struct WebManifest {
    /// [`WEB_FORMAT_VERSION`].
    pub format: u32,
    /// What the store is called (its file name).
    pub name: String,
    /// Bytes of the store file.
    pub store_bytes: u64,
    /// Cubes in the store.
    pub cube_count: u32,
    /// The environment cube, kept resident (pinned), if the store has one.
    pub env_cube: Option<u32>,
    /// The slot-table entry of a cube with nothing resident.
    pub no_slot: u32,
    /// The mesh's origin: the shaders work in coordinates relative to it.
    pub origin: [f32; 3],
    /// The mesh's bounds relative to `origin`.
    pub bounds: [[f32; 3]; 2],
    /// The store's camera (or the renderer's default view of the object).
    pub camera: WebCamera,
    /// The mode drawn unless one is asked for (as `oslf render`).
    pub default_mode: String,
    /// The background drawn unless one is asked for (as `oslf render`): `env` or `none`.
    pub default_background: String,
    /// The uniform's per-frame fields.
    pub uniform_fields: UniformFields,
    /// shade.wgsl's workgroup side.
    pub workgroup: u32,
    /// Indices in `indices.bin`.
    pub index_count: u32,
    /// Per object with textures: its index range in `indices.bin` as [first, count, object].
    pub draws: Vec<[u32; 3]>,
    /// The sample maps' WebGPU format (`rgba16uint` or `rgba32uint`).
    pub map_format: String,
    /// Bytes per sample-map texel.
    pub map_texel_bytes: u32,
    /// Side of a sample map.
    pub map_res: u32,
    /// Sample maps (layers).
    pub map_count: u32,
    /// Per object, its textures; empty when no object has any (gbuffer.wgsl then draws
    /// without group 1, with `fs_main`).
    pub textures: Vec<WebObjectTextures>,
    /// The encodings the page may choose between, the one it prefers first.
    pub variants: Vec<WebVariant>,
}

impl WebManifest {
    /// The encodings of the variants, preferred first.
    pub fn encodings(&self) -> Vec<&str> {
        self.variants.iter().map(|v| v.encoding.as_str()).collect()
    }
}

/// A store opened for a web page: the manifest, and the bytes of each resource on request.
pub struct WebStore {
    store: Arc<Store>,
    mesh: ObjectMesh,
    manifest: WebManifest,
    layouts: Vec<(String, FaceLayout)>,
}

/// The WebGPU name of a pool encoding's texture format, and the feature it needs.
fn web_format(e: Encoding) -> (&'static str, Option<&'static str>) {
    match e {
        Encoding::Rgb9e5 => ("rgb9e5ufloat", None),
        Encoding::Rgba16f => ("rgba16float", None),
        Encoding::Rgba32f => ("rgba32float", None),
        Encoding::Bc6h => ("bc6h-rgb-ufloat", Some("texture-compression-bc")),
    }
}

/// The name of an encoding in cube URLs.
fn encoding_name(e: Encoding) -> &'static str {
    match e {
        Encoding::Rgb9e5 => "rgb9e5",
        Encoding::Rgba16f => "rgba16f",
        Encoding::Rgba32f => "rgba32f",
        Encoding::Bc6h => "bc6h",
    }
}

/// What a variant's uniforms are built from.
struct VariantView<'a> {
    store: &'a Store,
    mesh: &'a ObjectMesh,
    /// The camera, relative to the mesh's origin.
    camera: &'a oslf_geometry::Camera,
    background: Background,
    textured: bool,
}

impl VariantView<'_> {
    /// The variant of the pool `layout`: its layout and every mode's uniform and constants.
    fn variant(&self, layout: &PoolLayout) -> WebVariant {
        let face = layout.face;
        let constants = store_constants(self.store, self.mesh, layout);
        let modes = Mode::ALL
            .iter()
            .map(|&mode| {
                let params = ShadingParams::of_mode(mode);
                let u = ShadeUniform::new(
                    &params,
                    glam::Mat4::IDENTITY,
                    self.camera,
                    [1, 1],
                    &constants,
                    self.background,
                );
                WebMode {
                    name: mode.name().into(),
                    uniform: words(&u),
                    constants: ShadeKey::of(&u)
                        .constants(layout.textures_in_use(), layout.face_shift, self.textured)
                        .into_iter()
                        .map(|(k, v)| (k.to_string(), v))
                        .collect(),
                }
            })
            .collect();
        let (texture_format, feature) = web_format(face.encoding);
        WebVariant {
            encoding: encoding_name(face.encoding).to_string(),
            texture_format: texture_format.into(),
            feature: feature.map(Into::into),
            slots: layout.slots,
            slots_per_texture: layout.slots_per_texture,
            face_shift: layout.face_shift,
            pools: layout.textures_in_use(),
            pool_sizes: (0..crate::cache::MAX_POOL_TEXTURES)
                .map(|t| {
                    layout
                        .texture_size(t)
                        .map(|s| [s.width, s.height, s.depth_or_array_layers])
                })
                .collect(),
            cube_res: face.res,
            levels: (0..face.levels)
                .map(|l| {
                    let (row_bytes, rows) = face.level_rows(l);
                    WebLevel {
                        side: face.side(l),
                        offset: face.level_offset(l),
                        row_bytes,
                        rows,
                    }
                })
                .collect(),
            depth_offset: face.depth.then(|| face.depth_offset()),
            face_bytes: face.payload_bytes(),
            modes,
            probe: if face.encoding.is_block_compressed() {
                block_probe(self.store, face)
            } else {
                None
            },
        }
    }
}

/// Per object of `meta`, its textures as gbuffer.wgsl's group 1 binds them.
fn object_texture_list(meta: &oslf_format::StoreMeta) -> Vec<WebObjectTextures> {
    meta.objects
        .iter()
        .map(|o| {
            let (params, images) = object_textures(o);
            WebObjectTextures {
                params: words(&params),
                images: BOUND_KINDS
                    .iter()
                    .zip(images)
                    .map(|(&kind, image)| {
                        image.map(|i| WebImage {
                            kind: kind_name(kind),
                            width: i.width,
                            height: i.height,
                        })
                    })
                    .collect(),
            }
        })
        .collect()
}

/// The brightest of the first face's blocks of the store's first cube that decodes, and its
/// texels; `None` when no block of it decodes.
fn block_probe(store: &Store, face: FaceLayout) -> Option<BlockProbe> {
    let payload = face.build(store, 0, 0).ok()?;
    let block_bytes = oslf_format::bc6h::BLOCK_BYTES;
    payload[..face.level_bytes(0)]
        .chunks_exact(block_bytes)
        .filter_map(|block| {
            let mut texels = vec![[0.0f32; 3]; 16];
            oslf_format::encoding::decode_face_texels(face.encoding, 4, block, &mut texels, 0, 0)
                .ok()?;
            let sum: f32 = texels.iter().map(|t| t[0] + t[1] + t[2]).sum();
            Some((sum, block, texels))
        })
        .max_by(|a, b| a.0.total_cmp(&b.0))
        .map(|(_, block, texels)| BlockProbe {
            block: block.to_vec(),
            texels,
        })
}

/// The file-name form of a texture kind.
fn kind_name(kind: TextureKind) -> String {
    kind.name().replace([' ', '-'], "_")
}

/// A Pod value as u32 words.
fn words<T: bytemuck::Pod>(v: &T) -> Vec<u32> {
    bytemuck::pod_collect_to_vec(bytemuck::bytes_of(v))
}

impl WebStore {
    /// Opens `store` (called `name`, `store_bytes` long) for pages whose GPU cache holds
    /// `config.gpu_slots` cubes (every cube up to the pool's default size when `None`), with
    /// WebGPU's default limits.
    pub fn new(store: Store, name: &str, store_bytes: u64, config: &CacheConfig) -> Result<Self> {
        let limits = wgpu::Limits::default();
        let store_encoding = store.header().encoding;
        let mut encodings = vec![upload_encoding(store_encoding, true)];
        if store_encoding == Encoding::Bc6h {
            encodings.push(upload_encoding(store_encoding, false));
        }
        let mesh = ObjectMesh::of_store(&store);
        let view = store_view(&store, &mesh);
        let camera = WebCamera {
            position: view.position.to_array(),
            target: view.target.to_array(),
            up: view.up.to_array(),
            vfov_deg: view.vfov_deg,
        };
        let background = if store.env_cube_index().is_some() {
            Background::Env
        } else {
            Background::None
        };
        let textured = store.meta().objects.iter().any(|o| o.textures.is_some());
        let relative = oslf_geometry::Camera {
            position: glam::Vec3::from_array(camera.position) - mesh.origin,
            target: glam::Vec3::from_array(camera.target) - mesh.origin,
            up: glam::Vec3::from_array(camera.up),
            vfov_deg: camera.vfov_deg,
        };
        let mut variants: Vec<WebVariant> = Vec::new();
        let mut layouts = Vec::new();
        for encoding in encodings {
            let face = FaceLayout::new(&store, encoding);
            if layouts.iter().any(|(_, f)| *f == face) {
                continue;
            }
            let layout = PoolLayout::plan(&limits, face, store.cube_count(), config)?;
            let view = VariantView {
                store: &store,
                mesh: &mesh,
                camera: &relative,
                background,
                textured,
            };
            variants.push(view.variant(&layout));
            layouts.push((encoding_name(face.encoding).to_string(), face));
        }
        let (map_format, map_texel_bytes) = sample_map_format(&store);
        let textures = if textured {
            object_texture_list(store.meta())
        } else {
            Vec::new()
        };
        let (lo, hi) = mesh.relative_bounds();
        let manifest = WebManifest {
            format: WEB_FORMAT_VERSION,
            name: name.to_string(),
            store_bytes,
            cube_count: store.cube_count(),
            env_cube: store.env_cube_index(),
            no_slot: NO_SLOT,
            origin: mesh.origin.to_array(),
            bounds: [lo.to_array(), hi.to_array()],
            camera,
            default_mode: Mode::default_for(store.meta()).name().into(),
            default_background: match background {
                Background::Env => "env".into(),
                _ => "none".into(),
            },
            uniform_fields: UniformFields {
                bytes: std::mem::size_of::<ShadeUniform>(),
                view_proj: std::mem::offset_of!(ShadeUniform, view_proj),
                camera_pos: std::mem::offset_of!(ShadeUniform, camera_pos),
                size: std::mem::offset_of!(ShadeUniform, size),
                m: std::mem::offset_of!(ShadeUniform, m),
                cam_right: std::mem::offset_of!(ShadeUniform, cam_right),
                cam_up: std::mem::offset_of!(ShadeUniform, cam_up),
                cam_forward: std::mem::offset_of!(ShadeUniform, cam_forward),
                background: std::mem::offset_of!(ShadeUniform, background),
                depth_steps: std::mem::offset_of!(ShadeUniform, depth_steps),
                mip_levels: std::mem::offset_of!(ShadeUniform, mip_levels),
            },
            workgroup: WORKGROUP,
            index_count: mesh.indices.len() as u32,
            draws: mesh
                .draws
                .iter()
                .map(|(r, o)| [r.start, r.end - r.start, *o])
                .collect(),
            map_format: match map_format {
                wgpu::TextureFormat::Rgba16Uint => "rgba16uint".into(),
                _ => "rgba32uint".into(),
            },
            map_texel_bytes,
            map_res: store.header().sample_map_resolution,
            map_count: store.meta().map_count() as u32,
            textures,
            variants,
        };
        Ok(Self {
            store: Arc::new(store),
            mesh,
            manifest,
            layouts,
        })
    }

    /// The manifest.
    pub fn manifest(&self) -> &WebManifest {
        &self.manifest
    }

    /// The store.
    pub fn store(&self) -> &Store {
        &self.store
    }

    /// Every resource name [`WebStore::resource`] answers, cubes aside.
    pub fn resource_names(&self) -> Vec<String> {
        let mut names: Vec<String> = [
            "vertices.bin",
            "indices.bin",
            "samples.bin",
            "patches.bin",
            "maps.bin",
        ]
        .map(String::from)
        .to_vec();
        for (o, t) in self.manifest.textures.iter().enumerate() {
            for image in t.images.iter().flatten() {
                names.push(format!("texture-{o}-{}.bin", image.kind));
            }
        }
        names
    }

    /// The bytes of resource `name` (see the module docs); `Ok(None)` for a name that is not
    /// one; errors when the store's bytes behind it are damaged.
    pub fn resource(&self, name: &str) -> Result<Option<Vec<u8>>> {
        let bytes = match name {
            "vertices.bin" => bytemuck::cast_slice(&self.mesh.vertices).to_vec(),
            "indices.bin" => bytemuck::cast_slice(&self.mesh.indices).to_vec(),
            "samples.bin" => {
                bytemuck::cast_slice(&sample_point_data(&self.store, &self.mesh)).to_vec()
            }
            "patches.bin" => {
                let mut data = patch_data(&self.mesh);
                if data.is_empty() {
                    data.push([0.0; 4]);
                }
                bytemuck::cast_slice(&data).to_vec()
            }
            "maps.bin" => {
                let mut all = Vec::new();
                for map in 0..self.manifest.map_count {
                    all.extend(sample_map_bytes(&self.store, map)?);
                }
                all
            }
            other => return Ok(self.texture(other)),
        };
        Ok(Some(bytes))
    }

    /// A `texture-O-KIND.bin` resource.
    fn texture(&self, name: &str) -> Option<Vec<u8>> {
        let rest = name.strip_prefix("texture-")?.strip_suffix(".bin")?;
        let (object, kind) = rest.split_once('-')?;
        let object: usize = object.parse().ok()?;
        let info = self.store.meta().objects.get(object)?;
        let (_, images) = object_textures(info);
        BOUND_KINDS
            .iter()
            .zip(images)
            .find(|(k, _)| kind_name(**k) == kind)
            .and_then(|(_, image)| image)
            .map(|image| bytemuck::cast_slice(&image.texels).to_vec())
    }

    /// Cube `cube`'s six face payloads in the variant whose encoding is `encoding`.
    /// Errors with [`RuntimeError::Parameter`] for a cube or encoding the store does not have,
    /// and with [`RuntimeError::Store`] when its bytes are damaged.
    pub fn cube(&self, cube: u32, encoding: &str) -> Result<Vec<u8>> {
        let face = self
            .layouts
            .iter()
            .find(|(name, _)| name == encoding)
            .map(|(_, f)| *f)
            .ok_or_else(|| {
                RuntimeError::Parameter(format!(
                    "encoding {encoding:?}: this store's cubes come as {}",
                    self.layouts
                        .iter()
                        .map(|(n, _)| n.as_str())
                        .collect::<Vec<_>>()
                        .join(" or ")
                ))
            })?;
        if cube >= self.store.cube_count() {
            return Err(RuntimeError::Parameter(format!(
                "cube {cube}: the store has {} cubes",
                self.store.cube_count()
            )));
        }
        let mut out = Vec::with_capacity(6 * face.payload_bytes());
        for f in 0..6u8 {
            let payload =
                face.build(&self.store, cube, f)
                    .map_err(|error| RuntimeError::Store {
                        path: format!("cube {cube} face {f}").into(),
                        error,
                    })?;
            out.extend(payload);
        }
        Ok(out)
    }
}
