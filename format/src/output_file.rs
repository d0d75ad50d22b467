//! The file a writer makes ([`crate::StoreWriter`], [`crate::ShardWriter`], and through them
//! `merge` and `convert`): it writes `<path>.partial` and renames it over `path` when finished.
//!
//! Two writers of one path would share the partial file and leave a store made of both, so a
//! writer holds an exclusive advisory lock (`flock`) on its partial file from opening it until
//! after the rename; a second writer is refused with [`Error::Busy`], which names the process
//! holding the lock where the system says (Linux's `/proc/locks`). The path must be absent or a
//! regular file: the rename would replace a device, a FIFO or a directory entry that is not a
//! store, so those are refused with [`Error::NotRegularFile`] before anything is written.

use std::fs::{File, Metadata, OpenOptions, TryLockError};
use std::io::{ErrorKind, Read};
use std::os::unix::fs::{FileTypeExt, MetadataExt};
use std::path::{Path, PathBuf};

use crate::error::{io_at, Error};

/// `<path>.partial`, beside `path`.
pub fn partial_path(path: &Path) -> PathBuf {
    let mut name = path
        .file_name()
        .map(|n| n.to_os_string())
        .unwrap_or_default();
    name.push(".partial");
    path.with_file_name(name)
}

/// How [`open_partial`] opens the partial file.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Open {
    /// Creates it, or empties an old one (after taking the lock).
    Create,
    /// Opens an existing one as it is ([`Error::NoPartial`] if there is none).
    Resume,
}

/// Checks that a writer may write `path`: it and its partial file are absent or regular files,
/// and no other writer holds the partial file. For callers that want to refuse before long work;
/// the writers check again, under the lock, when they open the partial file.
pub fn check_output(path: &Path) -> Result<(), Error> {
    check_regular(path)?;
    let partial = partial_path(path);
    check_regular(&partial)?;
    let file = match OpenOptions::new().read(true).open(&partial) {
        Ok(f) => f,
        Err(e) if e.kind() == ErrorKind::NotFound => return Ok(()),
        Err(e) => return Err(io_at(&partial, "open")(e)),
    };
    lock(&file, path, &partial)
    // Dropping `file` releases the lock.
}

/// Whether `a` and `b` name the same file (device and inode, so `./t.oslf`, a hard link and a
/// symbolic link all count as `t.oslf`). `false` when either does not exist.
pub fn same_file(a: &Path, b: &Path) -> bool {
    match (std::fs::metadata(a), std::fs::metadata(b)) {
        (Ok(a), Ok(b)) => a.dev() == b.dev() && a.ino() == b.ino(),
        _ => false,
    }
}

/// [`Error::SameFile`] if the output `output` (or its partial file) is the input `input`.
pub fn check_not_input(input: &Path, output: &Path) -> Result<(), Error> {
    if same_file(input, output) || same_file(input, &partial_path(output)) {
        return Err(Error::SameFile {
            input: input.to_path_buf(),
            output: output.to_path_buf(),
        });
    }
    Ok(())
}

/// Opens `<path>.partial` (the path `partial`) for reading and writing under an exclusive
/// lock held as long as the returned file is open. With [`Open::Create`] the file is emptied
/// once the lock is held, never before (a second writer must not destroy the first's work).
pub(crate) fn open_partial(path: &Path, partial: &Path, open: Open) -> Result<File, Error> {
    check_regular(path)?;
    // A writer that finishes renames its locked partial file to `path`, so a file locked after
    // it was opened may no longer be the one named `partial`: check, and open again if not.
    for _ in 0..16 {
        check_regular(partial)?;
        let file = match OpenOptions::new()
            .read(true)
            .write(true)
            .create(open == Open::Create)
            .truncate(false)
            .open(partial)
        {
            Ok(f) => f,
            Err(e) if e.kind() == ErrorKind::NotFound && open == Open::Resume => {
                return Err(Error::NoPartial(partial.to_path_buf()))
            }
            Err(e) => return Err(io_at(partial, "open")(e)),
        };
        let meta = file.metadata().map_err(io_at(partial, "stat"))?;
        if !meta.is_file() {
            return Err(not_regular(partial, &meta));
        }
        lock(&file, path, partial)?;
        match std::fs::symlink_metadata(partial) {
            Ok(m) if m.dev() == meta.dev() && m.ino() == meta.ino() => {}
            _ => continue,
        }
        if open == Open::Create {
            file.set_len(0).map_err(io_at(partial, "truncate"))?;
        }
        return Ok(file);
    }
    Err(Error::Busy {
        path: path.to_path_buf(),
        partial: partial.to_path_buf(),
        holder: "other writers that keep replacing it".into(),
    })
}

