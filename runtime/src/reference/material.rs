//! The CPU twin of gbuffer.wgsl's material functions (format docs, "Object textures"): a
//! textured object's material at texture coordinates, packed as the G-buffer's material
//! target holds it. Same functions, same order, same operations.

use glam::{Vec2, Vec3, Vec4};
use oslf_format::{ObjectTextures, TextureImage, TextureKind};
use oslf_shading::color::{linear_to_srgb, srgb_to_linear};

use crate::textures::BOUND_KINDS;

/// Texel `(x, y)` of `t` with repeat, its RGB decoded from sRGB when `srgb` (as `texel`).
fn texel(t: &TextureImage, x: i32, y: i32, srgb: bool) -> Vec3 {
    let (w, h) = (t.width as i32, t.height as i32);
    let p = (((x % w) + w) % w, ((y % h) + h) % h);
    let c = t.texels[(p.1 * w + p.0) as usize];
    let c = Vec3::new(c[0] as f32, c[1] as f32, c[2] as f32) / 255.0;
    if !srgb {
        return c;
    }
    Vec3::new(
        srgb_to_linear(c.x),
        srgb_to_linear(c.y),
        srgb_to_linear(c.z),
    )
}

/// Bilinear lookup at `uv` (v up), repeating (as `bilinear`).
pub fn bilinear(t: &TextureImage, uv: Vec2, srgb: bool) -> Vec3 {
    let size = Vec2::new(t.width as f32, t.height as f32);
    let u = uv.x - uv.x.floor();
    let v = uv.y - uv.y.floor();
    let x = u * size.x - 0.5;
    let y = (1.0 - v) * size.y - 0.5;
    let x0 = x.floor();
    let y0 = y.floor();
    let fx = (x - x0).clamp(0.0, 1.0);
    let fy = (y - y0).clamp(0.0, 1.0);
    let (ix, iy) = (x0 as i32, y0 as i32);
    let top = texel(t, ix, iy, srgb).lerp(texel(t, ix + 1, iy, srgb), fx);
    let bottom = texel(t, ix, iy + 1, srgb).lerp(texel(t, ix + 1, iy + 1, srgb), fx);
    top.lerp(bottom, fy)
}

/// WGSL's `pack2x16unorm`: each component clamped to [0, 1], times 65535, rounded to even.
pub fn pack2x16unorm(a: f32, b: f32) -> u32 {
    let q = |c: f32| (c.clamp(0.0, 1.0) * 65535.0).round_ties_even() as u32;
    q(a) | q(b) << 16
}

/// WGSL's `unpack2x16unorm`.
pub fn unpack2x16unorm(p: u32) -> Vec2 {
    Vec2::new((p & 0xffff) as f32, (p >> 16) as f32) / 65535.0
}

/// The material target's texel of an object with textures `t` at texture coordinates `uv`
/// (as `material_texel`; non-finite coordinates read at 0, as `fs_textured`).
pub fn material_texel(t: &ObjectTextures, uv: Vec2) -> [u32; 4] {
    let uv = if uv.x.abs() < 1e30 && uv.y.abs() < 1e30 {
        uv
    } else {
        Vec2::ZERO
    };
    let flags = BOUND_KINDS
        .iter()
        .enumerate()
        .filter(|(_, k)| t.image(**k).is_some())
        .fold(0u32, |f, (bit, _)| f | 1 << bit);
    let mut base = Vec3::ZERO;
    let mut mr = Vec3::ZERO;
    let mut glow = Vec3::ZERO;
    if let Some(img) = t.image(TextureKind::BaseColor) {
        base = bilinear(img, uv, true);
    }
    if let Some(img) = t.image(TextureKind::MetallicRoughness) {
        mr = bilinear(img, uv, false);
    }
    if let Some(img) = t.image(TextureKind::Emissive) {
        glow = bilinear(img, uv, true);
    }
    let mut occlusion = 1.0;
    if let Some(img) = t.image(TextureKind::Occlusion) {
        let ao = bilinear(img, uv, false).x.clamp(0.0, 1.0);
        occlusion = 1.0 + t.occlusion_strength * (ao - 1.0);
    }
    let code = glow
        .to_array()
        .map(|c| (linear_to_srgb(c) * 255.0).round_ties_even() as u32);
    [
        pack2x16unorm(base.x, base.y),
        pack2x16unorm(base.z, mr.z),
        pack2x16unorm(mr.y, occlusion),
        flags | code[0] << 8 | code[1] << 16 | code[2] << 24,
    ]
}

/// The shading normal with `t`'s normal texture at `uv`, from the interpolated unit normal `n`
/// and tangent `tangent` (as `mapped_normal`).
#[allow(clippy::neg_cmp_op_on_partial_ord)]
pub fn mapped_normal(t: &ObjectTextures, uv: Vec2, n: Vec3, tangent: Vec4) -> Vec3 {
    let Some(img) = t.image(TextureKind::Normal) else {
        return n;
    };
    let c = bilinear(img, uv, false) * 2.0 - Vec3::ONE;
    let t0 = tangent.truncate() - n * n.dot(tangent.truncate());
    let lt = t0.dot(t0);
    if !(lt > 1e-12) {
        return n;
    }
    let tn = t0 / lt.sqrt();
    let b = if tangent.w >= 0.0 { 1.0 } else { -1.0 } * n.cross(tn);
    let m = tn * (c.x * t.normal_scale) + b * (c.y * t.normal_scale) + n * c.z;
    let lm = m.dot(m);
    if !(lm > 1e-12) {
        return n;
    }
    m / lm.sqrt()
}
