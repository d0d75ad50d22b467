//! The container and its buffers: GLB chunks, the JSON document checked before the `gltf`
//! crate reads it, buffers (GLB binary chunk, data URIs, external files), buffer views, and
//! the document-level features warned about.

use std::borrow::Cow;
use std::path::Path;

use gltf::json::validation::Validate;

use oslf_util::input_file::{byte_size, Limit};

use super::import::SUPPORTED_EXTENSIONS;
use super::loader::{error, label, Loader};
use crate::input::{gltf_buffer_limit, MAX_MESH_BYTES};
use crate::Result;

pub(super) const GLB_MAGIC: &[u8; 4] = b"glTF";
pub(super) const CHUNK_JSON: u32 = 0x4E4F_534A;
pub(super) const CHUNK_BIN: u32 = 0x004E_4942;

pub(super) fn le_u32(b: &[u8], at: usize) -> Option<u32> {
    let s = b.get(at..at.checked_add(4)?)?;
    Some(u32::from_le_bytes([s[0], s[1], s[2], s[3]]))
}

/// Splits a GLB container into its JSON chunk and its BIN chunk (if any).
pub(super) fn split_glb<'b>(path: &Path, bytes: &'b [u8]) -> Result<(&'b [u8], Option<&'b [u8]>)> {
    let bad = |message: String| error(path, "GLB header", message);
    let version = le_u32(bytes, 4).ok_or_else(|| bad("the file ends inside the header".into()))?;
    if version != 2 {
        return Err(bad(format!("version {version}; only glTF 2 is supported")));
    }
    let length =
        le_u32(bytes, 8).ok_or_else(|| bad("the file ends inside the header".into()))? as usize;
    if length > bytes.len() || length < 12 {
        return Err(bad(format!(
            "the header gives a length of {length} bytes, the file has {}",
            bytes.len()
        )));
    }
    let bytes = &bytes[..length];
    let mut offset = 12;
    let mut json = None;
    let mut bin = None;
    let mut chunk = 0;
    while offset + 8 <= length {
        let at = format!("GLB chunk {chunk}");
        let chunk_length = le_u32(bytes, offset).unwrap_or(0) as usize;
        let kind = le_u32(bytes, offset + 4).unwrap_or(0);
        let start = offset + 8;
        let end = start
            .checked_add(chunk_length)
            .filter(|&e| e <= length)
            .ok_or_else(|| {
                error(
                    path,
                    at.clone(),
                    format!(
                        "{chunk_length} bytes from byte {start} run past the end of the file ({length} bytes)"
                    ),
                )
            })?;
        let data = &bytes[start..end];
        match (chunk, kind) {
            (0, CHUNK_JSON) => json = Some(data),
            (0, _) => {
                return Err(error(
                    path,
                    at,
                    format!("the first chunk must be JSON (type 0x4E4F534A), not 0x{kind:08X}"),
                ))
            }
            (1, CHUNK_BIN) => bin = Some(data),
            _ => {} // other chunks: ignored, as the specification says
        }
        offset = end.next_multiple_of(4);
        chunk += 1;
    }
    let json = json.ok_or_else(|| bad("the file has no JSON chunk".into()))?;
    Ok((json, bin))
}

