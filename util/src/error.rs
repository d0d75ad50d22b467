//! The one error type of `oslf-util`.

use std::path::PathBuf;

/// Two declared files of one command that are one file: their roles ("--output", "SCENE")
/// and paths as given.
#[derive(Debug)]
pub struct Conflict {
    pub first_role: String,
    pub first: PathBuf,
    pub second_role: String,
    pub second: PathBuf,
}

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
    /// An output file that could not be written: the open, a write, the flush, the sync or the
    /// rename failed ([`crate::output_file`]).
    #[error("cannot write {}: {error}", .path.display())]
    Output {
        path: PathBuf,
        error: std::io::Error,
    },
    /// An output path that exists and is not a regular file; it is left as it is.
    #[error("{role} {}: exists and is not a regular file ({kind}); outputs are written to new or regular files only, and this one is left as it is", .path.display())]
    OutputNotRegular {
        role: String,
        path: PathBuf,
        kind: &'static str,
    },
    /// An output directory path that exists and is not a directory.
    #[error("{role} {}: exists and is not a directory ({kind})", .path.display())]
    OutputNotDirectory {
        role: String,
        path: PathBuf,
        kind: &'static str,
    },
    /// An output that is an input of the same command ([`crate::door::Door`]): `first` is the
    /// output, `second` the input.
    #[error("{} {} is {} {} (the same file): a command never writes over its own input; give the output another path", .0.first_role, .0.first.display(), .0.second_role, .0.second.display())]
    OutputIsInput(Box<Conflict>),
    /// Two outputs of one command that are one file ([`crate::door::Door`]).
    #[error("{} {} and {} {} are the same file: each output needs a path of its own", .0.first_role, .0.first.display(), .0.second_role, .0.second.display())]
    SameOutput(Box<Conflict>),
}

pub type Result<T> = std::result::Result<T, UtilError>;
