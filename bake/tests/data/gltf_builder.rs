//! Writes small glTF 2.0 files for the tests (tests/gltf.rs) and the room example
//! (examples/make_room_gltf.rs): one binary buffer of views and accessors, and the JSON
//! around it, as `.glb`, `.gltf` with a data URI, or `.gltf` with an external `.bin`.
#![allow(dead_code)]

use serde_json::{json, Value};

/// Accessor component types.
pub const F32: u32 = 5126;
pub const U8: u32 = 5121;
pub const U16: u32 = 5123;
pub const U32: u32 = 5125;

#[derive(Default)]
pub struct Builder {
    pub bin: Vec<u8>,
    pub views: Vec<Value>,
    pub accessors: Vec<Value>,
}

impl Builder {
    pub fn new() -> Self {
        Self::default()
    }

    /// Appends bytes as a buffer view (4-byte aligned); returns its index.
    pub fn view(&mut self, bytes: &[u8]) -> usize {
        while !self.bin.len().is_multiple_of(4) {
            self.bin.push(0);
        }
        self.views.push(json!({
            "buffer": 0,
            "byteOffset": self.bin.len(),
            "byteLength": bytes.len(),
        }));
        self.bin.extend_from_slice(bytes);
        self.views.len() - 1
    }

    /// An accessor over a new view; `components` per element of `ty` ("SCALAR", "VEC2", ...).
    pub fn accessor(&mut self, bytes: &[u8], component_type: u32, ty: &str, count: usize) -> usize {
        let view = self.view(bytes);
        self.accessors.push(json!({
            "bufferView": view,
            "componentType": component_type,
            "count": count,
            "type": ty,
        }));
        self.accessors.len() - 1
    }

    /// f32 vec3 positions with the min / max the specification requires.
    pub fn positions(&mut self, p: &[[f32; 3]]) -> usize {
        let bytes: Vec<u8> = p.iter().flatten().flat_map(|v| v.to_le_bytes()).collect();
        let a = self.accessor(&bytes, F32, "VEC3", p.len());
        let mut lo = [f32::INFINITY; 3];
        let mut hi = [f32::NEG_INFINITY; 3];
        for v in p {
            for k in 0..3 {
                lo[k] = lo[k].min(v[k]);
                hi[k] = hi[k].max(v[k]);
            }
        }
        if p.iter().flatten().any(|v| !v.is_finite()) || p.is_empty() {
            lo = [0.0; 3];
            hi = [0.0; 3];
        }
        self.accessors[a]["min"] = json!(lo);
        self.accessors[a]["max"] = json!(hi);
        a
    }

    pub fn vec3(&mut self, p: &[[f32; 3]]) -> usize {
        let bytes: Vec<u8> = p.iter().flatten().flat_map(|v| v.to_le_bytes()).collect();
        self.accessor(&bytes, F32, "VEC3", p.len())
    }

    pub fn vec2(&mut self, p: &[[f32; 2]]) -> usize {
        let bytes: Vec<u8> = p.iter().flatten().flat_map(|v| v.to_le_bytes()).collect();
        self.accessor(&bytes, F32, "VEC2", p.len())
    }

    pub fn indices_u16(&mut self, i: &[u16]) -> usize {
        let bytes: Vec<u8> = i.iter().flat_map(|v| v.to_le_bytes()).collect();
        self.accessor(&bytes, U16, "SCALAR", i.len())
    }

    pub fn indices_u32(&mut self, i: &[u32]) -> usize {
        let bytes: Vec<u8> = i.iter().flat_map(|v| v.to_le_bytes()).collect();
        self.accessor(&bytes, U32, "SCALAR", i.len())
    }

    pub fn indices_u8(&mut self, i: &[u8]) -> usize {
        self.accessor(i, U8, "SCALAR", i.len())
    }

