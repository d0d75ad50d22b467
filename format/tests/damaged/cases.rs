//! Damaged and crafted files: each gives the right typed error, never a panic. Shared by the
//! three readers' test targets (damaged.rs: in memory, damaged_positioned.rs: `Store::open`,
//! damaged_mapped.rs: `Store::open_mapped`), each of which defines `open`.

use super::common::*;
use super::open;
use oslf_format::header::{Header, HEADER_BYTES, HEADER_CHECKSUM_OFFSET};
use oslf_format::*;
use proptest::prelude::*;
use xxhash_rust::xxh3::xxh3_64;

fn good() -> Vec<u8> {
    store_bytes(Spec {
        encoding: Encoding::Rgba16f,
        cube_res: 4,
        map_res: 3,
        points: 6,
        patches: 3,
        distance: true,
        env: true,
        seed: 11,
        mantissa_bits: 9,
    })
}

fn header(bytes: &[u8]) -> Header {
    Header::parse(bytes).unwrap()
}

fn put_u64(b: &mut [u8], off: usize, v: u64) {
    b[off..off + 8].copy_from_slice(&v.to_le_bytes());
}
fn put_u32(b: &mut [u8], off: usize, v: u32) {
    b[off..off + 4].copy_from_slice(&v.to_le_bytes());
}

/// Recomputes the header checksum so that deeper checks are reached.
fn reseal(b: &mut [u8]) {
    let sum = xxh3_64(&b[..HEADER_CHECKSUM_OFFSET]);
    put_u64(b, HEADER_CHECKSUM_OFFSET, sum);
}

/// Recomputes the metadata, points and maps checksums, the TOC trailer and the header checksum.
fn reseal_all(b: &mut [u8]) {
    let h = header_unchecked(b);
    let sum = |s: oslf_format::header::Section, b: &[u8]| {
        xxh3_64(&b[s.offset as usize..s.end() as usize])
    };
    let m = sum(h.meta, b);
    let p = sum(h.points, b);
    let s = sum(h.maps, b);
    put_u64(b, 152, m);
    put_u64(b, 160, p);
    put_u64(b, 168, s);
    let toc_entries_end = (h.toc.end() - 8) as usize;
    let t = xxh3_64(&b[h.toc.offset as usize..toc_entries_end]);
    put_u64(b, toc_entries_end, t);
    reseal(b);
}

fn header_unchecked(b: &[u8]) -> Header {
    let mut c = b[..HEADER_BYTES].to_vec();
    reseal(&mut c);
    Header::parse(&c).unwrap()
}

#[test]
fn the_good_file_opens() {
    let b = good();
    let s = open(&b).unwrap();
    s.verify().unwrap();
}

#[test]
fn truncation_at_every_section_boundary() {
    let b = good();
    let h = header(&b);
    let mut cuts = vec![0, 1, 7, 8, 100, HEADER_BYTES - 1, HEADER_BYTES];
    for s in [h.meta, h.points, h.maps, h.payload, h.irradiance, h.toc] {
        cuts.extend([s.offset as usize, s.end() as usize, s.end() as usize - 1]);
    }
    cuts.push(b.len() - 1);
    for cut in cuts {
        if cut >= b.len() {
            continue;
        }
        let e = open(&b[..cut])
            .err()
            .unwrap_or_else(|| panic!("cut {cut} opened"));
        if cut < HEADER_BYTES {
            assert!(
                matches!(
                    e,
                    Error::Truncated {
                        section: "header",
                        ..
                    }
                ),
                "{cut}: {e}"
            );
        } else {
            assert!(
                matches!(
                    e,
                    Error::InvalidHeader {
                        field: "file_size",
                        ..
                    }
                ),
                "{cut}: {e}"
            );
        }
    }
}

#[test]
fn truncation_at_random_points_with_patched_file_size() {
    // Also lie about the file size, so that the section bounds checks are reached.
    let b = good();
    let mut rng = Rng(99);
    for _ in 0..300 {
        let cut = HEADER_BYTES + (rng.next_u64() as usize % (b.len() - HEADER_BYTES));
        let mut t = b[..cut].to_vec();
        put_u64(&mut t, 144, cut as u64);
        reseal(&mut t);
        let e = open(&t).err().unwrap_or_else(|| panic!("cut {cut} opened"));
        assert!(
            matches!(
                e,
                Error::SectionOutOfBounds { .. } | Error::InvalidHeader { .. }
            ),
            "{cut}: {e}"
        );
    }
}

