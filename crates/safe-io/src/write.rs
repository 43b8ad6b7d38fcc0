//! Writing results: atomically over regular files, into streams, never over
//! an input or a directory.

use crate::FileKind;
use std::io::Write;
use std::path::{Path, PathBuf};

/// A refused or failed write: which step, on which file.
#[derive(Debug, thiserror::Error)]
#[error("{action} '{}': {source}", path.display())]
pub struct WriteError {
    /// The step that failed ("creating folder", "writing", "refusing to write", …).
    pub action: &'static str,
    /// The file or folder the step was about.
    pub path: PathBuf,
    /// The underlying error (for a refusal, the reason and the fix).
    #[source]
    pub source: std::io::Error,
}

fn refusal(path: &Path, why: String) -> WriteError {
    WriteError {
        action: "refusing to write",
        path: path.to_path_buf(),
        source: std::io::Error::new(std::io::ErrorKind::InvalidInput, why),
    }
}

/// Where the bytes of a write go.
enum Target {
    /// A new file or a regular file at this (resolved) path: replaced atomically.
    Replace(PathBuf),
    /// A character device or FIFO: written into.
    Stream,
}

/// Decides where a write to `path` goes, or refuses it.
fn target(path: &Path) -> Result<Target, WriteError> {
    if let Some(input) = crate::input_at(path) {
        return Err(refusal(
            path,
            format!(
                "it is the input '{}' (this command read it), and writing over the input \
                 would destroy it. Fix: choose another output name",
                input.display()
            ),
        ));
    }
    let meta = match std::fs::metadata(path) {
        Ok(m) => m,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
            return match std::fs::symlink_metadata(path) {
                // A symbolic link to nothing: replacing the link would hide the mistake.
                Ok(_) => Err(refusal(
                    path,
                    "it is a symbolic link to a missing file; remove the link or name \
                     another output"
                        .into(),
                )),
                Err(_) => Ok(Target::Replace(path.to_path_buf())),
            };
        }
        Err(source) => {
            return Err(WriteError {
                action: "inspecting",
                path: path.to_path_buf(),
                source,
            });
        }
    };
    match FileKind::of(&meta) {
        // Through a symbolic link the file it points to is replaced, and the link stays.
        FileKind::Regular => Ok(Target::Replace(
            std::fs::canonicalize(path).unwrap_or_else(|_| path.to_path_buf()),
        )),
        FileKind::CharDevice | FileKind::Fifo => Ok(Target::Stream),
        kind => Err(refusal(
            path,
            format!(
                "it is {}, which a result must not replace; give a file name",
                kind.describe()
            ),
        )),
    }
}

/// Refuses `path` as an output for the reasons [`write_atomic`] would,
/// without writing anything: a command checks its outputs before long work.
pub fn check_output(path: &Path) -> Result<(), WriteError> {
    target(path).map(|_| ())
}

/// Writes `bytes` to `path`: a new or regular file is replaced atomically
/// (the folder must exist; see [`create_parent`]), a character device or FIFO
/// is written into, and a directory, socket, block device or an input of the
/// process is refused (see the crate documentation).
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), WriteError> {
    write_atomic_with(path, &mut |w| w.write_all(bytes))
}

/// [`write_atomic`] of what `write` produces, streamed (through a buffer)
/// rather than held in memory whole.
pub fn write_atomic_with(
    path: &Path,
    write: &mut dyn FnMut(&mut dyn Write) -> std::io::Result<()>,
) -> Result<(), WriteError> {
    match target(path)? {
        Target::Replace(resolved) => replace(&resolved, write),
        Target::Stream => stream(path, write),
    }
}

