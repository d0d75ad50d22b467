//! Triangle-mesh objects round-trip; damaged mesh records give typed errors
//! naming the offset, object, vertex or triangle, never a panic.

use crate::common;

use common::*;
use oslf_format::header::{Header, Section, HEADER_BYTES, HEADER_CHECKSUM_OFFSET};
use oslf_format::writer::partial_path;
use oslf_format::*;
use xxhash_rust::xxh3::xxh3_64;

fn spec() -> Spec {
    Spec {
        encoding: Encoding::Rgba16f,
        points: 6,
        distance: true,
        seed: 11,
        ..Spec::default()
    }
}

fn mesh_fixture() -> Fixture {
    with_mesh(fixture(spec()), spec())
}

fn mesh_store_bytes() -> Vec<u8> {
    let f = mesh_fixture();
    let (_dir, path) = temp_store("mesh.oslf");
    write(&path, &f);
    std::fs::read(&path).unwrap()
}

fn put_u32(b: &mut [u8], off: usize, v: u32) {
    b[off..off + 4].copy_from_slice(&v.to_le_bytes());
}
fn put_u64(b: &mut [u8], off: usize, v: u64) {
    b[off..off + 8].copy_from_slice(&v.to_le_bytes());
}

/// Recomputes the section checksums, the TOC trailer and the header checksum.
fn reseal_all(b: &mut [u8]) {
    let mut c = b[..HEADER_BYTES].to_vec();
    let sum = xxh3_64(&c[..HEADER_CHECKSUM_OFFSET]);
    put_u64(&mut c, HEADER_CHECKSUM_OFFSET, sum);
    let h = Header::parse(&c).unwrap();
    let sum = |s: Section, b: &[u8]| xxh3_64(&b[s.offset as usize..s.end() as usize]);
    let (m, p, s) = (sum(h.meta, b), sum(h.points, b), sum(h.maps, b));
    put_u64(b, 152, m);
    put_u64(b, 160, p);
    put_u64(b, 168, s);
    let toc_entries_end = (h.toc.end() - 8) as usize;
    let t = xxh3_64(&b[h.toc.offset as usize..toc_entries_end]);
    put_u64(b, toc_entries_end, t);
    let sum = xxh3_64(&b[..HEADER_CHECKSUM_OFFSET]);
    put_u64(b, HEADER_CHECKSUM_OFFSET, sum);
}

/// Byte offset of object `index`'s kind field, walking the object records.
fn kind_offset(b: &[u8], meta: &StoreMeta, index: usize) -> usize {
    let h = Header::parse(b).unwrap();
    // Counts, bake parameters, mantissa_bits, the sampling record (format 1.2), the camera.
    let mut off = h.meta.offset as usize + 8 + 80 + 4 + 8 + 44;
    for o in &meta.objects[..index] {
        off += 4 + o.name.len() + 64 + 12 + 8 + 4;
        if let Some(m) = &o.mesh {
            off += 12 + 32 * m.positions.len() + 12 * m.triangles.len();
        }
        off += MATERIAL_RECORD + TEXTURE_FLAGS;
    }
    off + 4 + meta.objects[index].name.len() + 64 + 12 + 8
}

/// Bytes of an object's material record.
const MATERIAL_RECORD: usize = 24;

/// Bytes of an untextured object's texture record: its flag word 0.
const TEXTURE_FLAGS: usize = 4;

/// Byte offset of object `index`'s material record.
fn material_offset(b: &[u8], meta: &StoreMeta, index: usize) -> usize {
    let mesh = meta.objects[index]
        .mesh
        .as_ref()
        .map_or(0, |m| 12 + 32 * m.positions.len() + 12 * m.triangles.len());
    kind_offset(b, meta, index) + 4 + mesh
}

/// The metadata error of store bytes `b` with `bytes` written at `at` (resealed).
fn metadata_error(b: &[u8], at: usize, bytes: &[u8]) -> (u64, String) {
    let mut c = b.to_vec();
    c[at..at + bytes.len()].copy_from_slice(bytes);
    reseal_all(&mut c);
    match Store::from_bytes(&c) {
        Err(Error::InvalidMetadata { offset, detail }) => (offset, detail),
        other => panic!("{:?}", other.err()),
    }
}

