//! What a render keeps when it is killed or the disk fills: `kill -9` at any
//! moment leaves the last checkpoint whole, and `--resume` from it finishes
//! bit-identical to a render never interrupted; a write that runs out of
//! space leaves the previous film and images intact and no temporary file.

#![cfg(unix)]

use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Duration;

/// Three seconds of work in a test build at 4096 spp: enough passes and
/// checkpoints to be killed in the middle of.
const SCENE: &str = r#"[camera]
look_from = [0.0, 1.0, 2.0]
look_at = [0.0, 0.0, 0.0]
fov_deg = 40.0
resolution = [96, 64]

[film]
spp = 4096
exr = "out.exr"

[materials.m]
model = "ggx"
metal = "cu"
alpha = 0.2

[[shapes]]
type = "rectangle"
size = [1.0, 1.0]
material = "m"
transform = { rotate_deg = [-90.0, 0.0, 0.0] }

[[lights]]
type = "sphere"
center = [0.3, 1.0, 0.2]
radius = 0.2
radiance = 5.0
"#;

fn scratch(tag: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("lustre-crash-{tag}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    std::fs::write(d.join("s.toml"), SCENE).unwrap();
    d
}

fn lustre(dir: &Path) -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_lustre"));
    c.current_dir(dir);
    c
}

fn ok(c: &mut Command) {
    let out = c.output().unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

#[test]
fn kill_9_then_resume_is_bit_identical() {
    let d = scratch("kill");
    let spp = "4096";
    ok(lustre(&d).args([
        "render",
        "s.toml",
        "-q",
        "--spp",
        spp,
        "--film",
        "whole.film",
    ]));
    let whole = std::fs::read(d.join("whole.film")).unwrap();
    // Killed before any checkpoint, as the first appears, and a while after it; each
    // run resumed from whatever it left.
    for (after_checkpoint, kill_after_ms) in [(false, 150u64), (true, 0), (true, 1100)] {
        let _ = std::fs::remove_file(d.join("r.film"));
        let mut child = lustre(&d)
            .args([
                "render",
                "s.toml",
                "-q",
                "--spp",
                spp,
                "--film",
                "r.film",
                "--checkpoint-every",
                "1",
            ])
            .spawn()
            .unwrap();
        if after_checkpoint {
            let start = std::time::Instant::now();
            while !d.join("r.film").exists() {
                assert!(start.elapsed() < Duration::from_secs(60), "no checkpoint");
                std::thread::sleep(Duration::from_millis(5));
            }
        }
        std::thread::sleep(Duration::from_millis(kill_after_ms));
        // SIGKILL: no handler runs, nothing is flushed.
        child.kill().unwrap();
        child.wait().unwrap();
        let names: Vec<String> = std::fs::read_dir(&d)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        if let Ok(bytes) = std::fs::read(d.join("r.film")) {
            // What is there is a whole film.
            render::Film::from_bytes(&bytes).unwrap();
        }
        ok(lustre(&d).args([
            "render", "s.toml", "-q", "--spp", spp, "--film", "r.film", "--resume",
        ]));
        assert_eq!(
            std::fs::read(d.join("r.film")).unwrap(),
            whole,
            "killed after {kill_after_ms} ms (files then: {names:?})"
        );
    }
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn a_full_disk_leaves_the_previous_outputs_intact() {
    let d = scratch("full");
    let mnt = d.join("small");
    std::fs::create_dir_all(&mnt).unwrap();
    // A 64 KiB file system (needs root; elsewhere the test has nothing to check).
    let mounted = Command::new("mount")
        .args(["-t", "tmpfs", "-o", "size=64k", "tmpfs"])
        .arg(&mnt)
        .status()
        .is_ok_and(|s| s.success());
    if !mounted {
        eprintln!("skipped: cannot mount a small tmpfs here (not root)");
        return;
    }
    let small = SCENE.replace("resolution = [96, 64]", "resolution = [8, 6]");
    std::fs::write(d.join("small.toml"), small).unwrap();
    let run = |scene: &str| {
        lustre(&d)
            .args(["render", scene, "-q", "--spp", "4", "--film"])
            .arg(mnt.join("o.film"))
            .arg("--exr")
            .arg(mnt.join("o.exr"))
            .output()
            .unwrap()
    };
    let first = run("small.toml");
    let result = std::panic::catch_unwind(|| {
        assert!(first.status.success());
        let film = std::fs::read(mnt.join("o.film")).unwrap();
        let exr = std::fs::read(mnt.join("o.exr")).unwrap();
        // 96 × 64 pixels need 295 kB of film: the disk is full half-way.
        let second = run("s.toml");
        let err = String::from_utf8_lossy(&second.stderr);
        assert_eq!(second.status.code(), Some(1), "{err}");
        assert!(err.contains("o.film") || err.contains("o.exr"), "{err}");
        assert_eq!(std::fs::read(mnt.join("o.film")).unwrap(), film);
        assert_eq!(std::fs::read(mnt.join("o.exr")).unwrap(), exr);
        let mut names: Vec<String> = std::fs::read_dir(&mnt)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        names.sort();
        assert_eq!(names, ["o.exr", "o.film"], "temporary files left behind");
    });
    let _ = Command::new("umount").arg(&mnt).status();
    let _ = std::fs::remove_dir_all(&d);
    if let Err(e) = result {
        std::panic::resume_unwind(e);
    }
}
