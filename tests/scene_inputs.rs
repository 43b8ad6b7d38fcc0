//! `--resume` and `merge` refuse films rendered from different inputs, and
//! name the file that changed: every file a scene build reads (the scene,
//! an `include`d material file and the `nk_csv` it names, `psd_csv`,
//! `nk_csv`, a spectrum CSV, an environment map, an OBJ mesh) is hashed
//! into the film's fingerprint and recorded by name.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn lustre(dir: &Path, args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_lustre"))
        .current_dir(dir)
        .args(args)
        .output()
        .expect("run lustre")
}

fn ok(dir: &Path, args: &[&str]) {
    let out = lustre(dir, args);
    assert!(
        out.status.success(),
        "lustre {args:?} failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
}

/// Runs a command that must fail cleanly (exit 1, not a panic); returns stderr.
fn fails(dir: &Path, args: &[&str]) -> String {
    let out = lustre(dir, args);
    let err = String::from_utf8_lossy(&out.stderr).into_owned();
    assert_eq!(out.status.code(), Some(1), "lustre {args:?}: {err}");
    err
}

const SCENE: &str = r#"[camera]
look_from = [0.0, 1.0, 2.0]
look_at = [0.0, 0.0, 0.0]
fov_deg = 50.0
resolution = [6, 4]

[film]
spp = 2
seed = 5

[integrator]
max_depth = 2

[materials.fitted]
include = "mat/fit.toml"

[materials.psd]
model = "measured_psd"
psd_csv = "psd.csv"
metal = "cu"

[materials.table]
model = "ggx"
nk_csv = "nk2.csv"
alpha = 0.2

[[shapes]]
type = "rectangle"
size = [1.0, 1.0]
material = "fitted"
transform = { rotate_deg = [-90.0, 0.0, 0.0] }

[[shapes]]
type = "disk"
radius = 0.3
material = "psd"
transform = { translate = [0.5, 0.1, 0.0], rotate_deg = [-90.0, 0.0, 0.0] }

[[shapes]]
type = "mesh"
file = "tri.obj"
material = "table"

[[lights]]
type = "sphere"
center = [0.0, 1.0, -1.0]
radius = 0.1
radiance = 50.0
spectrum = "csv(light.csv)"

[[lights]]
type = "environment"
radiance = 0.5
file = "env.exr"
"#;

const FIT: &str = "[material]\nmodel = \"ggx\"\nalpha = 0.1\nnk_csv = \"nk.csv\"\n";
const NK: &str = "wavelength_nm,n,k\n300,0.5,3.0\n900,0.6,3.5\n";
const LIGHT: &str = "wavelength_nm,value\n360,1.0\n830,1.0\n";
const OBJ: &str = "v -0.2 0.05 0.3\nv 0.2 0.05 0.3\nv 0.0 0.3 0.3\nf 1 2 3\n";

fn write_env(path: &Path, v: f32) {
    let rgb = vec![[v, v * 0.9, v * 0.8]; 8 * 4];
    render::output::write_exr(path, 8, 4, &rgb).unwrap();
}

fn setup(dir: &Path) {
    let _ = std::fs::remove_dir_all(dir);
    std::fs::create_dir_all(dir.join("mat")).unwrap();
    std::fs::write(dir.join("scene.toml"), SCENE).unwrap();
    std::fs::write(dir.join("mat/fit.toml"), FIT).unwrap();
    std::fs::write(dir.join("mat/nk.csv"), NK).unwrap();
    std::fs::write(dir.join("nk2.csv"), NK).unwrap();
    std::fs::write(dir.join("light.csv"), LIGHT).unwrap();
    std::fs::write(dir.join("tri.obj"), OBJ).unwrap();
    let psd = std::fs::read_to_string(
        PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("scenes/psd/s138_kc.csv"),
    )
    .unwrap();
    std::fs::write(dir.join("psd.csv"), psd).unwrap();
    write_env(&dir.join("env.exr"), 0.5);
}

/// Changes one input file in a way that keeps the scene valid.
fn edit(dir: &Path, name: &str) {
    let p = dir.join(name);
    match name {
        "env.exr" => write_env(&p, 0.6),
        "scene.toml" => {
            let t = std::fs::read_to_string(&p).unwrap();
            std::fs::write(&p, t.replace("alpha = 0.2", "alpha = 0.25")).unwrap();
        }
        "psd.csv" => {
            let t = std::fs::read_to_string(&p).unwrap();
            let mut lines: Vec<String> = t.lines().map(String::from).collect();
            // Scale one PSD value by 1.1.
            let (z, v) = lines[5].split_once(',').unwrap();
            let v: f64 = v.parse().unwrap();
            lines[5] = format!("{z},{:e}", v * 1.1);
            std::fs::write(&p, lines.join("\n") + "\n").unwrap();
        }
        _ => {
            let t = std::fs::read_to_string(&p).unwrap();
            let t = t
                .replacen("0.6,3.5", "0.7,3.5", 1)
                .replacen("830,1.0", "830,2.0", 1)
                .replacen("alpha = 0.1", "alpha = 0.15", 1)
                .replacen("v 0.0 0.3 0.3", "v 0.0 0.35 0.3", 1);
            std::fs::write(&p, t).unwrap();
        }
    }
}

#[test]
fn merge_and_resume_name_the_changed_input() {
    let dir = std::env::temp_dir().join(format!("lustre-scene-inputs-{}", std::process::id()));
    // Shards from identical inputs merge, and settings that do not change
    // samples (spp, outputs) may differ between them.
    setup(&dir);
    ok(
        &dir,
        &[
            "render",
            "scene.toml",
            "--spp-range",
            "0..2",
            "--film",
            "a.film",
            "-q",
        ],
    );
    ok(
        &dir,
        &[
            "render",
            "scene.toml",
            "--spp-range",
            "2..4",
            "--film",
            "b.film",
            "--spp",
            "9",
            "-q",
        ],
    );
    ok(
        &dir,
        &["merge", "a.film", "b.film", "--film", "ab.film", "-q"],
    );
    // The same film twice: a duplicated shard.
    let e = fails(&dir, &["merge", "a.film", "a.film", "--film", "aa.film"]);
    assert!(e.contains("a.film") && e.contains("overlaps"), "{e}");

    for name in [
        "scene.toml",
        "mat/fit.toml",
        "mat/nk.csv",
        "psd.csv",
        "nk2.csv",
        "tri.obj",
        "light.csv",
        "env.exr",
    ] {
        setup(&dir);
        ok(
            &dir,
            &[
                "render",
                "scene.toml",
                "--spp-range",
                "0..2",
                "--film",
                "a.film",
                "-q",
            ],
        );
        ok(
            &dir,
            &[
                "render",
                "scene.toml",
                "--spp",
                "2",
                "--film",
                "full.film",
                "-q",
            ],
        );
        edit(&dir, name);
        ok(
            &dir,
            &[
                "render",
                "scene.toml",
                "--spp-range",
                "2..4",
                "--film",
                "b.film",
                "-q",
            ],
        );
        let e = fails(&dir, &["merge", "a.film", "b.film", "--film", "ab.film"]);
        assert!(
            e.contains("b.film") && e.contains(&format!("`{name}` changed")),
            "merge after editing {name}: {e}"
        );
        let e = fails(
            &dir,
            &[
                "render",
                "scene.toml",
                "--spp",
                "4",
                "--resume",
                "--film",
                "full.film",
            ],
        );
        assert!(
            e.contains("full.film") && e.contains(&format!("`{name}` changed")),
            "resume after editing {name}: {e}"
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}