/// The glTF document in `bytes` (a `.gltf` JSON text, or a `.glb` container) and the GLB
/// binary chunk, if any: the JSON checked where the `gltf` crate would otherwise panic, then
/// validated, every problem named by its JSON path.
pub(super) fn parse_document<'b>(
    path: &Path,
    bytes: &'b [u8],
) -> Result<(gltf::Document, Option<&'b [u8]>)> {
    let (json, bin) = if bytes.starts_with(GLB_MAGIC) {
        split_glb(path, bytes)?
    } else {
        (bytes, None)
    };
    let root: gltf::json::Root = gltf::json::deserialize::from_slice(json)
        .map_err(|e| error(path, "JSON", format!("not a glTF document: {e}")))?;
    // gltf-json's validation indexes the accessor a POSITION attribute names without checking
    // it first: check it here.
    for (m, mesh) in root.meshes.iter().enumerate() {
        for (p, prim) in mesh.primitives.iter().enumerate() {
            for (semantic, index) in &prim.attributes {
                if index.value() >= root.accessors.len() {
                    let name = match semantic {
                        gltf::json::validation::Checked::Valid(s) => s.to_string(),
                        gltf::json::validation::Checked::Invalid => "?".into(),
                    };
                    return Err(error(
                        path,
                        format!("meshes[{m}].primitives[{p}].attributes.{name}"),
                        format!(
                            "accessor {} does not exist (the file has {} accessors)",
                            index.value(),
                            root.accessors.len()
                        ),
                    ));
                }
            }
        }
    }
    // `Camera::projection` unwraps the projection its type names; validation only asks for one.
    for (i, camera) in root.cameras.iter().enumerate() {
        use gltf::json::camera::Type;
        use gltf::json::validation::Checked;
        let (missing, key) = match camera.type_ {
            Checked::Valid(Type::Perspective) => (camera.perspective.is_none(), "perspective"),
            Checked::Valid(Type::Orthographic) => (camera.orthographic.is_none(), "orthographic"),
            Checked::Invalid => (false, ""),
        };
        if missing {
            return Err(error(
                path,
                format!("cameras[{i}].{key}"),
                format!("is missing, but the camera's type is {key}"),
            ));
        }
    }
    // gltf-json asks every accessor without sparse values for a bufferView, but glTF 2.0
    // (3.6.2.1) makes it optional: an accessor without one is all zeros (read_raw reads it so).
    let optional_views: Vec<String> = (root.accessors.iter().enumerate())
        .filter(|(_, a)| a.buffer_view.is_none())
        .map(|(i, _)| format!("accessors[{i}].bufferView"))
        .collect();
    let mut problems: Vec<(String, String)> = Vec::new();
    root.validate(&root, gltf::json::Path::new, &mut |at, e| {
        let at = at().to_string();
        let optional =
            matches!(e, gltf::json::validation::Error::Missing) && optional_views.contains(&at);
        if !optional {
            problems.push((at, e.to_string()))
        }
    });
    if let Some((at, what)) = problems.first() {
        let more = match problems.len() {
            1 => String::new(),
            n => format!(" (and {} more problems)", n - 1),
        };
        let what = match what.as_str() {
            "Index out of bounds" => {
                "refers to something the file does not have (index out of range)"
            }
            "Missing data" => "is required but missing",
            "Unsupported extension" => {
                "names an extension this importer does not support, which the file requires"
            }
            "Invalid value" => "has an invalid value",
            other => other,
        };
        return Err(error(
            path,
            at.replace("[\"", ".").replace("\"]", ""),
            format!("{what}{more}"),
        ));
    }
    if !root.asset.version.starts_with("2.") {
        return Err(error(
            path,
            "asset.version",
            format!("{:?}: only glTF 2.x is supported", root.asset.version),
        ));
    }
    Ok((gltf::Document::from_json_without_validation(root), bin))
}

