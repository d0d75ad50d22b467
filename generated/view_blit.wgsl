// Assembled by oslf_shading::wgsl::assemble from WGSL modules (root `package::view_blit`).
// Do not edit: edit the modules, then run this crate's tests with OSLF_BLESS=1 to write
// this file again.
fn srgb_to_linear(c: f32) -> f32 {
    if (c <= 0.04045) {
        return c / 12.92;
    }
    return pow((c + 0.055) / 1.055, 2.4);
}

fn linear_to_srgb(c: f32) -> f32 {
    let x = select(clamp(c, 0.0, 1.0), 0.0, c != c);
    if (x <= 0.0031308) {
        return 12.92 * x;
    }
    return 1.055 * pow(x, 1.0 / 2.4) - 0.055;
}

fn aces(x_in: f32) -> f32 {
    if (!(x_in > 0.0)) {
        return 0.0;
    }
    let x = min(x_in, 1000000.0);
    return clamp((x * (2.51 * x + 0.03)) / (x * (2.43 * x + 0.59) + 0.14), 0.0, 1.0);
}

fn luminance(c: vec3<f32>) -> f32 {
    return 0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z;
}

struct Blit {
    exposure: f32,
    encode_srgb: u32,
    _pad: vec2<u32>
}

@group(0) @binding(0)
var<uniform> B: Blit;

@group(0) @binding(1)
var image: texture_2d<f32>;

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
