//! The scene as the GPU reads it: the BVH's nodes and triangles, materials with their
//! textures, delta lights and the environment, packed into the structs of
//! shader/capture.wgsl (`tests/layout.rs` compares both sides field by field).

use bytemuck::{Pod, Zeroable};
use glam::{Vec2, Vec3};
use obvhs::aabb::Aabb;
use obvhs::cwbvh::node::CwBvhNode;
use oslf_scene::environment::{Environment, EnvironmentModel};
use oslf_scene::light::Light;
use oslf_scene::material::{Material, Model};
use oslf_scene::texture::Texture;
use oslf_trace::bvh::TriangleRecord;
use oslf_trace::ray::ENVIRONMENT_OBJECT;

use crate::error::{GpuBakeError, Result};

/// `Tex::kind`: shader/scene.wgsl's `TEX_*`.
pub const TEX_CONSTANT: u32 = 0;
pub const TEX_CHECKER: u32 = 1;
pub const TEX_IMAGE: u32 = 2;
/// `Mat::model`: shader/scene.wgsl's `MODEL_*`.
pub const MODEL_LAMBERTIAN: u32 = 0;
pub const MODEL_METALLIC_ROUGHNESS: u32 = 1;
/// `GpuLight::kind`: shader/scene.wgsl's `LIGHT_*`.
pub const LIGHT_POINT: u32 = 0;
pub const LIGHT_SPOT: u32 = 1;
pub const LIGHT_SUN: u32 = 2;
/// `EnvironmentParams::kind`: shader/scene.wgsl's `ENV_*`.
pub const ENV_CONSTANT: u32 = 0;
pub const ENV_LAT_LONG: u32 = 1;
pub const ENV_SKY: u32 = 2;

oslf_gpu::gpu_struct! {
    /// A node of the compressed wide BVH (obvhs's `CwBvhNode`, Ylitie, Karras and Laine 2017),
    /// byte for byte: its 8 children's boxes quantised to 8 bits in the frame of `p` and the
    /// exponents `e`.
    #[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq)]
    pub struct Node as "Node" {
        /// The node box's lower corner.
        pub p: [f32; 3],
        /// Bytes 0–2: the exponents of the child boxes' scale per axis; byte 3: which children
        /// are inner nodes.
        pub e_imask: u32,
        /// The first inner child's node index (the others follow it in slot order).
        pub child_base: u32,
        /// The first triangle slot of the leaf children.
        pub primitive_base: u32,
        /// A byte per child (children 0–3 in the first word): an inner child's 24 + slot, a
        /// leaf's first triangle offset (low 5 bits) and its count in unary (high 3 bits).
        pub child_meta: [u32; 2],
        /// The children's quantised x planes: the min bytes of children 0–3 and 4–7, then the
        /// max bytes.
        pub x: [u32; 4],
        pub y: [u32; 4],
        pub z: [u32; 4],
    }
}

const _: () = assert!(std::mem::size_of::<Node>() == std::mem::size_of::<CwBvhNode>());

impl From<&CwBvhNode> for Node {
    fn from(n: &CwBvhNode) -> Self {
        // Both are 80 bytes of plain data with the same field order (see the docs above).
        bytemuck::cast(*n)
    }
}

oslf_gpu::gpu_struct! {
    /// A triangle's corners (`v0[3]`: the largest coordinate magnitude of the corners, the hit's
    /// `extent`; `v1[3]`: 1 where it belongs to no OSLF object, which the environment-map
    /// baseline's view keeps, else 0; read with the corners, so that the traversal needs no
    /// second load per triangle) and its unnormalised plane normal with that normal's length.
    #[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq)]
    pub struct Tri as "Tri" {
        pub v0: [f32; 4],
        pub v1: [f32; 4],
        pub v2: [f32; 4],
        pub plane: [f32; 4],
    }
}

oslf_gpu::gpu_struct! {
    /// What a hit on a triangle reports besides its distance.
    #[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq)]
    pub struct TriAttr as "TriAttr" {
        pub n0: [f32; 3],
        pub material: u32,
        pub n1: [f32; 3],
        pub object: u32,
        pub n2: [f32; 3],
        pub global: u32,
        pub gn: [f32; 3],
        pub _pad0: u32,
        pub uv01: [f32; 4],
        pub uv2: [f32; 2],
        pub _pad1: [u32; 2],
    }
}

oslf_gpu::gpu_struct! {
    /// A texture: constant (`a`), checker (`a`, `b`, `scale`) or an image of `width × height`
    /// RGB texels from texel `offset` of the texel buffer.
    #[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq)]
    pub struct Tex as "Tex" {
        pub kind: u32,
        pub width: u32,
        pub height: u32,
        pub offset: u32,
        pub a: [f32; 3],
        pub scale: f32,
        pub b: [f32; 3],
        pub _pad: f32,
    }
}