#[test]
fn wrong_magic_and_version() {
    let mut b = good();
    b[0] ^= 0x20;
    assert!(matches!(open(&b), Err(Error::BadMagic { .. })));
    // Unknown versions, and the versions of the development builds before format 1.0 (each
    // resealed, so that the version is the only thing wrong): each refused by number, the
    // development ones with the advice to bake again.
    for v in [
        0,
        9,
        VERSION_1_0 - 1,
        VERSION + 1,
        u32::MAX,
        1,
        2,
        3,
        5,
        7,
        8,
    ] {
        let mut b = good();
        put_u32(&mut b, 8, v);
        reseal(&mut b);
        let e = open(&b).err().unwrap();
        assert!(
            matches!(e, Error::UnsupportedVersion { found } if found == v),
            "{e}"
        );
        let development = (1..=LAST_DEVELOPMENT_VERSION).contains(&v);
        assert_eq!(
            e.to_string().contains("bake the scene again"),
            development,
            "{e}"
        );
        assert!(e.to_string().contains("header bytes 8..12"), "{e}");
    }
}

#[test]
fn flipped_bytes_in_each_section() {
    let b = good();
    let h = header(&b);
    // Header (past magic and version).
    for off in [12usize, 30, 70, 150, 200, 250] {
        let mut c = b.clone();
        c[off] ^= 0x10;
        assert!(
            matches!(
                open(&c),
                Err(Error::ChecksumMismatch {
                    section: "header",
                    ..
                })
            ),
            "{off}"
        );
    }
    let cases = [
        (h.meta, "metadata"),
        (h.points, "sample points"),
        (h.maps, "sample maps"),
        (h.toc, "table of contents"),
    ];
    for (s, name) in cases {
        for off in [s.offset, s.offset + s.size / 2, s.end() - 9] {
            let mut c = b.clone();
            c[off as usize] ^= 0x01;
            let e = open(&c).err().expect("opened");
            assert!(
                matches!(&e, Error::ChecksumMismatch { section, .. } if *section == name),
                "{name} @ {off}: {e}"
            );
        }
    }
    // Payload: the file opens, but reading or verifying the damaged face fails.
    let s = open(&b).unwrap();
    let e = s.face_entry(2, 3).unwrap();
    let mut c = b.clone();
    c[(e.offset + e.compressed_size / 2) as usize] ^= 0x40;
    let damaged = open(&c).unwrap();
    let mut raw = vec![0u8; damaged.face_raw_size()];
    assert!(matches!(
        damaged.read_face_raw(2, 3, &mut raw),
        Err(Error::FaceChecksum {
            cube: 2,
            face: 3,
            ..
        })
    ));
    assert!(damaged.read_face_raw(2, 2, &mut raw).is_ok());
    assert!(matches!(
        damaged.verify(),
        Err(Error::FaceChecksum {
            cube: 2,
            face: 3,
            ..
        })
    ));
    // A cube record header.
    let mut c = b.clone();
    let first = s.face_entry(1, 0).unwrap();
    c[first.offset as usize - 100] ^= 1;
    assert!(matches!(
        open(&c).unwrap().verify(),
        Err(Error::InvalidCubeRecord { cube: 1, .. })
    ));
}

