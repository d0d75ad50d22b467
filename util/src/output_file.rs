//! The one way out: every file oslf writes, other than a store (whose writer in `oslf-format`
//! writes `<path>.partial` under a lock and renames it), is written by [`write_with`].
//!
//! - The path must be absent or a regular file (a symbolic link is followed to the file it
//!   names): a directory, device, FIFO or socket there is refused before a byte is written,
//!   and left as it was.
//! - The bytes go to a new temporary file beside the target (created exclusively, so nothing
//!   that exists is ever opened for writing), which is flushed and synced; every write, the
//!   flush and the sync are checked. Only then is it renamed over the target, and the
//!   directory synced.
//! - On any failure the temporary file, which this module created, is removed; nothing else
//!   is ever deleted, and the target keeps what it had.

use std::fs::File;
use std::io::{BufWriter, ErrorKind, Write as _};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

use crate::error::{Result, UtilError};
use crate::input_file::kind;

/// Writes the file at `path` with `write`, through a temporary file beside it renamed into
/// place (see the module's docs). `write` gets a buffered writer that also seeks (image
/// encoders need both); it is flushed and synced after `write` returns.
///
/// # Errors
///
/// [`UtilError::OutputNotRegular`] for a target that exists and is not a regular file;
/// [`UtilError::Output`] naming `path` for any failed write, flush, sync or rename (and for an
/// error `write` returns).
pub fn write_with(
    path: &Path,
    write: impl FnOnce(&mut BufWriter<File>) -> std::io::Result<()>,
) -> Result<()> {
    let target = target(path)?;
    let tmp = temporary_beside(&target);
    let fail = |error: std::io::Error| UtilError::Output {
        path: path.to_path_buf(),
        error,
    };
    let file = std::fs::OpenOptions::new()
        .write(true)
        .create_new(true)
        .open(&tmp)
        .map_err(fail)?;
    let result = (|| {
        let mut out = BufWriter::new(file);
        write(&mut out)?;
        out.flush()?;
        let file = out.into_inner().map_err(|e| e.into_error())?;
        file.sync_all()?;
        drop(file);
        // The target may have been swapped for a device or FIFO while the bytes were written:
        // check again right before the rename, which would replace it.
        refuse_non_regular(path, &target).map_err(std::io::Error::other)?;
        std::fs::rename(&tmp, &target)?;
        sync_directory(&target)
    })();
    if let Err(error) = result {
        // Only the temporary file this call created, never the target.
        let _ = std::fs::remove_file(&tmp);
        return Err(match error.downcast::<UtilError>() {
            Ok(e) => e,
            Err(error) => fail(error),
        });
    }
    Ok(())
}

/// [`write_with`] of `bytes`.
pub fn write_bytes(path: &Path, bytes: &[u8]) -> Result<()> {
    write_with(path, |out| out.write_all(bytes))
}

/// Checks, without writing, that `path` may be written: absent, or a regular file (through
/// symbolic links). What [`crate::door::Door`] runs for every output before any work.
pub fn check_target(path: &Path) -> Result<()> {
    target(path).map(|_| ())
}

/// The file a write of `path` replaces: `path` itself, or for a symbolic link the file it
/// names (the link stays a link). Errors if that exists and is not a regular file.
fn target(path: &Path) -> Result<PathBuf> {
    if path.file_name().is_none() {
        return Err(UtilError::Output {
            path: path.to_path_buf(),
            error: std::io::Error::new(ErrorKind::InvalidInput, "names no file"),
        });
    }
    let target = match std::fs::symlink_metadata(path) {
        Ok(m) if m.file_type().is_symlink() => match std::fs::canonicalize(path) {
            Ok(resolved) => resolved,
            // A dangling link: the write creates the file it names.
            Err(_) => resolve_dangling(path),
        },
        _ => path.to_path_buf(),
    };
    refuse_non_regular(path, &target)?;
    Ok(target)
}

/// The path a dangling symbolic link `path` names (relative to its directory); `path` itself
/// if it is no link.
pub(crate) fn resolve_dangling(path: &Path) -> PathBuf {
    match std::fs::read_link(path) {
        Ok(to) if to.is_absolute() => to,
        Ok(to) => path.parent().unwrap_or_else(|| Path::new(".")).join(to),
        Err(_) => path.to_path_buf(),
    }
}

