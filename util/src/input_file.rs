//! Reading input files with bounds: only regular files, and at most a given number of bytes.
//!
//! A path handed to a program (a scene, a mesh, a texture, a buffer a glTF file names) can
//! name a device that never ends (`/dev/zero`), a FIFO that blocks the reader forever, or a
//! directory. [`read`] refuses all of these before reading a byte, and reads a regular file
//! only up to a limit, so that no input can exhaust memory or hang the program. Every error
//! names the file.
//!
//! The path is checked with `stat` first (so that no device is even opened), then opened with
//! `O_NONBLOCK` (so that a FIFO swapped in after the check cannot block the open) and checked
//! again with `fstat` on the open file, which is what is read.

use std::fs::File;
use std::io::Read as _;
use std::path::Path;

use crate::error::{Result, UtilError};

/// The most bytes a read may take, and what that bound is, for the message when a file is
/// larger: "the 64 MiB allowed for a scene file", "declared (byteLength 1024 + 4096 bytes)".
#[derive(Clone, Debug)]
pub struct Limit {
    pub bytes: u64,
    pub bound: String,
}

impl Limit {
    pub fn new(bytes: u64, bound: impl Into<String>) -> Limit {
        Limit {
            bytes,
            bound: bound.into(),
        }
    }
}

/// The whole content of the regular file at `path`, if it has at most `limit.bytes` bytes.
///
/// Errors: [`UtilError::Input`] if the path cannot be opened or read (it does not exist, no
/// permission), [`UtilError::NotRegular`] if it names a directory, FIFO, device or socket,
/// [`UtilError::TooLarge`] if the file has more than `limit.bytes` bytes (also when it grows
/// past them while being read).
pub fn read(path: &Path, limit: &Limit) -> Result<Vec<u8>> {
    let (file, len) = open(path)?;
    if len > limit.bytes {
        return Err(too_large(path, len, limit));
    }
    let mut bytes = Vec::with_capacity(len as usize);
    file.take(limit.bytes.saturating_add(1))
        .read_to_end(&mut bytes)
        .map_err(|error| input_error(path, error))?;
    if bytes.len() as u64 > limit.bytes {
        return Err(too_large(path, bytes.len() as u64, limit));
    }
    Ok(bytes)
}

/// The regular file at `path`, opened for reading, if it has at most `limit.bytes` bytes (for
/// readers that stream a file rather than take it whole).
pub fn open_within(path: &Path, limit: &Limit) -> Result<File> {
    let (file, len) = open(path)?;
    if len > limit.bytes {
        return Err(too_large(path, len, limit));
    }
    Ok(file)
}

/// The regular file at `path`, opened for reading, and its length in bytes.
pub fn open(path: &Path) -> Result<(File, u64)> {
    let before = std::fs::metadata(path).map_err(|error| input_error(path, error))?;
    check_regular(path, &before)?;
    let file = open_nonblocking(path).map_err(|error| input_error(path, error))?;
    let opened = file.metadata().map_err(|error| input_error(path, error))?;
    check_regular(path, &opened)?;
    Ok((file, opened.len()))
}

#[cfg(unix)]
fn open_nonblocking(path: &Path) -> std::io::Result<File> {
    use std::os::unix::fs::OpenOptionsExt as _;
    let flags = rustix::fs::OFlags::NONBLOCK | rustix::fs::OFlags::NOCTTY;
    std::fs::OpenOptions::new()
        .read(true)
        .custom_flags(flags.bits() as i32)
        .open(path)
}

#[cfg(not(unix))]
fn open_nonblocking(path: &Path) -> std::io::Result<File> {
    File::open(path)
}

fn check_regular(path: &Path, metadata: &std::fs::Metadata) -> Result<()> {
    if metadata.is_file() {
        return Ok(());
    }
    Err(UtilError::NotRegular {
        path: path.to_path_buf(),
        kind: kind(&metadata.file_type()),
    })
}

