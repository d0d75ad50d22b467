//! Store metadata (objects, patches, bake parameters, camera), sample points, and the binary
//! layout of the metadata section.

use crate::bytes::{ByteReader, ByteWriter};
use crate::encoding::{Encoding, RGB9E5_FULL_MANTISSA_BITS};
use crate::textures::{decode_textures, encode_textures, ObjectTextures};
use crate::{Error, MAX_CUBE_RESOLUTION, MAX_NAME_BYTES, MAX_SAMPLE_MAP_RESOLUTION};

/// One sample point: where a cube map was captured. 40 bytes, `#[repr(C)]`, stored as is.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct SamplePoint {
    /// The offset point (world space) where the cube was captured.
    pub position: [f32; 3],
    /// Unit direction of the ε offset from the base point (world space): a patch's normal, or
    /// a mesh triangle's geometric normal on its shading normal's side.
    pub normal: [f32; 3],
    /// Parameter of the base point on its sample map, in `[0, 1]²`: the patch's (u, v), or
    /// the local uv on a mesh's atlas page.
    pub uv: [f32; 2],
    /// Global sample-map index: a Bézier patch or an atlas page.
    pub patch: u32,
    /// Object index.
    pub object: u32,
}

/// Bytes of one [`SamplePoint`] on disk.
pub const SAMPLE_POINT_BYTES: usize = 40;
const _: () = assert!(std::mem::size_of::<SamplePoint>() == SAMPLE_POINT_BYTES);

/// A bicubic Bézier patch in object space.
#[derive(Clone, Debug, PartialEq)]
pub struct Patch {
    /// `CP_ij` at index `4 * i + j`, `i` along u, `j` along v.
    pub control_points: [[f32; 3]; 16],
}

/// An object: a contiguous range of sample maps (global map indices `first_patch ..
/// first_patch + patch_count`), each either a bicubic Bézier patch (`mesh` is `None`; its
/// control points are in [`StoreMeta::patches`]) or one page of a triangle mesh's atlas.
#[derive(Clone, Debug, PartialEq)]
pub struct ObjectInfo {
    /// UTF-8 name, at most [`MAX_NAME_BYTES`] bytes.
    pub name: String,
    /// Column-major object-to-world matrix.
    pub transform: [[f32; 4]; 4],
    /// Linear RGB base colour.
    pub base_color: [f32; 3],
    /// First global map index (patch or atlas page) of the object.
    pub first_patch: u32,
    /// Number of sample maps of the object: its Bézier patches, or the `k²` pages of its
    /// atlas.
    pub patch_count: u32,
    /// The triangle mesh of a mesh object; `None` for an object
    /// made of Bézier patches.
    pub mesh: Option<MeshInfo>,
    /// How the surface reflects ([`ObjectMaterial::default`]: a Lambertian surface of
    /// `base_color`).
    pub material: ObjectMaterial,
    /// A mesh object's material textures with their texture coordinates and tangents (`None`
    /// for untextured objects).
    pub textures: Option<ObjectTextures>,
}

/// Material model tag of a Lambertian object: only `base_color` matters.
pub const MATERIAL_LAMBERTIAN: u32 = 0;
/// Material model tag of glTF's metallic-roughness model: `base_color`,
/// `metallic` and `roughness` as in the glTF 2.0 specification's Appendix B.
pub const MATERIAL_METALLIC_ROUGHNESS: u32 = 1;

/// An object's material: its model and factors; the base colour is
/// [`ObjectInfo::base_color`].
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ObjectMaterial {
    /// [`MATERIAL_LAMBERTIAN`] or [`MATERIAL_METALLIC_ROUGHNESS`].
    pub model: u32,
    /// In `[0, 1]`; 0 for a Lambertian object.
    pub metallic: f32,
    /// Perceptual roughness in `[0, 1]` (GGX α = roughness²); 0 for a Lambertian object.
    pub roughness: f32,
    /// Emitted radiance, linear RGB, finite and ≥ 0.
    pub emission: [f32; 3],
}

impl ObjectMaterial {
    /// Whether this is glTF's metallic-roughness model.
    pub fn is_metallic_roughness(&self) -> bool {
        self.model == MATERIAL_METALLIC_ROUGHNESS
    }
}

