//! What the store says about the scene and the bake, besides the points, maps and cubes.

use glam::{Affine3A, Mat4, Vec3};
use oslf_format::{BakeParams, CameraInfo, MeshInfo, ObjectInfo, Patch, StoreMeta};

use crate::sample_points::Surfaces;
use oslf_scene::scene::Scene;
use oslf_trace::capture::strata_per_side;

/// Everything the store says about the scene and the bake, besides the points, maps and cubes.
/// A mesh object is stored in world space (identity transform) with its atlas's vertices.
pub fn store_meta(scene: &Scene, surfaces: &Surfaces) -> StoreMeta {
    let s = &scene.bake;
    let mut objects = Vec::new();
    let mut patches = Vec::new();
    for (i, o) in scene.objects.iter().enumerate() {
        let (transform, patch_count, mesh) = match surfaces.atlas(i) {
            None => (o.transform, o.object_patches.len() as u32, None),
            Some(atlas) => {
                let m = &atlas.mesh;
                let mesh = MeshInfo {
                    atlas_grid: atlas.grid,
                    positions: m.positions.iter().map(|p| p.to_array()).collect(),
                    normals: m.normals.iter().map(|n| n.to_array()).collect(),
                    uvs: m.uvs.iter().map(|uv| uv.to_array()).collect(),
                    triangles: m.triangles.clone(),
                };
                let material = scene.materials.get(o.material as usize);
                let (mesh, textures) = match (material, &o.mesh) {
                    (Some(material), Some(source)) => {
                        super::textures::object_textures(material, mesh, &source.mesh)
                    }
                    _ => (mesh, None),
                };
                (
                    Affine3A::IDENTITY,
                    atlas.grid * atlas.grid,
                    Some((mesh, textures)),
                )
            }
        };
        let (mesh, textures) = mesh.map_or((None, None), |(m, t)| (Some(m), t));
        objects.push(ObjectInfo {
            name: o.name.clone(),
            transform: Mat4::from(transform).to_cols_array_2d(),
            base_color: o.base_color.to_array(),
            first_patch: surfaces.first_map(i),
            patch_count,
            mesh,
            material: object_material(scene, o),
            textures,
        });
        patches.extend(o.object_patches.iter().map(|p| Patch {
            control_points: p.cp.map(|c| c.to_array()),
        }));
    }
    StoreMeta {
        objects,
        patches,
        bake: BakeParams {
            epsilon: s.epsilon,
            phi_samplemap_deg: s.phi_samplemap_deg,
            cube_resolution: s.cube_resolution,
            sample_map_resolution: s.sample_map_resolution,
            samples_per_texel: strata_per_side(s.samples_per_texel).pow(2),
            bounces: s.bounces,
            seed: s.seed,
            encoding: s.encoding,
            distance_channel: s.distance_channel,
            zstd_level: s.zstd_level,
            scene_hash: scene.hash,
            mantissa_bits: s.mantissa_bits,
            sampling: Some(oslf_format::Sampling {
                target_noise: s.target_noise,
                denoised: s.denoise,
            }),
        },
        camera: scene.camera.as_ref().map(|c| CameraInfo {
            position: c.position.to_array(),
            target: c.target.to_array(),
            up: c.up.to_array(),
            vfov_deg: c.vfov_deg,
        }),
        has_env_cube: s.env_cube,
    }
}

/// Centre of the bounding box of all OSLF patches' control points and mesh vertices (world
/// space).
pub fn object_centre(scene: &Scene) -> Vec3 {
    let mut lo = Vec3::splat(f32::MAX);
    let mut hi = Vec3::splat(f32::MIN);
    for c in scene.objects.iter().flat_map(|o| o.points()) {
        lo = lo.min(c);
        hi = hi.max(c);
    }
    (lo + hi) * 0.5
}

/// What the store records of object `o`'s material: its model, factors and emission (a mesh
/// object's image textures go to its texture record, [`super::textures`]).
fn object_material(
    scene: &Scene,
    o: &oslf_scene::scene::OslfObject,
) -> oslf_format::ObjectMaterial {
    let Some(m) = scene.materials.get(o.material as usize) else {
        return Default::default();
    };
    let (model, metallic, roughness) = match m.model {
        oslf_scene::material::Model::Lambertian => {
            (oslf_format::meta::MATERIAL_LAMBERTIAN, 0.0, 0.0)
        }
        oslf_scene::material::Model::MetallicRoughness {
            metallic,
            roughness,
        } => (
            oslf_format::meta::MATERIAL_METALLIC_ROUGHNESS,
            metallic,
            roughness,
        ),
    };
    oslf_format::ObjectMaterial {
        model,
        metallic,
        roughness,
        emission: m.emission.to_array(),
    }
}