fn refuse_non_regular(path: &Path, target: &Path) -> Result<()> {
    match std::fs::metadata(target) {
        Ok(m) if !m.is_file() => Err(UtilError::OutputNotRegular {
            role: "the output".into(),
            path: path.to_path_buf(),
            kind: kind(&m.file_type()),
        }),
        _ => Ok(()),
    }
}

/// A name for a new temporary file beside `target`: hidden, with the process id and a counter
/// (two writes of one process never share it).
fn temporary_beside(target: &Path) -> PathBuf {
    static NEXT: AtomicU64 = AtomicU64::new(0);
    let n = NEXT.fetch_add(1, Ordering::Relaxed);
    let name = target.file_name().unwrap_or_default().to_string_lossy();
    target.with_file_name(format!(".{name}.{}.{n}.tmp", std::process::id()))
}

/// Syncs the directory of `path`, so that the rename survives a crash.
fn sync_directory(path: &Path) -> std::io::Result<()> {
    #[cfg(unix)]
    {
        let dir = match path.parent() {
            Some(p) if !p.as_os_str().is_empty() => p,
            _ => Path::new("."),
        };
        File::open(dir)?.sync_all()
    }
    #[cfg(not(unix))]
    {
        let _ = path;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn names(dir: &Path) -> Vec<String> {
        let mut n: Vec<String> = std::fs::read_dir(dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().into_string().unwrap())
            .collect();
        n.sort();
        n
    }

    #[test]
    fn writes_replace_regular_files_whole_and_follow_links() {
        let tmp = tempfile::tempdir().unwrap();
        let dir = tmp.path();
        let a = dir.join("a.txt");
        write_bytes(&a, b"first").unwrap();
        write_bytes(&a, b"second").unwrap();
        assert_eq!(std::fs::read(&a).unwrap(), b"second");
        #[cfg(unix)]
        {
            let link = dir.join("link.txt");
            std::os::unix::fs::symlink(&a, &link).unwrap();
            write_bytes(&link, b"through the link").unwrap();
            assert!(std::fs::symlink_metadata(&link)
                .unwrap()
                .file_type()
                .is_symlink());
            assert_eq!(std::fs::read(&a).unwrap(), b"through the link");
        }
        assert!(names(dir).iter().all(|n| !n.ends_with(".tmp")));
    }

    /// A failing writer leaves the target as it was and removes only its temporary file.
    #[test]
    fn a_failed_write_changes_nothing_and_leaves_nothing() {
        let tmp = tempfile::tempdir().unwrap();
        let dir = tmp.path();
        let a = dir.join("a.txt");
        write_bytes(&a, b"keep").unwrap();
        let e = write_with(&a, |out| {
            out.write_all(b"half")?;
            Err(std::io::Error::other("disk full"))
        })
        .unwrap_err()
        .to_string();
        assert!(e.contains("a.txt") && e.contains("disk full"), "{e}");
        assert_eq!(std::fs::read(&a).unwrap(), b"keep");
        assert_eq!(names(dir), ["a.txt"]);
    }

    /// Devices, FIFOs and directories are refused, named, and kept.
    #[cfg(unix)]
    #[test]
    fn devices_fifos_and_directories_are_refused_and_kept() {
        use rustix::fs::{mkfifoat, Mode, CWD};
        let tmp = tempfile::tempdir().unwrap();
        let dir = tmp.path();
        let fifo = dir.join("pipe.png");
        mkfifoat(CWD, &fifo, Mode::from_raw_mode(0o600)).unwrap();
        let sub = dir.join("sub.exr");
        std::fs::create_dir(&sub).unwrap();
        for (path, kind) in [(&fifo, "a FIFO"), (&sub, "a directory")] {
            let e = write_bytes(path, b"x").unwrap_err().to_string();
            assert!(
                e.contains(&path.display().to_string()) && e.contains(kind),
                "{e}"
            );
            assert!(check_target(path).is_err());
        }
        let link = dir.join("to-fifo");
        std::os::unix::fs::symlink(&fifo, &link).unwrap();
        assert!(write_bytes(&link, b"x").is_err());
        assert_eq!(names(dir), ["pipe.png", "sub.exr", "to-fifo"]);
        use std::os::unix::fs::FileTypeExt as _;
        assert!(std::fs::metadata(&fifo).unwrap().file_type().is_fifo());
    }
}