/// A triangle-mesh object: vertices in object space and an atlas of
/// `atlas_grid`² pages, each an ordinary m×m sample map. Atlas uv `(s, t) ∈ [0, 1]²` spans the
/// whole grid; page `(px, py)` with `px = min(⌊s·k⌋, k−1)`, `py = min(⌊t·k⌋, k−1)` is map
/// `first_patch + py·k + px`, at local uv `(s·k − px, t·k − py)`.
///
/// Shading uses the interpolated vertex normal (barycentric, renormalized).
#[derive(Clone, Debug, PartialEq)]
pub struct MeshInfo {
    /// Pages per atlas side, `k` ≥ 1; the object's `patch_count` is `k²`.
    pub atlas_grid: u32,
    /// Vertex positions, object space (at least 3).
    pub positions: Vec<[f32; 3]>,
    /// Unit vertex normals, object space (one per vertex).
    pub normals: Vec<[f32; 3]>,
    /// Atlas uvs in `[0, 1]²` (one per vertex).
    pub uvs: Vec<[f32; 2]>,
    /// Vertex indices (each `< positions.len()`), at least one triangle.
    pub triangles: Vec<[u32; 3]>,
}

/// Object kind tag of a Bézier object.
pub const OBJECT_KIND_BEZIER: u32 = 0;
/// Object kind tag of a triangle-mesh object.
pub const OBJECT_KIND_MESH: u32 = 1;
/// Bytes of one mesh vertex record.
const VERTEX_BYTES: usize = 32;
/// Bytes of one mesh triangle record.
const TRIANGLE_BYTES: usize = 12;
/// How far from 1 a stored normal's length may be.
pub const NORMAL_LENGTH_TOLERANCE: f32 = 1e-3;

/// The viewpoint the scene was set up with.
#[derive(Clone, Debug, PartialEq)]
pub struct CameraInfo {
    pub position: [f32; 3],
    pub target: [f32; 3],
    pub up: [f32; 3],
    /// Vertical field of view in degrees, in `(0, 180)`.
    pub vfov_deg: f32,
}

/// The parameters of the bake.
#[derive(Clone, Debug, PartialEq)]
pub struct BakeParams {
    /// Offset of the sample points above the surface (> 0).
    pub epsilon: f32,
    /// Angular threshold used to build the sample maps, degrees.
    pub phi_samplemap_deg: f32,
    /// Cube-map face resolution, 1..=[`MAX_CUBE_RESOLUTION`].
    pub cube_resolution: u32,
    /// Sample-map resolution per patch, 1..=[`MAX_SAMPLE_MAP_RESOLUTION`].
    pub sample_map_resolution: u32,
    pub samples_per_texel: u32,
    pub bounces: u32,
    pub seed: u64,
    pub encoding: Encoding,
    /// Whether each face carries an `f32` distance plane.
    pub distance_channel: bool,
    /// zstd level the faces were compressed with.
    pub zstd_level: i32,
    /// Hash of the scene description (opaque to this crate).
    pub scene_hash: [u8; 32],
    /// RGB9E5 mantissa bits kept per channel, 1..=9 ([`crate::encoding::quantize_rgb9e5`],
    /// applied by [`crate::encode_cube`]); 9 (lossless) for the other encodings.
    pub mantissa_bits: u32,
    /// How each cube's texels were sampled and filtered (format 1.2); `None` in a store of
    /// format 1.0 or 1.1, which does not record it. Writers require it.
    pub sampling: Option<Sampling>,
}

/// How a bake sampled and filtered its cubes' texels (format 1.2's sampling record).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Sampling {
    /// The relative standard error each texel sampled down to, in (0, 1]; 0 where every
    /// texel took `samples_per_texel` samples.
    pub target_noise: f32,
    /// Whether each cube was denoised before it was stored.
    pub denoised: bool,
}

impl Default for BakeParams {
    fn default() -> Self {
        BakeParams {
            epsilon: 0.01,
            phi_samplemap_deg: 10.0,
            cube_resolution: 32,
            sample_map_resolution: 32,
            samples_per_texel: 16,
            bounces: 3,
            seed: 0,
            encoding: Encoding::Rgb9e5,
            distance_channel: false,
            zstd_level: 3,
            scene_hash: [0; 32],
            mantissa_bits: RGB9E5_FULL_MANTISSA_BITS,
            sampling: Some(Sampling::default()),
        }
    }
}

