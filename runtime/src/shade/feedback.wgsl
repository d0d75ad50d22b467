// Feedback marks.
// Its CPU twin: reference/feedback.rs.

import package::shade::bindings::{P, feedback};

// The faces this invocation has read, gathered per cube (`mark_face`) and written to the
// feedback buffer once at its end (`flush_marks`) instead of one atomic per read: the four
// candidates' cubes (`mark_cube`, set after `candidates`) and the environment cube; any other
// cube is marked at once. The buffer ends the frame with the same bits either way. Why: one
// atomic per read contends on the few cubes every pixel reads.
var<private> mark_cube: vec4<u32>;
var<private> mark_bits: vec4<u32>;
var<private> mark_env: u32;

fn mark_face(cube: u32, bits: u32) {
    if (cube == mark_cube.x) {
        mark_bits.x |= bits;
    } else if (cube == mark_cube.y) {
        mark_bits.y |= bits;
    } else if (cube == mark_cube.z) {
        mark_bits.z |= bits;
    } else if (cube == mark_cube.w) {
        mark_bits.w |= bits;
    } else if (cube == P.env_cube) {
        mark_env |= bits;
    } else {
        atomicOr(&feedback[cube], bits);
    }
}

fn flush_marks() {
    for (var k = 0u; k < 4u; k++) {
        if (mark_bits[k] != 0u) {
            atomicOr(&feedback[mark_cube[k]], mark_bits[k]);
        }
    }
    if (mark_env != 0u) {
        atomicOr(&feedback[P.env_cube], mark_env);
    }
}