/// Takes the exclusive lock on `file` (the partial file `partial` of `path`) without waiting.
fn lock(file: &File, path: &Path, partial: &Path) -> Result<(), Error> {
    match file.try_lock() {
        Ok(()) => Ok(()),
        Err(TryLockError::WouldBlock) => Err(Error::Busy {
            path: path.to_path_buf(),
            partial: partial.to_path_buf(),
            holder: file
                .metadata()
                .ok()
                .and_then(|m| holder(&m))
                .unwrap_or_else(|| "another process".into()),
        }),
        Err(TryLockError::Error(e)) => Err(io_at(partial, "lock")(e)),
    }
}

/// [`Error::NotRegularFile`] if `path` exists and is not a regular file (a symbolic link is
/// refused as such: the rename would replace the link, not what it points to).
fn check_regular(path: &Path) -> Result<(), Error> {
    match std::fs::symlink_metadata(path) {
        Ok(m) if m.is_file() => Ok(()),
        Ok(m) => Err(not_regular(path, &m)),
        Err(e) if e.kind() == ErrorKind::NotFound => Ok(()),
        Err(e) => Err(io_at(path, "stat")(e)),
    }
}

fn not_regular(path: &Path, meta: &Metadata) -> Error {
    let t = meta.file_type();
    let kind = if t.is_dir() {
        "a directory"
    } else if t.is_symlink() {
        "a symbolic link"
    } else if t.is_char_device() {
        "a character device"
    } else if t.is_block_device() {
        "a block device"
    } else if t.is_fifo() {
        "a FIFO"
    } else if t.is_socket() {
        "a socket"
    } else {
        "not a regular file"
    };
    Error::NotRegularFile {
        path: path.to_path_buf(),
        kind,
    }
}

/// Reads of `/proc/locks` [`holder`] makes before it gives up.
const LOCKS_READS: u32 = 8;

/// The process holding a `flock` on the file of `meta`, as `process 1234 (oslf bake …)`, from
/// Linux's `/proc/locks` and `/proc/PID/cmdline`; `None` where the system does not say.
pub(crate) fn holder(meta: &Metadata) -> Option<String> {
    let (major, minor) = dev_numbers(meta.dev());
    let id = format!("{major:02x}:{minor:02x}:{}", meta.ino());
    // A lock taken or released elsewhere while `/proc/locks` is read can hide other locks
    // from that read (seen with tests locking in parallel): read it again before giving up.
    let mut tries = 0;
    let pid = loop {
        let locks = read_bounded(Path::new("/proc/locks"), 4 << 20)?;
        match flock_pid(&String::from_utf8_lossy(&locks), &id, meta.ino()) {
            Some(pid) => break pid,
            None if tries < LOCKS_READS => tries += 1,
            None => return None,
        }
    };
    let command = read_bounded(Path::new(&format!("/proc/{pid}/cmdline")), 4096)
        .map(|c| {
            let words: Vec<String> = c
                .split(|&b| b == 0)
                .filter(|w| !w.is_empty())
                .map(|w| String::from_utf8_lossy(w).into_owned())
                .collect();
            words.join(" ")
        })
        .filter(|c| !c.is_empty());
    let me = if pid == std::process::id() {
        ", this process"
    } else {
        ""
    };
    Some(match command {
        Some(c) => format!("process {pid} ({c}{me})"),
        None => format!("process {pid}{me}"),
    })
}

/// The process that `/proc/locks` (`text`) lists as holding a `flock` on `id` ("fd:01:5678").
/// Overlay file systems (containers' `/tmp`) list the layer's inode, whose device differs from
/// the one `stat` reports: where no lock names `id`, one lock alone naming inode `ino` counts.
fn flock_pid(text: &str, id: &str, ino: u64) -> Option<u32> {
    // "1: FLOCK  ADVISORY  WRITE 1234 fd:01:5678 0 EOF" as (1234, "fd:01:5678").
    let flocks: Vec<(u32, &str)> = text
        .lines()
        .filter_map(|line| {
            let f: Vec<&str> = line.split_whitespace().collect();
            (f.get(1) == Some(&"FLOCK")).then_some(())?;
            Some((f.get(4)?.parse().ok()?, *f.get(5)?))
        })
        .collect();
    if let Some((pid, _)) = flocks.iter().find(|(_, lock)| *lock == id) {
        return Some(*pid);
    }
    let ino = format!(":{ino}");
    match flocks
        .iter()
        .filter(|(_, lock)| lock.ends_with(&ino))
        .collect::<Vec<_>>()
        .as_slice()
    {
        [(pid, _)] => Some(*pid),
        _ => None,
    }
}

/// glibc's `major()` and `minor()` of a `st_dev`.
fn dev_numbers(dev: u64) -> (u64, u64) {
    let major = ((dev >> 8) & 0xfff) | ((dev >> 32) & !0xfff);
    let minor = (dev & 0xff) | ((dev >> 12) & !0xff);
    (major, minor)
}

