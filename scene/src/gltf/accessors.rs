//! Accessors: typed, possibly sparse and normalized views of buffer data, read with every
//! offset and index checked.

use gltf::accessor::{DataType, Dimensions};

use super::loader::Loader;
use crate::Result;

impl<'d> Loader<'d> {
    /// The accessor's elements as `f32`, `count × components` values, normalized integers
    /// mapped to [0, 1] or [-1, 1]. `allowed` lists the component types accepted (`true`:
    /// normalized); `expected` describes them for the error.
    pub(super) fn read_floats(
        &self,
        accessor: &gltf::Accessor,
        at: &str,
        dims: Dimensions,
        allowed: &[(DataType, bool)],
        expected: &str,
    ) -> Result<Vec<f32>> {
        let ty = accessor.data_type();
        if accessor.dimensions() != dims
            || !allowed.contains(&(ty, accessor.normalized() || ty == DataType::F32))
        {
            return Err(self.err(
                at,
                format!(
                    "accessor {} has {} components of type {}{}, expected {expected}",
                    accessor.index(),
                    accessor.dimensions().multiplicity(),
                    type_name(ty),
                    if accessor.normalized() {
                        " (normalized)"
                    } else {
                        ""
                    }
                ),
            ));
        }
        let raw = self.read_raw(accessor, at)?;
        Ok(raw
            .into_iter()
            .map(|v| match (ty, accessor.normalized()) {
                (DataType::F32, _) => f32::from_bits(v as u32),
                (DataType::U8, true) => v as f32 / 255.0,
                (DataType::U16, true) => v as f32 / 65535.0,
                (DataType::I8, true) => (v as i8 as f32 / 127.0).max(-1.0),
                (DataType::I16, true) => (v as i16 as f32 / 32767.0).max(-1.0),
                (DataType::I8, false) => v as i8 as f32,
                (DataType::I16, false) => v as i16 as f32,
                _ => v as f32,
            })
            .collect())
    }

    /// Vertex indices: unsigned scalars.
    pub(super) fn read_indices(&self, accessor: &gltf::Accessor, at: &str) -> Result<Vec<u32>> {
        let ty = accessor.data_type();
        if accessor.dimensions() != Dimensions::Scalar
            || !matches!(ty, DataType::U8 | DataType::U16 | DataType::U32)
            || accessor.normalized()
        {
            return Err(self.err(
                at,
                format!(
                    "accessor {} has {} components of type {}, expected scalar u8, u16 or u32",
                    accessor.index(),
                    accessor.dimensions().multiplicity(),
                    type_name(ty)
                ),
            ));
        }
        Ok(self
            .read_raw(accessor, at)?
            .into_iter()
            .map(|v| v as u32)
            .collect())
    }

    /// Every component of every element as raw little-endian bits (zero-extended), the sparse
    /// substitution applied. Checks that every byte read lies within its buffer view.
    pub(super) fn read_raw(&self, accessor: &gltf::Accessor, at: &str) -> Result<Vec<u64>> {
        let index = accessor.index();
        let components = accessor.dimensions().multiplicity();
        let size = accessor.data_type().size();
        let element = components * size;
        let count = accessor.count();
        let read = |bytes: &[u8], offset: usize| -> u64 {
            let mut v = [0u8; 8];
            v[..size].copy_from_slice(&bytes[offset..offset + size]);
            u64::from_le_bytes(v)
        };
        // The elements' bytes, checked before anything is allocated: then the count is
        // bounded by the file's size.
        let source = match accessor.view() {
            None => {
                // Zeros (then the sparse values): nothing in the file bounds the count.
                const MAX_ELEMENTS: usize = 1 << 24;
                if count > MAX_ELEMENTS {
                    return Err(self.err(
                        at,
                        format!("accessor {index}: {count} elements without a bufferView is more than the {MAX_ELEMENTS} supported"),
                    ));
                }
                None
            }
            Some(view) => {
                let stride = view.stride().unwrap_or(element);
                if stride < element {
                    return Err(self.err(
                        at,
                        format!(
                            "accessor {index}: bufferView {} has a byteStride of {stride}, less than the element's {element} bytes",
                            view.index()
                        ),
                    ));
                }
                let bytes = self.view_bytes(&view);
                let end = if count == 0 {
                    Some(0)
                } else {
                    (count - 1)
                        .checked_mul(stride)
                        .and_then(|e| e.checked_add(element))
                        .and_then(|e| e.checked_add(accessor.offset()))
                };
                if end.is_none_or(|e| e > bytes.len()) {
                    return Err(self.err(
                        at,
                        format!(
                            "accessor {index} ({count} elements of {element} bytes, stride {stride}, from byte {}) runs past the end of bufferView {}, which has {} bytes",
                            accessor.offset(),
                            view.index(),
                            bytes.len()
                        ),
                    ));
                }
                Some((bytes, stride))
            }
        };
        let mut out = vec![0u64; count * components];
        if let Some((bytes, stride)) = source {
            for e in 0..count {
                let base = accessor.offset() + e * stride;
                for c in 0..components {
                    out[e * components + c] = read(bytes, base + c * size);
                }
            }
        }
        if let Some(sparse) = accessor.sparse() {
            let n = sparse.count();
            let indices = sparse.indices();
            let values = sparse.values();
            let isize = match indices.index_type() {
                gltf::accessor::sparse::IndexType::U8 => 1,
                gltf::accessor::sparse::IndexType::U16 => 2,
                gltf::accessor::sparse::IndexType::U32 => 4,
            };
            let ibytes = self.view_bytes(&indices.view());
            let vbytes = self.view_bytes(&values.view());
            let fits = |bytes: &[u8], offset: usize, each: usize| {
                n.checked_mul(each)
                    .and_then(|l| l.checked_add(offset))
                    .is_some_and(|e| e <= bytes.len())
            };
            if !fits(ibytes, indices.offset(), isize) || !fits(vbytes, values.offset(), element) {
                return Err(self.err(
                    format!("accessors[{index}].sparse"),
                    format!("{n} sparse indices or values run past the end of their buffer view"),
                ));
            }
            for k in 0..n {
                let mut v = [0u8; 4];
                let o = indices.offset() + k * isize;
                v[..isize].copy_from_slice(&ibytes[o..o + isize]);
                let target = u32::from_le_bytes(v) as usize;
                if target >= count {
                    return Err(self.err(
                        format!("accessors[{index}].sparse.indices"),
                        format!("index {target} (entry {k}) is out of range: the accessor has {count} elements"),
                    ));
                }
                let base = values.offset() + k * element;
                for c in 0..components {
                    out[target * components + c] = read(vbytes, base + c * size);
                }
            }
        }
        Ok(out)
    }
}

pub(super) fn type_name(t: DataType) -> &'static str {
    match t {
        DataType::I8 => "i8",
        DataType::U8 => "u8",
        DataType::I16 => "i16",
        DataType::U16 => "u16",
        DataType::U32 => "u32",
        DataType::F32 => "f32",
    }
}
