// Viewer: draws the renderer's linear Rgba32Float image to the window, tone mapped (exposure,
// the ACES fit of Narkowicz 2015 as in oslf_bake::image_file, then sRGB unless the surface
// format encodes it). Bindings in the order of `view.rs`'s blit layout.

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

fn aces(x: f32) -> f32 {
    let v = min(max(x, 0.0), 1e6);
    return clamp((v * (2.51 * v + 0.03)) / (v * (2.43 * v + 0.59) + 0.14), 0.0, 1.0);
}

fn srgb(c: f32) -> f32 {
    if (c <= 0.0031308) { return 12.92 * c; }
    return 1.055 * pow(c, 1.0 / 2.4) - 0.055;
}

@fragment
fn fs(@builtin(position) p: vec4<f32>) -> @location(0) vec4<f32> {
    let size = textureDimensions(image);
    let px = min(vec2<u32>(p.xy), size - vec2<u32>(1u));
    let c = textureLoad(image, vec2<i32>(px), 0);
    var rgb = vec3<f32>(aces(c.r * B.exposure), aces(c.g * B.exposure), aces(c.b * B.exposure));
    if (B.encode_srgb == 1u) {
        rgb = vec3<f32>(srgb(rgb.r), srgb(rgb.g), srgb(rgb.b));
    }
    return vec4<f32>(rgb, 1.0);
}