impl<'d> Loader<'d> {
    pub(super) fn load_buffers(&mut self, bin: Option<&'d [u8]>) -> Result<()> {
        for buffer in self.doc.buffers() {
            let i = buffer.index();
            let data: Cow<'d, [u8]> = match buffer.source() {
                gltf::buffer::Source::Bin => match bin {
                    Some(b) => Cow::Borrowed(b),
                    None => return Err(self.err(
                        format!("buffers[{i}]"),
                        "has no uri, so it is the GLB's BIN chunk, which the file does not have",
                    )),
                },
                gltf::buffer::Source::Uri(uri) => {
                    let declared = buffer.length() as u64;
                    if declared > MAX_MESH_BYTES {
                        return Err(self.err(
                            format!("buffers[{i}].byteLength"),
                            format!(
                                "{declared} is more than the {} a buffer may have",
                                byte_size(MAX_MESH_BYTES)
                            ),
                        ));
                    }
                    let limit = gltf_buffer_limit(declared);
                    Cow::Owned(self.read_uri(uri, &format!("buffers[{i}].uri"), &limit)?)
                }
            };
            if data.len() < buffer.length() {
                return Err(self.err(
                    format!("buffers[{i}]"),
                    format!(
                        "byteLength is {} but the data has only {} bytes",
                        buffer.length(),
                        data.len()
                    ),
                ));
            }
            self.buffers.push(data);
        }
        Ok(())
    }

    /// The bytes of a data URI or of a file relative to the glTF file, a regular file of at
    /// most `limit` bytes ([`crate::input`]). A reference with a scheme (`file:`, `http://`),
    /// an absolute path or one that leaves the glTF file's directory (`../x.bin`) is refused
    /// (docs/scene-format.md, "glTF scenes").
    pub(super) fn read_uri(&self, uri: &str, at: &str, limit: &Limit) -> Result<Vec<u8>> {
        if let Some(rest) = uri.strip_prefix("data:") {
            let Some((_, data)) = rest.split_once(";base64,") else {
                return Err(self.err(at, "a data URI must be base64-encoded (\";base64,\")"));
            };
            return base64_decode(data)
                .ok_or_else(|| self.err(at, "the data URI is not valid base64"));
        }
        let relative = percent_decode(uri)
            .ok_or_else(|| self.err(at, format!("{uri:?} is not a valid percent-encoded URI")))?;
        if let Some(problem) = reference_problem(uri, &relative) {
            return Err(self.err(
                at,
                format!(
                    "{uri:?} {problem}: only data URIs and relative references to files in \
                     the glTF file's directory or below it are read"
                ),
            ));
        }
        let file = self.dir.join(relative);
        let bytes =
            oslf_util::input_file::read(&file, limit).map_err(|e| self.err(at, e.to_string()))?;
        self.files.borrow_mut().push(file);
        Ok(bytes)
    }

    /// Every buffer view within its buffer.
    pub(super) fn check_views(&self) -> Result<()> {
        for view in self.doc.views() {
            let buffer = view.buffer();
            let end = view.offset().checked_add(view.length());
            if end.is_none_or(|e| e > buffer.length()) {
                return Err(self.err(
                    format!("bufferViews[{}]", view.index()),
                    format!(
                        "bytes {}..{} lie outside buffer {}, which has {} bytes",
                        view.offset(),
                        view.offset().saturating_add(view.length()),
                        buffer.index(),
                        buffer.length()
                    ),
                ));
            }
            if let Some(stride) = view.stride() {
                if !(4..=252).contains(&stride) || stride % 4 != 0 {
                    return Err(self.err(
                        format!("bufferViews[{}].byteStride", view.index()),
                        format!("{stride} must be a multiple of 4 in 4..=252"),
                    ));
                }
            }
        }
        Ok(())
    }

    pub(super) fn view_bytes(&self, view: &gltf::buffer::View) -> &[u8] {
        // Checked by `check_views`.
        &self.buffers[view.buffer().index()][view.offset()..view.offset() + view.length()]
    }

    pub(super) fn warn_document(&mut self) {
        let used: Vec<String> = self
            .doc
            .extensions_used()
            .filter(|e| !SUPPORTED_EXTENSIONS.contains(e))
            .map(str::to_string)
            .collect();
        for e in used {
            self.warn(format!(
                "extension {e} is not supported: what it adds is ignored"
            ));
        }
        let animations: Vec<String> = self
            .doc
            .animations()
            .map(|a| label("animations", a.index(), a.name()))
            .collect();
        if !animations.is_empty() {
            self.warn(format!(
                "animations are not supported: the scene is loaded at rest ({})",
                animations.join(", ")
            ));
        }
    }
}

/// Why a URI (`uri` as written, `decoded` its percent-decoded path) is not a relative
/// reference within the glTF file's directory, if it is not: it has a scheme (`file:`,
/// `https:`, a drive letter `C:`), is an absolute path (`/dev/zero`, `\\server\share`) or
/// climbs above the directory with `..`.
pub(super) fn reference_problem(uri: &str, decoded: &str) -> Option<&'static str> {
    // RFC 3986: scheme = ALPHA *( ALPHA / DIGIT / "+" / "-" / "." ) ":", before any "/".
    let head = uri.split(['/', '?', '#']).next().unwrap_or("");
    if let Some((scheme, _)) = head.split_once(':') {
        let mut chars = scheme.chars();
        if chars.next().is_some_and(|c| c.is_ascii_alphabetic())
            && chars.all(|c| c.is_ascii_alphanumeric() || "+-.".contains(c))
        {
            return Some("has a scheme");
        }
    }
    if decoded.starts_with(['/', '\\']) || Path::new(decoded).is_absolute() {
        return Some("is an absolute path");
    }
    let mut depth = 0i32;
    for part in decoded.split(['/', '\\']) {
        match part {
            "" | "." => {}
            ".." => depth -= 1,
            _ => depth += 1,
        }
        if depth < 0 {
            return Some("leaves the glTF file's directory");
        }
    }
    None
}

