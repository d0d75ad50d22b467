//! The context of reading one scene file: its text and path (for located errors and
//! relative paths) and the files it includes (for the scene's hash).

use std::ops::Range;
use std::path::{Path, PathBuf};

use toml::Spanned;

use oslf_util::UtilError;

use super::location::line_column;
use crate::error::{BakeError, Result};
use crate::input::{read_input, InputKind};

/// Reading one scene file.
pub(super) struct Ctx<'a> {
    pub(super) text: &'a str,
    pub(super) path: &'a Path,
    /// Every file the scene includes, in reading order (for [`crate::scene::Scene::hash`]).
    pub(super) included: std::cell::RefCell<Vec<PathBuf>>,
}

impl Ctx<'_> {
    /// An error at `span` of the text.
    pub(super) fn error_at(&self, span: Range<usize>, message: impl Into<String>) -> BakeError {
        let (line, column) = line_column(self.text, span.start);
        BakeError::Parse {
            path: self.path.to_path_buf(),
            line,
            column,
            message: message.into(),
        }
    }

    /// Located version of an error from a helper that does not know where it was called from.
    pub(super) fn locate(&self, span: Range<usize>, error: BakeError) -> BakeError {
        match error {
            BakeError::Invalid(message) => self.error_at(span, message),
            other => other,
        }
    }

    /// `relative` resolved against the scene file's directory (an absolute path as it is).
    pub(super) fn resolve(&self, relative: &str) -> PathBuf {
        let p = Path::new(relative);
        if p.is_absolute() {
            p.to_path_buf()
        } else {
            self.path.parent().unwrap_or_else(|| Path::new(".")).join(p)
        }
    }

    /// The file `path` names, which must exist and be a regular file (a directory, FIFO or
    /// device is refused as such, not as missing); recorded as included.
    pub(super) fn existing_file(&self, path: &Spanned<String>) -> Result<PathBuf> {
        let resolved = self.resolve(path.get_ref());
        match oslf_util::input_file::open(&resolved) {
            Ok(_) => {
                self.included.borrow_mut().push(resolved.clone());
                Ok(resolved)
            }
            Err(UtilError::Input { error, .. }) if error.kind() == std::io::ErrorKind::NotFound => {
                Err(self.error_at(
                    path.span(),
                    format!("file not found: {}", resolved.display()),
                ))
            }
            Err(e) => Err(self.error_at(path.span(), e.to_string())),
        }
    }
}

/// [`crate::scene::Scene::hash`]: SHA-256 of `text` and of the SHA-256 of each of `files`, in
/// order.
pub(super) fn scene_hash(text: &[u8], files: &[PathBuf]) -> Result<[u8; 32]> {
    use sha2::Digest;
    let mut hasher = sha2::Sha256::new();
    hasher.update(text);
    for file in files {
        // Every file here was read with the limit of its kind while the scene was built.
        let bytes = read_input(file, InputKind::Included)?;
        hasher.update(sha256(&bytes));
    }
    Ok(hasher.finalize().into())
}

fn sha256(bytes: &[u8]) -> [u8; 32] {
    use sha2::Digest;
    sha2::Sha256::digest(bytes).into()
}
