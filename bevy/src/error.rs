//! The crate's one error type.

/// What went wrong loading or drawing an OSLF object.
#[derive(Debug, thiserror::Error)]
pub enum OslfBevyError {
    /// The asset's bytes could not be read.
    #[error("{path}: reading the store: {source}")]
    Read {
        path: String,
        #[source]
        source: std::io::Error,
    },
    /// The bytes are not a valid store (the format crate's message: which section, which
    /// byte offset).
    #[error("{path}: {source}")]
    Store {
        path: String,
        #[source]
        source: oslf_format::Error,
    },
    /// The runtime refused the store, the view or the parameters.
    #[error("{0}")]
    Runtime(#[from] oslf_runtime::RuntimeError),
}