oslf_gpu::gpu_struct! {
    /// A material: model [`MODEL_LAMBERTIAN`] or [`MODEL_METALLIC_ROUGHNESS`] (glTF's).
    #[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq)]
    pub struct Mat as "Mat" {
        pub albedo: Tex,
        pub mr_texture: Tex,
        pub model: u32,
        pub metallic: f32,
        pub roughness: f32,
        pub _pad: u32,
        pub emission: [f32; 3],
        pub has_mr_texture: u32,
    }
}

oslf_gpu::gpu_struct! {
    /// A delta light: kind [`LIGHT_POINT`], [`LIGHT_SPOT`] or [`LIGHT_SUN`]; `power` is the intensity (point, spot) or the
    /// irradiance (sun).
    #[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq)]
    pub struct GpuLight as "Light" {
        pub position: [f32; 3],
        pub kind: u32,
        pub direction: [f32; 3],
        pub inner: f32,
        pub power: [f32; 3],
        pub outer: f32,
        pub angular_radius: f32,
        pub _pad0: u32,
        pub _pad1: u32,
        pub _pad2: u32,
    }
}

/// The environment's part of the shader's `Params` (the rest is per capture).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct EnvironmentParams {
    pub kind: u32,
    pub active: bool,
    pub size: [u32; 4],
    pub tables: [u32; 4],
    pub rotation: [f32; 4],
    pub constant: [f32; 4],
    pub perez: [[f32; 4]; 4],
    pub norm: [f32; 4],
    pub model_sun: [f32; 4],
    pub ground: [f32; 4],
}

/// A scene packed for the GPU.
#[derive(Clone, Debug, Default)]
pub struct GpuScene {
    pub nodes: Vec<Node>,
    /// Triangles in BVH leaf order.
    pub tris: Vec<Tri>,
    pub attrs: Vec<TriAttr>,
    pub materials: Vec<Mat>,
    /// RGB texels of the image textures and the lat-long map, three floats each.
    pub texels: Vec<f32>,
    pub lights: Vec<GpuLight>,
    /// The environment's sampling tables: the marginal's entries, then the conditionals'.
    pub env_tables: Vec<[f32; 2]>,
    pub environment: EnvironmentParams,
    /// Whether any material emits (the last vertex's BSDF sample is then a closest-hit
    /// query, as on the CPU).
    pub emitters: bool,
    /// The deepest leaf's depth.
    pub depth: usize,
}

fn v3(v: Vec3) -> [f32; 3] {
    v.to_array()
}

fn v4(v: Vec3, w: f32) -> [f32; 4] {
    [v.x, v.y, v.z, w]
}

impl GpuScene {
    /// Packs `triangles` (with the CPU's CWBVH built over them),
    /// `materials`, `lights` and `environment`.
    pub fn new(
        triangles: &[TriangleRecord],
        materials: &[Material],
        lights: &[Light],
        environment: &Environment,
    ) -> Result<Self> {
        if triangles.is_empty() {
            return Err(GpuBakeError::Scene("the scene has no triangles".into()));
        }
        let mut scene = GpuScene::default();
        let (nodes, order, depth) = build_bvh(triangles)?;
        scene.nodes = nodes;
        scene.depth = depth;
        for &i in &order {
            let t = &triangles[i as usize];
            let [a, b, c] = t.corners;
            let n = (b - a).cross(c - a);
            let extent = a.abs().max(b.abs()).max(c.abs()).max_element();
            scene.tris.push(Tri {
                v0: v4(a, extent),
                v1: v4(b, f32::from(u8::from(t.object == ENVIRONMENT_OBJECT))),
                v2: v4(c, 0.0),
                plane: v4(n, n.length()),
            });
            let [u0, u1, u2]: [Vec2; 3] = t.uvs;
            scene.attrs.push(TriAttr {
                n0: v3(t.normals[0]),
                material: t.material,
                n1: v3(t.normals[1]),
                object: t.object,
                n2: v3(t.normals[2]),
                global: t.global,
                gn: v3(t.geometric_normal),
                _pad0: 0,
                uv01: [u0.x, u0.y, u1.x, u1.y],
                uv2: [u2.x, u2.y],
                _pad1: [0; 2],
            });
        }
        for m in materials {
            let albedo = scene.texture(&m.albedo)?;
            let (mr_texture, has_mr_texture) = match &m.metallic_roughness_texture {
                Some(t) => (scene.texture(t)?, 1),
                None => (Tex::zeroed(), 0),
            };
            let (model, metallic, roughness) = match m.model {
                Model::Lambertian => (MODEL_LAMBERTIAN, 0.0, 0.0),
                Model::MetallicRoughness {
                    metallic,
                    roughness,
                } => (MODEL_METALLIC_ROUGHNESS, metallic, roughness),
            };
            scene.materials.push(Mat {
                albedo,
                mr_texture,
                model,
                metallic,
                roughness,
                _pad: 0,
                emission: v3(m.emission),
                has_mr_texture,
            });
        }
        scene.emitters = materials.iter().any(|m| m.emission != Vec3::ZERO);
        scene.lights = lights.iter().map(gpu_light).collect();
        scene.pack_environment(environment)?;
        Ok(scene)
    }

