//! Perspective cameras, placed in scene space.

use glam::{Affine3A, Vec3};
use oslf_geometry::Camera;

use super::import::{GltfCamera, Import};
use super::loader::{label, Loader};

impl<'d> Loader<'d> {
    pub(super) fn node_camera(
        &mut self,
        node: &gltf::Node,
        at: &str,
        camera: &gltf::Camera,
        world: &Affine3A,
        import: &mut Import,
    ) {
        let cam = label("cameras", camera.index(), camera.name());
        let gltf::camera::Projection::Perspective(p) = camera.projection() else {
            self.warn(format!(
                "{at}: {cam} is orthographic, which is not supported: skipped"
            ));
            return;
        };
        let position = world.transform_point3(Vec3::ZERO);
        let forward = world.transform_vector3(Vec3::NEG_Z).try_normalize();
        let up = world.transform_vector3(Vec3::Y).try_normalize();
        let vfov_deg = p.yfov().to_degrees();
        let (Some(forward), Some(up)) = (forward, up) else {
            self.warn(format!(
                "{at}: {cam}: the node's transform is singular, so the camera has no view direction: skipped"
            ));
            return;
        };
        let c = Camera {
            position,
            target: position + forward,
            up,
            vfov_deg,
        };
        if !(vfov_deg > 0.0 && vfov_deg < 180.0) || c.validate().is_err() {
            self.warn(format!(
                "{at}: {cam}: yfov {} rad is not a usable field of view: skipped",
                p.yfov()
            ));
            return;
        }
        import.cameras.push(GltfCamera {
            node: node
                .name()
                .map_or_else(|| format!("nodes[{}]", node.index()), str::to_string),
            name: camera.name().map(str::to_string),
            camera: c,
            aspect_ratio: p.aspect_ratio(),
        });
    }
}
