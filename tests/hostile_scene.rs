//! Scene files as a hostile user (or a bad editor) hands them over: every
//! truncation and single-character garbage edit of bundled scenes, extreme
//! numbers in every numeric field, arrays of the wrong length, oversized
//! files and misspelt keys in `include`d material files. Each must load or
//! fail with an error — never panic — and scenes that do load must render a
//! few samples without panicking.

use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::{Path, PathBuf};

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// One bundled scene per model, plus the default scene.
fn bundled() -> Vec<PathBuf> {
    let mut v = vec![root().join("scenes/default.toml")];
    for m in [
        "ggx",
        "beckmann",
        "ghs_ssa",
        "ghs",
        "two_scale",
        "measured_psd",
    ] {
        v.push(root().join(format!("scenes/samples/s138_{m}_45deg.toml")));
    }
    v
}

/// Loads `text` as if it were `path`; if it loads, traces a few camera
/// samples. Returns whether it loaded, or the panic message.
fn try_scene(path: &Path, text: &str) -> Result<bool, String> {
    catch_unwind(AssertUnwindSafe(|| match render::load_str(path, text) {
        Err(e) => {
            assert!(!e.to_string().is_empty());
            false
        }
        Ok(scene) => {
            let (w, h) = (scene.camera.width, scene.camera.height);
            for k in 0..8u32 {
                let (x, y) = ((k * 37) % w, (k * 11) % h);
                let _ = render::integrator::sample_pixel_checked(&scene, x, y, k as u64);
            }
            true
        }
    }))
    .map_err(|p| {
        p.downcast_ref::<String>()
            .cloned()
            .or_else(|| p.downcast_ref::<&str>().map(|s| s.to_string()))
            .unwrap_or_else(|| "non-string panic".into())
    })
}

/// Byte range of `text` to edit. Every valid edit rebuilds the scene's
/// material, which costs 20–150 ms for the table-based models; their
/// camera, film and light sections are the generator's and the same as in
/// the cheap scenes (edited in full there), so only their material table
/// is edited.
fn expensive(path: &Path) -> bool {
    let name = path.file_name().unwrap().to_string_lossy();
    ["_ghs_45", "_two_scale_", "_measured_psd_"]
        .iter()
        .any(|m| name.contains(m))
}

fn edit_range(path: &Path, text: &str) -> std::ops::Range<usize> {
    if !expensive(path) {
        return 0..text.len();
    }
    let start = text.find("[materials.").expect("a material table");
    let end = text[start + 1..]
        .find("\n[")
        .map_or(text.len(), |i| start + 1 + i);
    start..end
}

/// Whether byte `i` lies on a comment line (edits there leave the scene
/// valid, and for the table-based scenes only rebuild the same tables).
fn in_comment(text: &str, i: usize) -> bool {
    let start = text[..i].rfind('\n').map_or(0, |k| k + 1);
    text[start..].trim_start().starts_with('#')
}

fn char_boundaries(t: &str) -> Vec<usize> {
    (0..=t.len()).filter(|&i| t.is_char_boundary(i)).collect()
}

#[test]
fn every_truncation_of_bundled_scenes_is_an_error_or_a_scene() {
    let mut failures = Vec::new();
    let mut loaded = 0;
    let mut total = 0;
    for p in bundled() {
        let text = std::fs::read_to_string(&p).unwrap();
        for cut in char_boundaries(&text) {
            total += 1;
            match try_scene(&p, &text[..cut]) {
                Ok(true) => loaded += 1,
                Ok(false) => {}
                Err(m) => failures.push(format!("{} cut at {cut}: panic {m}", p.display())),
            }
        }
    }
    assert!(
        failures.is_empty(),
        "{} panics:\n{}",
        failures.len(),
        failures.join("\n")
    );
    // A prefix is a valid scene only when the cut falls in the trailing
    // lines of the last light (e.g. "radiance = 0.0" of "0.02").
    assert!(
        loaded < total / 20,
        "{loaded} of {total} truncations loaded"
    );
    eprintln!("{total} truncations: {loaded} still valid scenes, the rest errors, no panic");
}

