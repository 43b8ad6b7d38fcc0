//! Atomic file output for every crate of the workspace that writes results:
//! the bytes go to a temporary file in the destination's folder, are synced,
//! and the temporary file is renamed over the target. A reader never sees a
//! half-written file, and an interrupted or failed write leaves the previous
//! version intact (the temporary file is removed on failure).
#![deny(missing_docs)]

use std::io::Write;
use std::path::{Path, PathBuf};

/// A failed atomic write: which step failed, on which file.
#[derive(Debug, thiserror::Error)]
#[error("{action} '{}': {source}", path.display())]
pub struct WriteError {
    /// The step that failed ("creating folder", "creating temporary file", "writing", …).
    pub action: &'static str,
    /// The file or folder the step was about.
    pub path: PathBuf,
    /// The underlying error.
    #[source]
    pub source: std::io::Error,
}

/// Writes `bytes` to `path` atomically. The folder must exist (callers
/// that want it created say so with [`create_parent`]).
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), WriteError> {
    let fail = |action: &'static str, p: &Path| {
        let p = p.to_path_buf();
        move |source| WriteError {
            action,
            path: p,
            source,
        }
    };
    let Some(name) = path.file_name().map(|n| n.to_string_lossy().into_owned()) else {
        return Err(fail("writing", path)(std::io::Error::new(
            std::io::ErrorKind::InvalidInput,
            "the path has no file name",
        )));
    };
    let tmp = path.with_file_name(format!(".{name}.tmp-{}", std::process::id()));
    let result = (|| {
        let mut f = std::fs::File::create(&tmp).map_err(fail("creating temporary file", &tmp))?;
        f.write_all(bytes).map_err(fail("writing", &tmp))?;
        f.sync_all().map_err(fail("flushing", &tmp))?;
        drop(f);
        std::fs::rename(&tmp, path).map_err(fail("renaming temporary file to", path))
    })();
    if result.is_err() {
        // Best effort: the temporary file may not exist if creating it failed.
        let _ = std::fs::remove_file(&tmp);
    }
    result
}

/// Creates `path`'s parent folder (and its parents) if missing.
pub fn create_parent(path: &Path) -> Result<(), WriteError> {
    match path.parent().filter(|d| !d.as_os_str().is_empty()) {
        Some(dir) => std::fs::create_dir_all(dir).map_err(|source| WriteError {
            action: "creating folder",
            path: dir.to_path_buf(),
            source,
        }),
        None => Ok(()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn replaces_whole_files_and_leaves_no_temporary_behind() {
        let dir = std::env::temp_dir().join(format!("atomic-write-{}", std::process::id()));
        let path = dir.join("sub").join("out.txt");
        assert!(write_atomic(&path, b"first").is_err(), "missing folder");
        create_parent(&path).unwrap();
        write_atomic(&path, b"first").unwrap();
        write_atomic(&path, b"second, longer").unwrap();
        assert_eq!(std::fs::read(&path).unwrap(), b"second, longer");
        let names: Vec<_> = std::fs::read_dir(dir.join("sub"))
            .unwrap()
            .map(|e| e.unwrap().file_name())
            .collect();
        assert_eq!(names, ["out.txt"]);
        // A target that is a folder cannot be replaced: an error naming it, the folder intact.
        let e = write_atomic(&dir.join("sub"), b"x").unwrap_err();
        assert!(e.to_string().contains("sub"), "{e}");
        assert!(dir.join("sub").join("out.txt").exists());
        let names: Vec<_> = std::fs::read_dir(&dir).unwrap().collect();
        assert_eq!(names.len(), 1, "temporary file left behind");
        let _ = std::fs::remove_dir_all(&dir);
    }
}
