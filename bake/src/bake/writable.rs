//! Checking, before any slow work, that the bake's outputs can be written.

use std::path::Path;

use oslf_format::writer::partial_path;
use oslf_scene::error::{BakeError, Result};

/// Checks, without changing any file, that `path` can be written: its directory exists and
/// accepts a new file (a probe file is created there and removed at once), or, if `path`
/// exists, it is a file that opens for writing. `what` names the file in the error
/// ([`BakeError::Unwritable`]). Run it for every output before slow work.
pub fn check_writable(path: &Path, what: &'static str) -> Result<()> {
    check_file_writable(path, path, what)
}

/// [`check_writable`] for the store `output`, which is written through `<output>.partial`
/// and renamed: the partial file must be writable. [`crate::bake::bake`] runs it first.
/// It must not be busy either: [`oslf_format::check_output`] refuses a store whose partial file
/// another writer holds, naming that process, and a path that exists and is not a regular file.
pub fn check_store_writable(output: &Path) -> Result<()> {
    check_file_writable(output, &partial_path(output), "the store")?;
    Ok(oslf_format::check_output(output)?)
}

/// [`check_writable`] for `file`, naming `named` in the error (the store is written through
/// its partial file).
fn check_file_writable(named: &Path, file: &Path, what: &'static str) -> Result<()> {
    let fail = |detail: String| BakeError::Unwritable {
        what,
        path: named.to_path_buf(),
        detail,
    };
    let dir = match file.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    match std::fs::metadata(dir) {
        Ok(m) if m.is_dir() => {}
        Ok(_) => return Err(fail(format!("{} is not a directory", dir.display()))),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
            return Err(fail(format!(
                "the directory {} does not exist",
                dir.display()
            )))
        }
        Err(e) => return Err(fail(format!("{}: {e}", dir.display()))),
    }
    for path in [named, file] {
        match std::fs::metadata(path) {
            Ok(m) if !m.is_file() => {
                return Err(fail(format!(
                "{} exists and is not a regular file ({}); give a path for a new or regular file",
                path.display(),
                oslf_util::input_file::kind(&m.file_type())
            )))
            }
            _ => {}
        }
    }
    if file.exists() {
        // Opening for writing without truncating changes nothing.
        return match std::fs::OpenOptions::new().write(true).open(file) {
            Ok(_) => Ok(()),
            Err(e) => Err(fail(format!("{}: {e}", file.display()))),
        };
    }
    let mut name = std::ffi::OsString::from(".");
    name.push(file.file_name().unwrap_or_default());
    name.push(format!(".{}.probe", std::process::id()));
    let probe = dir.join(name);
    match std::fs::OpenOptions::new()
        .write(true)
        .create_new(true)
        .open(&probe)
    {
        Ok(_) => {
            let _ = std::fs::remove_file(&probe);
            Ok(())
        }
        Err(e) => Err(fail(format!(
            "cannot create a file in {}: {e}",
            dir.display()
        ))),
    }
}
