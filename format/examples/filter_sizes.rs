//! Bytes per texel of the cubes of a store re-encoded in each encoding, with and without the
//! face filter (zstd at the store's level). Bake losslessly (RGBA32F) first, then
//! `cargo run --release -p oslf-format --example filter_sizes -- store.oslf`.
use oslf_format::{encode_cube_with_filter, Encoding, Filter, Store};

fn main() {
    let path = std::env::args().nth(1).expect("store path");
    let store = Store::open(std::path::Path::new(&path)).expect("open");
    let cubes: Vec<_> = (0..store.cube_count())
        .map(|c| store.read_cube(c).expect("cube"))
        .collect();
    let texels = cubes.len() as f64 * 6.0 * f64::from(store.cube_resolution()).powi(2);
    println!("{path}: spp {}", store.meta().bake.samples_per_texel);
    for enc in Encoding::ALL {
        let mut params = store.meta().bake.clone();
        params.encoding = enc;
        let mut line = format!("  {:8}", enc.name());
        for filter in Filter::ALL {
            let mut bytes = 0u64;
            for (i, c) in cubes.iter().enumerate() {
                bytes += encode_cube_with_filter(c, &params, i as u32, filter)
                    .expect("encode")
                    .1
                    .compressed_bytes;
            }
            line += &format!("  {}: {:.3}", filter.name(), bytes as f64 / texels);
        }
        println!("{line}");
    }
}
