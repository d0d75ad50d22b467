// The proxy's main-pass shaders (proxy.rs). The plugin's own pass shades the object, so in
// Bevy's main pass the proxy is neither rasterised nor written: every vertex goes to one
// point outside the clip volume, so each triangle is culled before rasterisation. Bevy's
// shadow passes use their default shaders.

@vertex
fn vertex() -> @builtin(position) vec4<f32> {
    return vec4<f32>(2.0, 2.0, 2.0, 1.0);
}

@fragment
fn fragment() -> @location(0) vec4<f32> {
    return vec4<f32>(0.0);
}
