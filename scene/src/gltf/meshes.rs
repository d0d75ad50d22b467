//! Meshes: triangle primitives read into meshes (strips and fans as lists, flat normals
//! where absent, or the scene's rule), as environment shapes or OSLF objects.

use glam::{Affine3A, Vec2, Vec3};
use gltf::accessor::{DataType, Dimensions};
use gltf::mesh::Mode;
use gltf::Semantic;
use oslf_geometry::atlas::UvSource;

use super::import::{Import, ImportedObject};
use super::loader::{label, Loader};
use super::textures::UvMap;
use crate::material::Material;
use crate::normals::{shade, NormalRule, NormalsUsed};
use crate::scene::Shape;
use crate::Result;
use oslf_geometry::mesh::Mesh;

impl<'d> Loader<'d> {
    /// Reads `node`'s mesh into `import.shapes`, or, when `object` is set, into one
    /// `import.objects` entry (its primitives merged, with their raw `TEXCOORD_1` and
    /// `TEXCOORD_0` as atlas candidates where every primitive has them).
    #[allow(clippy::too_many_arguments)]
    pub(super) fn node_mesh(
        &mut self,
        node: &gltf::Node,
        at: &str,
        mesh: &gltf::Mesh,
        world: &Affine3A,
        object: bool,
        materials: &mut Vec<Material>,
        import: &mut Import,
    ) -> Result<()> {
        let mut merged: Option<ImportedObject> = None;
        let (mut lightmap, mut texture): (Option<Vec<Vec2>>, Option<Vec<Vec2>>) =
            (Some(Vec::new()), Some(Vec::new()));
        let mesh_label = label("meshes", mesh.index(), mesh.name());
        // The primitives read without and with usable `NORMAL`s.
        let mut with_normals: [Vec<usize>; 2] = Default::default();
        if node.weights().is_some() || mesh.weights().is_some() {
            self.warn(format!(
                "{at}: {mesh_label}: morph target weights are not supported: the base mesh is drawn"
            ));
        }
        if let Some(ext) = mesh.extensions() {
            let names: Vec<String> = ext.keys().cloned().collect();
            for e in names {
                self.warn(format!("{mesh_label}: extension {e} is not supported"));
            }
        }
        for prim in mesh.primitives() {
            let json_at = format!("meshes[{}].primitives[{}]", mesh.index(), prim.index());
            let what = format!("{mesh_label} primitive {}", prim.index());
            let triangles_from = match prim.mode() {
                Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan => prim.mode(),
                other => {
                    self.warn(format!(
                        "{what}: mode {other:?} is not supported (triangles only): skipped"
                    ));
                    continue;
                }
            };
            self.warn_primitive(&prim, &what);
            let material = prim.material();
            let (material_index, uv_map) = self.material(&material, materials)?;
            let PrimitiveMesh {
                mesh: mut m,
                vertices,
                split,
                had_normals,
            } = self.primitive_mesh(&prim, &json_at, &what, triangles_from, uv_map.as_ref())?;
            if m.triangles.is_empty() {
                continue;
            }
            with_normals[usize::from(had_normals)].push(prim.index());
            m.transform(world);
            if let Some(i) = m.positions.iter().position(|p| !p.is_finite()) {
                return Err(self.err(
                    format!("{json_at}.attributes.POSITION"),
                    format!(
                        "vertex {i} is not finite once the node transforms of {at} are applied"
                    ),
                ));
            }
            if !object {
                let file = self.path.file_name().unwrap_or(self.path.as_os_str());
                import.shapes.push(Shape {
                    name: format!("{}: {at}: {what}", file.to_string_lossy()),
                    mesh: m,
                    material: material_index,
                });
                continue;
            }
            for (set, uvs) in [(1, &mut lightmap), (0, &mut texture)] {
                match (
                    self.texcoords(&prim, set, &json_at, vertices)?,
                    uvs.as_mut(),
                ) {
                    // Flat-shaded primitives were split per triangle corner: follow the split.
                    (Some(read), Some(all)) => match &split {
                        None => all.extend(read),
                        Some(source) => all.extend(source.iter().map(|&i| read[i as usize])),
                    },
                    _ => *uvs = None,
                }
            }
            match &mut merged {
                None => {
                    merged = Some(ImportedObject {
                        node: node.name().unwrap_or_default().to_string(),
                        mesh: m,
                        uv_sets: Vec::new(),
                        material: material_index,
                        normals: NormalsUsed {
                            rule: None,
                            reason: String::new(),
                        },
                    })
                }
                Some(o) => {
                    if o.material != material_index {
                        self.warn(format!(
                            "{at}: an OSLF object has one material: {what} keeps the first primitive's"
                        ));
                    }
                    o.mesh.append(&m);
                }
            }
        }
        if let Some(mut o) = merged {
            o.uv_sets = [(UvSource::Lightmap, lightmap), (UvSource::Texture, texture)]
                .into_iter()
                .filter_map(|(s, uvs)| Some((s, uvs?)))
                .collect();
            o.normals = self.normals_used(&mesh_label, &with_normals);
            import.objects.push(o);
        }
        Ok(())
    }