/// Everything in the metadata section.
#[derive(Clone, Debug, PartialEq)]
pub struct StoreMeta {
    /// The objects, whose map ranges tile `0..map_count()` in order.
    pub objects: Vec<ObjectInfo>,
    /// Control points of the Bézier objects' patches only, in object order (their count is
    /// the sum of `patch_count` over the objects without a mesh); see
    /// [`StoreMeta::patches_of`]. Mesh objects' atlas pages have none.
    pub patches: Vec<Patch>,
    pub bake: BakeParams,
    pub camera: Option<CameraInfo>,
    /// One extra cube after the sample points' cubes (index = sample count): an environment
    /// map captured at the object's centre.
    pub has_env_cube: bool,
}

impl StoreMeta {
    /// Number of sample maps: Bézier patches plus atlas pages (the header's `patch_count`),
    /// the sum of the objects' `patch_count`.
    pub fn map_count(&self) -> usize {
        self.objects.iter().map(|o| o.patch_count as usize).sum()
    }

    /// The control points of object `object`'s Bézier patches (its maps in order); empty for
    /// a mesh object or an index out of range.
    pub fn patches_of(&self, object: usize) -> &[Patch] {
        let Some(o) = self.objects.get(object) else {
            return &[];
        };
        if o.mesh.is_some() {
            return &[];
        }
        let start: usize = self.objects[..object]
            .iter()
            .filter(|o| o.mesh.is_none())
            .map(|o| o.patch_count as usize)
            .sum();
        self.patches
            .get(start..start.saturating_add(o.patch_count as usize))
            .unwrap_or(&[])
    }
}

/// Minimum bytes of one object record (empty name, a Bézier object: name length, transform,
/// base colour, map range, kind).
const OBJECT_MIN_BYTES: usize = 4 + 64 + 12 + 8 + 4;
/// Bytes of one patch record.
const PATCH_BYTES: usize = 16 * 3 * 4;

/// Checks `mantissa_bits` against the encoding: 1..=9 for RGB9E5, exactly 9 otherwise.
pub fn check_mantissa_bits(encoding: Encoding, bits: u32) -> Result<(), String> {
    if !(1..=RGB9E5_FULL_MANTISSA_BITS).contains(&bits) {
        return Err(format!(
            "mantissa_bits {bits} must be in 1..={RGB9E5_FULL_MANTISSA_BITS}"
        ));
    }
    if bits != RGB9E5_FULL_MANTISSA_BITS && encoding != Encoding::Rgb9e5 {
        return Err(format!(
            "mantissa_bits {bits} needs the rgb9e5 encoding (the encoding is {encoding}; other encodings keep all bits, 9)"
        ));
    }
    Ok(())
}

/// Serialises the metadata section (layout in `docs/format.md`, "Metadata"). No validation:
/// [`decode_meta`] validates, and the writer checks its input by decoding what it encoded.
pub(crate) fn encode_meta(meta: &StoreMeta) -> Vec<u8> {
    let mut w = ByteWriter::default();
    w.u32(meta.objects.len() as u32);
    w.u32(u32::try_from(meta.map_count()).unwrap_or(u32::MAX));
    let b = &meta.bake;
    w.f32(b.epsilon);
    w.f32(b.phi_samplemap_deg);
    w.u32(b.cube_resolution);
    w.u32(b.sample_map_resolution);
    w.u32(b.samples_per_texel);
    w.u32(b.bounces);
    w.u64(b.seed);
    w.u32(b.encoding.tag());
    w.u32(u32::from(b.distance_channel));
    w.i32(b.zstd_level);
    w.u32(u32::from(meta.has_env_cube));
    w.bytes(&b.scene_hash);
    w.u32(b.mantissa_bits);
    // Format 1.2's sampling record; a meta without one is refused by the writer
    // (`Prefix::build`) before it is encoded.
    if let Some(s) = &b.sampling {
        w.f32(s.target_noise);
        w.u32(u32::from(s.denoised));
    }
    match &meta.camera {
        Some(c) => {
            w.u32(1);
            for v in c.position.iter().chain(&c.target).chain(&c.up) {
                w.f32(*v);
            }
            w.f32(c.vfov_deg);
        }
        None => w.bytes(&[0u8; 44]),
    }
    for o in &meta.objects {
        let name = o.name.as_bytes();
        // An over-long name is written with its true length; decode_meta rejects it.
        w.u32(u32::try_from(name.len()).unwrap_or(u32::MAX));
        w.bytes(name);
        for v in o.transform.iter().flatten() {
            w.f32(*v);
        }
        for v in o.base_color {
            w.f32(v);
        }
        w.u32(o.first_patch);
        w.u32(o.patch_count);
        match &o.mesh {
            None => w.u32(OBJECT_KIND_BEZIER),
            Some(m) => {
                w.u32(OBJECT_KIND_MESH);
                w.u32(m.atlas_grid);
                let count = |n: usize| u32::try_from(n).unwrap_or(u32::MAX);
                w.u32(count(m.positions.len()));
                w.u32(count(m.triangles.len()));
                // Vertices whose arrays disagree in length are written short; decode_meta
                // (run by the writer on what it encodes) then refuses them.
                for ((p, n), uv) in m.positions.iter().zip(&m.normals).zip(&m.uvs) {
                    for v in p.iter().chain(n).chain(uv) {
                        w.f32(*v);
                    }
                }
                for t in &m.triangles {
                    for i in t {
                        w.u32(*i);
                    }
                }
            }
        }
        let m = &o.material;
        w.u32(m.model);
        w.f32(m.metallic);
        w.f32(m.roughness);
        for v in m.emission {
            w.f32(v);
        }
        encode_textures(&mut w, o.textures.as_ref(), meta.bake.zstd_level);
    }
    for p in &meta.patches {
        for v in p.control_points.iter().flatten() {
            w.f32(*v);
        }
    }
    w.into_inner()
}

