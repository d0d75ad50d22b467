//! The GPU shader against the CPU reference, mode by mode, on lavapipe (or whatever adapter
//! the machine has: these tests fail, never skip, without one).

use crate::common;
use crate::common::knobs::Knobs;

use common::{compare, open_store};
use oslf_runtime::reference::StoreCubes;
use oslf_runtime::{
    Blend, CacheConfig, GlossyFilter, Gpu, Mode, Order, RenderOptions, Renderer, RuntimeError,
    Source,
};

const W: u32 = 96;
const H: u32 = 72;

/// [`common::check_parity`] at this file's frame size.
fn check(renderer: &mut Renderer, cubes: &StoreCubes, params: Knobs, label: &str) -> Vec<[f32; 4]> {
    common::check_parity(renderer, cubes, params, (W, H), label)
}

#[test]
fn every_mode_and_blend_matches_the_cpu_reference() {
    let store = open_store();
    let cubes = StoreCubes::decode(&store).unwrap();
    let mut r = Renderer::new(Gpu::headless().unwrap(), store, CacheConfig::default()).unwrap();
    let base = Knobs::default();
    let recon = check(
        &mut r,
        &cubes,
        Knobs {
            mode: Mode::Recon,
            ..base
        },
        "recon",
    );
    let mut mirrors = Vec::new();
    for blend in Blend::ALL {
        for n in [1.0, 4.0, 16.0] {
            if n != 4.0 && !matches!(blend, Blend::Reflection | Blend::Normal) {
                continue;
            }
            let p = Knobs {
                mode: Mode::Mirror,
                blend,
                blend_n: n,
                ..base
            };
            mirrors.push(check(
                &mut r,
                &cubes,
                p,
                &format!("mirror {} N={n}", blend.name()),
            ));
        }
    }
    // The blends are different functions: the images must differ.
    assert!(
        compare(&mirrors[0], &mirrors[1], 1e-3).1 < 0.9,
        "distance and angle blends coincide"
    );
    check(
        &mut r,
        &cubes,
        Knobs {
            mode: Mode::ReconMirror,
            ..base
        },
        "recon + C_s mirror",
    );
    let env = check(
        &mut r,
        &cubes,
        Knobs {
            mode: Mode::Mirror,
            source: Source::EnvMap,
            ..base
        },
        "mirror envmap",
    );
    assert!(
        compare(&env, &mirrors[0], 1e-3).1 < 0.9,
        "OSLF and environment map coincide"
    );
    for (p, label) in common::glossy_cases(base) {
        check(&mut r, &cubes, p, &label);
    }
    assert!(compare(&recon, &env, 1e-3).1 < 0.9);
}

