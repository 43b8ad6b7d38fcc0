//! Error types: reading files ([`ReadError`]) and analysing data ([`FitError`]).

use std::path::PathBuf;

/// A scan file could not be read or is not valid.
#[derive(Debug, thiserror::Error)]
pub enum ReadError {
    /// The operating system refused to read the file.
    #[error("{file}: cannot read the file: {source}")]
    Io {
        /// File that failed.
        file: PathBuf,
        /// Underlying error.
        source: std::io::Error,
    },
    /// A header field or the data block is missing, malformed or inconsistent.
    #[error("{file}: field `{field}`: {problem}. Fix: {fix}")]
    Invalid {
        /// File name (for messages only).
        file: String,
        /// Header field or data part concerned.
        field: String,
        /// What is wrong.
        problem: String,
        /// What the user can do about it.
        fix: String,
    },
    /// The format of the file could not be determined.
    #[error("{file}: unknown surface format. Fix: {fix}")]
    UnknownFormat {
        /// File name.
        file: String,
        /// Supported formats and how to force one.
        fix: String,
    },
}

/// An analysis step failed (too little data, a fit that did not converge, …).
#[derive(Debug, thiserror::Error)]
pub enum FitError {
    /// The input data cannot be analysed as requested.
    #[error("{what}: {problem}")]
    Data {
        /// Step that failed.
        what: &'static str,
        /// Explanation, including how to fix it when possible.
        problem: String,
    },
    /// A step failed on the stylus profile rather than on the scan, so a caller can name
    /// the right file.
    #[error("stylus profile: {0}")]
    Stylus(Box<FitError>),
}

impl FitError {
    pub(crate) fn data(what: &'static str, problem: impl Into<String>) -> Self {
        FitError::Data {
            what,
            problem: problem.into(),
        }
    }
}
