//! Wavefront OBJ loading (geometry only; materials are assigned by the scene file).

use std::io::{BufRead, Read};
use std::path::Path;

use glam::{Vec2, Vec3};

use crate::input::{read_input, InputKind};
use crate::normals::{shade, NormalRule, NormalsUsed, DEFAULT_CREASE_DEG};
use crate::{BakeError, Result};
use oslf_geometry::mesh::Mesh;

/// A `BufRead` over a byte slice that remembers how far the parser has read, so a parse error
/// can be located at the line where it was detected.
struct CountingReader<'a> {
    data: &'a [u8],
    pos: usize,
}

impl Read for CountingReader<'_> {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        let n = buf.len().min(self.data.len() - self.pos);
        buf[..n].copy_from_slice(&self.data[self.pos..self.pos + n]);
        self.pos += n;
        Ok(n)
    }
}

impl BufRead for CountingReader<'_> {
    fn fill_buf(&mut self) -> std::io::Result<&[u8]> {
        Ok(&self.data[self.pos..])
    }
    fn consume(&mut self, amt: usize) {
        self.pos = (self.pos + amt).min(self.data.len());
    }
}

impl CountingReader<'_> {
    /// 1-based number of the last line handed to the parser.
    fn current_line(&self) -> usize {
        let read = &self.data[..self.pos];
        let newlines = read.iter().filter(|&&b| b == b'\n').count();
        if read.last() == Some(&b'\n') {
            newlines.max(1)
        } else {
            newlines + 1
        }
    }
}

/// Refuses a position (`v`) or texture coordinate (`vt`) with a NaN or infinite component
/// (`nan`, `inf`, `1e39`), at its line and column: the same rule as glTF's `POSITION` and
/// `TEXCOORD_n`. (Normals that are not finite are replaced by computed ones instead.)
fn check_finite(path: &Path, data: &[u8]) -> Result<()> {
    for (i, line) in data.split(|&b| b == b'\n').enumerate() {
        let text = String::from_utf8_lossy(line);
        let mut words = text.split_whitespace();
        let what = match words.next() {
            Some("v") => "position",
            Some("vt") => "texture coordinate",
            _ => continue,
        };
        for word in words {
            if word.parse::<f32>().is_ok_and(|x| !x.is_finite()) {
                let column = word.as_ptr() as usize - text.as_ptr() as usize + 1;
                return Err(BakeError::Parse {
                    path: path.to_path_buf(),
                    line: i + 1,
                    column,
                    message: format!("{what} component {word} is not finite"),
                });
            }
        }
    }
    Ok(())
}

/// Loads all objects of an OBJ file into one mesh with [`load_obj_with`]'s default normals:
/// the file's `vn`, else computed with a crease angle of [`DEFAULT_CREASE_DEG`].
pub fn load_obj(path: &Path) -> Result<Mesh> {
    load_obj_with(path, None).map(|(mesh, _)| mesh)
}

/// Loads all objects of an OBJ file into one mesh: polygons triangulated, one index per
/// vertex; missing uvs are 0; a NaN or infinite position or texture coordinate is an error at
/// its line. Materials and `mtllib` files are ignored.
///
/// Normals: with `requested` (the scene file's `normals` key), computed by that rule for every
/// OBJ object of the file, replacing its `vn`s; without, the file's `vn`s where an OBJ object
/// has usable ones (one per vertex, non-zero and finite), else computed with a crease angle of
/// [`DEFAULT_CREASE_DEG`]. The second value says which rule the mesh got and why.
///
/// Errors name the file; parse errors also give the line where the parser detected them
/// (for index errors that can be the end of the object, as the parser checks them there).
pub fn load_obj_with(path: &Path, requested: Option<NormalRule>) -> Result<(Mesh, NormalsUsed)> {
    let data = read_input(path, InputKind::Mesh)?;
    check_finite(path, &data)?;
    let mut reader = CountingReader {
        data: &data,
        pos: 0,
    };
    let options = tobj::LoadOptions {
        triangulate: true,
        single_index: true,
        ignore_points: true,
        ignore_lines: true,
    };
    let (models, _materials) = tobj::load_obj_buf(&mut reader, &options, |_| {
        Err(tobj::LoadError::GenericFailure)
    })
    .map_err(|e| BakeError::Parse {
        path: path.to_path_buf(),
        line: reader.current_line(),
        column: 1,
        message: format!("OBJ {e}"),
    })?;
    let mut mesh = Mesh::new();
    // OBJ objects with usable `vn` normals.
    let mut with_normals = 0;
    for model in &models {
        let m = &model.mesh;
        let n = m.positions.len() / 3;
        let mut part = Mesh {
            positions: m
                .positions
                .chunks_exact(3)
                .map(|p| Vec3::new(p[0], p[1], p[2]))
                .collect(),
            normals: Vec::new(),
            uvs: if m.texcoords.len() == 2 * n {
                m.texcoords
                    .chunks_exact(2)
                    .map(|t| Vec2::new(t[0], t[1]))
                    .collect()
            } else {
                vec![Vec2::ZERO; n]
            },
            triangles: m
                .indices
                .chunks_exact(3)
                .map(|t| [t[0], t[1], t[2]])
                .collect(),
        };
        if let Some(i) = part.positions.iter().position(|p| !p.is_finite()) {
            return Err(BakeError::Invalid(format!(
                "{}: object {:?}: vertex {} has a non-finite position",
                path.display(),
                model.name,
                i + 1
            )));
        }
        let given: Vec<Vec3> = m
            .normals
            .chunks_exact(3)
            .map(|p| Vec3::new(p[0], p[1], p[2]))
            .collect();
        let usable = given.len() == n
            && given
                .iter()
                .all(|v| v.is_finite() && v.length_squared() > 0.0);
        with_normals += usable as usize;
        match (usable, requested) {
            (true, None) => {
                part.normals = given.into_iter().map(|v| v.normalize_or(Vec3::Z)).collect();
            }
            (_, rule) => {
                let rule = rule.unwrap_or(NormalRule::Crease {
                    crease_deg: DEFAULT_CREASE_DEG,
                });
                part = shade(&part.positions, &part.uvs, &part.triangles, rule).0;
            }
        }
        if let Some(i) = part.uvs.iter().position(|uv| !uv.is_finite()) {
            return Err(BakeError::Invalid(format!(
                "{}: object {:?}: vertex {} has a non-finite texture coordinate",
                path.display(),
                model.name,
                i + 1
            )));
        }
        part.validate().map_err(|e| {
            BakeError::Invalid(format!("{}: object {:?}: {e}", path.display(), model.name))
        })?;
        mesh.append(&part);
    }
    if mesh.triangles.is_empty() {
        return Err(BakeError::Invalid(format!(
            "{}: contains no faces",
            path.display()
        )));
    }
    let used = normals_used(path, requested, with_normals, models.len());
    Ok((mesh, used))
}

