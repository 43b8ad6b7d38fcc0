//! Errors of scene loading, rendering and film I/O.

use std::fmt;
use std::path::{Path, PathBuf};

/// A problem with a scene file (or a file it references), located as
/// precisely as the parser allows: file, line and column when known.
#[derive(Debug, Clone, PartialEq)]
pub struct SceneError {
    /// The file at fault.
    pub file: PathBuf,
    /// 1-based line and column, when the problem has a position.
    pub position: Option<(usize, usize)>,
    /// What is wrong and, where possible, the valid choices.
    pub message: String,
}

impl SceneError {
    /// An error without a position in `file`.
    pub fn new(file: &Path, message: impl Into<String>) -> SceneError {
        SceneError {
            file: file.to_path_buf(),
            position: None,
            message: message.into(),
        }
    }

    /// An error at byte offset `offset` of `text` (the contents of `file`).
    pub fn at(file: &Path, text: &str, offset: usize, message: impl Into<String>) -> SceneError {
        SceneError {
            file: file.to_path_buf(),
            position: Some(line_column(text, offset)),
            message: message.into(),
        }
    }
}

impl fmt::Display for SceneError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.position {
            Some((line, col)) => {
                write!(
                    f,
                    "{}:{}:{}: {}",
                    self.file.display(),
                    line,
                    col,
                    self.message
                )
            }
            None => write!(f, "{}: {}", self.file.display(), self.message),
        }
    }
}

impl std::error::Error for SceneError {}

/// 1-based (line, column) of byte `offset` in `text`; the column counts characters.
pub fn line_column(text: &str, offset: usize) -> (usize, usize) {
    let offset = offset.min(text.len());
    let before = text.get(..offset).unwrap_or(text);
    let line = before.matches('\n').count() + 1;
    let line_start = before.rfind('\n').map_or(0, |i| i + 1);
    let column = before[line_start..].chars().count() + 1;
    (line, column)
}

/// Anything that can stop a render or a merge.
#[derive(Debug, thiserror::Error)]
pub enum RenderError {
    /// The scene (or a file it references) is invalid.
    #[error(transparent)]
    Scene(#[from] SceneError),
    /// Reading or writing a file failed.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file involved.
        path: PathBuf,
        /// The underlying error.
        source: std::io::Error,
    },
    /// Encoding an output image failed.
    #[error("{}: cannot write image: {message}", path.display())]
    Image {
        /// The output file.
        path: PathBuf,
        /// The encoder's message.
        message: String,
    },
    /// A film (checkpoint or shard) is malformed or does not fit the others.
    #[error("{}: {message}", path.display())]
    Film {
        /// The film file.
        path: PathBuf,
        /// What is wrong and how to fix it.
        message: String,
    },
    /// Invalid command-line style options (sample ranges, thread counts).
    #[error("{0}")]
    Options(String),
}

impl RenderError {
    /// Wraps an I/O error with the path it concerns.
    pub fn io(path: &Path, source: std::io::Error) -> RenderError {
        RenderError::Io {
            path: path.to_path_buf(),
            source,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn line_column_counts_from_one() {
        let t = "a = 1\nbé = 2\n";
        assert_eq!(line_column(t, 0), (1, 1));
        assert_eq!(line_column(t, 6), (2, 1));
        assert_eq!(line_column(t, 9), (2, 3)); // after "bé" (é is two bytes)
        assert_eq!(line_column(t, 1000), (3, 1));
    }
}
