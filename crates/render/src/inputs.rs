//! Every file a scene build reads, read in one place.
//!
//! The film fingerprint must change whenever anything that determines the
//! sample values changes, so the scene build reads its files (the scene
//! itself, `include`d material files, `nk_csv`, `psd_csv`, spectrum CSVs,
//! environment maps, OBJ meshes) only through [`Inputs`], which hashes the
//! bytes it hands out. The record of (name, length, hash) per file travels
//! in the film, so that `--resume` and `merge` can name the file that
//! changed between two renders instead of only saying that something did.
//!
//! A file read twice (two materials sharing an `nk_csv`) is read once: the
//! build then also cannot see two versions of it.

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// Largest scene file accepted. The TOML parser holds the whole document in
/// memory at ~50 bytes per input byte before any key is checked; scenes are
/// a few kB (geometry belongs in OBJ files).
pub const MAX_SCENE_BYTES: u64 = 4 << 20;
/// Largest `include`d material file (a `lustre fit` file with its PSD table
/// is ~100 kB).
pub const MAX_TOML_BYTES: u64 = 8 << 20;
/// Largest CSV table (n, k; PSD; spectra).
pub const MAX_CSV_BYTES: u64 = 64 << 20;
/// Largest binary input (OBJ mesh, EXR environment map).
pub const MAX_BINARY_BYTES: u64 = 4 << 30;

/// One file the scene was built from.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct InputFile {
    /// Path relative to the scene file's directory (as the scene names it),
    /// or as given when outside it.
    pub name: String,
    /// Length in bytes of what was hashed.
    pub len: u64,
    /// 64-bit FNV-1a of the bytes (the scene file: of its normalised text).
    pub hash: u64,
}

/// 64-bit FNV-1a. Any single changed byte changes the hash (each step is a
/// bijection of the state).
pub fn fnv1a(bytes: &[u8], mut h: u64) -> u64 {
    for &b in bytes {
        h ^= b as u64;
        h = h.wrapping_mul(0x0000_0100_0000_01b3);
    }
    h
}

/// FNV-1a's offset basis.
pub const FNV_OFFSET: u64 = 0xcbf2_9ce4_8422_2325;

/// The files read by one scene build, with their hashes.
#[derive(Debug)]
pub struct Inputs {
    base: PathBuf,
    files: Vec<InputFile>,
    cache: HashMap<PathBuf, Arc<[u8]>>,
}

impl Inputs {
    /// An empty record for a scene whose file lies in `scene_dir`.
    pub fn new(scene_dir: &Path) -> Inputs {
        Inputs {
            base: scene_dir.to_path_buf(),
            files: Vec::new(),
            cache: HashMap::new(),
        }
    }

    /// The name under which `path` is recorded and reported.
    pub fn name_of(&self, path: &Path) -> String {
        let rel = path.strip_prefix(&self.base).unwrap_or(path);
        rel.display().to_string()
    }

    /// Records content that was not read from a file by [`Inputs::read`]
    /// (the scene's own normalised text).
    pub fn record(&mut self, name: String, bytes: &[u8]) {
        self.files.push(InputFile {
            name,
            len: bytes.len() as u64,
            hash: fnv1a(bytes, FNV_OFFSET),
        });
    }

    /// Reads `path` (at most `limit` bytes; `what` names the file's role in
    /// messages) and records it.
    pub fn read(&mut self, path: &Path, what: &str, limit: u64) -> Result<Arc<[u8]>, String> {
        if let Some(b) = self.cache.get(path) {
            return Ok(b.clone());
        }
        let bytes: Arc<[u8]> = safe_io::read_input(path, what, limit)
            .map_err(|e| e.to_string())?
            .into();
        let name = self.name_of(path);
        self.record(name, &bytes);
        self.cache.insert(path.to_path_buf(), bytes.clone());
        Ok(bytes)
    }

