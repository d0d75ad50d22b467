//! The runtime and the bake read an object's textures alike (format docs, "Object textures"):
//! from the same 8-bit texels, the runtime's CPU twin of its G-buffer (`material_texel`,
//! `mapped_normal`) and the bake's `Material` (which the truth shades the object with) give the
//! same base colour, metallic, roughness, occlusion, normal and emission on a table of texture
//! coordinates,
//! normals and tangents, repeating past [0, 1].

use std::sync::Arc;

use glam::{Vec2, Vec3, Vec4};
use oslf_format::{ObjectTextures, TextureImage, TextureKind};
use oslf_runtime::reference::material::{mapped_normal, material_texel, unpack2x16unorm};
use oslf_scene::material::{Material, Model, NormalTexture, OcclusionTexture};
use oslf_scene::texture::{ImageTexture, Texture};
use oslf_shading::color::srgb_to_linear;

/// A `w`×`h` image of codes `f(i)`.
fn codes(w: u32, h: u32, f: impl Fn(u32) -> [u8; 3]) -> Vec<[u8; 3]> {
    (0..w * h).map(f).collect()
}

/// The bake's linear image of `codes`: sRGB-decoded for colours, `c/255` for data.
fn bake_image(w: u32, h: u32, codes: &[[u8; 3]], srgb: bool) -> Texture {
    let decode = |c: u8| {
        let c = f32::from(c) / 255.0;
        if srgb {
            srgb_to_linear(c)
        } else {
            c
        }
    };
    let pixels = codes
        .iter()
        .map(|c| Vec3::from_array(c.map(decode)))
        .collect();
    Texture::Image(Arc::new(ImageTexture::from_pixels(w, h, pixels).unwrap()))
}

fn store_image(w: u32, h: u32, codes: &[[u8; 3]]) -> TextureImage {
    TextureImage {
        width: w,
        height: h,
        texels: codes.iter().map(|c| [c[0], c[1], c[2], 255]).collect(),
    }
}

#[test]
fn the_runtime_and_the_bake_read_textures_alike() {
    let base = codes(5, 3, |i| {
        [
            (i * 53 % 256) as u8,
            (i * 97 % 256) as u8,
            (255 - i * 17) as u8,
        ]
    });
    let mr = codes(3, 2, |i| [0, (25 + i * 40) as u8, (i * 51) as u8]);
    let normal = codes(2, 2, |i| {
        [
            [160, 128, 240],
            [100, 150, 230],
            [128, 128, 255],
            [30, 220, 140],
        ][i as usize]
    });
    let glow = codes(3, 3, |i| [(i * 80 % 256) as u8, 200, (40 + i * 20) as u8]);
    let occlusion = codes(4, 3, |i| [(30 + i * 19) as u8, 7, 250]);
    let (scale, strength) = (0.8, 0.7);
    let bake = Material {
        albedo: bake_image(5, 3, &base, true),
        model: Model::MetallicRoughness {
            metallic: 1.0,
            roughness: 1.0,
        },
        emission: Vec3::ONE,
        metallic_roughness_texture: Some(bake_image(3, 2, &mr, false)),
        normal_texture: Some(NormalTexture {
            texture: bake_image(2, 2, &normal, false),
            scale,
        }),
        emissive_texture: Some(bake_image(3, 3, &glow, true)),
        occlusion_texture: Some(OcclusionTexture {
            texture: bake_image(4, 3, &occlusion, false),
            strength,
        }),
    };
    let store = ObjectTextures {
        texcoords: Vec::new(),
        tangents: Vec::new(),
        normal_scale: scale,
        occlusion_strength: strength,
        images: vec![
            (TextureKind::BaseColor, store_image(5, 3, &base)),
            (TextureKind::MetallicRoughness, store_image(3, 2, &mr)),
            (TextureKind::Normal, store_image(2, 2, &normal)),
            (TextureKind::Occlusion, store_image(4, 3, &occlusion)),
            (TextureKind::Emissive, store_image(3, 3, &glow)),
        ],
    };
    let (mut worst, mut darkest) = ((0f32, 0f32, 0f32), 1f32);
    for k in 0..400 {
        let f = k as f32;
        let uv = Vec2::new((f * 0.137).sin() * 2.3, (f * 0.071).cos() * 1.7 + 0.4);
        let n = Vec3::new((f * 0.3).sin(), (f * 0.5).cos(), 1.2).normalize();
        let t = Vec4::new(
            (f * 0.2).cos(),
            0.4,
            (f * 0.7).sin(),
            if k % 3 == 0 { -1.0 } else { 1.0 },
        );
        let texel = material_texel(&store, uv);
        let rg = unpack2x16unorm(texel[0]);
        let bm = unpack2x16unorm(texel[1]);
        let ro = unpack2x16unorm(texel[2]);
        let want = bake.metallic_roughness(uv).unwrap();
        let got_base = Vec3::new(rg.x, rg.y, bm.x);
        worst.0 = worst
            .0
            .max((got_base - want.base_color).abs().max_element());
        worst.0 = worst.0.max(
            (bm.y - want.metallic)
                .abs()
                .max((ro.x - want.roughness).abs())
                .max((ro.y - bake.occlusion_at(uv)).abs()),
        );
        darkest = darkest.min(ro.y);
        // The emissive texture, kept to 8-bit sRGB codes in the G-buffer (w above the flags).
        let code = |shift: u32| srgb_to_linear(((texel[3] >> shift) & 0xff) as f32 / 255.0);
        let got_glow = Vec3::new(code(8), code(16), code(24));
        worst.2 = worst
            .2
            .max((got_glow - bake.emission_at(uv)).abs().max_element());
        let got_n = mapped_normal(&store, uv, n, t);
        let want_n = bake.mapped_normal(uv, n, t);
        worst.1 = worst.1.max((got_n - want_n).length());
        assert!((got_n.length() - 1.0).abs() < 1e-5);
    }
    println!(
        "largest difference: material {:.2e}, normal {:.2e}, emission {:.2e}",
        worst.0, worst.1, worst.2
    );
    // The occlusion texture darkens: codes 30..239 at strength 0.7 reach below 0.5.
    assert!(darkest < 0.5, "occlusion never below {darkest}");
    // The G-buffer keeps 16 bits per value (1.5e-5); the normals are the same arithmetic.
    assert!(worst.0 < 2e-5, "material differs by {}", worst.0);
    assert!(worst.1 < 1e-5, "normals differ by {}", worst.1);
    // Emission keeps 8-bit sRGB codes: half a code step, at most 1/255 of the range.
    assert!(worst.2 < 4e-3, "emission differs by {}", worst.2);
}