fn bad(offset: u64, detail: impl Into<String>) -> Error {
    Error::InvalidMetadata {
        offset,
        detail: detail.into(),
    }
}

/// Parses and validates the metadata section of a store of format `version` (the header's);
/// `base` is its byte offset in the file (for error messages).
pub(crate) fn decode_meta(bytes: &[u8], base: u64, version: u32) -> Result<StoreMeta, Error> {
    let mut r = ByteReader::new(bytes, base, "metadata");
    let object_count = r.u32()? as usize;
    let patch_count = r.u32()? as usize;
    let (bake, has_env_cube) = decode_bake_params(&mut r, version)?;
    let camera = decode_camera(&mut r)?;
    if object_count > r.remaining() / OBJECT_MIN_BYTES {
        return Err(bad(
            base,
            format!(
                "object count {object_count} cannot fit in {} bytes",
                r.remaining()
            ),
        ));
    }
    let objects = decode_objects(&mut r, object_count, patch_count)?;
    let bezier_patches: u64 = objects
        .iter()
        .filter(|o| o.mesh.is_none())
        .map(|o| u64::from(o.patch_count))
        .sum();
    let needed = bezier_patches * PATCH_BYTES as u64;
    if needed != r.remaining() as u64 {
        return Err(bad(
            r.offset(),
            format!(
                "{bezier_patches} Bézier patches need {needed} bytes but {} remain in the section",
                r.remaining()
            ),
        ));
    }
    let mut patches = Vec::with_capacity(bezier_patches as usize);
    for _ in 0..bezier_patches {
        let mut control_points = [[0f32; 3]; 16];
        for v in control_points.iter_mut().flatten() {
            *v = r.finite_f32("patch control point")?;
        }
        patches.push(Patch { control_points });
    }
    Ok(StoreMeta {
        objects,
        patches,
        bake,
        camera,
        has_env_cube,
    })
}