/// Standard base64 (RFC 4648, `+/`, padding optional, whitespace ignored).
pub(super) fn base64_decode(text: &str) -> Option<Vec<u8>> {
    let mut out = Vec::with_capacity(text.len() * 3 / 4);
    let mut acc = 0u32;
    let mut bits = 0;
    let mut padding = false;
    for c in text.bytes() {
        let v = match c {
            b'A'..=b'Z' => c - b'A',
            b'a'..=b'z' => c - b'a' + 26,
            b'0'..=b'9' => c - b'0' + 52,
            b'+' | b'-' => 62,
            b'/' | b'_' => 63,
            b'=' => {
                padding = true;
                continue;
            }
            b' ' | b'\n' | b'\r' | b'\t' => continue,
            _ => return None,
        };
        if padding {
            return None;
        }
        acc = (acc << 6) | u32::from(v);
        bits += 6;
        if bits >= 8 {
            bits -= 8;
            out.push((acc >> bits) as u8);
            acc &= (1 << bits) - 1;
        }
    }
    Some(out)
}

/// `%XX` escapes decoded (a URI's path, as a file name).
pub(super) fn percent_decode(s: &str) -> Option<String> {
    let bytes = s.as_bytes();
    let mut out = Vec::with_capacity(bytes.len());
    let mut i = 0;
    while i < bytes.len() {
        if bytes[i] == b'%' {
            let hex = std::str::from_utf8(bytes.get(i + 1..i + 3)?).ok()?;
            out.push(u8::from_str_radix(hex, 16).ok()?);
            i += 3;
        } else {
            out.push(bytes[i]);
            i += 1;
        }
    }
    String::from_utf8(out).ok()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn base64_round_trip() {
        assert_eq!(base64_decode("aGVsbG8=").unwrap(), b"hello");
        assert_eq!(base64_decode("aGVsbG8").unwrap(), b"hello");
        assert_eq!(base64_decode("AAEC/w==").unwrap(), [0, 1, 2, 255]);
        assert!(base64_decode("a*b").is_none());
        assert!(base64_decode("aG==VsbG8").is_none());
        assert_eq!(base64_decode("").unwrap(), b"");
    }

    #[test]
    fn references_stay_in_the_directory() {
        for ok in [
            "a.bin",
            "sub/a%20b.bin",
            "./a.bin",
            "sub/../a.bin",
            "./a:b.bin",
        ] {
            let decoded = percent_decode(ok).unwrap();
            assert_eq!(reference_problem(ok, &decoded), None, "{ok}");
        }
        for (bad, problem) in [
            ("/dev/zero", "is an absolute path"),
            ("%2Fdev%2Fzero", "is an absolute path"),
            ("\\\\server\\share\\a.bin", "is an absolute path"),
            ("file:///etc/passwd", "has a scheme"),
            ("file:a.bin", "has a scheme"),
            ("https://example.com/a.bin", "has a scheme"),
            ("C:/a.bin", "has a scheme"),
            ("../a.bin", "leaves the glTF file's directory"),
            ("sub/../../a.bin", "leaves the glTF file's directory"),
            ("%2E%2E/a.bin", "leaves the glTF file's directory"),
        ] {
            let decoded = percent_decode(bad).unwrap();
            assert_eq!(reference_problem(bad, &decoded), Some(problem), "{bad}");
        }
    }

    #[test]
    fn percent_decoding() {
        assert_eq!(percent_decode("a%20b.bin").unwrap(), "a b.bin");
        assert!(percent_decode("a%2").is_none());
        assert!(percent_decode("a%zz").is_none());
    }

    #[test]
    fn glb_container_errors() {
        let p = Path::new("x.glb");
        let mut glb = b"glTF".to_vec();
        assert!(split_glb(p, &glb).is_err());
        glb.extend(2u32.to_le_bytes());
        glb.extend(4u32.to_le_bytes()); // length below the header's 12
        assert!(split_glb(p, &glb).is_err());
        let mut glb = b"glTF".to_vec();
        glb.extend(2u32.to_le_bytes());
        glb.extend(28u32.to_le_bytes());
        glb.extend(1000u32.to_le_bytes()); // a chunk longer than the file
        glb.extend(CHUNK_JSON.to_le_bytes());
        glb.extend([0u8; 8]);
        let e = split_glb(p, &glb).unwrap_err().to_string();
        assert!(e.contains("GLB chunk 0"), "{e}");
    }
}
