// The twin of oslf-shading's color.rs: sRGB both ways, the ACES tone curve, luminance.

// The sRGB transfer function, encoded [0, 1] to linear.
fn srgb_to_linear(c: f32) -> f32 {
    if (c <= 0.04045) {
        return c / 12.92;
    }
    return pow((c + 0.055) / 1.055, 2.4);
}

// The inverse sRGB transfer function: clamped to [0, 1] first (NaN to 0 where the GPU keeps
// NaN through clamp), linear to encoded.
fn linear_to_srgb(c: f32) -> f32 {
    let x = select(clamp(c, 0.0, 1.0), 0.0, c != c);
    if (x <= 0.0031308) {
        return 12.92 * x;
    }
    return 1.055 * pow(x, 1.0 / 2.4) - 0.055;
}

// The ACES filmic tone curve (Narkowicz 2015 fit): NaN and negative values give 0.
fn aces(x_in: f32) -> f32 {
    if (!(x_in > 0.0)) {
        return 0.0;
    }
    let x = min(x_in, 1e6);
    return clamp((x * (2.51 * x + 0.03)) / (x * (2.43 * x + 0.59) + 0.14), 0.0, 1.0);
}

// Rec. 709 / sRGB luminance of linear RGB.
fn luminance(c: vec3<f32>) -> f32 {
    return 0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z;
}
