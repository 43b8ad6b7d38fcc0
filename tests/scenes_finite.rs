//! Render-level numerical stability: every scene under `scenes/` renders
//! without a NaN, infinite or negative radiance estimate, in both wavelength
//! modes; and corrupted numeric parameters in scene files are reported as
//! errors (or render finitely), never a panic.
//!
//! The film and `sample_pixel` replace non-finite samples by zero, so a check
//! on the image alone could never fail: these tests call the integrator's
//! `camera_sample` on every camera sample and inspect the raw per-wavelength
//! estimate.

use render::integrator::camera_sample;
use render::scene::desc::{SamplerKind, WavelengthMode};
use render::{Film, RenderOptions, Scene};
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::{Path, PathBuf};

const RES: u32 = 16;
const SPP: u64 = 2;

fn scenes_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes")
}

fn scene_files(dir: &Path, out: &mut Vec<PathBuf>) {
    let mut entries: Vec<PathBuf> = std::fs::read_dir(dir)
        .unwrap_or_else(|e| panic!("cannot list {}: {e}", dir.display()))
        .map(|e| e.expect("directory entry").path())
        .collect();
    entries.sort();
    for p in entries {
        if p.is_dir() {
            scene_files(&p, out);
        } else if p.extension().is_some_and(|e| e == "toml") {
            out.push(p);
        }
    }
}

/// The scene text with the resolution and spp replaced and image outputs dropped.
fn shrink(text: &str, width: u32, height: u32, spp: u64) -> String {
    text.lines()
        .filter_map(|line| {
            let key = line.split('=').next().unwrap_or("").trim();
            match key {
                "resolution" => Some(format!("resolution = [{width}, {height}]")),
                "spp" => Some(format!("spp = {spp}")),
                "exr" | "png" => None,
                _ => Some(line.to_string()),
            }
        })
        .collect::<Vec<_>>()
        .join("\n")
}

fn load_small(path: &Path) -> Scene {
    let text = std::fs::read_to_string(path).expect("read scene");
    let scene = render::load_str(path, &shrink(&text, RES, RES, SPP))
        .unwrap_or_else(|e| panic!("bundled scene does not load: {e}"));
    assert_eq!(
        (scene.camera.width, scene.camera.height),
        (RES, RES),
        "{}: resolution was not overridden",
        path.display()
    );
    scene
}

/// Every camera sample of every pixel, as `sample_pixel` draws it, but
/// returning the first raw estimate that is NaN, infinite or negative.
fn first_bad_sample(scene: &Scene, spp: u64) -> Option<String> {
    let cam = &scene.camera;
    for y in 0..cam.height {
        for x in 0..cam.width {
            for s in 0..spp {
                let cs = camera_sample(scene, x, y, s);
                // The exactly integrated part: finite, and its Y not negative
                // unless the scene's estimates are signed (a glossy control
                // variate's may be).
                if !(cs.xyz.iter().all(|v| v.is_finite())
                    && (cs.xyz[1] >= 0.0 || scene.signed_radiance))
                {
                    return Some(format!(
                        "pixel ({x}, {y}) sample {s}: exactly integrated XYZ {:?} (mode {:?}, sampler {:?})",
                        cs.xyz, scene.settings.mode, scene.settings.sampler
                    ));
                }
                if let Some(j) = (0..cs.wavelengths.len())
                    .find(|&j| !(cs.radiance[j].is_finite() && cs.radiance[j] >= 0.0))
                {
                    return Some(format!(
                        "pixel ({x}, {y}) sample {s}: radiance {} at λ = {:.3} nm (mode {:?}, sampler {:?})",
                        cs.radiance[j],
                        cs.wavelengths.lambdas()[j],
                        scene.settings.mode,
                        scene.settings.sampler
                    ));
                }
            }
        }
    }
    None
}

/// Checks one scene in both wavelength modes and through the film.
fn check_scene(path: &Path) -> Vec<String> {
    let mut scene = load_small(path);
    let mut bad = Vec::new();
    for (mode, sampler) in [
        (WavelengthMode::Single, SamplerKind::Sobol),
        (WavelengthMode::Hero, SamplerKind::Sobol),
        (WavelengthMode::Hero, SamplerKind::Independent),
    ] {
        scene.settings.mode = mode;
        scene.settings.sampler = sampler;
        // With the first bounce integrated over λ exactly (the default,
        // where some material is Fresnel-only) and with every wavelength
        // sampled.
        let tables = scene.spectral.take();
        if let Some(m) = first_bad_sample(&scene, SPP) {
            bad.push(format!("{}: sampled λ: {m}", path.display()));
        }
        scene.spectral = tables;
        if let Some(m) = first_bad_sample(&scene, SPP) {
            bad.push(format!("{}: {m}", path.display()));
        }
    }
    let mut film = Film::new(RES, RES, scene.fingerprint, scene.settings.seed, 0.0).unwrap();
    let opts = RenderOptions {
        threads: Some(1),
        ..RenderOptions::default()
    };
    match render::render_range(&scene, &mut film, 0..SPP, &opts) {
        Ok(o) if o.complete => {
            if film.rgb().iter().flatten().any(|v| !v.is_finite()) {
                bad.push(format!("{}: non-finite film pixel", path.display()));
            }
        }
        Ok(_) => bad.push(format!("{}: render stopped early", path.display())),
        Err(e) => bad.push(format!("{}: render failed: {e}", path.display())),
    }
    bad
}