/// Depth-corrected lookups, filtered importance sampling and the parallax-corrected baseline,
/// each on and off, against the CPU reference; each switch must change the image.
#[test]
fn depth_correction_filtering_and_parallax_match_the_cpu_reference() {
    let store = open_store();
    assert!(
        store.header().has_distance(),
        "the test store bakes distances"
    );
    // Distances on the distance lattice, which the GPU payload and the CPU reference both
    // read through FaceLayout.
    assert_eq!(
        store.header().distance_plane(),
        oslf_format::DistancePlane::Lattice { bits: 3 }
    );
    let cubes = StoreCubes::decode(&store).unwrap();
    let mut r = Renderer::new(Gpu::headless().unwrap(), store, CacheConfig::default()).unwrap();
    let base = Knobs {
        mode: Mode::Mirror,
        ..Default::default()
    };
    let depth = check(&mut r, &cubes, base, "mirror, depth-corrected");
    let plain = check(
        &mut r,
        &cubes,
        Knobs {
            depth: false,
            ..base
        },
        "mirror, plain",
    );
    assert!(
        compare(&depth, &plain, 1e-3).1 < 0.95,
        "depth correction changes nothing"
    );
    for blend in [
        Blend::Distance,
        Blend::Angle,
        Blend::Average,
        Blend::Reflection,
    ] {
        check(
            &mut r,
            &cubes,
            Knobs { blend, ..base },
            &format!("mirror {}, depth-corrected", blend.name()),
        );
    }
    let env = check(
        &mut r,
        &cubes,
        Knobs {
            source: Source::EnvMap,
            ..base
        },
        "mirror envmap",
    );
    let parallax = check(
        &mut r,
        &cubes,
        Knobs {
            source: Source::Parallax,
            ..base
        },
        "mirror parallax (fitted box)",
    );
    assert!(
        compare(&env, &parallax, 1e-3).1 < 0.9,
        "parallax correction changes nothing"
    );
    let given = r.proxy_box(&base.params()).expect("a fitted box");
    let shifted = [given[0], given[1].map(|v| v + 1.0)];
    check(
        &mut r,
        &cubes,
        Knobs {
            source: Source::Parallax,
            proxy_box: Some(shifted),
            ..base
        },
        "mirror parallax (given box)",
    );
    let glossy = |filter, order, depth, source| Knobs {
        mode: Mode::Glossy,
        glossy_filter: filter,
        order,
        depth,
        source,
        m: 8,
        nu: 20.0,
        nv: 20.0,
        ..Default::default()
    };
    let mip = check(
        &mut r,
        &cubes,
        glossy(GlossyFilter::Mip, Order::PerPoint, true, Source::Oslf),
        "glossy mip depth",
    );
    let point = check(
        &mut r,
        &cubes,
        glossy(GlossyFilter::Point, Order::PerPoint, true, Source::Oslf),
        "glossy point depth",
    );
    assert!(
        compare(&mip, &point, 1e-3).1 < 0.9,
        "filtering changes nothing"
    );
    for (filter, order, depth, source, label) in [
        (
            GlossyFilter::Mip,
            Order::PerDirection,
            true,
            Source::Oslf,
            "glossy mip per direction depth",
        ),
        (
            GlossyFilter::Point,
            Order::PerPoint,
            false,
            Source::Oslf,
            "glossy point plain",
        ),
        (
            GlossyFilter::Mip,
            Order::PerPoint,
            true,
            Source::EnvMap,
            "glossy mip envmap",
        ),
        (
            GlossyFilter::Mip,
            Order::PerPoint,
            true,
            Source::Parallax,
            "glossy mip parallax",
        ),
    ] {
        check(&mut r, &cubes, glossy(filter, order, depth, source), label);
    }
    // M = n²: the filtered grid's rows, where only each row's first sample runs the depth
    // iteration (the specular and, with R_d > 0, the diffuse samples).
    for (m, rd, label) in [
        (16, 0.0, "glossy mip depth, M = 16"),
        (9, 0.5, "glossy mip depth with diffuse, M = 9"),
    ] {
        check(
            &mut r,
            &cubes,
            Knobs {
                m,
                rd,
                ..glossy(GlossyFilter::Mip, Order::PerPoint, true, Source::Oslf)
            },
            label,
        );
    }
    // Per point visible: a sample a candidate cannot see read from a stand-in's cube (specular
    // and, with R_d > 0, diffuse samples). It must change pixels of this scene against per
    // point, so that the stand-ins themselves are what matches the reference.
    let knobs = |order| Knobs {
        m: 9,
        rd: 0.5,
        ..glossy(GlossyFilter::Mip, order, true, Source::Oslf)
    };
    let visible = check(
        &mut r,
        &cubes,
        knobs(Order::PerPointVisible),
        "glossy mip depth per point visible with diffuse, M = 9",
    );
    let point = check(
        &mut r,
        &cubes,
        knobs(Order::PerPoint),
        "glossy mip depth per point with diffuse, M = 9",
    );
    let (_, same, _) = compare(&visible, &point, 1e-4);
    assert!(
        same < 0.999,
        "per point visible changes {same} of the pixels"
    );
    // Per point searched: every sample read where its candidate's search meets the ray, a
    // hidden one where another's does; it must differ from per point visible too.
    let searched = check(
        &mut r,
        &cubes,
        knobs(Order::PerPointSearched),
        "glossy mip depth per point searched with diffuse, M = 9",
    );
    for (other, name) in [(&point, "per point"), (&visible, "per point visible")] {
        let (_, same, _) = compare(&searched, other, 1e-4);
        assert!(
            same < 0.999,
            "per point searched changes {same} of the pixels against {name}"
        );
    }
    // The pbr mode's filtered GGX samples: each candidate its own turn of the spiral
    // (`filter_xi`), with, below metallic 1, the diffuse samples' grid shared by all.
    for (metallic, label) in [
        (1.0, "pbr mip depth, metal, M = 16"),
        (0.5, "pbr mip depth, half metal, M = 16"),
    ] {
        check(
            &mut r,
            &cubes,
            Knobs {
                mode: Mode::Pbr,
                metallic,
                roughness: 0.6,
                m: 16,
                ..glossy(GlossyFilter::Mip, Order::PerPoint, true, Source::Oslf)
            },
            label,
        );
    }
}