/// Which normals an OBJ file's mesh got and why: `requested` (the scene file's key) or the
/// default, where `with_normals` of its `objects` OBJ objects had usable `vn`s.
fn normals_used(
    path: &Path,
    requested: Option<NormalRule>,
    with_normals: usize,
    objects: usize,
) -> NormalsUsed {
    let file = path.file_name().map_or_else(
        || path.display().to_string(),
        |f| f.to_string_lossy().into_owned(),
    );
    let default = NormalRule::Crease {
        crease_deg: DEFAULT_CREASE_DEG,
    };
    let (rule, reason) = match requested {
        Some(rule) if with_normals > 0 => (
            Some(rule),
            format!("asked for in the scene file; replaces {file}'s vn normals"),
        ),
        Some(rule) => (
            Some(rule),
            format!("asked for in the scene file; {file} has no normals"),
        ),
        None if with_normals == objects => (None, format!("{file}'s vn normals")),
        None if with_normals == 0 => (
            Some(default),
            format!("{file} has no normals; the default for OBJ"),
        ),
        None => (
            Some(default),
            format!(
                "{} of {file}'s {objects} OBJ objects have no normals; the default for OBJ \
                 (the others keep their vn normals)",
                objects - with_normals
            ),
        ),
    };
    NormalsUsed { rule, reason }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn write(dir: &Path, name: &str, text: &str) -> std::path::PathBuf {
        let p = dir.join(name);
        std::fs::write(&p, text).unwrap();
        p
    }

    #[test]
    fn loads_quad_and_computes_normals() {
        let tmp = tempfile::tempdir().unwrap();
        let p = write(
            tmp.path(),
            "quad.obj",
            "# quad\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n",
        );
        let m = load_obj(&p).unwrap();
        assert_eq!(m.triangles.len(), 2);
        assert!(m.normals.iter().all(|n| (*n - Vec3::Z).length() < 1e-6));
        assert!(m.uvs.iter().all(|uv| *uv == Vec2::ZERO));
        assert!((m.area() - 1.0).abs() < 1e-6);
    }

    #[test]
    fn non_finite_positions_and_texture_coordinates_are_located_errors() {
        let tmp = tempfile::tempdir().unwrap();
        for (text, line, column, what) in [
            (
                "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt nan 0\nvt 0 1\nf 1/1 2/2 3/3\n",
                5,
                4,
                "texture coordinate component nan",
            ),
            (
                "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0  inf\nf 1/1 2/2 3/3\n",
                6,
                7,
                "texture coordinate component inf",
            ),
            (
                "v 0 0 0\nv 1 1e39 0\nv 0 1 0\nf 1 2 3\n",
                2,
                5,
                "position component 1e39",
            ),
        ] {
            let p = write(tmp.path(), "nan.obj", text);
            match load_obj(&p) {
                Err(e @ BakeError::Parse { .. }) => {
                    let e = e.to_string();
                    assert!(
                        e.contains(&format!("nan.obj:{line}:{column}: {what} is not finite")),
                        "{e}"
                    );
                }
                other => panic!("{other:?}"),
            }
        }
    }

    #[test]
    fn errors_are_located() {
        let tmp = tempfile::tempdir().unwrap();
        let p = write(
            tmp.path(),
            "bad.obj",
            "v 0 0 0\nv 1 0 0\nv 1 x 0\nf 1 2 3\n",
        );
        match load_obj(&p) {
            Err(BakeError::Parse { path, line, .. }) => {
                assert_eq!(path, p);
                assert_eq!(line, 3);
            }
            other => panic!("{other:?}"),
        }
        let missing = tmp.path().join("no-such-file.obj");
        assert!(matches!(
            load_obj(&missing),
            Err(BakeError::Input(oslf_util::UtilError::Input { .. }))
        ));
        let p = write(tmp.path(), "empty.obj", "v 0 0 0\n");
        assert!(load_obj(&p).is_err());
        let p = write(
            tmp.path(),
            "oob.obj",
            "v 0 0 0\nv 1 0 0\nv 1 1 0\nf 1 2 9\n",
        );
        let e = load_obj(&p).unwrap_err().to_string();
        assert!(e.contains("oob.obj"), "{e}");
    }
}
