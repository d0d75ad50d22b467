//! The one error type of `oslf-util`.

use std::path::PathBuf;

/// What went wrong, and with which file.
#[derive(Debug, thiserror::Error)]
pub enum UtilError {
    /// An image could not be written (or its pixels do not make the image asked for).
    #[error("{}: {message}", .path.display())]
    Image { path: PathBuf, message: String },
    /// An input file that cannot be opened or read (missing, no permission). The I/O error is
    /// part of the message, not a source, so that a chain of causes prints it once.
    #[error("{}: {error}", .path.display())]
    Input {
        path: PathBuf,
        error: std::io::Error,
    },
    /// An input path that names a directory, FIFO, device or socket
    /// ([`crate::input_file::read`]); `kind` says which.
    #[error("not a regular file: {} ({kind}); inputs are read from regular files only", .path.display())]
    NotRegular { path: PathBuf, kind: &'static str },
    /// An input file larger than its bound: `bound` says what the bound is ("the 64 MiB
    /// allowed for a scene file", "declared (...)"), `limit` its bytes.
    #[error("{} is larger than {bound}: it has {size} bytes, at most {limit} are read", .path.display())]
    TooLarge {
        path: PathBuf,
        size: u64,
        limit: u64,
        bound: String,
    },
}

pub type Result<T> = std::result::Result<T, UtilError>;