#[test]
fn absurd_offsets_and_lengths() {
    let b = good();
    let h = header(&b);
    let patched = |f: &dyn Fn(&mut Vec<u8>)| {
        let mut c = b.clone();
        f(&mut c);
        reseal(&mut c);
        open(&c).err().expect("opened")
    };
    // Metadata size u64::MAX: overflows.
    let e = patched(&|c| put_u64(c, 72, u64::MAX));
    assert!(
        matches!(
            e,
            Error::SectionOutOfBounds {
                section: "metadata",
                ..
            }
        ),
        "{e}"
    );
    // TOC offset far past the end.
    let e = patched(&|c| put_u64(c, 128, 1 << 60));
    assert!(
        matches!(
            e,
            Error::SectionOutOfBounds {
                section: "table of contents",
                ..
            }
        ),
        "{e}"
    );
    // Misaligned points.
    let e = patched(&|c| put_u64(c, 80, h.points.offset + 4));
    assert!(
        matches!(
            e,
            Error::Misaligned {
                section: "sample points",
                ..
            }
        ),
        "{e}"
    );
    // Points overlapping the metadata.
    let e = patched(&|c| put_u64(c, 80, h.meta.offset));
    assert!(
        matches!(
            e,
            Error::SectionOverlap {
                first: "metadata",
                second: "sample points",
                ..
            }
        ),
        "{e}"
    );
    // A gap before the maps.
    let e = patched(&|c| put_u64(c, 96, h.maps.offset + 8));
    assert!(matches!(e, Error::InvalidHeader { .. }), "{e}");
    // Wrong file size.
    let e = patched(&|c| put_u64(c, 144, b.len() as u64 + 8));
    assert!(
        matches!(
            e,
            Error::InvalidHeader {
                field: "file_size",
                ..
            }
        ),
        "{e}"
    );
    // Absurd counts.
    let e = patched(&|c| put_u64(c, 40, u64::MAX));
    assert!(
        matches!(
            e,
            Error::InvalidHeader {
                field: "cube_count",
                ..
            }
        ),
        "{e}"
    );
    let e = patched(&|c| {
        put_u64(c, 32, u64::MAX - 1);
        put_u64(c, 40, u64::MAX);
    });
    assert!(
        matches!(
            e,
            Error::InvalidHeader {
                field: "cube_count",
                ..
            }
        ),
        "{e}"
    );
    let e = patched(&|c| put_u64(c, 48, 1 << 40));
    assert!(
        matches!(
            e,
            Error::InvalidHeader {
                field: "patch_count",
                ..
            }
        ),
        "{e}"
    );
    let e = patched(&|c| put_u32(c, 24, 1 << 30));
    assert!(
        matches!(
            e,
            Error::InvalidHeader {
                field: "cube_resolution",
                ..
            }
        ),
        "{e}"
    );
    let e = patched(&|c| put_u32(c, 16, 9));
    assert!(
        matches!(
            e,
            Error::InvalidHeader {
                field: "encoding",
                ..
            }
        ),
        "{e}"
    );
    let e = patched(&|c| put_u32(c, 20, 3));
    assert!(
        matches!(
            e,
            Error::InvalidHeader {
                field: "index_bytes",
                ..
            }
        ),
        "{e}"
    );
    let e = patched(&|c| put_u32(c, 20, 4));
    assert!(
        matches!(
            e,
            Error::InvalidHeader {
                field: "index_bytes",
                ..
            }
        ),
        "{e}"
    );
    let e = patched(&|c| put_u32(c, 12, 0x100 | 7));
    assert!(
        matches!(e, Error::InvalidHeader { field: "flags", .. }),
        "{e}"
    );
    let e = patched(&|c| c[220] = 1);
    assert!(
        matches!(
            e,
            Error::InvalidHeader {
                field: "reserved",
                ..
            }
        ),
        "{e}"
    );
    // The COMPLETE flag cleared (the irradiance flag kept).
    let e = patched(&|c| put_u32(c, 12, 3 | 8));
    assert!(matches!(e, Error::NotFinished), "{e}");
    // Points section size inconsistent with the count.
    let e = patched(&|c| put_u64(c, 32, 5));
    assert!(
        matches!(
            e,
            Error::InvalidHeader {
                field: "cube_count",
                ..
            }
        ),
        "{e}"
    );
    let e = patched(&|c| {
        put_u64(c, 32, 5);
        put_u64(c, 40, 6);
    });
    assert!(
        matches!(
            e,
            Error::SectionSize {
                section: "sample points",
                ..
            }
        ),
        "{e}"
    );
}