    /// Which normals an object made of `mesh_label`'s primitives got and why, given the
    /// primitives without (`with_normals[0]`) and with (`[1]`) usable `NORMAL`s.
    fn normals_used(&self, mesh_label: &str, with_normals: &[Vec<usize>; 2]) -> NormalsUsed {
        let prims = |list: &[usize], verb: (&str, &str)| {
            let numbers: Vec<String> = list.iter().map(usize::to_string).collect();
            let (noun, verb) = if list.len() == 1 {
                ("primitive", verb.0)
            } else {
                ("primitives", verb.1)
            };
            format!(
                "{} {mesh_label} {noun} {} {verb}",
                self.file,
                numbers.join(", ")
            )
        };
        let [without, with] = with_normals;
        let (rule, reason) = match self.normal_rule {
            Some(rule) if !with.is_empty() => (
                Some(rule),
                format!(
                    "asked for in the scene file; replaces the NORMAL {}",
                    prims(with, ("has", "have"))
                ),
            ),
            Some(rule) => (
                Some(rule),
                format!(
                    "asked for in the scene file; {} no NORMAL",
                    prims(without, ("has", "have"))
                ),
            ),
            None if without.is_empty() => (None, prims(with, ("has NORMAL", "have NORMAL"))),
            None => (
                Some(NormalRule::Flat),
                format!(
                    "{} no NORMAL; the glTF default{}",
                    prims(without, ("has", "have")),
                    if with.is_empty() {
                        ""
                    } else {
                        " (the others keep their NORMAL)"
                    }
                ),
            ),
        };
        NormalsUsed { rule, reason }
    }

    /// Warns about what the primitive uses and the import ignores: morph targets, vertex
    /// colours, extensions.
    fn warn_primitive(&mut self, prim: &gltf::Primitive, what: &str) {
        if prim.morph_targets().next().is_some() {
            self.warn(format!(
                "{what}: morph targets are not supported: the base mesh is drawn"
            ));
        }
        for (semantic, _) in prim.attributes() {
            if let Semantic::Colors(n) = semantic {
                self.warn(format!(
                    "{what}: vertex colours (COLOR_{n}) are not supported: ignored"
                ));
            }
        }
        if let Some(ext) = prim.extensions() {
            let names: Vec<String> = ext.keys().cloned().collect();
            for e in names {
                self.warn(format!("{what}: extension {e} is not supported"));
            }
        }
    }

