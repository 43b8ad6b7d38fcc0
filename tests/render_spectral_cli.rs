//! `lustre render --spectral N` and `lustre merge` of films with bands:
//! shards merge to the film of one render byte for byte, the EXR holds the
//! bands under pbrt-v4's channel names, and shards of other band counts are
//! refused naming both files.

use std::path::{Path, PathBuf};
use std::process::Command;

const SCENE: &str = r#"[camera]
look_from = [0.0, 0.5, 0.8]
look_at = [0.0, 0.0, 0.0]
fov_deg = 40.0
resolution = [12, 8]

[film]
spp = 6
seed = 4

[materials.m]
model = "ggx"
metal = "au"
alpha = 0.2

[[shapes]]
type = "rectangle"
size = [1.0, 1.0]
material = "m"
transform = { rotate_deg = [-90.0, 0.0, 0.0] }

[[lights]]
type = "sphere"
center = [0.0, 0.5, -0.8]
radius = 0.1
radiance = 20.0
"#;

fn dir() -> PathBuf {
    let d = std::env::temp_dir().join(format!("lustre-spectral-cli-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    std::fs::write(d.join("s.toml"), SCENE).unwrap();
    d
}

fn lustre(dir: &Path, args: &[&str]) -> (bool, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_lustre"))
        .current_dir(dir)
        .args(args)
        .output()
        .unwrap();
    (
        out.status.success(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

#[test]
fn spectral_shards_merge_exactly_and_other_band_counts_are_refused() {
    let d = dir();
    let ok = |args: &[&str]| {
        let (ok, err) = lustre(&d, args);
        assert!(ok, "{args:?}: {err}");
    };
    ok(&[
        "render",
        "s.toml",
        "-q",
        "--spectral",
        "12",
        "--exr",
        "whole.exr",
    ]);
    ok(&[
        "render",
        "s.toml",
        "-q",
        "--spectral",
        "12",
        "--spp-range",
        "0..4",
        "--film",
        "a.film",
    ]);
    ok(&[
        "render",
        "s.toml",
        "-q",
        "--spectral",
        "12",
        "--spp-range",
        "4..6",
        "--film",
        "b.film",
    ]);
    ok(&[
        "merge", "-q", "a.film", "b.film", "--film", "m.film", "--exr", "m.exr",
    ]);
    let read = |p: &str| std::fs::read(d.join(p)).unwrap();
    assert_eq!(read("m.film"), read("whole.film"));
    assert_eq!(&read("m.film")[..12], b"LUSTREFILM3\n");
    assert_eq!(read("m.exr"), read("whole.exr"));
    let exr = read("whole.exr");
    for name in ["S0.379,583nm", "S0.810,417nm"] {
        let found = exr.windows(name.len()).any(|w| w == name.as_bytes());
        assert!(found, "no channel {name}");
    }

    ok(&[
        "render",
        "s.toml",
        "-q",
        "--spectral",
        "5",
        "--spp-range",
        "4..6",
        "--film",
        "c.film",
    ]);
    let (ok, err) = lustre(&d, &["merge", "a.film", "c.film", "--film", "x.film"]);
    assert!(!ok);
    assert!(
        err.contains("c.film") && err.contains("a.film") && err.contains("5 spectral bands"),
        "{err}"
    );
    let (ok, err) = lustre(&d, &["render", "s.toml", "-q", "--spectral", "257"]);
    assert!(!ok && err.contains("1..=256"), "{err}");
    std::fs::remove_dir_all(&d).ok();
}