/// On a store baked without distances, the orders that read them are a parameter error naming
/// the order, not per point's frame under their name; the others render.
#[test]
fn orders_that_read_distances_are_refused_on_a_store_without_them() {
    let store = oslf_format::Store::open(&common::store_path_without_distances()).unwrap();
    assert!(!store.header().has_distance());
    let mut r = Renderer::new(Gpu::headless().unwrap(), store, CacheConfig::default()).unwrap();
    let camera = r.default_view();
    let opts = RenderOptions {
        width: 32,
        height: 24,
        ..Default::default()
    };
    for order in Order::ALL {
        let params = Knobs {
            mode: Mode::Glossy,
            m: 4,
            order,
            ..Default::default()
        }
        .params();
        match r.render(&camera, &params, &opts) {
            Err(RuntimeError::Parameter(m)) if order.reads_distances() => {
                assert!(
                    m.contains(order.name()) && m.contains("distance channel"),
                    "{m}"
                )
            }
            Ok(frame) if !order.reads_distances() => {
                assert!(common::all_finite(&frame.pixels), "{order:?}")
            }
            other => panic!("{order:?}: {:?}", other.map(|_| ())),
        }
    }
}

#[test]
fn extreme_parameters_stay_finite_and_agree() {
    let store = open_store();
    let cubes = StoreCubes::decode(&store).unwrap();
    let mut r = Renderer::new(Gpu::headless().unwrap(), store, CacheConfig::default()).unwrap();
    let base = Knobs::default();
    for (label, p) in [
        (
            "B^r N=1e4",
            Knobs {
                mode: Mode::Mirror,
                blend: Blend::Reflection,
                blend_n: 1e4,
                ..base
            },
        ),
        (
            "B^n N=1e4",
            Knobs {
                mode: Mode::Mirror,
                blend: Blend::Normal,
                blend_n: 1e4,
                ..base
            },
        ),
        (
            "B^r N=0",
            Knobs {
                mode: Mode::Mirror,
                blend: Blend::Reflection,
                blend_n: 0.0,
                ..base
            },
        ),
        (
            "AS n=0",
            Knobs {
                mode: Mode::Glossy,
                nu: 0.0,
                nv: 0.0,
                m: 4,
                ..base
            },
        ),
        (
            "AS n_u=1e6 n_v=1",
            Knobs {
                mode: Mode::Glossy,
                nu: 1e6,
                nv: 1.0,
                m: 4,
                ..base
            },
        ),
        (
            "AS n=1e6 per direction",
            Knobs {
                mode: Mode::Glossy,
                nu: 1e6,
                nv: 1e6,
                m: 4,
                order: Order::PerDirection,
                ..base
            },
        ),
        (
            "pbr roughness 0",
            Knobs {
                mode: Mode::Pbr,
                metallic: 1.0,
                roughness: 0.0,
                m: 4,
                ..base
            },
        ),
        (
            "pbr roughness 1 dielectric per direction",
            Knobs {
                mode: Mode::Pbr,
                metallic: 0.0,
                roughness: 1.0,
                m: 4,
                order: Order::PerDirection,
                ..base
            },
        ),
        (
            "phi_shader=0",
            Knobs {
                mode: Mode::Recon,
                phi_shader_deg: 0.0,
                ..base
            },
        ),
    ] {
        check(&mut r, &cubes, p, label);
    }
}