#[test]
fn crafted_metadata_sample_points_maps_and_toc() {
    let b = good();
    let h = header(&b);
    let crafted = |f: &dyn Fn(&mut Vec<u8>)| {
        let mut c = b.clone();
        f(&mut c);
        reseal_all(&mut c);
        open(&c).err().expect("opened")
    };
    let m = h.meta.offset as usize;
    // Object count absurd.
    let e = crafted(&|c| put_u32(c, m, u32::MAX));
    assert!(matches!(e, Error::InvalidMetadata { .. }), "{e}");
    // Patch count absurd.
    let e = crafted(&|c| put_u32(c, m + 4, u32::MAX));
    assert!(matches!(e, Error::InvalidMetadata { .. }), "{e}");
    // NaN epsilon.
    let e = crafted(&|c| put_u32(c, m + 8, f32::NAN.to_bits()));
    assert!(
        matches!(e, Error::InvalidMetadata { offset, .. } if offset == m as u64 + 8),
        "{e}"
    );
    // Cube resolution above the cap.
    let e = crafted(&|c| put_u32(c, m + 16, 16385));
    assert!(matches!(e, Error::InvalidMetadata { .. }), "{e}");
    // First object's name length absurd (objects start after 8 + 80 + 44 bytes).
    let e = crafted(&|c| put_u32(c, m + 132, 0x7fff_ffff));
    assert!(matches!(e, Error::InvalidMetadata { .. }), "{e}");
    // Sample point with NaN position / out-of-range patch.
    let p = h.points.offset as usize;
    let e = crafted(&|c| put_u32(c, p + 40, f32::INFINITY.to_bits()));
    assert!(
        matches!(e, Error::InvalidSamplePoint { index: 1, .. }),
        "{e}"
    );
    let e = crafted(&|c| put_u32(c, p + 40 * 2 + 32, 77));
    assert!(
        matches!(e, Error::InvalidSamplePoint { index: 2, .. }),
        "{e}"
    );
    // Sample-map index out of range (u16 maps: 0xFFF0 >= 6 points).
    let s = h.maps.offset as usize;
    let e = crafted(&|c| {
        c[s..s + 8].copy_from_slice(&[0xF0, 0xFF, 0, 0, 0xFF, 0xFF, 0xFF, 0xFF]);
    });
    assert!(
        matches!(
            e,
            Error::InvalidSampleMap {
                patch: 0,
                x: 0,
                y: 0,
                channel: 0,
                ..
            }
        ),
        "{e}"
    );
    // A valid index after a missing one, in patch 1 texel (2, 1).
    let t = s + (9 + 3 + 2) * 8; // patch 1 (9 texels), row 1, column 2
    let e = crafted(&|c| {
        c[t..t + 8].copy_from_slice(&[1, 0, 0xFF, 0xFF, 2, 0, 0xFF, 0xFF]);
    });
    assert!(
        matches!(
            e,
            Error::InvalidSampleMap {
                patch: 1,
                x: 2,
                y: 1,
                channel: 2,
                ..
            }
        ),
        "{e}"
    );
    // TOC: a compressed size that overlaps the next frame; a wrong raw size; a huge offset.
    let toc = h.toc.offset as usize;
    let e = crafted(&|c| {
        let v = u64::from_le_bytes(c[toc + 8..toc + 16].try_into().unwrap());
        put_u64(c, toc + 8, v + 1);
    });
    assert!(
        matches!(
            e,
            Error::InvalidToc {
                cube: 0,
                face: 1,
                ..
            }
        ),
        "{e}"
    );
    let e = crafted(&|c| put_u64(c, toc + 32 * 7 + 16, 1 << 40));
    assert!(
        matches!(
            e,
            Error::InvalidToc {
                cube: 1,
                face: 1,
                ..
            }
        ),
        "{e}"
    );
    let e = crafted(&|c| put_u64(c, toc + 32 * 3, u64::MAX - 3));
    assert!(
        matches!(
            e,
            Error::InvalidToc {
                cube: 0,
                face: 3,
                ..
            }
        ),
        "{e}"
    );
    let last = h.toc.size as usize - 8 - 32;
    let e = crafted(&|c| put_u64(c, toc + last + 8, 1 << 50));
    assert!(matches!(e, Error::InvalidToc { face: 5, .. }), "{e}");
}

#[test]
fn crafted_mantissa_bits_are_rejected() {
    // Metadata byte 88 (after the counts and 80 bytes of bake parameters) holds
    // mantissa_bits. `good()` is RGBA16F, so only 9 is valid.
    let at = HEADER_BYTES + 8 + 80;
    assert_eq!(
        u32::from_le_bytes(good()[at..at + 4].try_into().unwrap()),
        9
    );
    for (bits, says) in [
        (0, "1..=9"),
        (10, "1..=9"),
        (u32::MAX, "1..=9"),
        (5, "rgb9e5"),
    ] {
        let mut b = good();
        put_u32(&mut b, at, bits);
        reseal_all(&mut b);
        match open(&b) {
            Err(Error::InvalidMetadata { offset, detail }) => {
                assert_eq!(offset, at as u64);
                assert!(detail.contains(says), "{detail}");
            }
            other => panic!("bits {bits}: {:?}", other.err()),
        }
    }
}