    /// [`Inputs::read`] of a UTF-8 text file.
    pub fn read_text(&mut self, path: &Path, what: &str, limit: u64) -> Result<String, String> {
        let bytes = self.read(path, what, limit)?;
        match std::str::from_utf8(&bytes) {
            Ok(s) => Ok(s.to_string()),
            Err(e) => Err(format!(
                "{what} {} is not UTF-8 text (invalid byte at offset {})",
                path.display(),
                e.valid_up_to()
            )),
        }
    }

    /// The files read so far, in the order first read.
    pub fn files(&self) -> &[InputFile] {
        &self.files
    }

    /// Consumes the record, returning the files.
    pub fn into_files(self) -> Vec<InputFile> {
        self.files
    }
}

/// The fingerprint of a render: the estimator version and every input's
/// length and hash, in the order the build read them. Paths are left out,
/// so that the same scene tree fingerprints the same from any working
/// directory.
pub fn fingerprint(estimator: &str, files: &[InputFile]) -> u64 {
    let mut h = fnv1a(estimator.as_bytes(), FNV_OFFSET);
    for f in files {
        h = fnv1a(&f.len.to_le_bytes(), h);
        h = fnv1a(&f.hash.to_le_bytes(), h);
    }
    h
}

/// What differs between two input records, one line per file, naming each
/// changed, added or removed file; empty when the records agree.
pub fn describe_differences(ours: &[InputFile], theirs: &[InputFile]) -> Vec<String> {
    let mut out = Vec::new();
    for a in ours {
        match theirs.iter().find(|b| b.name == a.name) {
            Some(b) if (b.len, b.hash) != (a.len, a.hash) => {
                out.push(format!(
                    "`{}` changed ({} → {} bytes)",
                    a.name, b.len, a.len
                ));
            }
            Some(_) => {}
            None => out.push(format!("`{}` is read now but was not then", a.name)),
        }
    }
    for b in theirs {
        if !ours.iter().any(|a| a.name == b.name) {
            out.push(format!("`{}` was read then but is not now", b.name));
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_once_records_and_bounds() {
        let dir = std::env::temp_dir().join(format!("lustre-inputs-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let p = dir.join("a.csv");
        std::fs::write(&p, "1,2\n").unwrap();
        let mut inp = Inputs::new(&dir);
        assert_eq!(&*inp.read(&p, "CSV", 100).unwrap(), b"1,2\n");
        std::fs::write(&p, "3,4\n").unwrap();
        // The second read returns what the build already saw.
        assert_eq!(inp.read_text(&p, "CSV", 100).unwrap(), "1,2\n");
        assert_eq!(inp.files().len(), 1);
        assert_eq!(inp.files()[0].name, "a.csv");
        let mut inp2 = Inputs::new(&dir);
        let e = inp2.read(&p, "CSV", 2).unwrap_err();
        assert!(e.contains("larger than"), "{e}");
        let e = inp2.read(&dir.join("missing.csv"), "CSV", 9).unwrap_err();
        assert!(
            e.contains("cannot read CSV") && e.contains("missing.csv"),
            "{e}"
        );
        std::fs::write(&p, [0xff, 0xfe]).unwrap();
        let e = Inputs::new(&dir).read_text(&p, "CSV", 9).unwrap_err();
        assert!(e.contains("not UTF-8"), "{e}");
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn differences_name_the_file() {
        let f = |name: &str, hash| InputFile {
            name: name.into(),
            len: 3,
            hash,
        };
        let a = [f("s.toml", 1), f("fit.toml", 2)];
        let b = [f("s.toml", 1), f("fit.toml", 3)];
        let d = describe_differences(&a, &b);
        assert_eq!(d.len(), 1);
        assert!(d[0].contains("fit.toml") && d[0].contains("changed"));
        assert!(describe_differences(&a, &a).is_empty());
        assert_ne!(fingerprint("v", &a), fingerprint("v", &b));
        assert_ne!(fingerprint("v", &a), fingerprint("w", &a));
        let c = [f("s.toml", 1)];
        assert_eq!(describe_differences(&a, &c).len(), 1);
        assert_eq!(describe_differences(&c, &a).len(), 1);
    }
}