#[test]
fn object_materials_round_trip_and_damaged_ones_are_typed_errors() {
    let mut f = mesh_fixture();
    f.meta.objects[0].material = ObjectMaterial {
        model: meta::MATERIAL_METALLIC_ROUGHNESS,
        metallic: 0.5,
        roughness: 0.25,
        emission: [1.0, 0.0, 0.5],
    };
    f.meta.objects[2].material = ObjectMaterial {
        model: meta::MATERIAL_METALLIC_ROUGHNESS,
        metallic: 1.0,
        roughness: 0.0,
        emission: [0.0; 3],
    };
    let (_dir, path) = temp_store("materials.oslf");
    write(&path, &f);
    let store = Store::open(&path).unwrap();
    assert_eq!(store.meta(), &f.meta);
    let b = std::fs::read(&path).unwrap();
    for i in 0..f.meta.objects.len() {
        let m = material_offset(&b, &f.meta, i);
        let model = u32::from_le_bytes(b[m..m + 4].try_into().unwrap());
        assert_eq!(model, f.meta.objects[i].material.model, "object {i}");
    }
    let crafted = |at: usize, bytes: &[u8]| metadata_error(&b, at, bytes);
    let m0 = material_offset(&b, &f.meta, 0);
    let m1 = material_offset(&b, &f.meta, 1);
    let m2 = material_offset(&b, &f.meta, 2);
    for (what, at, bytes, offset, words) in [
        (
            "model 7",
            m0,
            7u32.to_le_bytes().to_vec(),
            m0,
            vec!["object 0", "unknown material model 7"],
        ),
        (
            "metallic 2",
            m2 + 4,
            2f32.to_le_bytes().to_vec(),
            m2,
            vec!["object 2", "must lie in [0, 1]"],
        ),
        (
            "Lambertian with roughness",
            m1 + 8,
            0.5f32.to_le_bytes().to_vec(),
            m1,
            vec!["object 1", "both must be 0"],
        ),
        (
            "negative emission",
            m0 + 16,
            (-1f32).to_le_bytes().to_vec(),
            m0,
            vec!["object 0", "negative"],
        ),
    ] {
        let (got, detail) = crafted(at, &bytes);
        assert_eq!(got, offset as u64, "{what}: {detail}");
        for w in words {
            assert!(detail.contains(w), "{what}: {detail}");
        }
    }
    // A NaN factor is refused where it stands.
    let (got, detail) = crafted(m0 + 8, &f32::NAN.to_le_bytes());
    assert_eq!(got, (m0 + 8) as u64, "{detail}");
    assert!(detail.contains("roughness"), "{detail}");
}

#[test]
fn a_store_with_bezier_and_mesh_objects_round_trips() {
    let f = mesh_fixture();
    let (_dir, path) = temp_store("mesh.oslf");
    write(&path, &f);
    let store = Store::open(&path).unwrap();
    let meta = store.meta();
    assert_eq!(meta, &f.meta);
    assert_eq!(meta.map_count(), 3 + 4);
    assert_eq!(store.header().patch_count, 7);
    assert_eq!(
        meta.patches.len(),
        3,
        "control points of Bézier patches only"
    );
    assert_eq!(meta.patches_of(0), &f.meta.patches[..1]);
    assert_eq!(meta.patches_of(1), &f.meta.patches[1..3]);
    assert!(meta.patches_of(2).is_empty());
    assert!(meta.patches_of(3).is_empty());
    assert_eq!(meta.objects[2].mesh.as_ref().unwrap(), &test_mesh());
    assert_eq!(store.sample_points(), &f.points[..]);
    let m2 = 9;
    for map in 0..7u32 {
        let view = store.sample_map(map).unwrap();
        for y in 0..3 {
            for x in 0..3 {
                let want = f.maps.indices[map as usize * m2 + (y * 3 + x) as usize];
                assert_eq!(view.get(x, y), Some(want), "map {map} texel ({x}, {y})");
            }
        }
    }
    assert!(store.sample_map(7).is_err());
    let r = store.verify().unwrap();
    assert_eq!(r.cubes as usize, f.cubes.len());
    // In memory too.
    let b = std::fs::read(&path).unwrap();
    assert_eq!(Store::from_bytes(&b).unwrap().meta(), &f.meta);
}