/// Format 1.2's sampling record (metadata bytes 92..100, after mantissa_bits): a target out
/// of (0, 1] or not finite, or a denoised flag other than 0 or 1, is refused at its offset.
#[test]
fn a_crafted_sampling_record_is_rejected() {
    let at = HEADER_BYTES + 8 + 84;
    let sampling = open(&good()).unwrap().meta().bake.sampling.unwrap();
    assert_eq!(
        f32::from_le_bytes(good()[at..at + 4].try_into().unwrap()),
        sampling.target_noise
    );
    let cases: [(usize, u32, &str); 5] = [
        (at, 1.5f32.to_bits(), "(0, 1]"),
        (at, (-0.1f32).to_bits(), "(0, 1]"),
        (at, f32::NAN.to_bits(), "target_noise"),
        (at, f32::INFINITY.to_bits(), "target_noise"),
        (at + 4, 2, "denoised"),
    ];
    for (off, value, says) in cases {
        let mut b = good();
        put_u32(&mut b, off, value);
        reseal_all(&mut b);
        match open(&b) {
            Err(Error::InvalidMetadata { offset, detail }) => {
                assert_eq!(offset, off as u64, "{detail}");
                assert!(detail.contains(says), "{detail}");
            }
            other => panic!("{value:#x} at {off}: {:?}", other.err()),
        }
    }
    // Both ends of the range are stores.
    for target in [1.0f32, 1e-6] {
        let mut b = good();
        put_u32(&mut b, at, target.to_bits());
        reseal_all(&mut b);
        let s = open(&b).unwrap();
        assert_eq!(s.meta().bake.sampling.unwrap().target_noise, target);
    }
}

#[test]
fn zip_bomb_frames_are_rejected() {
    // A frame that decompresses to more than the declared raw size (with checksums fixed).
    let b = good();
    let s = open(&b).unwrap();
    let e = s.face_entry(0, 0).unwrap();
    let raw = s.face_raw_size();
    let bomb = zstd::bulk::compress(&vec![0u8; raw * 100], 3).unwrap();
    assert!(
        bomb.len() as u64 <= e.compressed_size,
        "bomb must fit in place"
    );
    let mut c = b.clone();
    let o = e.offset as usize;
    c[o..o + bomb.len()].copy_from_slice(&bomb);
    // Pad the rest of the frame with a zstd skippable frame is not needed: zstd rejects
    // trailing garbage or the size check does; fix the checksum so decompression is reached.
    let frame = &c[o..o + e.compressed_size as usize];
    let sum = xxh3_64(frame);
    let h = header(&b);
    put_u64(&mut c, h.toc.offset as usize + 24, sum);
    reseal_all(&mut c);
    let store = open(&c).unwrap();
    let mut out = vec![0u8; raw];
    assert!(matches!(
        store.read_face_raw(0, 0, &mut out),
        Err(Error::Decompress {
            cube: 0,
            face: 0,
            ..
        })
    ));
}

#[test]
fn wrong_buffers_and_indices() {
    let s = open(&good()).unwrap();
    let mut small = vec![0u8; 3];
    assert!(matches!(
        s.read_face_raw(0, 0, &mut small),
        Err(Error::BufferSize { .. })
    ));
    assert!(matches!(
        s.face_entry(99, 0),
        Err(Error::CubeOutOfRange { cube: 99, count: 7 })
    ));
    assert!(matches!(
        s.face_entry(0, 6),
        Err(Error::FaceOutOfRange { face: 6 })
    ));
    assert!(matches!(
        s.sample_map(3),
        Err(Error::PatchOutOfRange { patch: 3, count: 3 })
    ));
    let mut rgb = vec![[0.0; 3]; 16];
    assert!(s.read_face(0, 0, &mut rgb, None).is_ok());
    let mut rgb = vec![[0.0; 3]; 15];
    assert!(matches!(
        s.read_face(0, 0, &mut rgb, None),
        Err(Error::BufferSize { .. })
    ));
    let no_dist = open(&store_bytes(Spec::default())).unwrap();
    let mut rgb = vec![[0.0; 3]; 16];
    let mut d = vec![0.0; 16];
    assert!(matches!(
        no_dist.read_face(0, 0, &mut rgb, Some(&mut d)),
        Err(Error::NoDistanceChannel)
    ));
}

