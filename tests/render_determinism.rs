//! The image depends only on (scene, seed, sample indices): not on the thread
//! count, and shards merged with `lustre merge` equal one render bit for bit.

use render::{Film, RenderOptions, Scene};
use std::path::PathBuf;
use std::process::Command;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

const SCENE: &str = r#"
[camera]
look_from = [0.0, 0.6, 1.0]
look_at = [0.0, 0.0, 0.0]
fov_deg = 40.0
resolution = [40, 24]

[film]
spp = 12
seed = 11

[integrator]
max_depth = 5
wavelengths = "hero"

[materials.steel]
model = "ggx"
metal = "stainless_steel"
alpha = 0.15

[materials.brass]
model = "beckmann"
metal = "brass"
alpha = 0.3

[[shapes]]
type = "rectangle"
size = [1.0, 1.0]
material = "steel"
transform = { rotate_deg = [-90.0, 0.0, 0.0] }

[[shapes]]
type = "sphere"
center = [0.0, 0.2, 0.0]
radius = 0.2
material = "brass"

[[lights]]
type = "rectangle"
size = [0.3, 0.3]
radiance = 20.0
spectrum = "blackbody(4000)"
transform = { translate = [0.0, 1.0, -0.5], rotate_deg = [90.0, 0.0, 0.0] }

[[lights]]
type = "environment"
radiance = 0.2
"#;

fn scene() -> Scene {
    render::load_str(&root().join("tests/determinism.toml"), SCENE).unwrap()
}

fn render(scene: &Scene, range: std::ops::Range<u64>, threads: usize) -> Film {
    let mut film = Film::new(40, 24, scene.fingerprint, scene.settings.seed, 0.0).unwrap();
    let opts = RenderOptions {
        threads: Some(threads),
        ..Default::default()
    };
    let out = render::render_range(scene, &mut film, range, &opts).unwrap();
    assert!(out.complete);
    film
}

#[test]
fn identical_across_thread_counts() {
    let s = scene();
    let a = render(&s, 0..6, 1);
    let b = render(&s, 0..6, 2);
    let c = render(&s, 0..6, 3);
    assert_eq!(a.sums(), b.sums());
    assert_eq!(a.sums(), c.sums());
    // A test that cannot fail is a defect: the image must not be trivial.
    assert!(a.sums().iter().filter(|p| p[1] != 0).count() > 900);
}

#[test]
fn merged_shards_equal_one_render() {
    let s = scene();
    let whole = render(&s, 0..12, 2);
    let mut merged = render(&s, 7..12, 2);
    merged.merge(&render(&s, 0..3, 1)).unwrap();
    merged.merge(&render(&s, 3..7, 2)).unwrap();
    assert_eq!(merged.ranges(), std::slice::from_ref(&(0..12)));
    assert_eq!(merged, whole);
    assert_eq!(merged.rgb(), whole.rgb());
}

/// The same through the command line: two `--spp-range` shards and `lustre merge`.
#[test]
fn cli_shards_and_merge() {
    let dir = std::env::temp_dir().join(format!("lustre-cli-merge-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let scene_file = dir.join("scene.toml");
    std::fs::write(&scene_file, SCENE).unwrap();
    let exe = env!("CARGO_BIN_EXE_lustre");
    let run = |args: &[&str]| {
        let out = Command::new(exe)
            .args(args)
            .current_dir(&dir)
            .output()
            .unwrap();
        assert!(
            out.status.success(),
            "{args:?}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
    };
    let s = scene_file.to_str().unwrap();
    run(&[
        "render",
        s,
        "--spp-range",
        "0..5",
        "--film",
        "a.film",
        "--threads",
        "1",
        "-q",
    ]);
    run(&[
        "render",
        s,
        "--spp-range",
        "5..12",
        "--film",
        "b.film",
        "--threads",
        "2",
        "-q",
    ]);
    run(&[
        "render",
        s,
        "--film",
        "whole.film",
        "--exr",
        "whole.exr",
        "-q",
    ]);
    run(&[
        "merge",
        "a.film",
        "b.film",
        "--film",
        "merged.film",
        "--exr",
        "merged.exr",
        "--png",
        "merged.png",
        "-q",
    ]);
    let merged = Film::load(&dir.join("merged.film")).unwrap();
    let whole = Film::load(&dir.join("whole.film")).unwrap();
    assert_eq!(merged, whole);
    let (_, _, a) = render::output::read_exr(&dir.join("merged.exr")).unwrap();
    let (_, _, b) = render::output::read_exr(&dir.join("whole.exr")).unwrap();
    assert_eq!(a, b);
    // Overlapping shards are refused.
    let out = Command::new(exe)
        .args(["merge", "a.film", "a.film", "--film", "x.film"])
        .current_dir(&dir)
        .output()
        .unwrap();
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("overlaps"));
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A time limit stops early and `--resume` completes to the same film.
#[test]
fn resume_completes_to_the_same_film() {
    let dir = std::env::temp_dir().join(format!("lustre-cli-resume-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("scene.toml"), SCENE).unwrap();
    let exe = env!("CARGO_BIN_EXE_lustre");
    let run = |args: &[&str]| {
        let out = Command::new(exe)
            .args(args)
            .current_dir(&dir)
            .output()
            .unwrap();
        assert!(
            out.status.success(),
            "{args:?}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
    };
    run(&[
        "render",
        "scene.toml",
        "--spp",
        "4",
        "--film",
        "r.film",
        "-q",
    ]);
    assert_eq!(Film::load(&dir.join("r.film")).unwrap().spp(), 4);
    run(&[
        "render",
        "scene.toml",
        "--spp",
        "12",
        "--film",
        "r.film",
        "--resume",
        "-q",
    ]);
    run(&[
        "render",
        "scene.toml",
        "--spp",
        "12",
        "--film",
        "ref.film",
        "-q",
    ]);
    let resumed = Film::load(&dir.join("r.film")).unwrap();
    assert_eq!(resumed.ranges(), std::slice::from_ref(&(0..12)));
    assert_eq!(resumed, Film::load(&dir.join("ref.film")).unwrap());
    std::fs::remove_dir_all(&dir).unwrap();
}

/// An already-expired time limit writes a valid (possibly empty) film and image.
#[test]
fn time_limit_writes_what_it_has() {
    let s = scene();
    let mut film = Film::new(40, 24, s.fingerprint, s.settings.seed, 0.0).unwrap();
    let opts = RenderOptions {
        threads: Some(2),
        time_limit: Some(std::time::Duration::from_millis(1)),
        ..Default::default()
    };
    let out = render::render_range(&s, &mut film, 0..100_000, &opts).unwrap();
    assert!(!out.complete);
    assert_eq!(film.spp(), out.rendered.end);
    assert!(film.spp() < 100_000);
}
