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
    /// An output that is an input of the same command ([`crate::door::Door`]).
    #[error("{output_role} {} is {input_role} {} (the same file): a command never writes over its own input; give the output another path", .output.display(), .input.display())]
    OutputIsInput {
        output_role: String,
        output: PathBuf,
        input_role: String,
        input: PathBuf,
    },
    /// Two outputs of one command that are one file ([`crate::door::Door`]).
    #[error("{first_role} {} and {second_role} {} are the same file: each output needs a path of its own", .first.display(), .second.display())]
    SameOutput {
        first_role: String,
        first: PathBuf,
        second_role: String,
        second: PathBuf,
    },
}

pub type Result<T> = std::result::Result<T, UtilError>;
