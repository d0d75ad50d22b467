//! Writing HDR cube maps as KTX2 (Khronos Texture 2.0), the container engines such as Bevy load
//! environment maps from.
//!
//! The file holds one uncompressed cube map: `VK_FORMAT_R16G16B16A16_SFLOAT` (linear RGB, alpha
//! 1), one mip level, six faces in KTX2's (and Vulkan's) order +X, −X, +Y, −Y, +Z, −Z, each
//! row-major from its top row (`KTXorientation` "rd"), in Vulkan's cube-map face convention, so
//! faces in that convention are written as they are. Layout (KTX 2.0 specification §3):
//!
//! | bytes | what |
//! | --- | --- |
//! | 0..12 | identifier `«KTX 20»\r\n\x1A\n` |
//! | 12..48 | vkFormat 97, typeSize 2, width = height = n, depth 0, layers 0, faces 6, levels 1, supercompression 0 |
//! | 48..80 | index: DFD offset and length, key/value offset and length, no supercompression data |
//! | 80..104 | level 0: byte offset, byte length, uncompressed byte length (`6 n² × 8`) |
//! | 104..196 | data format descriptor: its total size, then one basic block (RGBSDA, BT.709 primaries, linear, four 16-bit float samples R, G, B, A) |
//! | 196.. | key/value data: `KTXorientation` = "rd", `KTXwriter` = the writer's name, each padded to 4 bytes |
//! | then | the six faces (8 bytes per texel), starting on an 8-byte boundary |
//!
//! Half floats reach 65504: larger values are written as 65504 and counted, never as infinity.

use std::io::Write;
use std::path::Path;

use half::f16;

use crate::output_file::write_with;
use crate::Result;

/// The largest finite half float.
pub const F16_MAX: f32 = 65504.0;

/// `VK_FORMAT_R16G16B16A16_SFLOAT`.
const VK_FORMAT_R16G16B16A16_SFLOAT: u32 = 97;
const IDENTIFIER: [u8; 12] = [
    0xAB, 0x4B, 0x54, 0x58, 0x20, 0x32, 0x30, 0xBB, 0x0D, 0x0A, 0x1A, 0x0A,
];
/// Header (12 + 36), index (32) and one level entry (24).
const LEVELS_END: usize = 104;
/// The data format descriptor: its size field and one basic block of four samples.
const DFD_LENGTH: usize = 4 + 24 + 4 * 16;

/// Writes the cube `faces` (six faces of `n × n` linear RGB texels, in the order and orientation
/// above) to `out` as KTX2; `writer` names the program in `KTXwriter`. Returns how many channel
/// values were above [`F16_MAX`] and written as it (negative and NaN values are written as 0).
///
/// # Errors
///
/// Any error of `out`; `InvalidInput` when a face does not hold `n²` texels or `n` is 0.
pub fn write_cube(
    out: &mut impl Write,
    n: u32,
    faces: &[Vec<[f32; 3]>; 6],
    writer: &str,
) -> std::io::Result<u64> {
    let texels = n as usize * n as usize;
    if n == 0 || faces.iter().any(|f| f.len() != texels) {
        return Err(std::io::Error::new(
            std::io::ErrorKind::InvalidInput,
            format!(
                "a KTX2 cube needs six faces of {n}² texels, got {:?}",
                faces.each_ref().map(Vec::len)
            ),
        ));
    }
    let mut kvd = Vec::new();
    for (key, value) in [("KTXorientation", "rd"), ("KTXwriter", writer)] {
        let entry = [key.as_bytes(), &[0], value.as_bytes(), &[0]].concat();
        kvd.extend_from_slice(&(entry.len() as u32).to_le_bytes());
        kvd.extend_from_slice(&entry);
        kvd.resize(kvd.len().next_multiple_of(4), 0);
    }
    let kvd_offset = LEVELS_END + DFD_LENGTH;
    let data_offset = (kvd_offset + kvd.len()).next_multiple_of(8);
    let data_length = (6 * texels * 8) as u64;

    let mut head = Vec::with_capacity(data_offset);
    head.extend_from_slice(&IDENTIFIER);
    let u32s = [VK_FORMAT_R16G16B16A16_SFLOAT, 2, n, n, 0, 0, 6, 1, 0];
    u32s.iter()
        .for_each(|v| head.extend_from_slice(&v.to_le_bytes()));
    for v in [LEVELS_END, DFD_LENGTH, kvd_offset, kvd.len()] {
        head.extend_from_slice(&(v as u32).to_le_bytes());
    }
    head.extend_from_slice(&[0; 16]); // no supercompression global data
    for v in [data_offset as u64, data_length, data_length] {
        head.extend_from_slice(&v.to_le_bytes());
    }
    head.extend_from_slice(&dfd());
    head.extend_from_slice(&kvd);
    head.resize(data_offset, 0);
    out.write_all(&head)?;

    let mut clamped = 0u64;
    let mut row = Vec::with_capacity(n as usize * 8);
    for face in faces {
        for line in face.chunks(n as usize) {
            row.clear();
            for texel in line {
                for &v in texel.iter().chain(&[1.0]) {
                    let v = if v > F16_MAX {
                        clamped += 1;
                        F16_MAX
                    } else if v >= 0.0 {
                        v
                    } else {
                        0.0
                    };
                    row.extend_from_slice(&f16::from_f32(v).to_le_bytes());
                }
            }
            out.write_all(&row)?;
        }
    }
    Ok(clamped)
}