fn replace(
    path: &Path,
    write: &mut dyn FnMut(&mut dyn Write) -> std::io::Result<()>,
) -> Result<(), WriteError> {
    let fail = |action: &'static str, p: &Path| {
        let p = p.to_path_buf();
        move |source| WriteError {
            action,
            path: p,
            source,
        }
    };
    let Some(name) = path.file_name().map(|n| n.to_string_lossy().into_owned()) else {
        return Err(refusal(path, "the path has no file name".into()));
    };
    let tmp = path.with_file_name(format!(".{name}.tmp-{}", std::process::id()));
    let result = (|| {
        let f = std::fs::File::create(&tmp).map_err(fail("creating temporary file", &tmp))?;
        let mut buf = std::io::BufWriter::new(f);
        write(&mut buf).map_err(fail("writing", &tmp))?;
        let f = buf
            .into_inner()
            .map_err(|e| fail("writing", &tmp)(e.into_error()))?;
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

/// Writes into a character device or FIFO as `cp` would, except that a FIFO
/// nobody reads is an error rather than a wait without end.
fn stream(
    path: &Path,
    write: &mut dyn FnMut(&mut dyn Write) -> std::io::Result<()>,
) -> Result<(), WriteError> {
    let fail = |action: &'static str| {
        move |source| WriteError {
            action,
            path: path.to_path_buf(),
            source,
        }
    };
    let mut opts = std::fs::OpenOptions::new();
    opts.write(true);
    #[cfg(unix)]
    {
        use std::os::unix::fs::OpenOptionsExt;
        opts.custom_flags(libc::O_NONBLOCK);
    }
    let mut f = opts.open(path).map_err(|e| {
        #[cfg(unix)]
        if e.raw_os_error() == Some(libc::ENXIO) {
            return refusal(
                path,
                "it is a FIFO that no process is reading; start the reader first".into(),
            );
        }
        fail("opening")(e)
    })?;
    #[cfg(unix)]
    {
        // Open without waiting, then write with the device's normal blocking.
        use std::os::fd::AsRawFd;
        let fd = f.as_raw_fd();
        // SAFETY: fcntl on a descriptor this function owns, flags read then written back.
        let flags = unsafe { libc::fcntl(fd, libc::F_GETFL) };
        if flags < 0 || unsafe { libc::fcntl(fd, libc::F_SETFL, flags & !libc::O_NONBLOCK) } < 0 {
            return Err(fail("configuring")(std::io::Error::last_os_error()));
        }
    }
    let mut buf = std::io::BufWriter::new(&mut f);
    write(&mut buf).map_err(fail("writing"))?;
    buf.flush().map_err(fail("flushing"))
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

    fn temp(name: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("safe-io-write-{}-{name}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(&d).unwrap();
        d
    }

    fn names(dir: &Path) -> Vec<String> {
        let mut v: Vec<_> = std::fs::read_dir(dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        v.sort();
        v
    }

    #[test]
    fn replaces_whole_files_and_leaves_no_temporary_behind() {
        let dir = temp("replace");
        let path = dir.join("sub").join("out.txt");
        assert!(write_atomic(&path, b"first").is_err(), "missing folder");
        create_parent(&path).unwrap();
        write_atomic(&path, b"first").unwrap();
        write_atomic(&path, b"second, longer").unwrap();
        assert_eq!(std::fs::read(&path).unwrap(), b"second, longer");
        assert_eq!(names(&dir.join("sub")), ["out.txt"]);
        // A folder is refused by name and left intact.
        let e = write_atomic(&dir.join("sub"), b"x").unwrap_err();
        assert!(e.to_string().contains("a directory"), "{e}");
        assert!(check_output(&dir.join("sub")).is_err());
        assert_eq!(names(&dir.join("sub")), ["out.txt"]);
        assert_eq!(names(&dir), ["sub"], "temporary file left behind");
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn an_input_is_refused_under_every_name() {
        let dir = temp("inputs");
        let input = dir.join("scan.di");
        std::fs::write(&input, b"scan").unwrap();
        crate::protect_inputs();
        crate::read_input(&input, "scan", 100).unwrap();
        let mut spellings = vec![input.clone(), dir.join(".").join("scan.di")];
        #[cfg(unix)]
        {
            std::os::unix::fs::symlink(&input, dir.join("judge.json")).unwrap();
            std::fs::hard_link(&input, dir.join("hard.json")).unwrap();
            spellings.push(dir.join("judge.json"));
            spellings.push(dir.join("hard.json"));
        }
        for p in &spellings {
            let e = write_atomic(p, b"{}").unwrap_err();
            assert!(e.to_string().contains("is the input"), "{e}");
            assert!(check_output(p).is_err());
        }
        assert_eq!(std::fs::read(&input).unwrap(), b"scan");
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[cfg(unix)]
    #[test]
    fn a_symbolic_link_to_an_output_keeps_the_link() {
        let dir = temp("link");
        std::fs::write(dir.join("real.png"), b"old").unwrap();
        std::os::unix::fs::symlink(dir.join("real.png"), dir.join("link.png")).unwrap();
        write_atomic(&dir.join("link.png"), b"new").unwrap();
        assert!(
            std::fs::symlink_metadata(dir.join("link.png"))
                .unwrap()
                .file_type()
                .is_symlink()
        );
        assert_eq!(std::fs::read(dir.join("real.png")).unwrap(), b"new");
        std::os::unix::fs::symlink(dir.join("gone"), dir.join("dangling")).unwrap();
        let e = write_atomic(&dir.join("dangling"), b"x").unwrap_err();
        assert!(e.to_string().contains("missing file"), "{e}");
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[cfg(unix)]
    #[test]
    fn devices_and_fifos_are_written_into_never_replaced() {
        use std::os::unix::fs::FileTypeExt;
        let dir = temp("devices");
        // /dev/null stays a character device.
        write_atomic(Path::new("/dev/null"), b"film bytes").unwrap();
        assert!(
            std::fs::metadata("/dev/null")
                .unwrap()
                .file_type()
                .is_char_device()
        );
        let fifo = dir.join("pipe");
        let c = std::ffi::CString::new(fifo.to_str().unwrap()).unwrap();
        assert_eq!(unsafe { libc::mkfifo(c.as_ptr(), 0o600) }, 0);
        // Nobody reading: an error at once, not a hang.
        let e = write_atomic(&fifo, b"x").unwrap_err();
        assert!(e.to_string().contains("no process is reading"), "{e}");
        let reader = {
            let fifo = fifo.clone();
            std::thread::spawn(move || std::fs::read(fifo).unwrap())
        };
        // Retry until the reader has the FIFO open.
        let mut tries = 0;
        while let Err(e) = write_atomic(&fifo, b"through the pipe") {
            tries += 1;
            assert!(tries < 500, "{e}");
            std::thread::sleep(std::time::Duration::from_millis(10));
        }
        assert_eq!(reader.join().unwrap(), b"through the pipe");
        assert!(std::fs::metadata(&fifo).unwrap().file_type().is_fifo());
        // A socket is refused.
        let sock = dir.join("sock");
        let _listener = std::os::unix::net::UnixListener::bind(&sock).unwrap();
        let e = write_atomic(&sock, b"x").unwrap_err();
        assert!(e.to_string().contains("a socket"), "{e}");
        let _ = std::fs::remove_dir_all(&dir);
    }
}
