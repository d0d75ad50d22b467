//! shader/capture.wgsl's structs are the Rust structs that fill them (field by field: name,
//! order, offset, size, type), and the constants both sides use are equal. A change to either
//! side alone fails here.

use std::mem::size_of;

use oslf_bake_gpu::capture::{Job, Params, TexelOut, TraceHit, TraceRay};
use oslf_bake_gpu::scene::{GpuLight, Mat, Node, Tex, Tri, TriAttr};
use oslf_runtime::wgsl_fields as fields;
use oslf_runtime::wgsl_layout::{check_struct, constant_value, parse};

#[test]
fn the_shader_structs_are_the_rust_structs() {
    let module = parse("capture shader", oslf_bake_gpu::shader::source());
    let check = |name: &str, fields: Vec<oslf_runtime::wgsl_layout::Field>, size: usize| {
        check_struct(&module, name, &fields, size, false)
    };
    check(
        "Params",
        fields!(Params {
            resolution,
            strata,
            max_bounces,
            flags,
            seed,
            texels,
            row_invocations,
            first,
            _pad1,
            _pad0,
            env_size,
            env_tables,
            env_rotation,
            env_constant,
            perez_y,
            perez_x,
            perez_yc,
            perez_e,
            norm,
            model_sun,
            ground,
            rounds,
            target_noise,
            _pad2,
        }),
        size_of::<Params>(),
    );
    check(
        "Node",
        fields!(Node {
            p,
            e_imask,
            child_base,
            primitive_base,
            child_meta,
            x,
            y,
            z
        }),
        size_of::<Node>(),
    );
    check("Tri", fields!(Tri { v0, v1, v2, plane }), size_of::<Tri>());
    check(
        "TriAttr",
        fields!(TriAttr {
            n0,
            material,
            n1,
            object,
            n2,
            global,
            gn,
            _pad0,
            uv01,
            uv2,
            _pad1
        }),
        size_of::<TriAttr>(),
    );
    check(
        "Tex",
        fields!(Tex {
            kind,
            width,
            height,
            offset,
            a,
            scale,
            b,
            _pad
        }),
        size_of::<Tex>(),
    );
    check(
        "Light",
        fields!(GpuLight {
            position,
            kind,
            direction,
            inner,
            power,
            outer,
            angular_radius,
            _pad0,
            _pad1,
            _pad2,
        }),
        size_of::<GpuLight>(),
    );
    check(
        "Job",
        fields!(Job {
            origin,
            index,
            sees_objects,
            _pad
        }),
        size_of::<Job>(),
    );
    check(
        "TexelOut",
        fields!(TexelOut {
            radiance,
            distance,
            lum_sum,
            lum_sq,
            closest,
            shadow_hit,
            nodes,
            tris,
            samples,
            _pad
        }),
        size_of::<TexelOut>(),
    );
    check(
        "TraceRay",
        fields!(TraceRay {
            origin,
            t_max,
            dir,
            flags
        }),
        size_of::<TraceRay>(),
    );
    check(
        "PreviewCamera",
        fields!(oslf_bake_gpu::preview::PreviewCamera {
            position,
            width,
            right,
            height,
            up,
            tan_half,
            forward,
            spp,
        }),
        size_of::<oslf_bake_gpu::preview::PreviewCamera>(),
    );
    check(
        "TraceHit",
        fields!(TraceHit {
            t,
            triangle,
            b1,
            b2,
            nodes,
            tris,
            _pad
        }),
        size_of::<TraceHit>(),
    );
    check(
        "Mat",
        fields!(Mat {
            albedo,
            mr_texture,
            model,
            metallic,
            roughness,
            _pad,
            emission,
            has_mr_texture,
        }),
        size_of::<Mat>(),
    );
}

/// The GPU's node is obvhs's `CwBvhNode`, field by field.
#[test]
fn a_gpu_node_is_the_cpus_cwbvh_node() {
    use obvhs::cwbvh::node::CwBvhNode;
    let bytes = |k: u8| std::array::from_fn::<u8, 8, _>(|i| k + i as u8);
    let cpu = CwBvhNode {
        p: glam::Vec3::new(1.5, -2.0, 3.25),
        e: [120, 121, 122],
        imask: 0b1010_0101,
        child_base_idx: 77,
        primitive_base_idx: 99,
        child_meta: bytes(10),
        child_min_x: bytes(20),
        child_max_x: bytes(30),
        child_min_y: bytes(40),
        child_max_y: bytes(50),
        child_min_z: bytes(60),
        child_max_z: bytes(70),
    };
    let gpu = Node::from(&cpu);
    let word =
        |b: [u8; 8], half: usize| u32::from_le_bytes(b[4 * half..4 * half + 4].try_into().unwrap());
    let planes = |lo: [u8; 8], hi: [u8; 8]| [word(lo, 0), word(lo, 1), word(hi, 0), word(hi, 1)];
    assert_eq!(gpu.p, [1.5, -2.0, 3.25]);
    assert_eq!(gpu.e_imask, 120 | 121 << 8 | 122 << 16 | 0b1010_0101 << 24);
    assert_eq!((gpu.child_base, gpu.primitive_base), (77, 99));
    assert_eq!(
        gpu.child_meta,
        [word(cpu.child_meta, 0), word(cpu.child_meta, 1)]
    );
    assert_eq!(gpu.x, planes(cpu.child_min_x, cpu.child_max_x));
    assert_eq!(gpu.y, planes(cpu.child_min_y, cpu.child_max_y));
    assert_eq!(gpu.z, planes(cpu.child_min_z, cpu.child_max_z));
}