#[test]
fn single_character_garbage_edits_are_errors_or_scenes() {
    const GARBAGE: [&str; 12] = [
        "\"", "[", "]", "=", "{", "\u{0}", "é", "\\", "\n", "#", "-", "9",
    ];
    // Edits that keep a table-based scene valid rebuild its tables; for
    // those scenes valid variants are left to the extreme-number test and
    // only the first eight (syntax-breaking) characters are used.
    let mut failures = Vec::new();
    let mut total = 0;
    for p in bundled() {
        let t0 = std::time::Instant::now();
        let text = std::fs::read_to_string(&p).unwrap();
        let range = edit_range(&p, &text);
        for (i, ch) in text.char_indices() {
            if !range.contains(&i) || (expensive(&p) && in_comment(&text, i)) {
                continue;
            }
            let garbage = if expensive(&p) {
                &GARBAGE[..8]
            } else {
                &GARBAGE[..]
            };
            for g in garbage {
                let edited = format!("{}{g}{}", &text[..i], &text[i + ch.len_utf8()..]);
                total += 1;
                if let Err(m) = try_scene(&p, &edited) {
                    failures.push(format!("{} byte {i} → {g:?}: panic {m}", p.display()));
                }
            }
        }
        eprintln!("{}: {:.1} s", p.display(), t0.elapsed().as_secs_f64());
    }
    assert!(
        failures.is_empty(),
        "{} panics:\n{}",
        failures.len(),
        failures.join("\n")
    );
    eprintln!("{total} garbage edits: no panic");
}

/// Every number in the scene replaced, one at a time, by extreme values.
#[test]
fn extreme_numbers_in_every_field_are_errors_or_scenes() {
    const EXTREMES: [&str; 12] = [
        "0",
        "-1",
        "-0.0",
        "1e308",
        "1e-308",
        "nan",
        "inf",
        "-inf",
        "4294967296",
        "18446744073709551615",
        "1e30",
        "3",
    ];
    let mut failures = Vec::new();
    let mut total = 0;
    for p in bundled() {
        let text = std::fs::read_to_string(&p).unwrap();
        let bytes = text.as_bytes();
        // Number tokens: maximal runs of [0-9.eE+-] starting with a digit or
        // sign, outside comments and strings (good enough for these files).
        let mut i = 0;
        let mut numbers = Vec::new();
        let mut in_comment = false;
        let mut in_string = false;
        while i < bytes.len() {
            let c = bytes[i];
            if c == b'\n' {
                in_comment = false;
            } else if !in_string && c == b'#' {
                in_comment = true;
            } else if !in_comment && c == b'"' {
                in_string = !in_string;
            } else if !in_comment
                && !in_string
                && (c.is_ascii_digit() || c == b'-')
                && i > 0
                && matches!(bytes[i - 1], b' ' | b'[' | b',' | b'=')
            {
                let start = i;
                while i < bytes.len()
                    && matches!(bytes[i], b'0'..=b'9' | b'.' | b'e' | b'E' | b'+' | b'-')
                {
                    i += 1;
                }
                numbers.push(start..i);
                continue;
            }
            i += 1;
        }
        let range = edit_range(&p, &text);
        numbers.retain(|r| range.contains(&r.start));
        assert!(
            expensive(&p) || numbers.len() >= 15,
            "{}: {} numbers",
            p.display(),
            numbers.len()
        );
        for r in &numbers {
            for x in EXTREMES {
                let edited = format!("{}{x}{}", &text[..r.start], &text[r.end..]);
                total += 1;
                if let Err(m) = try_scene(&p, &edited) {
                    failures.push(format!(
                        "{} `{}` → {x}: panic {m}",
                        p.display(),
                        &text[r.clone()]
                    ));
                }
            }
        }
    }
    assert!(
        failures.is_empty(),
        "{} panics:\n{}",
        failures.len(),
        failures.join("\n")
    );
    eprintln!("{total} extreme-number edits: no panic");
}

const SMALL: &str = r#"[camera]
look_from = [0.0, 1.0, 2.0]
look_at = [0.0, 0.0, 0.0]
fov_deg = 40.0
resolution = [8, 6]

[film]
spp = 1

[materials.m]
model = "ggx"
metal = "brass"
alpha = 0.2

[[shapes]]
type = "rectangle"
size = [1.0, 1.0]
material = "m"
transform = { translate = [0.0, 0.0, 0.0], rotate_deg = [-90.0, 0.0, 0.0] }

[[lights]]
type = "point"
position = [0.0, 1.0, 0.0]
intensity = 1.0
"#;

