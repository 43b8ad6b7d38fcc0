//! The bundled paper-sample scenes are what `lustre scenes` writes from
//! `brdf::paper` (one home for the samples and the model rules): a stale or
//! hand-edited scene file fails here.

use std::path::Path;
use std::process::Command;

#[test]
fn committed_scenes_are_generated_from_the_library() {
    let dir = std::env::temp_dir().join(format!("lustre-scenes-{}", std::process::id()));
    let out = Command::new(env!("CARGO_BIN_EXE_lustre"))
        .args(["scenes", "--quiet", "--out"])
        .arg(&dir)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let repo = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
    let mut n = 0;
    for sub in ["samples", "psd", "preview", "assets"] {
        let mut names: Vec<_> = std::fs::read_dir(dir.join(sub))
            .unwrap()
            .map(|e| e.unwrap().file_name())
            .collect();
        names.sort();
        // Hand-written notes (assets/README.md) are not generated.
        let mut committed: Vec<_> = std::fs::read_dir(repo.join(sub))
            .unwrap()
            .map(|e| e.unwrap().file_name())
            .filter(|n| n != "README.md")
            .collect();
        committed.sort();
        assert_eq!(names, committed, "scenes/{sub}: run `lustre scenes`");
        for name in names {
            let a = std::fs::read_to_string(dir.join(sub).join(&name)).unwrap();
            let b = std::fs::read_to_string(repo.join(sub).join(&name)).unwrap();
            assert!(a == b, "scenes/{sub}/{name:?} differs from `lustre scenes`");
            n += 1;
        }
    }
    // 105 plates, 5 PSD tables, 5 previews, 3 OBJ assets.
    assert_eq!(n, 5 * 7 * 3 + 5 + 5 + 3);
    let _ = std::fs::remove_dir_all(&dir);
}
