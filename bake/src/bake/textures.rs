//! A mesh object's material textures as the store holds them: the images
//! the bake itself shades the object with, and per store vertex their texture coordinates and,
//! with a normal texture, MikkTSpace tangents.

use glam::Vec3;
use oslf_format::{MeshInfo, ObjectTextures, TextureImage, TextureKind};

use oslf_scene::material::{Material, NormalTexture, OcclusionTexture};
use oslf_shading::color::linear_to_srgb;

use oslf_scene::texture::{ImageTexture, Texture};

/// The textures of a mesh object whose material has image textures, with its store mesh:
/// `atlas` (the atlas's mesh, whose triangle `i` is `source`'s triangle `i`) with each vertex
/// split where the triangles around it read different texture coordinates of `source`.
/// `None` (and the atlas mesh unchanged) for a material without images.
pub fn object_textures(
    material: &Material,
    atlas: MeshInfo,
    source: &oslf_geometry::Mesh,
) -> (MeshInfo, Option<ObjectTextures>) {
    let mut images = Vec::new();
    if let Texture::Image(img) = &material.albedo {
        images.push((TextureKind::BaseColor, quantize(img, true)));
    }
    if let Some(Texture::Image(img)) = &material.metallic_roughness_texture {
        images.push((TextureKind::MetallicRoughness, quantize(img, false)));
    }
    let mut normal_scale = 1.0;
    if let Some(NormalTexture {
        texture: Texture::Image(img),
        scale,
    }) = &material.normal_texture
    {
        images.push((TextureKind::Normal, quantize(img, false)));
        normal_scale = *scale;
    }
    let mut occlusion_strength = 1.0;
    if let Some(OcclusionTexture {
        texture: Texture::Image(img),
        strength,
    }) = &material.occlusion_texture
    {
        images.push((TextureKind::Occlusion, quantize(img, false)));
        occlusion_strength = *strength;
    }
    if let Some(Texture::Image(img)) = &material.emissive_texture {
        images.push((TextureKind::Emissive, quantize(img, true)));
    }
    if images.is_empty() || source.uvs.len() != source.positions.len() {
        return (atlas, None);
    }
    let has_normal = images.iter().any(|(k, _)| *k == TextureKind::Normal);
    let tangents = has_normal.then(|| oslf_geometry::tangents::corner_tangents(source));
    let (mesh, texcoords, tangents) = split_vertices(atlas, source, tangents.as_deref());
    let textures = ObjectTextures {
        texcoords,
        tangents,
        normal_scale,
        occlusion_strength,
        images,
    };
    (mesh, Some(textures))
}

/// `img` as RGBA8: sRGB-encoded (`srgb`) or linear, rounded to the nearest code; alpha 255.
/// An image the bake decoded from 8-bit texels with factor 1 comes back to its own codes.
fn quantize(img: &ImageTexture, srgb: bool) -> TextureImage {
    let code = |c: f32| {
        let c = if srgb { linear_to_srgb(c) } else { c };
        (c.clamp(0.0, 1.0) * 255.0).round() as u8
    };
    TextureImage {
        width: img.width,
        height: img.height,
        texels: img
            .pixels
            .iter()
            .map(|p: &Vec3| [code(p.x), code(p.y), code(p.z), 255])
            .collect(),
    }
}

/// The atlas mesh with one vertex per distinct (atlas vertex, texture coordinate, tangent)
/// triple, and those coordinates and tangents (empty without `tangents`, given per triangle
/// corner): corner `c` of triangle `i` reads `source`'s corner `c` of triangle `i`.
fn split_vertices(
    atlas: MeshInfo,
    source: &oslf_geometry::Mesh,
    tangents: Option<&[[glam::Vec4; 3]]>,
) -> (MeshInfo, Vec<[f32; 2]>, Vec<[f32; 4]>) {
    let mut index = std::collections::HashMap::new();
    let mut out = MeshInfo {
        atlas_grid: atlas.atlas_grid,
        positions: Vec::new(),
        normals: Vec::new(),
        uvs: Vec::new(),
        triangles: Vec::with_capacity(atlas.triangles.len()),
    };
    let (mut texcoords, mut out_tangents) = (Vec::new(), Vec::new());
    for (i, (t, src)) in atlas.triangles.iter().zip(&source.triangles).enumerate() {
        let tri = std::array::from_fn(|c| {
            let (a, s) = (t[c] as usize, src[c] as usize);
            let tc = source.uvs[s].to_array();
            let tangent = tangents.map(|t| t[i][c].to_array());
            let key = (
                a,
                tc.map(f32::to_bits),
                tangent.map(|t| t.map(f32::to_bits)),
            );
            *index.entry(key).or_insert_with(|| {
                out.positions.push(atlas.positions[a]);
                out.normals.push(atlas.normals[a]);
                out.uvs.push(atlas.uvs[a]);
                texcoords.push(tc);
                out_tangents.extend(tangent);
                (out.positions.len() - 1) as u32
            })
        });
        out.triangles.push(tri);
    }
    (out, texcoords, out_tangents)
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec2;

    #[test]
    fn vertices_split_where_texture_coordinates_differ_and_images_keep_their_codes() {
        // Two triangles sharing an atlas edge whose texture coordinates jump (a texture seam).
        let atlas = MeshInfo {
            atlas_grid: 1,
            positions: vec![[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [1.0, 1.0, 0.0]],
            normals: vec![[0.0, 0.0, 1.0]; 4],
            uvs: vec![[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [1.0, 1.0]],
            triangles: vec![[0, 1, 2], [1, 3, 2]],
        };
        let mut source = oslf_geometry::Mesh::new();
        source.positions = vec![Vec3::ZERO; 6];
        source.normals = vec![Vec3::Z; 6];
        source.uvs = [0.0, 0.1, 0.2, 0.5, 0.6, 0.7]
            .map(|u| Vec2::new(u, 0.0))
            .to_vec();
        source.triangles = vec![[0, 1, 2], [3, 4, 5]];
        let codes = [0u8, 1, 54, 128, 187, 255];
        let pixels = codes
            .iter()
            .map(|&b| Vec3::splat(oslf_shading::color::srgb_to_linear(f32::from(b) / 255.0)))
            .collect();
        let img = ImageTexture::from_pixels(3, 2, pixels).unwrap();
        let mut material = Material::lambertian(Vec3::ONE);
        material.albedo = Texture::Image(std::sync::Arc::new(img));
        let (mesh, textures) = object_textures(&material, atlas, &source);
        let t = textures.expect("an image albedo is stored");
        // Atlas vertices 1 and 2 are shared but read 0.1/0.5 and 0.2/0.7: six vertices.
        assert_eq!(mesh.positions.len(), 6);
        assert_eq!(t.texcoords.len(), 6);
        for (tri, src) in mesh.triangles.iter().zip(&source.triangles) {
            for c in 0..3 {
                assert_eq!(
                    t.texcoords[tri[c] as usize][0],
                    source.uvs[src[c] as usize].x
                );
            }
        }
        let image = t.image(TextureKind::BaseColor).unwrap();
        let got: Vec<u8> = image.texels.iter().map(|p| p[0]).collect();
        assert_eq!(got, codes);
        // A constant material stores nothing and keeps the atlas mesh.
        let plain = Material::lambertian(Vec3::ONE);
        let (_, none) = object_textures(&plain, mesh.clone(), &source);
        assert!(none.is_none());
    }
}