fn small_error(from: &str, to: &str) -> String {
    assert!(SMALL.contains(from), "test bug: {from}");
    match render::load_str(
        &root().join("tests/small.toml"),
        &SMALL.replacen(from, to, 1),
    ) {
        Ok(_) => panic!("`{to}` was accepted"),
        Err(e) => e.to_string(),
    }
}

#[test]
fn arrays_must_have_exactly_their_length() {
    render::load_str(&root().join("tests/small.toml"), SMALL).unwrap();
    for (from, to) in [
        ("resolution = [8, 6]", "resolution = [8, 6, 7]"),
        ("resolution = [8, 6]", "resolution = [8]"),
        ("resolution = [8, 6]", "resolution = []"),
        (
            "look_from = [0.0, 1.0, 2.0]",
            "look_from = [0.0, 1.0, 2.0, 5.0]",
        ),
        ("look_at = [0.0, 0.0, 0.0]", "look_at = [0.0, 0.0]"),
        ("size = [1.0, 1.0]", "size = [1.0, 1.0, 1.0]"),
        (
            "translate = [0.0, 0.0, 0.0]",
            "translate = [0.0, 0.0, 0.0, 0.0]",
        ),
        ("rotate_deg = [-90.0, 0.0, 0.0]", "rotate_deg = [-90.0]"),
        (
            "position = [0.0, 1.0, 0.0]",
            "position = [0.0, 1.0, 0.0, 1.0]",
        ),
        ("alpha = 0.2", "nk = [1.5, 2.0, 3.0]"),
    ] {
        let e = small_error(from, to);
        assert!(e.contains("an array of exactly"), "{to}: {e}");
        assert!(e.contains("small.toml:"), "{to}: {e}");
    }
    let e = small_error("resolution = [8, 6]", "resolution = [8, 6, 7]");
    assert!(e.contains("invalid length 3"), "{e}");
}

#[test]
fn resolution_must_be_two_positive_integers_within_the_pixel_budget() {
    for to in [
        "resolution = [0, 6]",
        "resolution = [8, -6]",
        "resolution = [8.5, 6]",
        "resolution = [32768, 32768]",
        "resolution = [32769, 1]",
        "resolution = [4294967296, 1]",
        "resolution = [\"8\", 6]",
    ] {
        let e = small_error("resolution = [8, 6]", to);
        assert!(e.contains("small.toml:5:"), "{to}: {e}");
    }
}