#[test]
fn a_mesh_store_resumes_byte_identical_and_names_a_changed_mesh() {
    let f = mesh_fixture();
    let (_dir, reference) = temp_store("ref.oslf");
    write(&reference, &f);
    let want = std::fs::read(&reference).unwrap();
    let (_dir2, path) = temp_store("r.oslf");
    let mut w = StoreWriter::create(&path, &f.meta, &f.points, &f.maps).unwrap();
    for (i, c) in f.cubes.iter().enumerate().take(5) {
        w.append(encode_cube(c, &f.meta.bake, i as u32).unwrap().0)
            .unwrap();
    }
    w.sync().unwrap();
    drop(w);
    // A bake whose mesh differs is refused, naming it.
    let mut other = f.meta.clone();
    other.objects[2].mesh.as_mut().unwrap().positions[4][2] = 0.25;
    let e = StoreWriter::resume(&path, &other, &f.points, &f.maps)
        .err()
        .unwrap();
    assert!(
        matches!(&e, Error::ResumeSettings { differences, .. } if differences.iter().any(|d| d.starts_with("the vertices or triangles of object 2"))),
        "{e}"
    );
    let mut other = f.meta.clone();
    other.objects[2].mesh.as_mut().unwrap().atlas_grid = 1;
    other.objects[2].patch_count = 1;
    assert!(StoreWriter::resume(&path, &other, &f.points, &f.maps).is_err());
    let mut w = StoreWriter::resume(&path, &f.meta, &f.points, &f.maps).unwrap();
    assert_eq!(w.next_cube(), 5);
    for i in 5..f.cubes.len() {
        w.append(encode_cube(&f.cubes[i], &f.meta.bake, i as u32).unwrap().0)
            .unwrap();
    }
    w.finish().unwrap();
    assert_eq!(std::fs::read(&path).unwrap(), want);
    assert!(!partial_path(&path).exists());
}

/// The writer refuses a mesh it could not read back.
#[test]
fn the_writer_validates_meshes() {
    let f = mesh_fixture();
    let (_dir, path) = temp_store("bad.oslf");
    let create = |meta: &StoreMeta| {
        StoreWriter::create(&path, meta, &f.points, &f.maps)
            .err()
            .expect("created")
    };
    let mut m = f.meta.clone();
    m.objects[2].mesh.as_mut().unwrap().normals[1] = [0.0, 0.0, 2.0];
    let e = create(&m);
    assert!(
        matches!(&e, Error::InvalidMetadata { detail, .. } if detail.contains("vertex 1 normal")),
        "{e}"
    );
    let mut m = f.meta.clone();
    m.objects[2].mesh.as_mut().unwrap().uvs.pop();
    assert!(matches!(create(&m), Error::InvalidMetadata { .. }));
    let mut m = f.meta.clone();
    m.objects[2].patch_count = 5;
    assert!(matches!(create(&m), Error::InvalidMetadata { .. }));
    // Control points for a mesh object are not stored: one too many is refused.
    let mut m = f.meta.clone();
    m.patches.push(m.patches[0].clone());
    assert!(matches!(create(&m), Error::InvalidMetadata { .. }));
}

