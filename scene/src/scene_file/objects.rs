//! The OSLF objects (`[[object]]`: Bézier patches or an OBJ mesh), the environment shapes
//! (`[[plane]]`, `[[box]]`, `[[cylinder]]`, `[[sphere]]`, `[[revolution]]`, `[[mesh]]`) and
//! their materials.

use std::ops::Range;
use std::sync::Arc;

use glam::{Affine3A, Vec2, Vec3};
use oslf_geometry::atlas::UvSource;
use toml::Spanned;

use super::context::Ctx;
use super::raw::{RawMaterial, RawObject, RawScene, RawTransform};
use crate::error::{BakeError, Result};
use crate::input::{read_input, InputKind};
use crate::material::{Material, Model};
use crate::scene::{epsilon_problem, MeshSource, OslfObject, Shape};
use crate::texture::{ImageTexture, Texture};
use crate::{obj, shapes};
use oslf_geometry::bezier::{self, BezierPatch};
use oslf_geometry::mesh::Mesh;

impl Ctx<'_> {
    /// The `[[object]]`s, in order, each checked against the ε the file gives (with where it
    /// gives it; `None`: ε is chosen from the objects, within what each allows).
    pub(super) fn objects(
        &self,
        raw: Vec<Spanned<RawObject>>,
        epsilon: &Option<(f32, Range<usize>)>,
        materials: &mut Vec<Material>,
    ) -> Result<Vec<OslfObject>> {
        let mut objects = Vec::new();
        for spanned in raw {
            let span = spanned.span();
            let object =
                self.object(spanned.into_inner(), span.clone(), objects.len(), materials)?;
            self.check_epsilon(epsilon, &object)?;
            objects.push(object);
        }
        Ok(objects)
    }

    /// One `[[object]]` (at `span`), the `index`-th.
    fn object(
        &self,
        o: RawObject,
        span: Range<usize>,
        index: usize,
        materials: &mut Vec<Material>,
    ) -> Result<OslfObject> {
        let transform = o.transform.affine();
        let (patches, mesh, normals) = match (&o.patches, &o.mesh) {
            (Some(patches), None) => {
                if let Some(normals) = &o.normals {
                    return Err(self.error_at(
                        normals.span(),
                        "`normals` sets how a `mesh` object's normals are computed; Bézier patches have exact ones",
                    ));
                }
                let patches = self.object_patches(patches, o.select.as_ref())?;
                (patches, None, None)
            }
            (None, Some(path)) => {
                if let Some(select) = &o.select {
                    return Err(self.error_at(
                        select.span(),
                        "`select` picks patches; a `mesh` object has none",
                    ));
                }
                let file = self.existing_file(path)?;
                let requested = o.normals.as_ref().map(|n| n.get_ref().0);
                let (mut mesh, normals) = obj::load_obj_with(&file, requested)?;
                mesh.transform(&transform);
                // An OBJ without `vt` reads as all-zero uvs: no texture set then.
                let uv_sets = if mesh.uvs.iter().any(|&uv| uv != Vec2::ZERO) {
                    vec![(UvSource::Texture, mesh.uvs.clone())]
                } else {
                    Vec::new()
                };
                let source = MeshSource::new(mesh, uv_sets);
                (Vec::new(), Some(source), Some(normals))
            }
            _ => {
                return Err(self.error_at(
                    span,
                    "an [[object]] needs exactly one of `patches` (Bézier patches) or `mesh` (an OBJ file)",
                ))
            }
        };
        let (material, base_color) = self.material(&o.material, materials)?;
        let world = patches.iter().map(|p| p.transformed(&transform)).collect();
        Ok(OslfObject {
            name: o.name.unwrap_or_else(|| format!("object{index}")),
            object_patches: patches,
            patches: world,
            mesh,
            transform,
            material,
            base_color,
            normals,
            sample_spacing: o.sample_spacing.map(|s| s.0),
        })
    }

    /// The environment shapes, in the order plane, box, cylinder, sphere, revolution, mesh.
    pub(super) fn shapes(
        &self,
        raw: &RawScene,
        materials: &mut Vec<Material>,
    ) -> Result<Vec<Shape>> {
        let mut shapes_out = Vec::new();
        let mut add = |name: String,
                       mesh: Mesh,
                       t: &RawTransform,
                       m: &Spanned<RawMaterial>,
                       materials: &mut Vec<Material>|
         -> Result<()> {
            let mut mesh = mesh;
            mesh.transform(&t.affine());
            let (material, _) = self.material(m, materials)?;
            shapes_out.push(Shape {
                name,
                mesh,
                material,
            });
            Ok(())
        };
        for (p_index, p) in raw.plane.iter().enumerate() {
            let mesh = shapes::plane(Vec2::new(p.size[0].0, p.size[1].0))
                .map_err(|e| self.locate(p.material.span(), e))?;
            let name = format!("[[plane]] {p_index}");
            add(name, mesh, &p.transform, &p.material, materials)?;
        }
        for (b_index, b) in raw.boxes.iter().enumerate() {
            let mesh = shapes::cuboid(Vec3::new(b.size[0].0, b.size[1].0, b.size[2].0))
                .map_err(|e| self.locate(b.material.span(), e))?;
            let name = format!("[[box]] {b_index}");
            add(name, mesh, &b.transform, &b.material, materials)?;
        }
        for (c_index, c) in raw.cylinder.iter().enumerate() {
            let mesh = shapes::cylinder(c.radius.0, c.height.0, c.segments.0, c.capped)
                .map_err(|e| self.locate(c.material.span(), e))?;
            let name = format!("[[cylinder]] {c_index}");
            add(name, mesh, &c.transform, &c.material, materials)?;
        }
        for (s_index, s) in raw.sphere.iter().enumerate() {
            let mesh = shapes::sphere(s.radius.0, s.segments.0)
                .map_err(|e| self.locate(s.material.span(), e))?;
            let name = format!("[[sphere]] {s_index}");
            add(name, mesh, &s.transform, &s.material, materials)?;
        }
        for (r_index, r) in raw.revolution.iter().enumerate() {
            let profile: Vec<Vec2> = r
                .profile
                .get_ref()
                .iter()
                .map(|[a, b]| Vec2::new(a.0, b.0))
                .collect();
            let mesh = shapes::revolution(&profile, r.segments.0)
                .map_err(|e| self.locate(r.profile.span(), e))?;
            let name = format!("[[revolution]] {r_index}");
            add(name, mesh, &r.transform, &r.material, materials)?;
        }
        for m in &raw.mesh {
            let file = self.existing_file(&m.path)?;
            let (mesh, _) = obj::load_obj_with(&file, m.normals.map(|n| n.0))?;
            let name = format!("[[mesh]] {:?}", m.path.get_ref());
            add(name, mesh, &m.transform, &m.material, materials)?;
        }
        Ok(shapes_out)
    }

    /// Adds a material, returning its index and its mean albedo.
    pub(super) fn material(
        &self,
        m: &Spanned<RawMaterial>,
        materials: &mut Vec<Material>,
    ) -> Result<(u32, Vec3)> {
        let raw = m.get_ref();
        let count = raw.color.is_some() as u32
            + raw.checker.is_some() as u32
            + raw.texture.is_some() as u32;
        if count != 1 {
            return Err(self.error_at(
                m.span(),
                "a material needs exactly one of `color`, `checker` or `texture`",
            ));
        }
        let (albedo, mean) = if let Some(c) = raw.color {
            (Texture::Constant(c.0), c.0)
        } else if let Some(c) = &raw.checker {
            (
                Texture::Checker {
                    a: c.a.0,
                    b: c.b.0,
                    scale: c.scale.0,
                },
                (c.a.0 + c.b.0) * 0.5,
            )
        } else {
            let spanned = raw.texture.as_ref().expect("counted above");
            let file = self.existing_file(spanned)?;
            let image = ImageTexture::load(&file)?;
            let mean =
                image.pixels.iter().copied().sum::<Vec3>() / image.pixels.len().max(1) as f32;
            (Texture::Image(Arc::new(image)), mean)
        };
        let model = match (raw.metallic, raw.roughness) {
            (None, None) => Model::Lambertian,
            (Some(metallic), Some(roughness)) => Model::MetallicRoughness {
                metallic: metallic.0,
                roughness: roughness.0,
            },
            _ => {
                return Err(self.error_at(
                    m.span(),
                    "a metallic-roughness material needs both `metallic` and `roughness`",
                ))
            }
        };
        let emission = raw.emission.map_or(Vec3::ZERO, |e| e.0);
        let material = Material {
            albedo,
            model,
            emission,
            metallic_roughness_texture: None,
            normal_texture: None,
            emissive_texture: None,
            occlusion_texture: None,
        };
        materials.push(material);
        Ok(((materials.len() - 1) as u32, mean))
    }

    /// The patches an `[[object]]` names: the built-in teapot or a patch file, cut to
    /// `select`.
    fn object_patches(
        &self,
        patches: &Spanned<String>,
        select: Option<&Spanned<[u32; 2]>>,
    ) -> Result<Vec<BezierPatch>> {
        let mut out = if patches.get_ref() == "newell-teapot" {
            bezier::newell_teapot()
        } else {
            let file = self.existing_file(patches)?;
            let bytes = read_input(&file, InputKind::Text)?;
            let text = String::from_utf8(bytes).map_err(|e| {
                BakeError::Invalid(format!(
                    "{}: not valid UTF-8 (byte {})",
                    file.display(),
                    e.utf8_error().valid_up_to()
                ))
            })?;
            bezier::parse_patch_file(&text, &file)?
        };
        if let Some(select) = select {
            let [first, end] = *select.get_ref();
            if first >= end || end as usize > out.len() {
                return Err(self.error_at(
                    select.span(),
                    format!(
                        "select = [{first}, {end}] is not a non-empty range within the {} patches",
                        out.len()
                    ),
                ));
            }
            out = out[first as usize..end as usize].to_vec();
        }
        Ok(out)
    }

    /// Refuses a given ε (located where the file gives it) that the bake cannot honour for
    /// `object` ([`epsilon_problem`]). A chosen one (`None`) is chosen within the limits.
    pub(super) fn check_epsilon(
        &self,
        epsilon: &Option<(f32, Range<usize>)>,
        object: &OslfObject,
    ) -> Result<()> {
        let Some((epsilon, span)) = epsilon else {
            return Ok(());
        };
        match epsilon_problem(*epsilon, object) {
            Some(message) => Err(self.error_at(span.clone(), message)),
            None => Ok(()),
        }
    }
}

/// OSLF objects of the glTF nodes chosen as objects (world space, identity transform), their
/// base colour the material's mean albedo.
pub(super) fn mesh_objects(
    imported: Vec<crate::gltf::ImportedObject>,
    materials: &[Material],
) -> Vec<OslfObject> {
    imported
        .into_iter()
        .map(|o| OslfObject {
            name: o.node,
            object_patches: Vec::new(),
            patches: Vec::new(),
            mesh: Some(MeshSource::new(o.mesh, o.uv_sets)),
            transform: Affine3A::IDENTITY,
            material: o.material,
            base_color: materials[o.material as usize].mean_albedo(),
            normals: Some(o.normals),
            sample_spacing: None,
        })
        .collect()
}
