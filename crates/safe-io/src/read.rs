//! Bounded reads of regular files.

use crate::FileKind;
use std::io::Read;
use std::path::{Path, PathBuf};

/// A refused or failed read, naming the file, its role and the fix.
#[derive(Debug, thiserror::Error)]
pub enum ReadError {
    /// The path names something other than a regular file.
    #[error(
        "{what} '{}' is {}, not a regular file; name a file (a FIFO or device would block \
         or never end)",
        path.display(),
        kind.describe()
    )]
    NotRegular {
        /// The role of the file ("scene file", "nk_csv", …).
        what: String,
        /// The path as given.
        path: PathBuf,
        /// What it is instead.
        kind: FileKind,
    },
    /// The file is larger than its kind allows.
    #[error(
        "{what} '{}' is larger than {} (the limit for this kind of file); it cannot be \
         what is expected here: check the path",
        path.display(),
        human_size(*limit)
    )]
    TooLarge {
        /// The role of the file.
        what: String,
        /// The path as given.
        path: PathBuf,
        /// The limit in bytes.
        limit: u64,
    },
    /// Opening or reading failed.
    #[error("cannot read {what} '{}': {source}", path.display())]
    Io {
        /// The role of the file.
        what: String,
        /// The path as given.
        path: PathBuf,
        /// The underlying error.
        #[source]
        source: std::io::Error,
    },
}

impl ReadError {
    /// The path the error is about.
    pub fn path(&self) -> &Path {
        match self {
            ReadError::NotRegular { path, .. }
            | ReadError::TooLarge { path, .. }
            | ReadError::Io { path, .. } => path,
        }
    }
}

/// "4 MiB", "2 GiB", "512 bytes".
fn human_size(bytes: u64) -> String {
    match bytes {
        b if b >= 1 << 30 && b % (1 << 30) == 0 => format!("{} GiB", b >> 30),
        b if b >= 1 << 20 && b % (1 << 20) == 0 => format!("{} MiB", b >> 20),
        b if b >= 1 << 10 && b % (1 << 10) == 0 => format!("{} KiB", b >> 10),
        b => format!("{b} bytes"),
    }
}

fn open_nonblocking(path: &Path) -> std::io::Result<std::fs::File> {
    let mut opts = std::fs::OpenOptions::new();
    opts.read(true);
    // Opening a FIFO for reading blocks until a writer appears; non-blocking,
    // it opens at once and the kind check below refuses it. Regular files
    // ignore the flag.
    #[cfg(unix)]
    {
        use std::os::unix::fs::OpenOptionsExt;
        opts.custom_flags(libc::O_NONBLOCK);
    }
    opts.open(path)
}

/// Reads the regular file at `path` (following symbolic links), at most
/// `limit` bytes, and records it as an input of the process
/// ([`crate::register_input`]). `what` names the file's role in messages.
pub fn read_input(path: &Path, what: &str, limit: u64) -> Result<Vec<u8>, ReadError> {
    let bytes = read_regular(path, what, limit)?;
    crate::register_input(path);
    Ok(bytes)
}

/// [`read_input`] without recording the file as an input: for a file this
/// process wrote and will write again (a checkpoint it resumes, a scene file
/// it regenerates), which must stay writable.
pub fn read_regular(path: &Path, what: &str, limit: u64) -> Result<Vec<u8>, ReadError> {
    let io = |source| ReadError::Io {
        what: what.to_string(),
        path: path.to_path_buf(),
        source,
    };
    let file = open_nonblocking(path).map_err(io)?;
    // The kind comes from the open handle, so a path swapped after a check
    // cannot slip a device in.
    let meta = file.metadata().map_err(io)?;
    let kind = FileKind::of(&meta);
    if kind != FileKind::Regular {
        return Err(ReadError::NotRegular {
            what: what.to_string(),
            path: path.to_path_buf(),
            kind,
        });
    }
    let too_large = || ReadError::TooLarge {
        what: what.to_string(),
        path: path.to_path_buf(),
        limit,
    };
    if meta.len() > limit {
        return Err(too_large());
    }
    let mut bytes = Vec::with_capacity(meta.len() as usize);
    // `take` bounds the read even if the file grows while it is read.
    file.take(limit.saturating_add(1))
        .read_to_end(&mut bytes)
        .map_err(io)?;
    if bytes.len() as u64 > limit {
        return Err(too_large());
    }
    Ok(bytes)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn temp(name: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("safe-io-read-{}-{name}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(&d).unwrap();
        d
    }

    #[test]
    fn reads_regular_files_within_the_limit_and_records_them() {
        let d = temp("ok");
        let p = d.join("a.csv");
        std::fs::write(&p, "400,1\n").unwrap();
        crate::protect_inputs();
        assert_eq!(read_input(&p, "nk_csv", 6).unwrap(), b"400,1\n");
        assert!(crate::input_at(&p).is_some());
        let e = read_input(&p, "nk_csv", 5).unwrap_err();
        assert!(matches!(e, ReadError::TooLarge { limit: 5, .. }), "{e}");
        assert!(e.to_string().contains("5 bytes") && e.to_string().contains("a.csv"));
        let e = read_input(&d.join("missing.csv"), "nk_csv", 5).unwrap_err();
        assert!(matches!(e, ReadError::Io { .. }), "{e}");
        let _ = std::fs::remove_dir_all(&d);
    }

    #[test]
    fn refuses_directories_devices_and_fifos_without_blocking() {
        let d = temp("kinds");
        let e = read_input(&d, "mesh", 1 << 20).unwrap_err();
        assert!(
            matches!(
                e,
                ReadError::NotRegular {
                    kind: FileKind::Directory,
                    ..
                }
            ),
            "{e}"
        );
        #[cfg(unix)]
        {
            let e = read_input(Path::new("/dev/zero"), "nk_csv", 1 << 20).unwrap_err();
            assert!(
                matches!(
                    e,
                    ReadError::NotRegular {
                        kind: FileKind::CharDevice,
                        ..
                    }
                ),
                "{e}"
            );
            assert!(e.to_string().contains("/dev/zero"), "{e}");
            let fifo = d.join("pipe");
            let c = std::ffi::CString::new(fifo.to_str().unwrap()).unwrap();
            assert_eq!(unsafe { libc::mkfifo(c.as_ptr(), 0o600) }, 0);
            // With no writer, a blocking open would never return.
            let e = read_input(&fifo, "include", 1 << 20).unwrap_err();
            assert!(
                matches!(
                    e,
                    ReadError::NotRegular {
                        kind: FileKind::Fifo,
                        ..
                    }
                ),
                "{e}"
            );
        }
        let _ = std::fs::remove_dir_all(&d);
    }

    #[test]
    fn sizes_read_as_people_write_them() {
        assert_eq!(human_size(4 << 20), "4 MiB");
        assert_eq!(human_size(2 << 30), "2 GiB");
        assert_eq!(human_size(1000), "1000 bytes");
    }
}
