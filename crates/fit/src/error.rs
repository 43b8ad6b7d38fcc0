//! Error types: reading files ([`ReadError`]) and analysing data ([`FitError`]).

/// A scan file could not be read or is not valid.
#[derive(Debug, thiserror::Error)]
pub enum ReadError {
    /// The path is not a regular file, or is larger than any scan
    /// ([`crate::io::MAX_SCAN_BYTES`]); the message names it and the fix.
    #[error(transparent)]
    NotAScanFile(#[from] safe_io::ReadError),
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
    /// The extension names a format whose files carry a signature (magic bytes), and this
    /// file does not carry it: reading it by its extension would parse whatever overwrote
    /// the signature, or fail later with an error about some other field.
    #[error(
        "{file}: the file's signature does not match its extension: `.{extension}` names \
         the `{format}` format, whose files have {expected} at byte {offset}, but this file \
         has {found} there. Fix: the file is damaged (its first bytes overwritten) or misnamed; re-copy \
         or re-export it, or give it the extension of the format it is in"
    )]
    Signature {
        /// File name.
        file: String,
        /// The file's extension (lower case, no dot).
        extension: String,
        /// The format that extension names (its `--format` name).
        format: &'static str,
        /// The signature that format's files carry.
        expected: &'static str,
        /// Where the signature stands.
        offset: usize,
        /// What stands there instead.
        found: String,
    },
    /// The file is in a format recognised by its signature or container that is not read
    /// (yet), or is no height map at all (an image, a spreadsheet).
    #[error("{file}: {what}. Fix: {fix}")]
    NotRead {
        /// File name.
        file: String,
        /// What the file is.
        what: String,
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