/// What a file that is not a regular file is, in words (`a FIFO`, `a directory`, ...).
pub fn kind(t: &std::fs::FileType) -> &'static str {
    if t.is_dir() {
        return "a directory";
    }
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt as _;
        if t.is_fifo() {
            return "a FIFO";
        }
        if t.is_char_device() {
            return "a character device";
        }
        if t.is_block_device() {
            return "a block device";
        }
        if t.is_socket() {
            return "a socket";
        }
    }
    "neither a regular file nor a directory"
}

fn input_error(path: &Path, error: std::io::Error) -> UtilError {
    UtilError::Input {
        path: path.to_path_buf(),
        error,
    }
}

fn too_large(path: &Path, size: u64, limit: &Limit) -> UtilError {
    UtilError::TooLarge {
        path: path.to_path_buf(),
        size,
        limit: limit.bytes,
        bound: limit.bound.clone(),
    }
}

/// `bytes` in words for messages and limits: "64 MiB", "1 GiB", "4096 bytes".
pub fn byte_size(bytes: u64) -> String {
    const UNITS: [(u64, &str); 3] = [(1 << 30, "GiB"), (1 << 20, "MiB"), (1 << 10, "KiB")];
    for (unit, name) in UNITS {
        if bytes >= unit && bytes.is_multiple_of(unit) {
            return format!("{} {name}", bytes / unit);
        }
    }
    format!("{bytes} bytes")
}

#[cfg(test)]
mod tests {
    use super::*;

    fn limit(bytes: u64) -> Limit {
        Limit::new(bytes, format!("the {} allowed", byte_size(bytes)))
    }

    #[test]
    fn reads_a_regular_file_within_its_limit() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("a.txt");
        std::fs::write(&path, b"hello").unwrap();
        assert_eq!(read(&path, &limit(5)).unwrap(), b"hello");
        let e = read(&path, &limit(4)).unwrap_err().to_string();
        assert!(
            e.contains("a.txt is larger than the 4 bytes allowed"),
            "{e}"
        );
        assert!(e.contains("5 bytes"), "{e}");
    }

    #[test]
    fn refuses_what_is_not_a_regular_file_naming_it() {
        let dir = tempfile::tempdir().unwrap();
        let e = read(dir.path(), &limit(1 << 20)).unwrap_err().to_string();
        assert!(e.starts_with("not a regular file: "), "{e}");
        assert!(e.contains("(a directory)"), "{e}");
        #[cfg(unix)]
        {
            let e = read(Path::new("/dev/zero"), &limit(1 << 20))
                .unwrap_err()
                .to_string();
            assert!(e.contains("/dev/zero (a character device)"), "{e}");
        }
        let missing = dir.path().join("missing.bin");
        let e = read(&missing, &limit(1)).unwrap_err().to_string();
        assert!(e.contains("missing.bin"), "{e}");
        assert!(matches!(
            read(&missing, &limit(1)),
            Err(UtilError::Input { .. })
        ));
    }

    /// A FIFO with no writer would block a plain `open` forever: it is refused at once. The
    /// read runs on a thread so that a regression fails the test instead of hanging it.
    #[cfg(unix)]
    #[test]
    fn refuses_a_fifo_without_blocking() {
        let dir = tempfile::tempdir().unwrap();
        let fifo = dir.path().join("pipe");
        rustix::fs::mkfifoat(
            rustix::fs::CWD,
            &fifo,
            rustix::fs::Mode::from_raw_mode(0o600),
        )
        .unwrap();
        let (tx, rx) = std::sync::mpsc::channel();
        let path = fifo.clone();
        std::thread::spawn(move || {
            let _ = tx.send(read(&path, &limit(1 << 20)).map_err(|e| e.to_string()));
        });
        let e = rx
            .recv_timeout(std::time::Duration::from_secs(10))
            .expect("reading a FIFO blocked")
            .unwrap_err();
        assert!(e.contains("not a regular file"), "{e}");
        assert!(e.contains("(a FIFO)"), "{e}");
    }

    #[test]
    fn byte_sizes_in_words() {
        assert_eq!(byte_size(64 << 20), "64 MiB");
        assert_eq!(byte_size(1 << 30), "1 GiB");
        assert_eq!(byte_size(4096), "4 KiB");
        assert_eq!(byte_size(1000), "1000 bytes");
    }
}
