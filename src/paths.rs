//! Path identity for the commands that refuse to write over their inputs.

use std::path::{Path, PathBuf};

/// Whether two paths name the same file: the same absolute path after
/// removing `.` and `..`, or the same file once both exist (symbolic links).
pub fn same_file(a: &Path, b: &Path) -> bool {
    fn lexical(p: &Path) -> PathBuf {
        let abs = std::path::absolute(p).unwrap_or_else(|_| p.to_path_buf());
        let mut out = PathBuf::new();
        for c in abs.components() {
            match c {
                std::path::Component::CurDir => {}
                std::path::Component::ParentDir => {
                    out.pop();
                }
                c => out.push(c),
            }
        }
        out
    }
    if lexical(a) == lexical(b) {
        return true;
    }
    matches!(
        (std::fs::canonicalize(a), std::fs::canonicalize(b)),
        (Ok(x), Ok(y)) if x == y
    )
}