/// Parses and validates the bake parameters and the environment-cube flag of a store of
/// format `version` (the sampling record from 1.2 on).
fn decode_bake_params(r: &mut ByteReader<'_>, version: u32) -> Result<(BakeParams, bool), Error> {
    let at = r.offset();
    let epsilon = r.finite_f32("epsilon")?;
    if epsilon <= 0.0 {
        return Err(bad(at, format!("epsilon {epsilon} must be > 0")));
    }
    let at = r.offset();
    let phi_samplemap_deg = r.finite_f32("phi_samplemap_deg")?;
    if !(0.0..=180.0).contains(&phi_samplemap_deg) {
        return Err(bad(
            at,
            format!("phi_samplemap_deg {phi_samplemap_deg} must be in [0, 180]"),
        ));
    }
    let at = r.offset();
    let cube_resolution = r.u32()?;
    if cube_resolution == 0 || cube_resolution > MAX_CUBE_RESOLUTION {
        return Err(bad(
            at,
            format!("cube_resolution {cube_resolution} must be in 1..={MAX_CUBE_RESOLUTION}"),
        ));
    }
    let at = r.offset();
    let sample_map_resolution = r.u32()?;
    if sample_map_resolution == 0 || sample_map_resolution > MAX_SAMPLE_MAP_RESOLUTION {
        return Err(bad(
            at,
            format!(
                "sample_map_resolution {sample_map_resolution} must be in 1..={MAX_SAMPLE_MAP_RESOLUTION}"
            ),
        ));
    }
    let samples_per_texel = r.u32()?;
    let bounces = r.u32()?;
    let seed = r.u64()?;
    let at = r.offset();
    let tag = r.u32()?;
    let encoding =
        Encoding::from_tag(tag).ok_or_else(|| bad(at, format!("unknown encoding tag {tag}")))?;
    let distance_channel = r.bool("distance_channel")?;
    let at = r.offset();
    let zstd_level = r.i32()?;
    if !zstd::compression_level_range().contains(&zstd_level) {
        return Err(bad(at, format!("zstd_level {zstd_level} out of range")));
    }
    let has_env_cube = r.bool("has_env_cube")?;
    let mut scene_hash = [0u8; 32];
    scene_hash.copy_from_slice(r.take(32)?);
    let at = r.offset();
    let mantissa_bits = r.u32()?;
    check_mantissa_bits(encoding, mantissa_bits).map_err(|detail| bad(at, detail))?;
    let sampling = if version >= crate::VERSION {
        Some(decode_sampling(r)?)
    } else {
        None
    };
    let bake = BakeParams {
        epsilon,
        phi_samplemap_deg,
        cube_resolution,
        sample_map_resolution,
        samples_per_texel,
        bounces,
        seed,
        encoding,
        distance_channel,
        zstd_level,
        scene_hash,
        mantissa_bits,
        sampling,
    };
    Ok((bake, has_env_cube))
}

/// Parses and validates format 1.2's sampling record.
fn decode_sampling(r: &mut ByteReader<'_>) -> Result<Sampling, Error> {
    let at = r.offset();
    let target_noise = r.finite_f32("target_noise")?;
    if !(target_noise == 0.0 || (target_noise > 0.0 && target_noise <= 1.0)) {
        return Err(bad(
            at,
            format!("target_noise {target_noise} must be 0 or in (0, 1]"),
        ));
    }
    let denoised = r.bool("denoised")?;
    Ok(Sampling {
        target_noise,
        denoised,
    })
}

/// Parses and validates the camera record (all zero when there is none).
fn decode_camera(r: &mut ByteReader<'_>) -> Result<Option<CameraInfo>, Error> {
    let at = r.offset();
    let camera_present = r.bool("camera present")?;
    let mut cam = [0f32; 10];
    for v in &mut cam {
        *v = r.finite_f32("camera")?;
    }
    if camera_present {
        if !(cam[9] > 0.0 && cam[9] < 180.0) {
            return Err(bad(
                at,
                format!("camera vfov_deg {} must be in (0, 180)", cam[9]),
            ));
        }
        Ok(Some(CameraInfo {
            position: [cam[0], cam[1], cam[2]],
            target: [cam[3], cam[4], cam[5]],
            up: [cam[6], cam[7], cam[8]],
            vfov_deg: cam[9],
        }))
    } else {
        if cam.iter().any(|v| v.to_bits() != 0) {
            return Err(bad(at, "absent camera must be all zero"));
        }
        Ok(None)
    }
}