#[test]
fn a_pool_spread_over_four_texture_arrays_renders_the_same() {
    let store = open_store();
    let cubes = StoreCubes::decode(&store).unwrap();
    let count = store.cube_count();
    let config = CacheConfig {
        slots_per_texture: Some(count.div_ceil(4)),
        ..Default::default()
    };
    let mut r = Renderer::new(Gpu::headless().unwrap(), store, config).unwrap();
    assert_eq!(r.cache().slots(), count);
    let base = Knobs::default();
    for mode in [Mode::ReconMirror, Mode::Glossy] {
        check(
            &mut r,
            &cubes,
            Knobs { mode, m: 4, ..base },
            &format!("{mode:?} over 4 arrays"),
        );
    }
}

/// The distance planes the GPU samples and the CPU reference reads are the store's decoded
/// distances as binary16, face by face, with and without BC6H on the adapter: the payload
/// FaceLayout builds for the GPU pool, the CPU reference's planes (StoreCubes, built from
/// the same payloads) and `depth_to_f16` of `Store::read_face`'s distances agree bit for bit,
/// and every distance read lies on the store's distance lattice. No GPU needed.
#[test]
fn distance_planes_reach_gpu_and_cpu_alike() {
    use oslf_runtime::face::{depth_to_f16, FaceLayout};
    use oslf_runtime::reference::CubeTexels;
    let store = open_store();
    let plane = store.header().distance_plane();
    let oslf_format::DistancePlane::Lattice { bits } = plane else {
        panic!("the test store bakes distances: {plane}");
    };
    let n = store.cube_resolution();
    let t = (n * n) as usize;
    let mut hits = 0;
    for has_bc in [true, false] {
        let layout = FaceLayout::for_store(&store, has_bc);
        let cubes = StoreCubes::decode_as(&store, layout).unwrap();
        let mut rgb = vec![[0f32; 3]; t];
        let mut d = vec![0f32; t];
        for cube in 0..store.cube_count() {
            for face in 0..6u8 {
                store
                    .read_face(cube, face as usize, &mut rgb, Some(&mut d))
                    .unwrap();
                let payload = layout.build(&store, cube, face).unwrap();
                let gpu = layout.decode_depth(&payload);
                for (i, v) in d.iter().enumerate() {
                    let want = depth_to_f16(*v).to_f32();
                    let (x, y) = (i as u32 % n, i as u32 / n);
                    assert_eq!(gpu[i].to_bits(), want.to_bits(), "cube {cube} face {face}");
                    let cpu = cubes.depth(cube, face as usize, x, y).unwrap();
                    assert_eq!(cpu.to_bits(), want.to_bits(), "cube {cube} face {face}");
                    assert_eq!(plane.quantize(*v), *v, "cube {cube} face {face} texel {i}");
                    hits += usize::from(*v != f32::MAX);
                }
            }
        }
    }
    assert!(hits > 0 && bits > 0);
}