    /// The primitive's `TEXCOORD_{set}` as read (no texture transform), `None` if absent;
    /// `n` is its vertex count.
    pub(super) fn texcoords(
        &mut self,
        prim: &gltf::Primitive,
        set: u32,
        json_at: &str,
        n: usize,
    ) -> Result<Option<Vec<Vec2>>> {
        let Some(acc) = prim.get(&Semantic::TexCoords(set)) else {
            return Ok(None);
        };
        let at = format!("{json_at}.attributes.TEXCOORD_{set}");
        let flat = self.read_floats(
            &acc,
            &at,
            Dimensions::Vec2,
            &[
                (DataType::F32, true),
                (DataType::U8, true),
                (DataType::U16, true),
            ],
            "vec2 of f32, normalized u8 or normalized u16",
        )?;
        if flat.len() != 2 * n {
            return Err(self.err(
                at,
                format!(
                    "accessor {} has {} elements, POSITION has {n}",
                    acc.index(),
                    flat.len() / 2
                ),
            ));
        }
        let uvs: Vec<Vec2> = flat.chunks_exact(2).map(Vec2::from_slice).collect();
        if let Some(i) = uvs.iter().position(|p| !p.is_finite()) {
            return Err(self.err(
                at,
                format!("accessor {}: element {i} is not finite", acc.index()),
            ));
        }
        Ok(Some(uvs))
    }

    /// One triangle primitive (`mode`: list, strip or fan) as a mesh: positions, indices,
    /// texture coordinates mapped by `uv_map` (zero without one), normals (flat where absent
    /// or unusable).
    pub(super) fn primitive_mesh(
        &mut self,
        prim: &gltf::Primitive,
        json_at: &str,
        what: &str,
        mode: Mode,
        uv_map: Option<&UvMap>,
    ) -> Result<PrimitiveMesh> {
        let positions = self.positions(prim, json_at)?;
        let n = positions.len();
        let indices: Vec<u32> = match prim.indices() {
            Some(acc) => self.indices(&acc, json_at, n)?,
            None => (0..n as u32).collect(),
        };
        let triangles = self.triangles(&indices, mode, what);
        let uvs: Vec<Vec2> = match uv_map {
            None => vec![Vec2::ZERO; n],
            Some(map) => self.mapped_uvs(prim, map, json_at, what, n)?,
        };
        let given = self.normals(prim, json_at, what, n)?;
        let had_normals = given.is_some();
        let vertices = positions.len();
        let (mesh, split) = match (given, self.normal_rule) {
            (Some(normals), None) => (
                Mesh {
                    positions,
                    normals,
                    uvs,
                    triangles,
                },
                None,
            ),
            (_, rule) => {
                let (mesh, source) = shade(
                    &positions,
                    &uvs,
                    &triangles,
                    rule.unwrap_or(NormalRule::Flat),
                );
                (mesh, Some(source))
            }
        };
        mesh.validate()
            .map_err(|e| self.err(json_at.to_string(), e.to_string()))?;
        Ok(PrimitiveMesh {
            mesh,
            vertices,
            split,
            had_normals,
        })
    }

    /// The primitive's `POSITION`s, every one finite.
    fn positions(&self, prim: &gltf::Primitive, json_at: &str) -> Result<Vec<Vec3>> {
        let pos_at = format!("{json_at}.attributes.POSITION");
        let accessor = prim
            .get(&Semantic::Positions)
            .ok_or_else(|| self.err(&pos_at, "missing"))?;
        let flat = self.read_floats(
            &accessor,
            &pos_at,
            Dimensions::Vec3,
            &[(DataType::F32, true)],
            "f32 vec3",
        )?;
        let positions: Vec<Vec3> = flat.chunks_exact(3).map(Vec3::from_slice).collect();
        if let Some(i) = positions.iter().position(|p| !p.is_finite()) {
            return Err(self.err(
                pos_at,
                format!(
                    "accessor {}: vertex {i} is {} (not finite)",
                    accessor.index(),
                    positions[i]
                ),
            ));
        }
        Ok(positions)
    }

    /// The indices of accessor `acc`, each below the `n` vertices.
    fn indices(&self, acc: &gltf::Accessor, json_at: &str, n: usize) -> Result<Vec<u32>> {
        let at = format!("{json_at}.indices");
        let idx = self.read_indices(acc, &at)?;
        if let Some((e, v)) = idx.iter().enumerate().find(|(_, &v)| v as usize >= n) {
            return Err(self.err(
                at,
                format!(
                    "accessor {}: index {v} (element {e}) is out of range: POSITION has {n} vertices",
                    acc.index()
                ),
            ));
        }
        Ok(idx)
    }