/// [`write_cube`] to the file `path`, through a temporary file beside it renamed into place
/// (as the images of [`crate::image_file`]): on failure `path` is left as it was.
///
/// # Errors
///
/// [`crate::UtilError::Image`] naming `path`: a target that is not a regular file, or any
/// write or rename error.
pub fn write_cube_file(
    path: &Path,
    n: u32,
    faces: &[Vec<[f32; 3]>; 6],
    writer: &str,
) -> Result<u64> {
    let mut clamped = 0;
    write_with(path, |out| {
        clamped = write_cube(out, n, faces, writer)?;
        Ok(())
    })?;
    Ok(clamped)
}

/// The data format descriptor of `R16G16B16A16_SFLOAT` (Khronos Data Format 1.3, basic block).
fn dfd() -> Vec<u8> {
    let mut d = Vec::with_capacity(DFD_LENGTH);
    d.extend_from_slice(&(DFD_LENGTH as u32).to_le_bytes());
    // vendorId 0 and descriptorType 0; versionNumber 2 and descriptorBlockSize.
    d.extend_from_slice(&0u32.to_le_bytes());
    d.extend_from_slice(&(2u32 | ((DFD_LENGTH as u32 - 4) << 16)).to_le_bytes());
    // colorModel RGBSDA (1), colorPrimaries BT709 (1), transferFunction LINEAR (1), flags 0.
    d.extend_from_slice(&[1, 1, 1, 0]);
    d.extend_from_slice(&[0; 4]); // texel block 1×1×1×1
    d.extend_from_slice(&[8, 0, 0, 0, 0, 0, 0, 0]); // bytesPlane0 = 8
    for (i, channel) in [0u8, 1, 2, 15].into_iter().enumerate() {
        d.extend_from_slice(&(16 * i as u16).to_le_bytes()); // bitOffset
        d.push(15); // bitLength − 1
        d.push(channel | 0x80 | 0x40); // FLOAT | SIGNED qualifiers
        d.extend_from_slice(&[0; 4]); // samplePosition
        d.extend_from_slice(&(-1f32).to_bits().to_le_bytes()); // sampleLower
        d.extend_from_slice(&1f32.to_bits().to_le_bytes()); // sampleUpper
    }
    d
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn header_and_data_are_where_the_layout_says() {
        let n = 3u32;
        let faces: [Vec<[f32; 3]>; 6] =
            std::array::from_fn(|f| (0..9).map(|i| [f as f32, i as f32, 1e6]).collect());
        let mut out = Vec::new();
        let clamped = write_cube(&mut out, n, &faces, "test").unwrap();
        assert_eq!(clamped, 6 * 9);
        assert_eq!(&out[..12], &IDENTIFIER);
        let u32_at = |o: usize| u32::from_le_bytes(out[o..o + 4].try_into().unwrap());
        let u64_at = |o: usize| u64::from_le_bytes(out[o..o + 8].try_into().unwrap());
        assert_eq!(
            (0..9).map(|k| u32_at(12 + 4 * k)).collect::<Vec<_>>(),
            [97, 2, 3, 3, 0, 0, 6, 1, 0]
        );
        assert_eq!((u32_at(48), u32_at(52)), (104, 92));
        let (offset, length) = (u64_at(80) as usize, u64_at(88) as usize);
        assert_eq!(offset % 8, 0);
        assert_eq!((length, out.len()), (6 * 9 * 8, offset + length));
        // Face 4, texel 5: (4, 5, 65504, 1) as halves.
        let t = offset + (4 * 9 + 5) * 8;
        let half = |k: usize| f16::from_le_bytes([out[t + 2 * k], out[t + 2 * k + 1]]).to_f32();
        assert_eq!(
            [half(0), half(1), half(2), half(3)],
            [4.0, 5.0, F16_MAX, 1.0]
        );
    }

    #[test]
    fn a_face_of_the_wrong_size_is_refused() {
        let mut faces: [Vec<[f32; 3]>; 6] = std::array::from_fn(|_| vec![[0.0; 3]; 4]);
        faces[2].pop();
        let e = write_cube(&mut Vec::new(), 2, &faces, "test").unwrap_err();
        assert!(e.to_string().contains("[4, 4, 3, 4, 4, 4]"), "{e}");
    }
}