/// The split-sum baseline of the pbr mode (the environment cube prefiltered per roughness)
/// against the CPU reference, plain and parallax-corrected, metallic and with a diffuse base;
/// roughness blurs it, and it asks for what it needs.
#[test]
fn the_split_sum_baseline_matches_the_cpu_reference() {
    let store = open_store();
    let cubes = StoreCubes::decode(&store).unwrap();
    let mut r = Renderer::new(Gpu::headless().unwrap(), store, CacheConfig::default()).unwrap();
    let base = Knobs {
        mode: Mode::Pbr,
        glossy_filter: GlossyFilter::SplitSum,
        source: Source::EnvMap,
        metallic: 1.0,
        object_material: false,
        ..Default::default()
    };
    let mut images = Vec::new();
    for source in [Source::EnvMap, Source::Parallax] {
        for (metallic, roughness) in [(1.0, 0.05), (1.0, 0.4), (1.0, 1.0), (0.3, 0.4)] {
            let p = Knobs {
                source,
                metallic,
                roughness,
                ..base
            };
            let label = format!(
                "split-sum {} metallic {metallic} roughness {roughness}",
                source.name()
            );
            images.push(check(&mut r, &cubes, p, &label));
        }
    }
    // Rougher is blurrier: the images differ by roughness and by source.
    assert!(
        compare(&images[0], &images[2], 1e-3).1 < 0.9,
        "roughness changes nothing"
    );
    assert!(
        compare(&images[1], &images[5], 1e-3).1 < 0.9,
        "parallax changes nothing"
    );
    // The Monte Carlo env baseline of the same lobe draws about the same mean.
    let mc = check(
        &mut r,
        &cubes,
        Knobs {
            glossy_filter: GlossyFilter::Mip,
            m: 64,
            roughness: 0.4,
            ..base
        },
        "pbr env Monte Carlo, roughness 0.4",
    );
    let mean = |img: &[[f32; 4]]| {
        let on: Vec<_> = img.iter().filter(|p| p[3] > 0.0).collect();
        on.iter().map(|p| p[0] + p[1] + p[2]).sum::<f32>() / on.len() as f32
    };
    let (a, b) = (mean(&images[1]), mean(&mc));
    assert!(
        (a / b - 1.0).abs() < 0.25,
        "split-sum mean {a}, Monte Carlo {b}"
    );
    // Only a baseline of the pbr mode, over a probe: `PbrIntegration::SplitSum` holds a
    // `Probe` and no other mode has it (the CLI's refusals: tests/cli_sources.rs).
    let p = base.params();
    assert!(p.split_sum() && p.source() == Source::EnvMap && p.monte_carlo().is_none());
}

/// The diffuse part read from the stored irradiance (format 1.1) against the CPU reference,
/// for the term 5.4 and glTF's diffuse base, per point and per direction, each beside the
/// sampled diffuse it replaces: the GPU and CPU agree, the two sources give different images,
/// and their means over the object agree within 3 % (measured: 0.1–1.0 %) (the sampled one at M = 64, the stored
/// one at M = 4: its diffuse needs no samples). Stored irradiance does not depend on M.
#[test]
fn the_stored_irradiance_matches_the_cpu_reference_and_the_sampled_diffuse() {
    use oslf_runtime::DiffuseSource;
    let store = open_store();
    assert!(
        store.irradiance().is_some(),
        "the fixture is a format 1.1 store"
    );
    let cubes = StoreCubes::decode(&store).unwrap();
    let mut r = Renderer::new(Gpu::headless().unwrap(), store, CacheConfig::default()).unwrap();
    let glossy = Knobs {
        mode: Mode::Glossy,
        rs: 0.3,
        rd: 0.7,
        nu: 20.0,
        nv: 20.0,
        ..Knobs::default()
    };
    let pbr = Knobs {
        mode: Mode::Pbr,
        metallic: 0.0,
        roughness: 0.5,
        object_material: false,
        ..Knobs::default()
    };
    for (base, label) in [
        (glossy, "glossy, R_d 0.7"),
        (
            Knobs {
                order: Order::PerDirection,
                ..glossy
            },
            "glossy per direction, R_d 0.7",
        ),
        (pbr, "pbr, dielectric"),
        (
            Knobs {
                source: Source::EnvMap,
                ..pbr
            },
            "pbr envmap, dielectric",
        ),
    ] {
        let stored = check(
            &mut r,
            &cubes,
            Knobs {
                m: 4,
                diffuse: DiffuseSource::Irradiance,
                ..base
            },
            &format!("{label}, stored irradiance"),
        );
        let stored_16 = check(
            &mut r,
            &cubes,
            Knobs {
                m: 16,
                diffuse: DiffuseSource::Irradiance,
                ..base
            },
            &format!("{label}, stored irradiance, M = 16"),
        );
        let sampled = check(
            &mut r,
            &cubes,
            Knobs {
                m: 64,
                diffuse: DiffuseSource::Samples,
                ..base
            },
            &format!("{label}, sampled diffuse"),
        );
        assert!(
            compare(&stored, &sampled, 1e-3).1 < 0.9,
            "{label}: the sources coincide"
        );
        let (a, b) = (common::mean(&stored_16), common::mean(&sampled));
        println!("{label}: mean {a:.4} stored, {b:.4} sampled");
        assert!(
            (a - b).abs() < 0.03 * b,
            "{label}: mean {a} stored, {b} sampled"
        );
    }
}
