//! The node hierarchy: the scene's nodes traversed depth first with their transforms, each
//! node's mesh, camera and light read.

use std::collections::HashSet;

use glam::{Affine3A, Mat4, Quat, Vec3};

use super::import::{Import, Options};
use super::loader::{label, Loader};
use crate::material::Material;
use crate::Result;

/// Whether a node's `extras` hold `"oslf": true`.
pub(super) fn marked_oslf(node: &gltf::Node) -> bool {
    node.extras().as_ref().is_some_and(|raw| {
        serde_json::from_str::<serde_json::Value>(raw.get())
            .is_ok_and(|v| v.get("oslf") == Some(&serde_json::Value::Bool(true)))
    })
}

impl<'d> Loader<'d> {
    pub(super) fn traverse(
        &mut self,
        options: &Options,
        materials: &mut Vec<Material>,
        import: &mut Import,
    ) -> Result<()> {
        let doc = self.doc;
        let scene = doc.default_scene().or_else(|| doc.scenes().next());
        let roots: Vec<gltf::Node> = match &scene {
            Some(s) => {
                if doc.scenes().len() > 1 {
                    self.warn(format!(
                        "the file has {} scenes; only {} is loaded",
                        doc.scenes().len(),
                        label("scenes", s.index(), s.name())
                    ));
                }
                s.nodes().collect()
            }
            None => {
                let children: HashSet<usize> = doc
                    .nodes()
                    .flat_map(|n| n.children().map(|c| c.index()).collect::<Vec<_>>())
                    .collect();
                doc.nodes()
                    .filter(|n| !children.contains(&n.index()))
                    .collect()
            }
        };
        let mut seen = HashSet::new();
        let mut stack: Vec<(gltf::Node, Mat4)> = roots
            .into_iter()
            .rev()
            .map(|n| (n, Mat4::IDENTITY))
            .collect();
        while let Some((node, parent)) = stack.pop() {
            let at = label("nodes", node.index(), node.name());
            if !seen.insert(node.index()) {
                return Err(self.err(
                    format!("nodes[{}]", node.index()),
                    "the node is reached twice: the node hierarchy must be a set of trees",
                ));
            }
            let local = self.local_transform(&node)?;
            let global = parent * local;
            let world = Affine3A::from_mat4(global);
            let world = options.transform * world;
            if let Some(mesh) = node.mesh() {
                let object = node
                    .name()
                    .is_some_and(|n| options.objects.iter().any(|o| o == n))
                    || (options.objects_from_extras && marked_oslf(&node));
                self.node_mesh(&node, &at, &mesh, &world, object, materials, import)?;
            }
            if node.skin().is_some() {
                self.warn(format!(
                    "{at}: skins are not supported: the mesh is drawn unskinned"
                ));
            }
            if let Some(camera) = node.camera() {
                self.node_camera(&node, &at, &camera, &world, import);
            }
            if let Some(light) = node.light() {
                if options.lights {
                    let l = self.node_light(&at, &light, &world, options.watts_per_lumen)?;
                    import.lights.push(l);
                }
            }
            if let Some(ext) = node.extensions() {
                let names: Vec<String> = ext.keys().cloned().collect();
                for e in names {
                    self.warn(format!("{at}: extension {e} is not supported"));
                }
            }
            let children: Vec<gltf::Node> = node.children().collect();
            for child in children.into_iter().rev() {
                stack.push((child, global));
            }
        }
        Ok(())
    }

    pub(super) fn local_transform(&self, node: &gltf::Node) -> Result<Mat4> {
        let i = node.index();
        let m = match node.transform() {
            gltf::scene::Transform::Matrix { matrix } => {
                let m = Mat4::from_cols_array_2d(&matrix);
                if !m.is_finite() {
                    return Err(self.err(format!("nodes[{i}].matrix"), "has a non-finite element"));
                }
                if m.row(3) != glam::Vec4::W {
                    return Err(self.err(
                        format!("nodes[{i}].matrix"),
                        format!(
                            "the last row is {}, not [0, 0, 0, 1]: a node matrix must be affine",
                            m.row(3)
                        ),
                    ));
                }
                m
            }
            gltf::scene::Transform::Decomposed {
                translation,
                rotation,
                scale,
            } => {
                let t = Vec3::from(translation);
                let s = Vec3::from(scale);
                let q = Quat::from_array(rotation);
                if !t.is_finite() {
                    return Err(self.err(format!("nodes[{i}].translation"), "is not finite"));
                }
                if !s.is_finite() {
                    return Err(self.err(format!("nodes[{i}].scale"), "is not finite"));
                }
                if !q.is_finite() || q.length_squared() < 1e-12 {
                    return Err(self.err(
                        format!("nodes[{i}].rotation"),
                        format!("{rotation:?} is not a unit quaternion"),
                    ));
                }
                Mat4::from_scale_rotation_translation(s, q.normalize(), t)
            }
        };
        Ok(m)
    }
}
