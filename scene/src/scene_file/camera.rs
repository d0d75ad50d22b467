//! The scene's camera: a `[camera]` table, checked as the renderers need it, or a camera of
//! an included glTF file.

use glam::Vec3;
use oslf_geometry::camera::{VFOV_MAX_DEG, VFOV_MIN_DEG};
use oslf_geometry::Camera;
use toml::Spanned;

use super::context::Ctx;
use super::raw::RawCamera;
use crate::error::Result;
use crate::gltf::GltfCamera;

/// A `[camera]` as written: explicit, or naming a glTF camera (resolved once the includes are
/// read).
pub(super) enum CameraSpec {
    Explicit(Camera),
    Gltf(Spanned<String>),
}

impl Ctx<'_> {
    /// The `[camera]`, checked as the renderers need it: errors point at the key at fault
    /// (or at the table when the key was left at its default).
    pub(super) fn camera(&self, raw: Spanned<RawCamera>) -> Result<CameraSpec> {
        let table = raw.span();
        let c = raw.into_inner();
        if let Some(name) = c.gltf {
            if c.position.is_some() || c.target.is_some() || c.up.is_some() || c.vfov.is_some() {
                return Err(self.error_at(
                    table,
                    "a [camera] with `gltf` takes the glTF camera as it is: give no position, target, up or vfov with it",
                ));
            }
            return Ok(CameraSpec::Gltf(name));
        }
        let (Some(position), Some(target)) = (c.position, c.target) else {
            return Err(self.error_at(
                table,
                "the [camera] needs `position` and `target` (or `gltf = \"NodeName\"`, a camera of an included glTF file)",
            ));
        };
        let vec = |v: Vec3| format!("[{}, {}, {}]", v.x, v.y, v.z);
        let camera = Camera {
            position: position.0,
            target: target.get_ref().0,
            up: c.up.as_ref().map_or(Vec3::Z, |u| u.get_ref().0).normalize(),
            vfov_deg: c.vfov.as_ref().map_or(40.0, |v| v.get_ref().0),
        };
        let Some(forward) = (camera.target - camera.position).try_normalize() else {
            return Err(self.error_at(
                target.span(),
                format!(
                    "the camera's target {} coincides with its position",
                    vec(camera.target)
                ),
            ));
        };
        if forward.cross(camera.up).length_squared() < 1e-12 {
            let (span, up) = match &c.up {
                Some(u) => (u.span(), format!("up {}", vec(u.get_ref().0))),
                None => (table.clone(), "up (default [0, 0, 1])".to_string()),
            };
            return Err(self.error_at(
                span,
                format!(
                    "the camera's {up} is parallel to its view direction {} (from position to target), so the image has no defined vertical: choose an up that is not",
                    vec(forward)
                ),
            ));
        }
        if !(VFOV_MIN_DEG..=VFOV_MAX_DEG).contains(&camera.vfov_deg) {
            let span = c.vfov.as_ref().map_or(table.clone(), |v| v.span());
            return Err(self.error_at(
                span,
                format!(
                    "the camera's vfov {} must be within {VFOV_MIN_DEG} to {VFOV_MAX_DEG} degrees",
                    camera.vfov_deg
                ),
            ));
        }
        // Whatever else the renderers refuse.
        camera
            .validate()
            .map_err(|e| self.locate(table, e.into()))?;
        Ok(CameraSpec::Explicit(camera))
    }

    /// The scene camera: the `[camera]`'s, the glTF camera it names, or (without a
    /// `[camera]`) the first camera of the included glTF files.
    pub(super) fn resolve_camera(
        &self,
        spec: Option<CameraSpec>,
        cameras: &[GltfCamera],
    ) -> Result<Option<Camera>> {
        Ok(match spec {
            Some(CameraSpec::Explicit(c)) => Some(c),
            Some(CameraSpec::Gltf(name)) => {
                let wanted = name.get_ref();
                let found = cameras
                    .iter()
                    .find(|c| &c.node == wanted)
                    .or_else(|| cameras.iter().find(|c| c.name.as_ref() == Some(wanted)));
                match found {
                    Some(c) => Some(c.camera),
                    None => {
                        let known: Vec<String> =
                            cameras.iter().map(|c| format!("{:?}", c.node)).collect();
                        return Err(self.error_at(
                            name.span(),
                            format!(
                                "no glTF camera named {wanted:?} (the included glTF files have {})",
                                if known.is_empty() {
                                    "no perspective camera".to_string()
                                } else {
                                    format!("cameras on nodes {}", known.join(", "))
                                }
                            ),
                        ));
                    }
                }
            }
            None => cameras.first().map(|c| c.camera),
        })
    }
}
