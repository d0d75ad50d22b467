//! The camera's projection and a default view of an object.

use glam::{Mat4, Vec3};
use oslf_geometry::Camera;

use super::Renderer;
use crate::geometry::ObjectMesh;

/// The camera's view-projection matrix (right-handed, depth 0..1 as wgpu wants), with near and
/// far planes from the distance to the target.
pub fn view_projection(camera: &Camera, width: u32, height: u32) -> Mat4 {
    use glam::Vec4;
    let (r, u, f) = camera.basis();
    let p = camera.position;
    let view = Mat4::from_cols(
        Vec4::new(r.x, u.x, -f.x, 0.0),
        Vec4::new(r.y, u.y, -f.y, 0.0),
        Vec4::new(r.z, u.z, -f.z, 0.0),
        Vec4::new(-r.dot(p), -u.dot(p), f.dot(p), 1.0),
    );
    let dist = (camera.target - p).length().max(1e-6);
    let (near, far) = (dist * 1e-3, dist * 1e3);
    let aspect = width.max(1) as f32 / height.max(1) as f32;
    let h = 1.0 / (0.5 * camera.vfov_deg.to_radians()).tan();
    let depth = far / (near - far);
    let proj = Mat4::from_cols(
        Vec4::new(h / aspect, 0.0, 0.0, 0.0),
        Vec4::new(0.0, h, 0.0, 0.0),
        Vec4::new(0.0, 0.0, depth, -1.0),
        Vec4::new(0.0, 0.0, depth * near, 0.0),
    );
    proj * view
}

/// A camera that frames the whole object from the front-left, above (for stores without one).
pub fn default_camera(mesh: &ObjectMesh) -> Camera {
    let (lo, hi) = mesh.bounds();
    let centre = (lo + hi) * 0.5;
    let radius = ((hi - lo).length() * 0.5).max(1e-6);
    let dir = Vec3::new(0.55, -0.75, 0.45).normalize();
    Camera {
        position: centre + dir * radius * 3.2,
        target: centre,
        up: Vec3::Z,
        vfov_deg: 40.0,
    }
}

/// The camera of `store` (drawn as `mesh`), or [`default_camera`] when it has none.
pub(crate) fn store_view(store: &oslf_format::Store, mesh: &ObjectMesh) -> Camera {
    match &store.meta().camera {
        Some(c) => Camera {
            position: Vec3::from_array(c.position),
            target: Vec3::from_array(c.target),
            up: Vec3::from_array(c.up),
            vfov_deg: c.vfov_deg,
        },
        None => default_camera(mesh),
    }
}

impl Renderer {
    /// The store's camera, or [`default_camera`] when it has none.
    pub fn default_view(&self) -> Camera {
        store_view(&self.store, &self.mesh)
    }
}