#[test]
fn every_bundled_scene_renders_finite() {
    let mut files = Vec::new();
    scene_files(&scenes_dir(), &mut files);
    assert!(
        files.len() >= 2 && files.iter().any(|f| f.ends_with("default.toml")),
        "expected scenes/default.toml and scenes/samples/*.toml, found {files:?}"
    );
    // Scenes are independent: split them over the available cores.
    let workers = std::thread::available_parallelism().map_or(2, |n| n.get().min(4));
    let chunks: Vec<Vec<PathBuf>> = (0..workers)
        .map(|w| files.iter().skip(w).step_by(workers).cloned().collect())
        .collect();
    let bad: Vec<String> = std::thread::scope(|s| {
        let handles: Vec<_> = chunks
            .iter()
            .map(|chunk| {
                s.spawn(move || {
                    chunk
                        .iter()
                        .flat_map(|p| check_scene(p))
                        .collect::<Vec<_>>()
                })
            })
            .collect();
        handles
            .into_iter()
            .flat_map(|h| h.join().expect("scene worker panicked"))
            .collect()
    });
    assert!(
        bad.is_empty(),
        "{} problem(s) in {} scenes:\n{}",
        bad.len(),
        files.len(),
        bad.join("\n")
    );
}

/// Values that a hand-edited scene file could plausibly contain by mistake.
const BAD_VALUES: [&str; 6] = ["0", "-1", "nan", "inf", "-inf", "1e-300"];

/// Replaces the value of every `key = <number>` line (one at a time) in a
/// scene by each of [`BAD_VALUES`]. Loading must return an error naming the
/// scene file, or build a scene whose samples are all finite and ≥ 0; it must
/// never panic.
#[test]
fn corrupted_numbers_are_reported_not_panicking() {
    let dir = scenes_dir();
    // One scene per material model, plus the default scene (sphere + environment light).
    let scenes = [
        "default.toml",
        "samples/s138_beckmann_45deg.toml",
        "samples/s138_ghs_ssa_grazing.toml",
        "samples/s027_ghs_normal.toml",
        "samples/s091_two_scale_45deg.toml",
        "samples/s280_measured_psd_normal.toml",
    ];
    let mut problems = Vec::new();
    let mut reported = 0usize;
    let mut accepted = 0usize;
    for rel in scenes {
        let path = dir.join(rel);
        let text = shrink(
            &std::fs::read_to_string(&path).expect("read scene"),
            4,
            4,
            1,
        );
        let lines: Vec<&str> = text.lines().collect();
        for (i, line) in lines.iter().enumerate() {
            let Some((key, value)) = line.split_once('=') else {
                continue;
            };
            let key = key.trim();
            if key.starts_with('#') || value.trim().parse::<f64>().is_err() {
                continue;
            }
            for bad in BAD_VALUES {
                let mut edited = lines.clone();
                let new_line = format!("{key} = {bad}");
                edited[i] = &new_line;
                let edited = edited.join("\n");
                let what = format!("{rel} line {}: `{new_line}`", i + 1);
                let outcome = catch_unwind(AssertUnwindSafe(|| {
                    match render::load_str(&path, &edited) {
                        Err(e) => Err(e.to_string()),
                        Ok(mut scene) => {
                            let mut bad_sample = None;
                            for mode in [WavelengthMode::Single, WavelengthMode::Hero] {
                                scene.settings.mode = mode;
                                bad_sample = bad_sample.or(first_bad_sample(&scene, 1));
                            }
                            Ok(bad_sample)
                        }
                    }
                }));
                match outcome {
                    Err(_) => problems.push(format!("{what}: panicked")),
                    Ok(Err(msg)) => {
                        reported += 1;
                        if !msg.contains(rel.rsplit('/').next().unwrap_or(rel)) {
                            problems.push(format!("{what}: error does not name the file: {msg}"));
                        }
                    }
                    Ok(Ok(Some(m))) => problems.push(format!("{what}: accepted, but {m}")),
                    Ok(Ok(None)) => accepted += 1,
                }
            }
        }
    }
    // Most of these values are invalid (zero or negative sizes, NaN, ...): a
    // loader that accepted everything would pass the finiteness check vacuously.
    assert!(
        reported > accepted,
        "only {reported} of {} corrupted scenes were rejected",
        reported + accepted
    );
    assert!(
        problems.is_empty(),
        "{} problem(s) ({reported} rejected, {accepted} accepted and finite):\n{}",
        problems.len(),
        problems.join("\n")
    );
}