    /// The triangles of `indices` read as a strip, a fan or a list (`mode`).
    fn triangles(&mut self, indices: &[u32], mode: Mode, what: &str) -> Vec<[u32; 3]> {
        let mut triangles: Vec<[u32; 3]> = Vec::new();
        match mode {
            Mode::TriangleStrip => {
                for i in 0..indices.len().saturating_sub(2) {
                    let t = if i % 2 == 0 {
                        [indices[i], indices[i + 1], indices[i + 2]]
                    } else {
                        [indices[i + 1], indices[i], indices[i + 2]]
                    };
                    triangles.push(t);
                }
            }
            Mode::TriangleFan => {
                for i in 1..indices.len().saturating_sub(1) {
                    triangles.push([indices[i], indices[i + 1], indices[0]]);
                }
            }
            _ => {
                if !indices.len().is_multiple_of(3) {
                    self.warn(format!(
                        "{what}: {} indices is not a multiple of 3: the last {} are ignored",
                        indices.len(),
                        indices.len() % 3
                    ));
                }
                triangles.extend(indices.chunks_exact(3).map(|t| [t[0], t[1], t[2]]));
            }
        }
        triangles
    }

    /// The texture coordinates `map` reads (its `TEXCOORD_n`), mapped into the texture; (0, 0)
    /// where the primitive lacks the set.
    fn mapped_uvs(
        &mut self,
        prim: &gltf::Primitive,
        map: &UvMap,
        json_at: &str,
        what: &str,
        n: usize,
    ) -> Result<Vec<Vec2>> {
        let semantic = Semantic::TexCoords(map.set);
        Ok(match prim.get(&semantic) {
            None => {
                self.warn(format!(
                    "{what}: the material's texture uses TEXCOORD_{}, which the primitive does not have: the texture is read at uv (0, 0)",
                    map.set
                ));
                vec![map.apply(Vec2::ZERO); n]
            }
            Some(_) => {
                let uvs = self
                    .texcoords(prim, map.set, json_at, n)?
                    .expect("the attribute is present");
                if uvs.iter().any(|&uv| map.beyond_clamp(uv)) {
                    self.warn(format!(
                        "{what}: texture coordinates beyond [0, 1] along a CLAMP_TO_EDGE axis are not supported: the texture repeats there"
                    ));
                }
                uvs.into_iter().map(|uv| map.apply(uv)).collect()
            }
        })
    }

    /// The primitive's unit `NORMAL`s, `None` where it has none or some are zero or not
    /// finite (then flat normals are used).
    fn normals(
        &mut self,
        prim: &gltf::Primitive,
        json_at: &str,
        what: &str,
        n: usize,
    ) -> Result<Option<Vec<Vec3>>> {
        let Some(acc) = prim.get(&Semantic::Normals) else {
            return Ok(None);
        };
        let at = format!("{json_at}.attributes.NORMAL");
        let flat = self.read_floats(
            &acc,
            &at,
            Dimensions::Vec3,
            &[(DataType::F32, true)],
            "f32 vec3",
        )?;
        if flat.len() != 3 * n {
            return Err(self.err(
                at,
                format!(
                    "accessor {} has {} elements, POSITION has {n}",
                    acc.index(),
                    flat.len() / 3
                ),
            ));
        }
        let normals: Vec<Vec3> = flat.chunks_exact(3).map(Vec3::from_slice).collect();
        if normals
            .iter()
            .all(|v| v.is_finite() && v.length_squared() > 0.0)
        {
            Ok(Some(normals.into_iter().map(|v| v.normalize()).collect()))
        } else {
            self.warn(format!(
                "{what}: some normals are zero or not finite: computed ones are used (flat unless the scene asks otherwise)"
            ));
            Ok(None)
        }
    }
}

/// A primitive read into a mesh.
pub(super) struct PrimitiveMesh {
    mesh: Mesh,
    /// Elements of the primitive's `POSITION` accessor.
    vertices: usize,
    /// Where the normals were computed (vertices split where normals differ): the accessor
    /// element of each mesh vertex.
    split: Option<Vec<u32>>,
    /// Whether the primitive has usable `NORMAL`s (used or not).
    had_normals: bool,
}
