// Viewer: draws the renderer's linear Rgba32Float image to the window, tone mapped as the PNG
// previews are (exposure, oslf-shading's `aces`, then `linear_to_srgb` unless the surface
// format encodes it). Bindings in the order of `view.rs`'s blit layout; view.rs puts
// oslf-shading's WGSL modules before this file.

import package::shading::color::{aces, linear_to_srgb};

struct Blit {
    exposure: f32,
    encode_srgb: u32,
    _pad: vec2<u32>,
};

@group(0) @binding(0) var<uniform> B: Blit;
@group(0) @binding(1) var image: texture_2d<f32>;

@vertex
fn vs(@builtin(vertex_index) i: u32) -> @builtin(position) vec4<f32> {
    let x = f32((i << 1u) & 2u);
    let y = f32(i & 2u);
    return vec4<f32>(x * 2.0 - 1.0, 1.0 - y * 2.0, 0.0, 1.0);
}

@fragment
fn fs(@builtin(position) p: vec4<f32>) -> @location(0) vec4<f32> {
    let size = textureDimensions(image);
    let px = min(vec2<u32>(p.xy), size - vec2<u32>(1u));
    let c = textureLoad(image, vec2<i32>(px), 0);
    var rgb = vec3<f32>(aces(c.r * B.exposure), aces(c.g * B.exposure), aces(c.b * B.exposure));
    if (B.encode_srgb == 1u) {
        rgb = vec3<f32>(linear_to_srgb(rgb.r), linear_to_srgb(rgb.g), linear_to_srgb(rgb.b));
    }
    return vec4<f32>(rgb, 1.0);
}
