// The proxy's main-pass fragment shader (proxy.rs): its colour and depth writes are switched
// off, as the plugin's own pass shades the object; Bevy's shadow and prepass passes use their
// default shaders.

@fragment
fn fragment() -> @location(0) vec4<f32> {
    return vec4<f32>(0.0);
}