#[test]
fn oversized_scene_files_are_refused_before_parsing() {
    let dir = std::env::temp_dir().join(format!("lustre-hostile-scene-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    // The issue's case: a 50 MB resolution array (2.3 GB to parse).
    let p = dir.join("huge.toml");
    let mut text = SMALL.replace("resolution = [8, 6]", "resolution = [8, 6");
    text.reserve(50 << 20);
    while text.len() < 50 << 20 {
        text.push_str(", 1");
    }
    text.push_str("]\n");
    std::fs::write(&p, &text).unwrap();
    let e = render::load_scene(&p).err().expect("refused").to_string();
    assert!(e.contains("huge.toml") && e.contains("larger than"), "{e}");
    // Not UTF-8.
    let q = dir.join("latin1.toml");
    let mut b = SMALL.as_bytes().to_vec();
    b[2] = 0xe9;
    std::fs::write(&q, &b).unwrap();
    let e = render::load_scene(&q).err().expect("refused").to_string();
    assert!(e.contains("latin1.toml:1:3") && e.contains("UTF-8"), "{e}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// An `include`d material file as `lustre fit` writes it (diagnostics
/// tables and provenance keys included).
const FIT_FILE: &str = r#"# written by lustre fit
[provenance]
file = "scan.x3p"
sha256 = "00"
tool = "lustre fit 0.1.0"

[material]
metal = "brass"
model = "ggx"
sigma_um = 0.138
lc_um = 2.0
gamma = 2.0
alpha = 0.05
alpha_beckmann = 0.06

[fit]
sigma_um_err = 0.001
kc_degenerate = false

[two_scale.cutoff_10]
beta = 0.01
beta_source = "psd"
sigma_um = 0.1
lc_um = 1.0
gamma = 2.5
cutoff_um = 5.5
fit_f_range_per_m = [1.0, 2.0]
kc_degenerate = false

[psd]
source = "kc"
integral_um2 = 0.019
zeta_rad_per_um = [0.01, 0.1, 1.0, 10.0]
p_um4 = [1.0, 0.9, 0.1, 0.001]
"#;

#[test]
fn include_files_reject_unknown_keys_and_accept_what_fit_writes() {
    let dir = std::env::temp_dir().join(format!("lustre-include-keys-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let scene = SMALL.replace(
        "model = \"ggx\"\nmetal = \"brass\"\nalpha = 0.2",
        "include = \"fit.toml\"",
    );
    let sp = dir.join("scene.toml");
    std::fs::write(&sp, &scene).unwrap();
    let load = |fit: &str| {
        std::fs::write(dir.join("fit.toml"), fit).unwrap();
        render::load_scene(&sp)
            .map(|_| ())
            .map_err(|e| e.to_string())
    };
    load(FIT_FILE).unwrap();
    for (from, to, key) in [
        ("gamma = 2.0\nalpha", "gama = 2.0\nalpha", "gama"),
        ("alpha = 0.05", "alpah = 0.05", "alpah"),
        ("beta = 0.01", "betta = 0.01", "betta"),
        ("p_um4 = ", "p_m4 = ", "p_m4"),
        ("[fit]", "[fitt]", "fitt"),
        (
            "[material]\n",
            "[material]\nenergie = \"krywonos\"\n",
            "energie",
        ),
    ] {
        assert!(FIT_FILE.contains(from), "test bug: {from}");
        let e = load(&FIT_FILE.replacen(from, to, 1)).unwrap_err();
        assert!(e.contains(&format!("unknown field `{key}`")), "{to}: {e}");
        assert!(
            e.contains("fit.toml:") && e.contains("expected"),
            "{to}: {e}"
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// An environment map's NaN, infinite or negative texels are refused, naming the
/// file and the first such pixel (they were zeroed, or made the image negative);
/// `rotate_deg` must be finite with or without a map.
#[test]
fn environment_maps_hold_finite_non_negative_radiance() {
    let dir = std::env::temp_dir().join(format!("lustre-hostile-env-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let scene = |file: &str, rotate: &str| {
        SMALL.replace(
            "[[lights]]\ntype = \"point\"",
            &format!(
                "[[lights]]\ntype = \"environment\"\nradiance = 1.0\n{file}rotate_deg = {rotate}\n\n\
                 [[lights]]\ntype = \"point\""
            ),
        )
    };
    let (w, h) = (8u32, 4u32);
    for (bad, label) in [(f32::NAN, "NaN"), (f32::INFINITY, "inf"), (-0.25, "-0.25")] {
        let mut px = vec![[0.5f32; 3]; (w * h) as usize];
        px[(2 * w + 5) as usize][1] = bad;
        let map = dir.join("env.exr");
        render::output::write_exr(&map, w, h, &px).unwrap();
        let e = render::load_str(&dir.join("s.toml"), &scene("file = \"env.exr\"\n", "0.0"))
            .err()
            .unwrap_or_else(|| panic!("a texel of {label} was accepted"))
            .to_string();
        assert!(
            e.contains("env.exr") && e.contains("pixel (5, 2)") && e.contains(label),
            "{label}: {e}"
        );
    }
    // All-NaN: the sky went black before.
    let px = vec![[f32::NAN; 3]; (w * h) as usize];
    render::output::write_exr(&dir.join("env.exr"), w, h, &px).unwrap();
    let e = render::load_str(&dir.join("s.toml"), &scene("file = \"env.exr\"\n", "0.0"))
        .err()
        .unwrap()
        .to_string();
    assert!(e.contains("pixel (0, 0)"), "{e}");
    // A sound map loads; rotate_deg = nan is refused with or without one.
    render::output::write_exr(&dir.join("env.exr"), w, h, &vec![[0.5f32; 3]; 32]).unwrap();
    render::load_str(&dir.join("s.toml"), &scene("file = \"env.exr\"\n", "30.0")).unwrap();
    for file in ["file = \"env.exr\"\n", ""] {
        let e = render::load_str(&dir.join("s.toml"), &scene(file, "nan"))
            .err()
            .unwrap()
            .to_string();
        assert!(e.contains("rotate_deg must be finite"), "{file}: {e}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}