/// Parses and validates the `object_count` object records, whose map ranges must tile
/// `0..patch_count` in order.
fn decode_objects(
    r: &mut ByteReader<'_>,
    object_count: usize,
    patch_count: usize,
) -> Result<Vec<ObjectInfo>, Error> {
    let mut objects = Vec::with_capacity(object_count);
    let mut prev_end = 0u64;
    for i in 0..object_count {
        let at = r.offset();
        let len = r.u32()? as usize;
        if len > MAX_NAME_BYTES {
            return Err(bad(
                at,
                format!("object {i}: name length {len} exceeds {MAX_NAME_BYTES}"),
            ));
        }
        let name = std::str::from_utf8(r.take(len)?)
            .map_err(|e| bad(at + 4, format!("object {i}: name is not UTF-8: {e}")))?
            .to_string();
        let mut transform = [[0f32; 4]; 4];
        for v in transform.iter_mut().flatten() {
            *v = r.finite_f32("object transform")?;
        }
        let mut base_color = [0f32; 3];
        for v in &mut base_color {
            *v = r.finite_f32("object base_color")?;
        }
        let at = r.offset();
        let first_patch = r.u32()?;
        let count = r.u32()?;
        let end = u64::from(first_patch) + u64::from(count);
        if u64::from(first_patch) != prev_end || end > patch_count as u64 {
            return Err(bad(
                at,
                format!(
                    "object {i}: map range {first_patch}..{end} does not start where the previous object ends ({prev_end}) or exceeds the map count {patch_count}"
                ),
            ));
        }
        prev_end = end;
        let mesh = decode_mesh(r, i, count)?;
        let material = decode_material(r, i)?;
        let textures = decode_textures(r, i, mesh.as_ref().map(|m| m.positions.len()))?;
        objects.push(ObjectInfo {
            name,
            transform,
            base_color,
            first_patch,
            patch_count: count,
            mesh,
            material,
            textures,
        });
    }
    if prev_end != patch_count as u64 {
        return Err(bad(
            r.offset(),
            format!(
                "the objects' maps end at {prev_end}, but the map count is {patch_count} (object ranges must tile 0..{patch_count})"
            ),
        ));
    }
    Ok(objects)
}

/// Parses the material record of object `i`: model, factors, emission.
fn decode_material(r: &mut ByteReader<'_>, i: usize) -> Result<ObjectMaterial, Error> {
    let at = r.offset();
    let model = r.u32()?;
    let metallic = r.finite_f32("object metallic")?;
    let roughness = r.finite_f32("object roughness")?;
    let mut emission = [0f32; 3];
    for v in &mut emission {
        *v = r.finite_f32("object emission")?;
    }
    let problem = match model {
        MATERIAL_LAMBERTIAN if metallic != 0.0 || roughness != 0.0 => Some(format!(
            "a Lambertian material has metallic {metallic} and roughness {roughness} (both must be 0)"
        )),
        MATERIAL_LAMBERTIAN => None,
        MATERIAL_METALLIC_ROUGHNESS
            if !(0.0..=1.0).contains(&metallic) || !(0.0..=1.0).contains(&roughness) =>
        {
            Some(format!(
                "metallic {metallic} and roughness {roughness} must lie in [0, 1]"
            ))
        }
        MATERIAL_METALLIC_ROUGHNESS => None,
        other => Some(format!(
            "unknown material model {other} (0 Lambertian, 1 metallic-roughness)"
        )),
    };
    let problem = problem.or_else(|| {
        emission
            .iter()
            .any(|v| *v < 0.0)
            .then(|| format!("emission {emission:?} is negative"))
    });
    match problem {
        Some(p) => Err(bad(at, format!("object {i}: {p}"))),
        None => Ok(ObjectMaterial {
            model,
            metallic,
            roughness,
            emission,
        }),
    }
}

