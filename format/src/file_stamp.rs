//! What a memory-mapped store remembers of its file: size and modification time when it was
//! mapped, to tell afterwards whether the file was written in place ([`crate::Store::changed_since_open`]).

use std::fs::{File, Metadata};
use std::path::{Path, PathBuf};
use std::time::SystemTime;

/// A file's size and modification time at one moment, and its path for messages.
#[derive(Debug)]
pub(crate) struct FileStamp {
    path: PathBuf,
    len: u64,
    modified: Option<SystemTime>,
}

impl FileStamp {
    /// The stamp of `meta`, the metadata of the file at `path`.
    pub(crate) fn of(path: &Path, meta: &Metadata) -> FileStamp {
        FileStamp {
            path: path.to_path_buf(),
            len: meta.len(),
            modified: meta.modified().ok(),
        }
    }

    /// How `file` (the same open file) differs from the stamp now, in words; `None` if its size
    /// and modification time are as they were.
    pub(crate) fn changed(&self, file: &File) -> Option<String> {
        let meta = match file.metadata() {
            Ok(m) => m,
            Err(e) => {
                return Some(format!(
                    "{}: cannot stat the mapped file: {e}",
                    self.path.display()
                ))
            }
        };
        let now = FileStamp::of(&self.path, &meta);
        if (now.len, now.modified) == (self.len, self.modified) {
            return None;
        }
        Some(format!(
            "{} was written in place while it was memory-mapped ({} bytes when opened, {} now{}): what was read may be of neither version",
            self.path.display(),
            self.len,
            now.len,
            if now.len == self.len {
                ", modification time changed"
            } else {
                ""
            }
        ))
    }
}