#[test]
fn damaged_mesh_records_are_typed_errors() {
    let b = mesh_store_bytes();
    let f = mesh_fixture();
    let k = kind_offset(&b, &f.meta, 2);
    // The Bézier objects' kinds are 0.
    assert_eq!(b[kind_offset(&b, &f.meta, 0)..][..4], [0; 4]);
    assert_eq!(b[k..k + 4], 1u32.to_le_bytes());
    let (grid, vcount, tcount, verts) = (k + 4, k + 8, k + 12, k + 16);
    let v = 5;
    let tris = verts + 32 * v;
    let crafted = |f: &dyn Fn(&mut Vec<u8>)| -> (u64, String) {
        let mut c = b.clone();
        f(&mut c);
        reseal_all(&mut c);
        match Store::from_bytes(&c) {
            Err(Error::InvalidMetadata { offset, detail }) => (offset, detail),
            other => panic!("{:?}", other.err()),
        }
    };
    let check = |what: &str, e: (u64, String), offset: usize, words: &[&str]| {
        assert_eq!(e.0, offset as u64, "{what}: {}", e.1);
        for w in words {
            assert!(e.1.contains(w), "{what}: {:?} lacks {w:?}", e.1);
        }
    };
    check(
        "bad kind",
        crafted(&|c| put_u32(c, k, 2)),
        k,
        &["object 2", "kind 2"],
    );
    check(
        "grid 3 for 4 maps",
        crafted(&|c| put_u32(c, grid, 3)),
        grid,
        &["object 2", "atlas grid 3"],
    );
    check(
        "grid 0",
        crafted(&|c| put_u32(c, grid, 0)),
        grid,
        &["object 2", "atlas grid 0"],
    );
    check(
        "index out of range",
        crafted(&|c| put_u32(c, tris + 12 + 8, 5)),
        tris + 12,
        &["object 2", "triangle 1", "index 5"],
    );
    check(
        "non-finite position",
        crafted(&|c| put_u32(c, verts + 32 * 3 + 4, f32::NAN.to_bits())),
        verts + 32 * 3,
        &["object 2", "vertex 3", "non-finite"],
    );
    check(
        "infinite uv",
        crafted(&|c| put_u32(c, verts + 32 * 2 + 28, f32::INFINITY.to_bits())),
        verts + 32 * 2,
        &["object 2", "vertex 2", "non-finite"],
    );
    check(
        "non-unit normal",
        crafted(&|c| put_u32(c, verts + 32 + 20, 0.9f32.to_bits())),
        verts + 32 + 12,
        &["object 2", "vertex 1 normal", "not 1"],
    );
    check(
        "uv outside [0, 1]",
        crafted(&|c| put_u32(c, verts + 32 * 4 + 24, 1.5f32.to_bits())),
        verts + 32 * 4 + 24,
        &["object 2", "vertex 4 atlas uv"],
    );
    check(
        "negative uv",
        crafted(&|c| put_u32(c, verts + 32 * 4 + 28, (-0.01f32).to_bits())),
        verts + 32 * 4 + 24,
        &["object 2", "vertex 4 atlas uv"],
    );
    check(
        "too few vertices",
        crafted(&|c| put_u32(c, vcount, 2)),
        vcount,
        &["object 2", "at least 3 vertices"],
    );
    check(
        "no triangles",
        crafted(&|c| put_u32(c, tcount, 0)),
        vcount,
        &["object 2", "1 triangle"],
    );
    // Bytes after the counts: the vertices, triangles, the mesh object's material record
    // and texture records, and the 3 Bézier patches.
    let h = Header::parse(&b).unwrap();
    let left = h.meta.end() as usize - verts;
    assert_eq!(
        left,
        32 * v + 12 * 4 + MATERIAL_RECORD + TEXTURE_FLAGS + 3 * 192
    );
    let fit = ((left - 32 * v) / 12) as u32;
    for (what, at, n) in [
        ("huge vertex count", vcount, u32::MAX),
        ("huge triangle count", tcount, u32::MAX),
        ("vertex count past the section", vcount, 1000),
        ("triangle count one past the section", tcount, fit + 1),
    ] {
        check(
            what,
            crafted(&|c| put_u32(c, at, n)),
            vcount,
            &["object 2", "bytes but", "remain"],
        );
    }
    // Vertex and triangle counts that fit but misplace everything after: still typed.
    for n in [3u32, 4, 6] {
        crafted(&|c| put_u32(c, vcount, n));
    }
    for n in [1u32, 3, 5] {
        crafted(&|c| put_u32(c, tcount, n));
    }
    // A store whose objects do not tile the maps.
    let first = kind_offset(&b, &f.meta, 2) - 8;
    check(
        "gap before the mesh",
        crafted(&|c| put_u32(c, first, 4)),
        first,
        &["object 2", "map range 4..8"],
    );
}

/// Every byte of the mesh record, flipped, and every truncation of the metadata: an error or a
/// store, never a panic.
#[test]
fn every_damaged_mesh_byte_is_handled() {
    let b = mesh_store_bytes();
    let f = mesh_fixture();
    let k = kind_offset(&b, &f.meta, 2);
    let end = k + 16 + 32 * 5 + 12 * 4;
    for at in k..end {
        for x in [0x01u8, 0x80, 0xff] {
            let mut c = b.clone();
            c[at] ^= x;
            reseal_all(&mut c);
            let _ = Store::from_bytes(&c);
        }
    }
    let h = Header::parse(&b).unwrap();
    for cut in 1..=16u64 {
        let mut c = b.clone();
        put_u64(&mut c, 72, h.meta.size - cut);
        reseal_all(&mut c);
        assert!(Store::from_bytes(&c).is_err(), "metadata cut by {cut}");
    }
}

/// The mesh fixture's object 2 with every kind of texture: 2×1 base colour, 1×1 the others.
fn textured_fixture() -> Fixture {
    let mut f = mesh_fixture();
    let v = f.meta.objects[2].mesh.as_ref().unwrap().positions.len();
    let image = |w: u32, h: u32, seed: u8| TextureImage {
        width: w,
        height: h,
        texels: (0..w * h)
            .map(|i| [seed, i as u8 * 40, 255 - seed, 255])
            .collect(),
    };
    f.meta.objects[2].material = ObjectMaterial {
        model: meta::MATERIAL_METALLIC_ROUGHNESS,
        metallic: 1.0,
        roughness: 0.5,
        emission: [2.0, 1.0, 0.0],
    };
    f.meta.objects[2].textures = Some(ObjectTextures {
        texcoords: (0..v).map(|i| [i as f32 * 0.5, -1.25]).collect(),
        tangents: (0..v)
            .map(|i| [1.0, 0.0, 0.0, if i % 2 == 0 { 1.0 } else { -1.0 }])
            .collect(),
        normal_scale: 0.75,
        occlusion_strength: 0.5,
        images: TextureKind::ALL
            .into_iter()
            .enumerate()
            .map(|(k, kind)| (kind, image(2 - (k > 0) as u32, 1, 30 * k as u8)))
            .collect(),
    });
    f
}

