// The twin of oslf-shading's fresnel.rs (fresnel_ + its names): Schlick's approximation.

// (1 − c)⁵, 1 − c clamped to [0, 1].
fn fresnel_schlick_weight(c: f32) -> f32 {
    let k = clamp(1.0 - c, 0.0, 1.0);
    let k2 = k * k;
    return k2 * k2 * k;
}

// f0 + (1 − f0)(1 − c)⁵ (Eq. 5.7).
fn fresnel_schlick(f0: f32, c: f32) -> f32 {
    return f0 + (1.0 - f0) * fresnel_schlick_weight(c);
}