#[test]
fn open_missing_and_empty_files() {
    let (_dir, path) = temp_store("none.oslf");
    assert!(matches!(Store::open(&path), Err(Error::Io { .. })));
    std::fs::write(&path, b"").unwrap();
    assert!(matches!(Store::open(&path), Err(Error::Truncated { .. })));
    assert!(matches!(
        Store::from_bytes(&[]),
        Err(Error::Truncated { .. })
    ));
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 512, ..ProptestConfig::default() })]

    /// Random byte damage anywhere: an error or a store whose every operation returns
    /// (never a panic); with the checksums resealed, deeper parsers see the damage too.
    #[test]
    fn random_damage_never_panics(
        flips in proptest::collection::vec((any::<usize>(), any::<u8>()), 1..6),
        do_reseal in any::<bool>(),
        cut in proptest::option::of(any::<usize>()),
    ) {
        let mut c = GOOD.with(|g| g.clone());
        for (pos, v) in flips {
            let n = c.len();
            c[pos % n] ^= v | 1;
        }
        if do_reseal
            && c.len() >= HEADER_BYTES
            && Header::parse(&{ let mut h = c[..HEADER_BYTES].to_vec(); reseal(&mut h); h }).is_ok()
        {
            {
                let h = header_unchecked(&c);
                let ok = [h.meta, h.points, h.maps, h.toc].iter().all(|s| {
                    s.offset.checked_add(s.size).is_some_and(|e| e <= c.len() as u64) && s.size >= 8
                });
                if ok { reseal_all(&mut c); } else { reseal(&mut c); }
            }
        }
        if let Some(cut) = cut {
            let n = c.len();
            c.truncate(cut % n);
        }
        if let Ok(s) = Store::from_bytes(&c) {
            let _ = s.verify();
            for p in 0..4 { let _ = s.sample_map(p).map(|m| m.get(0, 0)); }
            let mut rgb = vec![[0.0; 3]; 16];
            let _ = s.read_face(0, 0, &mut rgb, None);
        }
    }
}

thread_local! {
    static GOOD: Vec<u8> = good();
}

#[test]
fn unknown_filter_id_is_a_typed_error() {
    for id in [4u32, 7, u32::MAX] {
        let mut b = good();
        put_u32(&mut b, 176, id);
        reseal(&mut b);
        let e = open(&b).err().expect("must fail");
        assert!(
            matches!(e, Error::UnknownFilter { id: got, offset: 176 } if got == id),
            "{e}"
        );
    }
}

#[test]
fn hostile_filtered_frames_decode_without_panicking() {
    // Valid zstd frames of arbitrary content, re-sealed, must decode to some bytes (the
    // filter never fails on content) or a typed error, for every encoding.
    for encoding in Encoding::ALL {
        let spec = Spec {
            encoding,
            cube_res: 5,
            distance: true,
            ..Spec::default()
        };
        let f = fixture(spec);
        let (_dir, path) = temp_store("hostile.oslf");
        let mut w = StoreWriter::create(&path, &f.meta, &f.points, &f.maps).unwrap();
        let raw = oslf_format::cube::face_raw_size(encoding, 5, true).unwrap() as usize;
        let mut rng = Rng(99);
        for (i, c) in f.cubes.iter().enumerate() {
            let (e, _) = encode_cube(c, &f.meta.bake, i as u32).unwrap();
            w.append(e).unwrap();
        }
        w.finish().unwrap();
        let store = Store::open(&path).unwrap();
        // Decode garbage through the public unfilter (what read_face_raw runs).
        for _ in 0..64 {
            let junk: Vec<u8> = (0..raw).map(|_| rng.next_u64() as u8).collect();
            let mut out = vec![0u8; raw];
            for filter in Filter::ALL {
                let plane = store.header().distance_plane();
                let size =
                    oslf_format::filter::filtered_face_size(filter, encoding, 5, plane, 9).unwrap();
                oslf_format::filter::unfilter_face(
                    filter,
                    encoding,
                    5,
                    plane,
                    &junk[..size],
                    &mut out,
                )
                .unwrap();
            }
        }
        assert!(store.verify().is_ok());
    }
}