#[test]
fn object_textures_round_trip_and_damaged_ones_are_typed_errors() {
    let f = textured_fixture();
    let (_dir, path) = temp_store("textures.oslf");
    write(&path, &f);
    let store = Store::open(&path).unwrap();
    assert_eq!(store.meta(), &f.meta);
    let b = std::fs::read(&path).unwrap();
    let flags_at = material_offset(&b, &f.meta, 2) + MATERIAL_RECORD;
    assert_eq!(
        u32::from_le_bytes(b[flags_at..flags_at + 4].try_into().unwrap()),
        0x1f
    );
    let v = f.meta.objects[2].mesh.as_ref().unwrap().positions.len();
    let tangents_at = flags_at + 12 + 8 * v;
    let first_image = tangents_at + 16 * v;
    let crafted = |at: usize, bytes: &[u8]| metadata_error(&b, at, bytes);
    let bezier_flags = material_offset(&b, &f.meta, 0) + MATERIAL_RECORD;
    for (what, at, bytes, offset, words) in [
        (
            "unknown flag",
            flags_at,
            0x3fu32.to_le_bytes().to_vec(),
            flags_at,
            vec!["object 2", "unknown bits"],
        ),
        (
            "Bézier textures",
            bezier_flags,
            1u32.to_le_bytes().to_vec(),
            bezier_flags,
            vec!["object 0", "Bézier"],
        ),
        (
            "occlusion strength 2",
            flags_at + 8,
            2f32.to_le_bytes().to_vec(),
            flags_at + 8,
            vec!["object 2", "occlusion strength 2"],
        ),
        (
            "texcoord NaN",
            flags_at + 12,
            f32::NAN.to_le_bytes().to_vec(),
            flags_at + 12,
            vec!["texture coordinate"],
        ),
        (
            "tangent w 0.5",
            tangents_at + 12,
            0.5f32.to_le_bytes().to_vec(),
            tangents_at,
            vec!["object 2", "vertex 0 tangent"],
        ),
        (
            "long tangent",
            tangents_at + 16,
            2f32.to_le_bytes().to_vec(),
            tangents_at + 16,
            vec!["vertex 1 tangent"],
        ),
        (
            "zero width",
            first_image,
            0u32.to_le_bytes().to_vec(),
            first_image,
            vec!["base colour texture of 0×1"],
        ),
        (
            "huge",
            first_image,
            16385u32.to_le_bytes().to_vec(),
            first_image,
            vec!["16385×1"],
        ),
        // 1×1 where the frame holds 2×1: the frame decompresses past the size asked for.
        (
            "short size",
            first_image,
            1u32.to_le_bytes().to_vec(),
            first_image + 12,
            vec!["base colour texture"],
        ),
    ] {
        let (got, detail) = crafted(at, &bytes);
        assert_eq!(got, offset as u64, "{what}: {detail}");
        for w in words {
            assert!(detail.contains(w), "{what}: {detail}");
        }
    }
    // A frame length past the section's end is refused, not read.
    let (_, detail) = crafted(first_image + 8, &u32::MAX.to_le_bytes());
    assert!(detail.contains("metadata"), "{detail}");
}

#[test]
fn writers_refuse_textures_that_do_not_fit_the_mesh() {
    let mut f = textured_fixture();
    f.meta.objects[2].textures.as_mut().unwrap().texcoords.pop();
    let (_dir, path) = temp_store("bad-textures.oslf");
    let e = StoreWriter::create(&path, &f.meta, &f.points, &f.maps)
        .err()
        .expect("refused");
    assert!(
        e.to_string()
            .contains("4 texture coordinates for 5 vertices"),
        "{e}"
    );
    let mut f = textured_fixture();
    f.meta.objects[0].textures = f.meta.objects[2].textures.clone();
    let e = StoreWriter::create(&path, &f.meta, &f.points, &f.maps)
        .err()
        .expect("refused");
    assert!(
        e.to_string()
            .contains("object 0: a Bézier object cannot hold textures"),
        "{e}"
    );
    assert!(!path.exists());
}