/// At most `limit` bytes of `path`; `None` on any error.
fn read_bounded(path: &Path, limit: u64) -> Option<Vec<u8>> {
    let mut bytes = Vec::new();
    File::open(path)
        .ok()?
        .take(limit)
        .read_to_end(&mut bytes)
        .ok()?;
    Some(bytes)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_locked_partial_file_is_refused_and_named() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("s.oslf");
        let partial = partial_path(&path);
        let first = open_partial(&path, &partial, Open::Create).unwrap();
        for open in [Open::Create, Open::Resume] {
            let e = open_partial(&path, &partial, open).unwrap_err();
            let Error::Busy { holder, .. } = &e else {
                panic!("{e}")
            };
            // Where the system lists this process's lock, the message names this process.
            let me = std::process::id().to_string();
            let listed = std::fs::read_to_string("/proc/locks").is_ok_and(|l| {
                l.lines()
                    .any(|l| l.contains("FLOCK") && l.split_whitespace().nth(4) == Some(&me))
            });
            assert!(!listed || holder.contains(&format!("process {me}")), "{e}");
        }
        assert!(matches!(check_output(&path), Err(Error::Busy { .. })));
        drop(first);
        check_output(&path).unwrap();
        open_partial(&path, &partial, Open::Resume).unwrap();
    }

    #[test]
    fn lock_holders_are_found_by_device_and_inode_or_inode_alone() {
        let locks = "1: FLOCK  ADVISORY  WRITE 41 00:2f:77 0 EOF\n\
                     2: POSIX  ADVISORY  WRITE 42 fd:01:5678 0 EOF\n\
                     3: FLOCK  ADVISORY  WRITE 43 fd:01:5678 0 EOF\n\
                     4: FLOCK  ADVISORY  WRITE 44 08:01:5678 0 EOF\n";
        assert_eq!(flock_pid(locks, "fd:01:5678", 5678), Some(43));
        // An overlay's device differs: the one lock on inode 77 is it.
        assert_eq!(flock_pid(locks, "00:30:77", 77), Some(41));
        // Two locks on inode 5678 elsewhere: no guess.
        assert_eq!(flock_pid(locks, "00:30:5678", 5678), None);
        assert_eq!(flock_pid(locks, "00:30:99", 99), None);
        // Inode 7 is not inode 77.
        assert_eq!(flock_pid(locks, "00:30:7", 7), None);
    }

    #[test]
    fn creating_empties_only_after_the_lock() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("s.oslf");
        let partial = partial_path(&path);
        let first = open_partial(&path, &partial, Open::Create).unwrap();
        std::fs::write(&partial, b"first writer's bytes").unwrap();
        open_partial(&path, &partial, Open::Create).unwrap_err();
        assert_eq!(std::fs::read(&partial).unwrap(), b"first writer's bytes");
        drop(first);
        let second = open_partial(&path, &partial, Open::Create).unwrap();
        assert_eq!(second.metadata().unwrap().len(), 0);
    }

    #[test]
    fn only_regular_files_are_outputs() {
        let dir = tempfile::tempdir().unwrap();
        for (path, kind) in [
            (Path::new("/dev/null").to_path_buf(), "a character device"),
            (dir.path().to_path_buf(), "a directory"),
        ] {
            let e = check_output(&path).unwrap_err();
            assert!(
                matches!(&e, Error::NotRegularFile { kind: k, .. } if *k == kind),
                "{e}"
            );
            let e = open_partial(&path, &partial_path(&path), Open::Create).unwrap_err();
            assert!(matches!(e, Error::NotRegularFile { .. }), "{e}");
        }
        let path = dir.path().join("s.oslf");
        std::fs::create_dir(partial_path(&path)).unwrap();
        let e = open_partial(&path, &partial_path(&path), Open::Create).unwrap_err();
        assert!(matches!(e, Error::NotRegularFile { .. }), "{e}");
        let target = dir.path().join("elsewhere");
        std::fs::write(&target, b"keep").unwrap();
        let linked = dir.path().join("l.oslf");
        std::os::unix::fs::symlink(&target, partial_path(&linked)).unwrap();
        let e = open_partial(&linked, &partial_path(&linked), Open::Create).unwrap_err();
        assert!(
            matches!(
                e,
                Error::NotRegularFile {
                    kind: "a symbolic link",
                    ..
                }
            ),
            "{e}"
        );
        assert_eq!(std::fs::read(&target).unwrap(), b"keep");
    }

    #[test]
    fn files_are_compared_by_identity() {
        let dir = tempfile::tempdir().unwrap();
        let a = dir.path().join("t.oslf");
        std::fs::write(&a, b"x").unwrap();
        let dotted = dir.path().join(".").join("t.oslf");
        let linked = dir.path().join("u.oslf");
        std::fs::hard_link(&a, &linked).unwrap();
        assert!(same_file(&a, &dotted) && same_file(&a, &linked));
        assert!(matches!(
            check_not_input(&a, &dotted),
            Err(Error::SameFile { .. })
        ));
        let other = dir.path().join("v.oslf");
        assert!(!same_file(&a, &other));
        check_not_input(&a, &other).unwrap();
        std::fs::write(partial_path(&other), b"y").unwrap();
        check_not_input(&a, &other).unwrap();
        assert!(check_not_input(&partial_path(&other), &other).is_err());
    }
}
