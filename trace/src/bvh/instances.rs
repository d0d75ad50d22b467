//! The scene's triangles as the BVH takes them: environment shapes and the OSLF objects
//! tessellated finely enough for a given error.

use oslf_geometry::mesh::Mesh;
use oslf_scene::scene::Scene;

use super::Instance;
use crate::ray::ENVIRONMENT_OBJECT;

/// Every triangle of `scene` for ray tracing: environment shapes and (with `include_objects`)
/// the OSLF objects tessellated finely enough that the tessellation error stays below
/// `max_error`.
pub fn scene_instances(scene: &Scene, include_objects: bool, max_error: f32) -> Vec<Instance> {
    let mut out: Vec<Instance> = scene
        .shapes
        .iter()
        .map(|s| Instance {
            name: s.name.clone(),
            mesh: s.mesh.clone(),
            material: s.material,
            object: ENVIRONMENT_OBJECT,
        })
        .collect();
    if include_objects {
        for (i, object) in scene.objects.iter().enumerate() {
            let mut mesh = Mesh::default();
            for patch in &object.patches {
                mesh.append(&patch.tessellate(patch.tessellation_level(max_error)));
            }
            if let Some(source) = &object.mesh {
                mesh.append(&source.mesh);
            }
            out.push(Instance {
                name: format!("object {:?}", object.name),
                mesh,
                material: object.material,
                object: i as u32,
            });
        }
    }
    out
}