    /// An sRGB PNG (8-bit RGB, row 0 at the top) in a buffer view; returns the view.
    pub fn png(&mut self, width: u32, height: u32, rgb: &[u8]) -> usize {
        let img = image::RgbImage::from_raw(width, height, rgb.to_vec()).expect("size");
        let mut png = Vec::new();
        img.write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png)
            .expect("PNG");
        self.view(&png)
    }

    /// `json` with `asset`, `buffers` (one, with `uri` if given), `bufferViews` and
    /// `accessors` filled in.
    pub fn document(&self, mut json: Value, uri: Option<String>) -> Value {
        json["asset"] = json!({"version": "2.0", "generator": "oslf gltf_builder"});
        let mut buffer = json!({"byteLength": self.bin.len()});
        if let Some(uri) = uri {
            buffer["uri"] = json!(uri);
        }
        if !self.bin.is_empty() {
            json["buffers"] = json!([buffer]);
        }
        if !self.views.is_empty() {
            json["bufferViews"] = json!(self.views);
        }
        if !self.accessors.is_empty() {
            json["accessors"] = json!(self.accessors);
        }
        json
    }

    /// Binary glTF.
    pub fn glb(&self, json: Value) -> Vec<u8> {
        glb_from(&self.document(json, None), &self.bin)
    }

    /// Writes the `.glb` of `json` to `out` for an example generator and says so with its
    /// size and `triangles` (a failed write ends the generator, naming the path).
    pub fn write_glb(&self, json: Value, out: &std::path::Path, triangles: usize) {
        let glb = self.glb(json);
        std::fs::write(out, &glb).unwrap_or_else(|e| panic!("{}: {e}", out.display()));
        println!(
            "{} ({} bytes, {triangles} triangles)",
            out.display(),
            glb.len()
        );
    }

    /// `.gltf` text with the buffer inline as a data URI.
    pub fn gltf_embedded(&self, json: Value) -> Vec<u8> {
        let uri = format!(
            "data:application/octet-stream;base64,{}",
            base64_encode(&self.bin)
        );
        serde_json::to_vec_pretty(&self.document(json, Some(uri))).unwrap()
    }

    /// `.gltf` text referring to an external buffer file `bin_name`; returns (gltf, bin).
    pub fn gltf_external(&self, json: Value, bin_name: &str) -> (Vec<u8>, Vec<u8>) {
        let doc = self.document(json, Some(bin_name.to_string()));
        (serde_json::to_vec_pretty(&doc).unwrap(), self.bin.clone())
    }
}

/// A GLB container around a JSON document and a BIN chunk.
pub fn glb_from(doc: &Value, bin: &[u8]) -> Vec<u8> {
    let mut json = serde_json::to_vec(doc).unwrap();
    while !json.len().is_multiple_of(4) {
        json.push(b' ');
    }
    let mut bin = bin.to_vec();
    while !bin.len().is_multiple_of(4) {
        bin.push(0);
    }
    let total = 12 + 8 + json.len() + if bin.is_empty() { 0 } else { 8 + bin.len() };
    let mut out = Vec::with_capacity(total);
    out.extend_from_slice(b"glTF");
    out.extend(2u32.to_le_bytes());
    out.extend((total as u32).to_le_bytes());
    out.extend((json.len() as u32).to_le_bytes());
    out.extend(0x4E4F_534Au32.to_le_bytes());
    out.extend(&json);
    if !bin.is_empty() {
        out.extend((bin.len() as u32).to_le_bytes());
        out.extend(0x004E_4942u32.to_le_bytes());
        out.extend(&bin);
    }
    out
}

pub fn base64_encode(bytes: &[u8]) -> String {
    const A: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut out = String::new();
    for chunk in bytes.chunks(3) {
        let b = [
            chunk[0],
            *chunk.get(1).unwrap_or(&0),
            *chunk.get(2).unwrap_or(&0),
        ];
        let n = (u32::from(b[0]) << 16) | (u32::from(b[1]) << 8) | u32::from(b[2]);
        for k in 0..4 {
            if k <= chunk.len() {
                out.push(A[((n >> (18 - 6 * k)) & 63) as usize] as char);
            } else {
                out.push('=');
            }
        }
    }
    out
}
