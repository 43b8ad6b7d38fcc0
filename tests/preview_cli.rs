//! `lustre preview` end to end through the built binary: a paper sample's
//! models in a grid, a material file alone, and clear errors for bad input.

use std::path::Path;
use std::process::{Command, Output};

fn lustre(args: &[&str], dir: &Path) -> Output {
    Command::new(env!("CARGO_BIN_EXE_lustre"))
        .args(args)
        .current_dir(dir)
        .output()
        .expect("run lustre")
}

fn scratch(name: &str) -> std::path::PathBuf {
    let d = std::env::temp_dir().join(format!("lustre-preview-cli-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn png_size(path: &Path) -> (u32, u32) {
    let b = std::fs::read(path).unwrap();
    assert_eq!(&b[1..4], b"PNG", "{} is not a PNG", path.display());
    let be = |i: usize| u32::from_be_bytes([b[i], b[i + 1], b[i + 2], b[i + 3]]);
    (be(16), be(20))
}

#[test]
fn sample_models_grid_writes_images_and_scenes() {
    let dir = scratch("grid");
    let out = lustre(
        &[
            "preview",
            "--sample",
            "s280",
            "--models",
            "ggx,ghs_ssa",
            "--size",
            "24x18",
            "--spp",
            "2",
            "--threads",
            "2",
            "-o",
            "g/s280.png",
        ],
        &dir,
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let g = dir.join("g");
    for f in [
        "s280.png",
        "s280_ggx.exr",
        "s280_ghs_ssa.exr",
        "s280_ggx.toml",
        "s280_ghs_ssa.toml",
        "assets/preview_object.obj",
        "assets/preview_floor_a.obj",
        "assets/preview_floor_b.obj",
    ] {
        assert!(g.join(f).is_file(), "missing {f}");
    }
    let (w, h) = png_size(&g.join("s280.png"));
    assert!(w > 48 && h > 18, "grid is {w}×{h}");
    // The written scene renders on its own, from its directory.
    let again = lustre(&["render", "s280_ggx.toml", "--spp", "1", "-q"], &g);
    assert!(
        again.status.success(),
        "{}",
        String::from_utf8_lossy(&again.stderr)
    );
    assert!(g.join("s280_ggx.png").is_file());
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn material_file_alone_and_in_the_studio() {
    let dir = scratch("material");
    std::fs::write(
        dir.join("steel.toml"),
        "[material]\nmodel = \"ggx\"\nmetal = \"stainless_steel\"\nalpha = 0.05\n",
    )
    .unwrap();
    let out = lustre(
        &[
            "preview",
            "steel.toml",
            "--light",
            "studio",
            "--size",
            "20x15",
            "--spp",
            "2",
            "-q",
        ],
        &dir,
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert_eq!(png_size(&dir.join("out/preview/steel.png")), (20, 15));
    assert!(dir.join("out/preview/steel.exr").is_file());
    let scene = std::fs::read_to_string(dir.join("out/preview/steel.toml")).unwrap();
    assert!(scene.contains("type = \"rectangle\"") && !scene.contains("type = \"sky\""));
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn bad_input_is_a_clear_error() {
    let dir = scratch("errors");
    for (args, want) in [
        (vec!["preview", "--sample", "S999"], "unknown sample"),
        (
            vec!["preview", "--sample", "S280", "--models", "phong"],
            "unknown model",
        ),
        (vec!["preview", "missing.toml"], "missing.toml"),
        (
            vec![
                "preview",
                "--sample",
                "S280",
                "--turbidity",
                "1",
                "--models",
                "ggx",
            ],
            "--turbidity 1",
        ),
        // Named as the flag, not as a line of the generated scene file.
        (
            vec!["preview", "--sample", "S280", "--sun-elevation", "100"],
            "--sun-elevation 100",
        ),
        (
            vec![
                "preview",
                "--sample",
                "S280",
                "--light",
                "both",
                "--sun-elevation",
                "0",
            ],
            "--sun-elevation 0",
        ),
        (
            vec!["preview", "--sample", "S280", "--time-limit", "soon"],
            "time-limit",
        ),
    ] {
        let out = lustre(&args, &dir);
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success(), "{args:?} succeeded");
        assert!(err.contains(want), "{args:?}: {err}");
        assert!(!err.contains("panicked"), "{args:?}: {err}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn preview_and_compare_never_write_over_the_material_file() {
    // `lustre preview steel.toml --out steel.png` wrote its scene file `steel.toml` over the
    // fitted material (and then failed to load it as one); `compare --out steel.toml` would
    // write its PNG there. Both now refuse before writing anything.
    let dir = scratch("overwrite");
    let material = "[material]\nmodel = \"ggx\"\nmetal = \"stainless_steel\"\nalpha = 0.05\n";
    std::fs::write(dir.join("steel.toml"), material).unwrap();
    for args in [
        vec!["preview", "steel.toml", "--out", "steel.png"],
        vec!["preview", "steel.toml", "--out", "./steel.toml"],
        vec![
            "preview",
            "steel.toml",
            "--models",
            "ggx",
            "--out",
            "steel.png",
        ],
        vec!["compare", "--material", "steel.toml", "--out", "steel.toml"],
    ] {
        let mut args = args;
        args.extend(["--size", "8x6", "--spp", "1", "-q"]);
        let out = lustre(&args, &dir);
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success(), "{args:?} succeeded");
        assert!(
            err.contains("is the input") && err.contains("steel.toml") && err.contains("Fix:"),
            "{args:?}: {err}"
        );
        assert_eq!(
            std::fs::read_to_string(dir.join("steel.toml")).unwrap(),
            material,
            "{args:?} changed the material file"
        );
    }
    // Another name beside it is fine.
    let out = lustre(
        &[
            "preview",
            "steel.toml",
            "--out",
            "steel_preview.png",
            "--size",
            "8x6",
            "--spp",
            "1",
            "-q",
        ],
        &dir,
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert_eq!(
        std::fs::read_to_string(dir.join("steel.toml")).unwrap(),
        material
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn an_unknown_model_in_the_material_file_is_blamed_on_the_file() {
    // It was reported as `--models phong: unknown model`, naming a flag that was never given.
    let dir = scratch("filemodel");
    std::fs::write(
        dir.join("steel.toml"),
        "[material]\nmodel = \"phong\"\nmetal = \"stainless_steel\"\nalpha = 0.05\n",
    )
    .unwrap();
    let out = lustre(
        &["preview", "steel.toml", "--size", "8x6", "--spp", "1"],
        &dir,
    );
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success());
    assert!(
        err.contains("steel.toml:2: `model = \"phong\"`")
            && err.contains("Fix:")
            && !err.contains("--models phong"),
        "{err}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}
