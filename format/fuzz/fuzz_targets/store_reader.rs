//! Fuzzes the store parser: `Store::from_bytes`, then every read path on what it accepts.
#![no_main]

use libfuzzer_sys::fuzz_target;
use oslf_format::Store;

fuzz_target!(|data: &[u8]| {
    let Ok(store) = Store::from_bytes(data) else {
        return;
    };
    let _ = store.sample_points().len();
    let patches = store.meta().map_count() as u32;
    for patch in 0..patches.min(8) {
        if let Ok(map) = store.sample_map(patch) {
            let r = map.resolution();
            let _ = map.get(0, 0);
            let _ = map.get(r.saturating_sub(1), r.saturating_sub(1));
            let _ = map.get(r, 0);
        }
    }
    let _ = store.sample_map(patches);
    let texels = (store.cube_resolution() as usize).pow(2);
    if texels <= 1 << 16 {
        let mut rgb = vec![[0.0f32; 3]; texels];
        let mut dist = vec![0.0f32; texels];
        for cube in 0..store.cube_count().min(4) {
            for face in 0..6 {
                let _ = store.face_entry(cube, face);
                let _ = store.read_face(cube, face, &mut rgb, None);
                let _ = store.read_face(cube, face, &mut rgb, Some(&mut dist));
            }
        }
        let _ = store.read_face(store.cube_count(), 0, &mut rgb, None);
        let _ = store.verify();
    }
});
