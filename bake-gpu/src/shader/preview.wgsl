// The bake's preview (trace/src/preview.rs): its bindings and what its entry point (`preview`
// in capture.wgsl, the root module) needs: the scene camera's rays, their stratified samples
// and the random stream keyed by (seed, x, y) as on the CPU.

import package::layouts::{PreviewCamera};
import package::scene::{ONE_MINUS_EPSILON, safe_normalize};
import package::shading::random::{GOLDEN, Rng, add64, mix64, rng_vec2};

@group(0) @binding(12) var<uniform> camera: PreviewCamera;
@group(0) @binding(13) var<storage, read_write> pixels: array<vec4<f32>>;

// `hash_u64(&[a, b, c])`.
fn hash3(a: vec2<u32>, b: vec2<u32>, c: vec2<u32>) -> vec2<u32> {
    var h = mix64(GOLDEN ^ vec2<u32>(3u, 0u));
    h = mix64(h ^ mix64(add64(a, GOLDEN)));
    h = mix64(h ^ mix64(add64(b, GOLDEN)));
    h = mix64(h ^ mix64(add64(c, GOLDEN)));
    return h;
}

// `stratified_2d`: a jittered sample in stratum `i` of `n`.
fn stratified_2d(i_in: u32, n_in: u32, rng: ptr<function, Rng>) -> vec2<f32> {
    let n = max(n_in, 1u);
    let i = i_in % n;
    var kx = u32(sqrt(f32(n)));
    while kx * kx < n {
        kx += 1u;
    }
    while kx > 1u && (kx - 1u) * (kx - 1u) >= n {
        kx -= 1u;
    }
    let ky = (n + kx - 1u) / kx;
    let j = rng_vec2(rng);
    let x = (f32(i % kx) + j.x) / f32(kx);
    let y = (f32(i / kx) + j.y) / f32(ky);
    return vec2<f32>(min(x, ONE_MINUS_EPSILON), min(y, ONE_MINUS_EPSILON));
}

// `Camera::direction` of the pixel position (px, py).
fn camera_direction(px: f32, py: f32) -> vec3<f32> {
    let w = f32(max(camera.width, 1u));
    let h = f32(max(camera.height, 1u));
    let sx = (2.0 * px / w - 1.0) * (w / h) * camera.tan_half;
    let sy = (1.0 - 2.0 * py / h) * camera.tan_half;
    let d = safe_normalize(camera.forward + camera.right * sx + camera.up * sy);
    if all(d == vec3<f32>(0.0)) {
        return camera.forward;
    }
    return d;
}
