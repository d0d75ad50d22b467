//! Temporary lab: compares candidate pre-zstd filters on a real store (RGBA32F reference).
use oslf_format::encoding::encode_texels;
use oslf_format::{Encoding, Store};

fn zz(v: i32) -> u32 {
    ((v << 1) ^ (v >> 31)) as u32
}

fn entropy(bytes: &[u8]) -> f64 {
    let mut h = [0u64; 256];
    for b in bytes {
        h[*b as usize] += 1;
    }
    let n = bytes.len() as f64;
    h.iter()
        .filter(|c| **c > 0)
        .map(|c| {
            let p = *c as f64 / n;
            -p * p.log2()
        })
        .sum::<f64>()
        * n
        / 8.0
}

/// Neighbour predictor over a plane of i64 values (n x n), given an accessor.
#[derive(Clone, Copy, Debug)]
enum Pred {
    None,
    Left,
    Up,
    Avg,
    Paeth,
    Med,
    Avg4,
    Grad,
}

fn predict(p: Pred, l: i64, u: i64, ul: i64, ur: i64) -> i64 {
    match p {
        Pred::None => 0,
        Pred::Left => l,
        Pred::Up => u,
        Pred::Avg => (l + u) >> 1,
        Pred::Paeth => {
            let pp = l + u - ul;
            let (pa, pb, pc) = ((pp - l).abs(), (pp - u).abs(), (pp - ul).abs());
            if pa <= pb && pa <= pc {
                l
            } else if pb <= pc {
                u
            } else {
                ul
            }
        }
        Pred::Med => {
            let (mn, mx) = (l.min(u), l.max(u));
            if ul >= mx {
                mn
            } else if ul <= mn {
                mx
            } else {
                l + u - ul
            }
        }
        Pred::Avg4 => (2 * l + 2 * u + ul + ur + 3) >> 3 << 0,
        Pred::Grad => l + u - ul,
    }
}

/// Neighbours with edge rules: row 0 uses left only, column 0 uses up.
fn neigh(v: &[i64], n: usize, x: usize, y: usize) -> Option<(i64, i64, i64, i64)> {
    let at = |x: usize, y: usize| v[y * n + x];
    match (x, y) {
        (0, 0) => None,
        (_, 0) => {
            let l = at(x - 1, 0);
            Some((l, l, l, l))
        }
        (0, _) => {
            let u = at(0, y - 1);
            let ur = if n > 1 { at(1, y - 1) } else { u };
            Some((u, u, u, ur))
        }
        _ => {
            let ur = if x + 1 < n {
                at(x + 1, y - 1)
            } else {
                at(x, y - 1)
            };
            Some((at(x - 1, y), at(x, y - 1), at(x - 1, y - 1), ur))
        }
    }
}

fn main() {
    let path = std::env::args().nth(1).expect("store path");
    let store = Store::open(std::path::Path::new(&path)).expect("open");
    let n = store.cube_resolution() as usize;
    let texels = n * n;
    let mut faces: Vec<Vec<[f32; 3]>> = Vec::new();
    for c in 0..store.cube_count() {
        let cube = store.read_cube(c).expect("cube");
        for f in cube.faces {
            faces.push(f);
        }
    }
    if std::env::var("DUMP").is_ok() {
        for f in 0..6 {
            println!("face {f}");
            dump(&store, 100, f);
        }
        return;
    }
    let total_texels = (faces.len() * texels) as f64;
    let mut comp = zstd::bulk::Compressor::new(3).unwrap();
    let mut report = |name: &str, planes_of: &dyn Fn(&[[f32; 3]]) -> Vec<u8>| {
        let (mut z, mut h) = (0usize, 0f64);
        for f in &faces {
            let b = planes_of(f);
            z += comp.compress(&b).unwrap().len();
            h += entropy(&b);
        }
        println!(
            "{name:40} zstd {:.3} B/texel   order0 {:.3}",
            z as f64 / total_texels,
            h / total_texels
        );
    };
    let enc = |e: Encoding, f: &[[f32; 3]]| {
        let mut out = vec![0u8; f.len() * e.bytes_per_texel()];
        encode_texels(e, f, &mut out).unwrap();
        out
    };
    for e in Encoding::ALL {
        report(&format!("{} raw", e.name()), &|f| enc(e, f));
        report(&format!("{} byte-shuffle", e.name()), &|f| {
            let b = enc(e, f);
            let w = e.bytes_per_texel();
            let mut o = Vec::with_capacity(b.len());
            for k in 0..w {
                o.extend(b.iter().skip(k).step_by(w));
            }
            o
        });
    }
    // Integer channel filters for RGBA16F / RGBA32F.
    for e in [Encoding::Rgba16f, Encoding::Rgba32f] {
        let w = e.bytes_per_texel() / 4;
        for sp in [Pred::None, Pred::Left, Pred::Avg, Pred::Med] {
            for chroma in [false, true] {
                let name = format!("{} int sp={sp:?} chroma={chroma}", e.name());
                report(&name, &|f| {
                    let b = enc(e, f);
                    let ch: [Vec<i64>; 4] = std::array::from_fn(|c| {
                        (0..texels)
                            .map(|i| {
                                let mut v = 0i64;
                                for k in 0..w {
                                    v |= (b[i * 4 * w + c * w + k] as i64) << (8 * k);
                                }
                                v
                            })
                            .collect()
                    });
                    let mask = (1i64 << (8 * w)) - 1;
                    let mut res: [Vec<u64>; 4] = Default::default();
                    for y in 0..n {
                        for x in 0..n {
                            let i = y * n + x;
                            let g = &ch[1];
                            let pg = neigh(g, n, x, y)
                                .map(|(l, u, ul, ur)| predict(sp, l, u, ul, ur))
                                .unwrap_or(0);
                            for c in 0..4 {
                                let p = if c == 1 || c == 3 || !chroma {
                                    neigh(&ch[c], n, x, y)
                                        .map(|(l, u, ul, ur)| predict(sp, l, u, ul, ur))
                                        .unwrap_or(0)
                                } else {
                                    let d: Vec<i64> =
                                        (0..texels).map(|j| ch[c][j] - g[j]).collect();
                                    let pd = neigh(&d, n, x, y)
                                        .map(|(l, u, ul, ur)| predict(Pred::Avg, l, u, ul, ur))
                                        .unwrap_or(0);
                                    g[i] + pd
                                };
                                let _ = pg;
                                let r = (ch[c][i] - p) & mask;
                                let half = 1i64 << (8 * w - 1);
                                let sr = if r >= half { r - 2 * half } else { r };
                                let z = ((sr << 1) ^ (sr >> 63)) as u64 & mask as u64;
                                res[c].push(z);
                            }
                        }
                    }
                    let mut o = Vec::new();
                    for c in [1, 0, 2, 3] {
                        for k in 0..w {
                            o.extend(res[c].iter().map(|v| (*v >> (8 * k)) as u8));
                        }
                    }
                    o
                });
            }
        }
    }
}

#[allow(dead_code)]
pub fn dump(store: &Store, cube: u32, face: usize) {
    let n = store.cube_resolution() as usize;
    let c = store.read_cube(cube).unwrap();
    for y in 0..n {
        let row: Vec<String> = (0..n)
            .map(|x| {
                let v = c.faces[face][y * n + x];
                format!("{:.3}", v[1])
            })
            .collect();
        println!("{}", row.join(" "));
    }
}