#[test]
fn filter_swapped_on_a_quantized_store_is_a_typed_error() {
    // A 3-bit RGB9E5 store is written with filter 3, whose frames decompress to 2 bytes per
    // texel; read as filter 2 they are short of the 4 bytes per texel it expects.
    let b = store_bytes(Spec {
        encoding: Encoding::Rgb9e5,
        mantissa_bits: 3,
        distance: true,
        ..Spec::default()
    });
    let store = open(&b).unwrap();
    assert_eq!(store.header().filter, Filter::PredictPacked);
    let mut raw = vec![0u8; store.face_raw_size()];
    store.read_face_raw(0, 0, &mut raw).unwrap();
    let mut c = b.clone();
    put_u32(&mut c, 176, Filter::PredictRows.id());
    reseal(&mut c);
    let store = open(&c).unwrap();
    let e = store.read_face_raw(0, 0, &mut raw).unwrap_err();
    assert!(
        matches!(
            e,
            Error::Decompress {
                cube: 0,
                face: 0,
                ..
            }
        ),
        "{e}"
    );
    // The other way round, a lossless store's frames (4 bytes per texel) read as filter 3 with
    // 9 bits (also 4 bytes per texel) decode to some texels without an error or a panic.
    let b = store_bytes(Spec::default());
    let mut c = b.clone();
    put_u32(&mut c, 176, Filter::PredictPacked.id());
    reseal(&mut c);
    let store = open(&c).unwrap();
    let mut raw = vec![0u8; store.face_raw_size()];
    store.read_face_raw(0, 0, &mut raw).unwrap();
}

#[test]
fn the_good_file_verifies_its_padding_and_decoded_faces() {
    let b = good();
    let r = open(&b).unwrap().verify().unwrap();
    assert!(r.padding_bytes > 0, "{r:?}");
    assert_ne!(header(&b).decoded_checksum, 0);
}

/// Every padding region (after the metadata, sample points and maps; after each cube
/// record's frames) must be zero: verify names the first non-zero byte.
#[test]
fn non_zero_padding_fails_verify_naming_the_offset() {
    let b = good();
    let h = header(&b);
    let s = open(&b).unwrap();
    let mut regions = vec![];
    for (end, next, what) in [
        (
            h.meta.end(),
            h.points.offset,
            "after the metadata section".to_string(),
        ),
        (
            h.points.end(),
            h.maps.offset,
            "after the sample points section".into(),
        ),
        (
            h.maps.end(),
            h.payload.offset,
            "after the sample maps section".into(),
        ),
    ] {
        regions.push((end, next, what));
    }
    for cube in 0..s.cube_count() {
        let last = s.face_entry(cube, 5).unwrap();
        let end = last.offset + last.compressed_size;
        regions.push((
            end,
            end.next_multiple_of(8),
            format!("after the frames of cube {cube}"),
        ));
    }
    let mut tested = 0;
    for (start, end, what) in regions {
        for at in start..end {
            let mut c = b.clone();
            c[at as usize] = 0x5a;
            // Padding is outside every checksum: the store opens, and verify catches it.
            let store = open(&c).unwrap();
            match store.verify() {
                Err(Error::NonZeroPadding {
                    region,
                    offset,
                    value: 0x5a,
                }) => {
                    assert_eq!((region.as_str(), offset), (what.as_str(), at));
                    assert_eq!(
                        store.verify().unwrap_err().to_string(),
                        format!(
                            "padding byte at byte offset {at} ({what}) is 0x5a; padding must be zero"
                        )
                    );
                }
                other => panic!("{what} @ {at}: {other:?}"),
            }
            tested += 1;
        }
    }
    assert!(
        tested >= 4,
        "the fixture has padding after the metadata and some cubes"
    );
    assert!(
        !h.meta.end().is_multiple_of(8),
        "the fixture pads its metadata"
    );
}

