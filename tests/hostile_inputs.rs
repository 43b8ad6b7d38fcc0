//! Inputs that are not regular files: a FIFO with no writer (a blocking open
//! never returns), `/dev/zero` (a read never ends), a directory. Every file a
//! command reads, named as each of these, is refused at once with the path
//! and what it is; never a hang or a read until the memory runs out.

#![cfg(unix)]

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

const SCENE: &str = r#"[camera]
look_from = [0.0, 1.0, 2.0]
look_at = [0.0, 0.0, 0.0]
fov_deg = 40.0
resolution = [4, 3]

[film]
spp = 1

[materials.m]
model = "ggx"
metal = "brass"
alpha = 0.2
MATERIAL_EXTRA

[[shapes]]
type = "rectangle"
size = [1.0, 1.0]
material = "m"
transform = { rotate_deg = [-90.0, 0.0, 0.0] }
SHAPE_EXTRA

[[lights]]
type = "point"
position = [0.0, 1.0, 0.0]
intensity = 1.0
LIGHT_EXTRA
"#;

fn scratch(tag: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("lustre-inputs-{tag}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// Runs lustre with `stdin`, failing the test if it runs past 60 s (a hang).
fn lustre(dir: &Path, args: &[&str], stdin: &str) -> (i32, String, String) {
    use std::io::Write;
    let mut child = Command::new(env!("CARGO_BIN_EXE_lustre"))
        .current_dir(dir)
        .args(args)
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    child
        .stdin
        .take()
        .unwrap()
        .write_all(stdin.as_bytes())
        .unwrap();
    let start = Instant::now();
    loop {
        if child.try_wait().unwrap().is_some() {
            break;
        }
        if start.elapsed() > Duration::from_secs(60) {
            child.kill().unwrap();
            panic!("{args:?} hangs");
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    let out = child.wait_with_output().unwrap();
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// Makes `name` in `dir` a FIFO, a link to /dev/zero or a directory.
fn bad_input(dir: &Path, name: &str, kind: &str) -> PathBuf {
    let p = dir.join(name);
    match kind {
        "fifo" => {
            let c = std::ffi::CString::new(p.to_str().unwrap()).unwrap();
            assert_eq!(unsafe { libc::mkfifo(c.as_ptr(), 0o600) }, 0);
        }
        "zero" => std::os::unix::fs::symlink("/dev/zero", &p).unwrap(),
        "dir" => std::fs::create_dir(&p).unwrap(),
        _ => unreachable!(),
    }
    p
}

const KINDS: [(&str, &str); 3] = [
    ("fifo", "a FIFO"),
    ("zero", "a character device"),
    ("dir", "a directory"),
];

#[test]
fn every_scene_input_is_refused_unless_a_regular_file() {
    // (what the scene names, the file's name, where it goes in the scene)
    let uses = [
        (
            "include",
            "fit.toml",
            "MATERIAL_EXTRA",
            "include = \"fit.toml\"",
        ),
        ("nk_csv", "nk.csv", "MATERIAL_EXTRA", "nk_csv = \"nk.csv\""),
        (
            "mesh",
            "m.obj",
            "SHAPE_EXTRA",
            "\n[[shapes]]\ntype = \"mesh\"\nfile = \"m.obj\"\nmaterial = \"m\"",
        ),
        (
            "environment map",
            "env.exr",
            "LIGHT_EXTRA",
            "\n[[lights]]\ntype = \"environment\"\nradiance = 1.0\nfile = \"env.exr\"",
        ),
        (
            "spectrum",
            "sp.csv",
            "LIGHT_EXTRA",
            "spectrum = \"csv(sp.csv)\"",
        ),
    ];
    for (what, file, slot, text) in uses {
        for (kind, described) in KINDS {
            let d = scratch("scene");
            let mut scene = SCENE.replace(slot, text);
            for other in ["MATERIAL_EXTRA", "SHAPE_EXTRA", "LIGHT_EXTRA"] {
                scene = scene.replace(other, "");
            }
            if what == "nk_csv" {
                scene = scene.replace("metal = \"brass\"\n", "");
            }
            std::fs::write(d.join("s.toml"), scene).unwrap();
            bad_input(&d, file, kind);
            let (code, _, err) = lustre(
                &d,
                &["render", "s.toml", "-q", "--no-film", "--png", "o.png"],
                "",
            );
            assert_eq!(code, 1, "{what} as {kind}: {err}");
            assert!(
                err.contains(file) && err.contains(described),
                "{what} as {kind}: {err}"
            );
            let _ = std::fs::remove_dir_all(&d);
        }
    }
    // The scene file itself.
    for (kind, described) in KINDS {
        let d = scratch("scene-self");
        bad_input(&d, "s.toml", kind);
        let (code, _, err) = lustre(&d, &["render", "s.toml", "-q"], "");
        assert_eq!(code, 1, "scene as {kind}: {err}");
        assert!(err.contains(described), "scene as {kind}: {err}");
        let _ = std::fs::remove_dir_all(&d);
    }
}

#[test]
fn command_inputs_are_refused_unless_regular_files() {
    for (kind, described) in KINDS {
        let d = scratch("cmd");
        bad_input(&d, "x.film", kind);
        bad_input(&d, "scan.txt", kind);
        bad_input(&d, "nk.csv", kind);
        bad_input(&d, "mat.toml", kind);
        let runs: [(&[&str], &str); 5] = [
            (&["merge", "x.film", "--png", "o.png"], ""),
            (&["fit", "scan.txt", "--no-plots", "-o", "m.toml"], ""),
            (&["fit", "stats", "scan.txt"], ""),
            (
                &[
                    "preview", "mat.toml", "--size", "8x6", "--spp", "1", "-o", "p.png",
                ],
                "",
            ),
            (&["judge", "scan.txt", "--no-plots", "-o", "j"], ""),
        ];
        for (args, stdin) in runs {
            let (code, _, err) = lustre(&d, args, stdin);
            assert_eq!(code, 1, "{args:?} on {kind}: {err}");
            assert!(err.contains(described), "{args:?} on {kind}: {err}");
        }
        // A `brdf eval` line naming the table: an error line, and the stream goes on.
        let line = r#"{"model":"ggx","alpha":0.2,"nk_csv":"nk.csv","lambda_nm":550,"theta_i_deg":30,"theta_o_deg":30,"phi_o_deg":180}"#;
        let good = r#"{"model":"ggx","alpha":0.2,"metal":"cu","lambda_nm":550,"theta_i_deg":30,"theta_o_deg":30,"phi_o_deg":180}"#;
        let (code, out, err) = lustre(&d, &["brdf", "eval"], &format!("{line}\n{good}\n"));
        assert_eq!(code, 0, "{err}");
        let lines: Vec<&str> = out.lines().collect();
        assert_eq!(lines.len(), 2, "{out}");
        assert!(
            lines[0].contains("error") && lines[0].contains(described),
            "{kind}: {}",
            lines[0]
        );
        assert!(lines[1].contains("\"f\""), "{}", lines[1]);
        let _ = std::fs::remove_dir_all(&d);
    }
}
