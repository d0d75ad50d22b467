// Background: what pixels off the object show.
// Its CPU twin: reference/background.rs.

import package::shade::bindings::{BACKGROUND, INVALID, P};
import package::shade::pixel::{finite3};
import package::shade::seams::{seamless_read};

// The unit direction of the camera ray through the centre of pixel `px`, as
// oslf_geometry::Camera::direction computes it; the viewing direction where that degenerates.
fn camera_ray(px: vec2<u32>) -> vec3<f32> {
    let w = f32(P.size.x);
    let h = f32(P.size.y);
    let aspect = w / h;
    let tan_half = P.cam_right.w;
    let sx = (2.0 * (f32(px.x) + 0.5) / w - 1.0) * aspect * tan_half;
    let sy = (1.0 - 2.0 * (f32(px.y) + 0.5) / h) * tan_half;
    let d = P.cam_forward.xyz + P.cam_right.xyz * sx + P.cam_up.xyz * sy;
    let l2 = dot(d, d);
    if (l2 > 0.0 && l2 <= 3.0e38) {
        return d * inverseSqrt(l2);
    }
    return P.cam_forward.xyz;
}

// What background pixel `px` shows, alpha 0. The environment cube is pinned resident, so it is
// read without a feedback mark: the cache statistics stay those of the object. It is filtered
// across face edges (`seamless_read`), so the background shows no seams.
fn background(px: vec2<u32>) -> vec4<f32> {
    if (BACKGROUND == 0u) {
        return vec4<f32>(0.0);
    }
    var c = P.bg_color.rgb;
    if (BACKGROUND == 1u) {
        c = vec3<f32>(0.0);
        if (P.env_cube != INVALID) {
            c = seamless_read(P.env_cube, camera_ray(px));
        }
    }
    return vec4<f32>(finite3(c), 0.0);
}