#[test]
fn the_shader_constants_are_the_crates() {
    let module = parse("capture shader", oslf_bake_gpu::shader::source());
    let value = |name: &str| {
        let (_, c) = module
            .constants
            .iter()
            .find(|(_, c)| c.name.as_deref() == Some(name))
            .unwrap_or_else(|| panic!("no constant {name}"));
        constant_value(&module, c).unwrap_or_else(|| panic!("{name} is no literal"))
    };
    assert_eq!(
        value("OFFSET_RELATIVE"),
        f64::from(oslf_trace::integrator::OFFSET_RELATIVE)
    );
    assert_eq!(
        value("SELF_TOLERANCE"),
        f64::from(oslf_trace::bvh::SELF_TOLERANCE)
    );
    assert_eq!(value("STACK") as usize, oslf_trace::bvh::MAX_BVH_DEPTH);
    assert_eq!(value("SLAB_PAD"), f64::from(oslf_trace::bvh::SLAB_PAD));
    assert_eq!(
        value("ONE_MINUS_EPSILON"),
        f64::from(oslf_shading::random::ONE_MINUS_EPSILON)
    );
    // The workgroup size is an override (chosen per adapter), its default the GPU's.
    let workgroup = module
        .overrides
        .iter()
        .find(|(_, o)| o.name.as_deref() == Some("WORKGROUP"))
        .and_then(|(_, o)| o.init)
        .map(|init| &module.global_expressions[init]);
    assert!(
        matches!(
            workgroup,
            Some(wgpu::naga::Expression::Literal(wgpu::naga::Literal::U32(n)))
                if *n == oslf_bake_gpu::capture::WORKGROUP
        ),
        "{workgroup:?}"
    );
    assert_eq!(value("F32_MAX"), f64::from(f32::MAX));
    use oslf_bake_gpu::scene as packed;
    for (name, v) in [
        ("TEX_CONSTANT", packed::TEX_CONSTANT),
        ("TEX_CHECKER", packed::TEX_CHECKER),
        ("TEX_IMAGE", packed::TEX_IMAGE),
        ("MODEL_LAMBERTIAN", packed::MODEL_LAMBERTIAN),
        ("MODEL_METALLIC_ROUGHNESS", packed::MODEL_METALLIC_ROUGHNESS),
        ("LIGHT_POINT", packed::LIGHT_POINT),
        ("LIGHT_SPOT", packed::LIGHT_SPOT),
        ("LIGHT_SUN", packed::LIGHT_SUN),
        ("ENV_CONSTANT", packed::ENV_CONSTANT),
        ("ENV_LAT_LONG", packed::ENV_LAT_LONG),
        ("ENV_SKY", packed::ENV_SKY),
        ("FLAG_DISTANCE", oslf_bake_gpu::capture::FLAG_DISTANCE),
    ] {
        assert_eq!(value(name) as u32, v, "{name}");
    }
}

/// The overrides the shader is specialized on are those the host sets, no more and no fewer.
#[test]
fn the_shader_overrides_are_the_scene_features() {
    let module = parse("capture shader", oslf_bake_gpu::shader::source());
    let mut declared: Vec<&str> = module
        .overrides
        .iter()
        .filter_map(|(_, o)| o.name.as_deref())
        .filter(|n| *n != "WORKGROUP")
        .collect();
    let features = oslf_bake_gpu::features::SceneFeatures::of(&Default::default()).unwrap();
    let mut set: Vec<&str> = features.constants().iter().map(|c| c.0).collect();
    declared.sort_unstable();
    set.sort_unstable();
    assert_eq!(declared, set);
}

/// The embedded shader is what its modules assemble to (`OSLF_BLESS=1` writes it).
#[test]
fn the_embedded_shader_is_its_modules_assembled() {
    let file = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("generated/capture.wgsl");
    oslf_shading::wgsl::check_assembled(
        &file,
        oslf_bake_gpu::shader::ROOT,
        &oslf_bake_gpu::shader::modules(),
    )
    .unwrap_or_else(|e| panic!("{e}"));
}