/// Parses the kind and mesh record of object `i` (its kind, and a mesh object's atlas
/// grid, vertices and triangles); `maps` is the object's map count.
fn decode_mesh(r: &mut ByteReader<'_>, i: usize, maps: u32) -> Result<Option<MeshInfo>, Error> {
    let at = r.offset();
    match r.u32()? {
        OBJECT_KIND_BEZIER => return Ok(None),
        OBJECT_KIND_MESH => {}
        kind => {
            return Err(bad(
                at,
                format!("object {i}: unknown kind {kind} (0 Bézier patches, 1 triangle mesh)"),
            ))
        }
    }
    let at = r.offset();
    let atlas_grid = r.u32()?;
    if atlas_grid == 0 || u64::from(atlas_grid) * u64::from(atlas_grid) != u64::from(maps) {
        return Err(bad(
            at,
            format!(
                "object {i}: atlas grid {atlas_grid} must be ≥ 1 with {atlas_grid}² equal to its map count {maps}"
            ),
        ));
    }
    let at = r.offset();
    let vertex_count = r.u32()? as usize;
    let triangle_count = r.u32()? as usize;
    if vertex_count < 3 || triangle_count < 1 {
        return Err(bad(
            at,
            format!(
                "object {i}: a mesh needs at least 3 vertices and 1 triangle ({vertex_count} vertices, {triangle_count} triangles)"
            ),
        ));
    }
    let needed = (vertex_count as u64) * VERTEX_BYTES as u64
        + (triangle_count as u64) * TRIANGLE_BYTES as u64;
    if needed > r.remaining() as u64 {
        return Err(bad(
            at,
            format!(
                "object {i}: {vertex_count} vertices and {triangle_count} triangles need {needed} bytes but {} remain in the section",
                r.remaining()
            ),
        ));
    }
    let mut positions = Vec::with_capacity(vertex_count);
    let mut normals = Vec::with_capacity(vertex_count);
    let mut uvs = Vec::with_capacity(vertex_count);
    for v in 0..vertex_count {
        let at = r.offset();
        let mut f = [0f32; 8];
        for x in &mut f {
            *x = r.f32()?;
        }
        if !f.iter().all(|x| x.is_finite()) {
            return Err(bad(
                at,
                format!("object {i}: vertex {v} has a non-finite field {f:?}"),
            ));
        }
        let n = [f[3], f[4], f[5]];
        let len = n.iter().map(|x| f64::from(*x).powi(2)).sum::<f64>().sqrt();
        if (len - 1.0).abs() > f64::from(NORMAL_LENGTH_TOLERANCE) {
            return Err(bad(
                at + 12,
                format!("object {i}: vertex {v} normal {n:?} has length {len}, not 1"),
            ));
        }
        let uv = [f[6], f[7]];
        if !uv.iter().all(|x| (0.0..=1.0).contains(x)) {
            return Err(bad(
                at + 24,
                format!("object {i}: vertex {v} atlas uv {uv:?} outside [0, 1]²"),
            ));
        }
        positions.push([f[0], f[1], f[2]]);
        normals.push(n);
        uvs.push(uv);
    }
    let mut triangles = Vec::with_capacity(triangle_count);
    for t in 0..triangle_count {
        let at = r.offset();
        let tri = [r.u32()?, r.u32()?, r.u32()?];
        if let Some(&bad_index) = tri.iter().find(|&&x| x as usize >= vertex_count) {
            return Err(bad(
                at,
                format!(
                    "object {i}: triangle {t} vertex index {bad_index} out of range ({vertex_count} vertices)"
                ),
            ));
        }
        triangles.push(tri);
    }
    Ok(Some(MeshInfo {
        atlas_grid,
        positions,
        normals,
        uvs,
        triangles,
    }))
}

/// Encodes sample points little-endian, field by field (works on any host).
pub(crate) fn encode_points(points: &[SamplePoint]) -> Vec<u8> {
    let mut w = ByteWriter::default();
    for p in points {
        for v in p.position.iter().chain(&p.normal).chain(&p.uv) {
            w.f32(*v);
        }
        w.u32(p.patch);
        w.u32(p.object);
    }
    w.into_inner()
}

/// Checks every sample point: finite fields, uv in `[0, 1]`, patch and object
/// in range, patch inside its object's range.
pub(crate) fn validate_points(points: &[SamplePoint], meta: &StoreMeta) -> Result<(), Error> {
    for (i, p) in points.iter().enumerate() {
        let fail = |detail: String| Error::InvalidSamplePoint {
            index: i as u64,
            detail,
        };
        if !p
            .position
            .iter()
            .chain(&p.normal)
            .chain(&p.uv)
            .all(|v| v.is_finite())
        {
            return Err(fail(format!("non-finite field in {p:?}")));
        }
        if !p.uv.iter().all(|v| (0.0..=1.0).contains(v)) {
            return Err(fail(format!("uv {:?} outside [0, 1]", p.uv)));
        }
        let object = meta.objects.get(p.object as usize).ok_or_else(|| {
            fail(format!(
                "object {} out of range ({} objects)",
                p.object,
                meta.objects.len()
            ))
        })?;
        let start = u64::from(object.first_patch);
        let end = start + u64::from(object.patch_count);
        if !(start..end).contains(&u64::from(p.patch)) {
            return Err(fail(format!(
                "patch {} is not one of object {}'s patches {start}..{end}",
                p.patch, p.object
            )));
        }
    }
    Ok(())
}