    /// The texture `t`, its image appended to the texel buffer.
    fn texture(&mut self, t: &Texture) -> Result<Tex> {
        let mut tex = Tex::zeroed();
        match t {
            Texture::Constant(c) => {
                tex.kind = TEX_CONSTANT;
                tex.a = v3(*c);
            }
            Texture::Checker { a, b, scale } => {
                tex.kind = TEX_CHECKER;
                tex.a = v3(*a);
                tex.b = v3(*b);
                tex.scale = *scale;
            }
            Texture::Image(img) => {
                tex.kind = TEX_IMAGE;
                tex.width = img.width;
                tex.height = img.height;
                tex.offset = self.append_texels(&img.pixels)?;
            }
        }
        Ok(tex)
    }

    /// Appends `pixels`; returns the index of the first.
    fn append_texels(&mut self, pixels: &[Vec3]) -> Result<u32> {
        let first = self.texels.len() / 3;
        let end = first + pixels.len();
        if end > (u32::MAX / 3) as usize {
            return Err(GpuBakeError::Scene(format!(
                "the scene's images hold {end} texels; the GPU path addresses at most {}",
                u32::MAX / 3
            )));
        }
        self.texels.extend(pixels.iter().flat_map(|p| p.to_array()));
        Ok(first as u32)
    }

    fn pack_environment(&mut self, environment: &Environment) -> Result<()> {
        let mut e = EnvironmentParams {
            active: !environment.is_black(),
            ..Default::default()
        };
        let sampling = match environment.model() {
            EnvironmentModel::Constant(c) => {
                e.kind = ENV_CONSTANT;
                e.constant = v4(c, 0.0);
                None
            }
            EnvironmentModel::LatLong { map, sampling } => {
                e.kind = ENV_LAT_LONG;
                let first = self.append_texels(&map.pixels)?;
                e.size = [map.width, map.height, first, 0];
                Some(sampling)
            }
            EnvironmentModel::Sky { model, sampling } => {
                e.kind = ENV_SKY;
                let [y, x, yc] = model.perez;
                e.perez = [
                    [y[0], y[1], y[2], y[3]],
                    [x[0], x[1], x[2], x[3]],
                    [yc[0], yc[1], yc[2], yc[3]],
                    [y[4], x[4], yc[4], 0.0],
                ];
                e.norm = v4(model.norm, 0.0);
                e.model_sun = v4(model.model_sun, 0.0);
                e.ground = v4(model.ground, 0.0);
                Some(sampling)
            }
        };
        if let Some(s) = sampling {
            e.rotation = [s.cos_rot, s.sin_rot, 0.0, 0.0];
            let (marginal, conditional) = s.distribution.tables();
            e.tables = [
                s.distribution.width() as u32,
                s.distribution.height() as u32,
                0,
                0,
            ];
            self.env_tables.extend_from_slice(marginal);
            self.env_tables.extend_from_slice(conditional);
        }
        self.environment = e;
        Ok(())
    }
}

fn gpu_light(l: &Light) -> GpuLight {
    let mut g = GpuLight::zeroed();
    match *l {
        Light::Point {
            position,
            intensity,
        } => {
            g.kind = LIGHT_POINT;
            g.position = v3(position);
            g.power = v3(intensity);
        }
        Light::Spot {
            position,
            direction,
            intensity,
            inner_angle,
            outer_angle,
        } => {
            g.kind = LIGHT_SPOT;
            g.position = v3(position);
            g.direction = v3(direction);
            g.power = v3(intensity);
            g.inner = inner_angle;
            g.outer = outer_angle;
        }
        Light::Sun {
            direction,
            irradiance,
            angular_radius,
        } => {
            g.kind = LIGHT_SUN;
            g.direction = v3(direction);
            g.power = v3(irradiance);
            g.angular_radius = angular_radius;
        }
    }
    g
}

/// The CPU's CWBVH over `triangles` ([`oslf_trace::bvh::build_cwbvh`]): its nodes, the
/// triangles' order in the leaves and the deepest leaf's depth.
fn build_bvh(triangles: &[TriangleRecord]) -> Result<(Vec<Node>, Vec<u32>, usize)> {
    let aabbs: Vec<Aabb> = triangles
        .iter()
        .map(|t| Aabb::from_points(&t.corners.map(glam::Vec3A::from)))
        .collect();
    let bvh =
        oslf_trace::bvh::build_cwbvh(&aabbs).map_err(|e| GpuBakeError::Scene(e.to_string()))?;
    let depth = oslf_trace::bvh::cwbvh_depth(&bvh.nodes);
    Ok((
        bvh.nodes.iter().map(Node::from).collect(),
        bvh.primitive_indices,
        depth,
    ))
}
