//! Bytes per cube-map texel of a store's cube data, split into colour and distances: the
//! frames as stored, the texel part alone (filtered as the store filters it, without its
//! distance plane, and compressed at the store's zstd level), and the difference, the
//! distance planes' share. `cargo run --release -p oslf-format --example distance_sizes --
//! STORE...` (docs/measurements.md, "Compact distances").
use oslf_format::filter::{filter_face_quantized, filtered_face_size};
use oslf_format::{DistancePlane, Store};

fn main() {
    for path in std::env::args().skip(1) {
        let store = Store::open(std::path::Path::new(&path)).expect("open");
        let h = store.header();
        let bake = &store.meta().bake;
        let (enc, res) = (h.encoding, h.cube_resolution);
        let color_bytes = enc.face_bytes(res).expect("face size");
        let filtered = filtered_face_size(
            h.filter,
            enc,
            res,
            DistancePlane::Absent,
            bake.mantissa_bits,
        );
        let mut out = vec![0u8; filtered.expect("filtered size")];
        let mut raw = vec![0u8; store.face_raw_size()];
        let (mut total, mut color) = (0u64, 0u64);
        for cube in 0..store.cube_count() {
            for face in 0..6 {
                total += store.face_entry(cube, face).expect("entry").compressed_size;
                store.read_face_raw(cube, face, &mut raw).expect("face");
                let texels = &raw[..color_bytes];
                filter_face_quantized(
                    h.filter,
                    enc,
                    res,
                    DistancePlane::Absent,
                    bake.mantissa_bits,
                    texels,
                    &mut out,
                )
                .expect("filter");
                color += zstd::bulk::compress(&out, bake.zstd_level)
                    .expect("zstd")
                    .len() as u64;
            }
        }
        let texels = f64::from(store.cube_count()) * 6.0 * f64::from(res).powi(2);
        let file = store.file_size() as f64;
        println!(
            "{path}: {enc} {res}², distance {}: cube data {:.3} B/texel (colour {:.3}, distance {:.3}); whole file {:.3} B/texel ({} bytes, {} texels)",
            h.distance_plane(),
            total as f64 / texels,
            color as f64 / texels,
            (total - color) as f64 / texels,
            file / texels,
            store.file_size(),
            texels
        );
    }
}