/// The frame checksums cover the compressed bytes; a changed face filter id (header resealed)
/// or a changed mantissa_bits (metadata resealed) decodes the same frames to other texels,
/// which verify catches with the checksum of the decoded faces.
#[test]
fn a_changed_filter_id_or_mantissa_bits_fails_verify() {
    // Filters 0, 1 and 2 decompress to the same size. On RGBA16F filters 1 and 2 are the
    // same transform (they differ only on RGB9E5 texels), so 2 → 1 decodes the same bytes.
    let rgba16f = good();
    let rgb9e5 = store_bytes(Spec::default());
    for (b, other) in [
        (&rgba16f, Filter::None),
        (&rgb9e5, Filter::None),
        (&rgb9e5, Filter::Predict),
    ] {
        assert_eq!(header(b).filter, Filter::PredictRows);
        let mut c = b.clone();
        put_u32(&mut c, 176, other.id());
        reseal(&mut c);
        let store = open(&c).unwrap();
        let mut raw = vec![0u8; store.face_raw_size()];
        if header(b).has_distance() && other == Filter::None {
            // Filters 1 to 3 store a distance in 2 bytes, filter 0 in 4, so
            // the frame decompresses to the wrong size, a typed error naming the face.
            let e = store.read_face_raw(0, 0, &mut raw).unwrap_err();
            assert!(e.to_string().contains("decompressed to"), "{e}");
            assert!(store.verify().is_err());
            continue;
        }
        store.read_face_raw(0, 0, &mut raw).unwrap();
        let e = store.verify().unwrap_err();
        assert!(
            matches!(e, Error::DecodedChecksum { stored, computed }
                if stored == header(b).decoded_checksum && computed != stored),
            "{other}: {e}"
        );
        assert!(e.to_string().contains("header byte offset 180"), "{e}");
        assert!(e.to_string().contains("face filter id at byte 176"), "{e}");
    }
    let mut c = rgba16f.clone();
    put_u32(&mut c, 176, Filter::Predict.id());
    reseal(&mut c);
    open(&c).unwrap().verify().unwrap();
    // RGB9E5 with 5 mantissa bits, filter 3: 6 bits pack into as many bytes (3 planes).
    let b = store_bytes(Spec {
        mantissa_bits: 5,
        distance: true,
        ..Spec::default()
    });
    let h = header(&b);
    assert_eq!(h.filter, Filter::PredictPacked);
    open(&b).unwrap().verify().unwrap();
    let at = HEADER_BYTES + 8 + 80;
    let mut c = b.clone();
    put_u32(&mut c, at, 6);
    reseal_all(&mut c);
    assert_eq!(open(&c).unwrap().meta().bake.mantissa_bits, 6);
    assert!(matches!(
        open(&c).unwrap().verify(),
        Err(Error::DecodedChecksum { .. })
    ));
    // Changing the decoded checksum itself is caught the same way.
    let mut c = b.clone();
    c[180] ^= 1;
    reseal(&mut c);
    assert!(matches!(
        open(&c).unwrap().verify(),
        Err(Error::DecodedChecksum { .. })
    ));
}

/// The irradiance section (format 1.1): a flipped byte fails its checksum; a coefficient that
/// is not finite, resealed, is refused naming its cube and byte offset; a finite coefficient
/// changed and resealed opens but fails full verification against the cube's faces; a section
/// of the wrong size is refused; the flag cleared with the fields left is refused.
#[test]
fn a_damaged_irradiance_section_is_refused() {
    let b = good();
    let h = header(&b);
    assert!(h.has_irradiance());
    let cubes = h.cube_count as usize;
    assert_eq!(
        h.irradiance.size as usize,
        cubes * irradiance::IRRADIANCE_CUBE_BYTES
    );
    let at = h.irradiance.offset as usize + irradiance::IRRADIANCE_CUBE_BYTES + 4 * 5;
    let mut c = b.clone();
    c[at] ^= 0x10;
    let e = open(&c).err().unwrap();
    assert!(
        matches!(
            e,
            Error::ChecksumMismatch {
                section: "irradiance",
                ..
            }
        ),
        "{e}"
    );
    let reseal_irradiance = |c: &mut Vec<u8>| {
        let s = h.irradiance;
        let sum = xxh3_64(&c[s.offset as usize..s.end() as usize]);
        put_u64(c, 204, sum);
        reseal(c);
    };
    let mut c = b.clone();
    c[at..at + 4].copy_from_slice(&f32::INFINITY.to_le_bytes());
    reseal_irradiance(&mut c);
    let e = open(&c).err().unwrap();
    assert!(
        matches!(e, Error::InvalidIrradiance { cube: 1, coefficient: 1, channel: 2, offset, .. } if offset == at as u64),
        "{e}"
    );
    let mut c = b.clone();
    let v = f32::from_le_bytes(c[at..at + 4].try_into().unwrap());
    c[at..at + 4].copy_from_slice(&(v + 0.25).to_le_bytes());
    reseal_irradiance(&mut c);
    let store = open(&c).unwrap();
    let e = store.verify().unwrap_err();
    assert!(
        matches!(e, Error::IrradianceMismatch { cube: 1, .. }),
        "{e}"
    );
    let mut c = b.clone();
    put_u64(&mut c, 196, h.irradiance.size - 8);
    reseal(&mut c);
    assert!(open(&c).is_err());
    let mut c = b.clone();
    put_u32(&mut c, 12, h.flags & !8);
    reseal(&mut c);
    let e = open(&c).err().unwrap();
    assert!(
        matches!(
            e,
            Error::InvalidHeader {
                field: "irradiance",
                offset: 188,
                ..
            }
        ),
        "{e}"
    );
}
