//! The files this process has read as inputs, so that no writer replaces one.
//!
//! A process-wide record rather than a list each command passes along: a
//! writer cannot forget to consult it, and a new command is covered without
//! knowing it exists. A program turns it on once ([`protect_inputs`]; the
//! `lustre` command line does, first thing): a long-lived library caller (a
//! notebook that reads a map, then writes a new one by the same name) decides
//! for itself. Files are identified by device and inode where the platform
//! has them, so a hard link or a symbolic link to an input is the input;
//! elsewhere by canonical path.

use std::path::{Path, PathBuf};
use std::sync::Mutex;
use std::sync::atomic::{AtomicBool, Ordering};

#[derive(Clone, Debug, PartialEq, Eq)]
enum FileId {
    #[cfg(unix)]
    Inode { dev: u64, ino: u64 },
    #[cfg(not(unix))]
    Canonical(PathBuf),
}

struct Input {
    id: FileId,
    path: PathBuf,
}

static INPUTS: Mutex<Vec<Input>> = Mutex::new(Vec::new());
static PROTECTING: AtomicBool = AtomicBool::new(false);

/// From now on, every file this process reads through [`crate::read_input`]
/// (or names to [`register_input`]) is refused as an output.
pub fn protect_inputs() {
    PROTECTING.store(true, Ordering::SeqCst);
}

fn id_of(path: &Path) -> Option<FileId> {
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt;
        let m = std::fs::metadata(path).ok()?;
        Some(FileId::Inode {
            dev: m.dev(),
            ino: m.ino(),
        })
    }
    #[cfg(not(unix))]
    {
        std::fs::canonicalize(path).ok().map(FileId::Canonical)
    }
}

fn lock() -> std::sync::MutexGuard<'static, Vec<Input>> {
    // A panic while holding the lock cannot leave the list half-updated.
    INPUTS.lock().unwrap_or_else(|p| p.into_inner())
}

/// Records `path` as an input of this process, once [`protect_inputs`] was
/// called: [`crate::write_atomic`] and [`crate::check_output`] refuse it from
/// now on. [`crate::read_input`] calls this itself; call it for inputs read
/// by other means. A path that does not exist is not recorded (nothing there
/// can be lost).
pub fn register_input(path: &Path) {
    if !PROTECTING.load(Ordering::SeqCst) {
        return;
    }
    let Some(id) = id_of(path) else { return };
    let mut inputs = lock();
    // A record whose name no longer leads to its file is stale (the file was
    // deleted and its inode number may now be this file's).
    inputs.retain(|i| i.id != id || id_of(&i.path).as_ref() == Some(&i.id));
    if !inputs.iter().any(|i| i.id == id) {
        inputs.push(Input {
            id,
            path: std::path::absolute(path).unwrap_or_else(|_| path.to_path_buf()),
        });
    }
}

/// Whether two paths name the same file: the same absolute path after
/// removing `.` and `..` (so two outputs not yet written compare too), or the
/// same file once both exist (symbolic and hard links).
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
    lexical(a) == lexical(b) || matches!((id_of(a), id_of(b)), (Some(x), Some(y)) if x == y)
}

/// The recorded input that `path` names (under whatever spelling, link or
/// hard link), as it was named when read; `None` if it names none.
pub fn input_at(path: &Path) -> Option<PathBuf> {
    let id = id_of(path)?;
    // An input deleted since it was read guards nothing, and its inode number
    // may have passed to a new file: the recorded name must still lead to it.
    lock()
        .iter()
        .find(|i| i.id == id && id_of(&i.path).as_ref() == Some(&id))
        .map(|i| i.path.clone())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn links_and_spellings_of_an_input_are_the_input() {
        let dir = std::env::temp_dir().join(format!("safe-io-inputs-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let input = dir.join("scan.txt");
        let other = dir.join("other.txt");
        std::fs::write(&input, "1 2\n").unwrap();
        std::fs::write(&other, "3 4\n").unwrap();
        protect_inputs();
        register_input(&input);
        assert_eq!(input_at(&input).as_deref(), Some(input.as_path()));
        // Deleted, it guards nothing (its inode number may pass to a new file).
        let gone = dir.join("gone.txt");
        std::fs::write(&gone, "5 6\n").unwrap();
        register_input(&gone);
        assert!(input_at(&gone).is_some());
        std::fs::remove_file(&gone).unwrap();
        std::fs::write(dir.join("new.txt"), "7 8\n").unwrap();
        assert!(input_at(&dir.join("new.txt")).is_none());
        assert!(input_at(&dir.join(".").join("scan.txt")).is_some());
        assert!(input_at(&other).is_none());
        assert!(input_at(&dir.join("missing")).is_none());
        assert!(same_file(
            &dir.join("a").join("..").join("new"),
            &dir.join("new")
        ));
        assert!(!same_file(&input, &other));
        #[cfg(unix)]
        {
            std::os::unix::fs::symlink(&input, dir.join("sym")).unwrap();
            std::fs::hard_link(&input, dir.join("hard")).unwrap();
            assert!(input_at(&dir.join("sym")).is_some());
            assert!(input_at(&dir.join("hard")).is_some());
            assert!(same_file(&dir.join("hard"), &input));
        }
        let _ = std::fs::remove_dir_all(&dir);
    }
}
