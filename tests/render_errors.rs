//! Bad scene files give the documented errors: file, line, column, and the
//! valid choices — never a panic.

#[path = "support/scene_fixtures.rs"]
mod scene_fixtures;

use std::path::PathBuf;

const GOOD: &str = r#"[camera]
look_from = [0.0, 1.0, 2.0]
look_at = [0.0, 0.0, 0.0]
fov_deg = 40.0
resolution = [8, 8]

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

[[lights]]
type = "point"
position = [0.0, 1.0, 0.0]
intensity = 1.0
"#;

fn path() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/bad.toml")
}

/// Loads `GOOD` with `from` replaced by `to`; returns the error text.
fn error(from: &str, to: &str) -> String {
    assert!(GOOD.contains(from), "test bug: `{from}` not in the scene");
    let text = GOOD.replacen(from, to, 1);
    match render::load_str(&path(), &text) {
        Ok(_) => panic!("`{to}` was accepted"),
        Err(e) => e.to_string(),
    }
}

/// `GOOD` with an `[integrator]` table of `keys`.
fn with_integrator(keys: &str) -> String {
    format!("{GOOD}\n[integrator]\n{keys}\n")
}

/// The error text of `GOOD` with an `[integrator]` table of `keys`.
fn integrator_error(keys: &str) -> String {
    match render::load_str(&path(), &with_integrator(keys)) {
        Ok(_) => panic!("`{keys}` was accepted"),
        Err(e) => e.to_string(),
    }
}

#[test]
fn the_good_scene_loads() {
    let s = render::load_str(&path(), GOOD).unwrap();
    assert!(
        s.prepared.contains("no BVH") && s.prepared.contains("no environment sampling"),
        "{}",
        s.prepared
    );
}

#[test]
fn unknown_key_names_position_and_valid_keys() {
    let e = error("fov_deg = 40.0", "fov = 40.0");
    assert!(e.contains("bad.toml:4:1"), "{e}");
    assert!(
        e.contains("unknown field `fov`") && e.contains("fov_deg"),
        "{e}"
    );
}

#[test]
fn wrong_type_is_located() {
    let e = error("spp = 1", "spp = \"many\"");
    assert!(e.contains("bad.toml:8:7"), "{e}");
    assert!(e.contains("invalid type") && e.contains("u64"), "{e}");
}

#[test]
fn invalid_values_are_rejected_with_the_range() {
    let e = error("spp = 1", "spp = 0");
    assert!(e.contains(":8:7") && e.contains("expected 1..="), "{e}");
    let e = error("fov_deg = 40.0", "fov_deg = 190.0");
    assert!(e.contains(":4:") && e.contains("0 < fov_deg < 179"), "{e}");
    let e = error("alpha = 0.2", "alpha = 3.0");
    assert!(
        e.contains("[materials.m]") && e.contains("alpha") && e.contains("≤ 1"),
        "{e}"
    );
    let e = error("intensity = 1.0", "intensity = -1.0");
    assert!(e.contains("lights[0]") && e.contains("> 0"), "{e}");
    let e = error("size = [1.0, 1.0]", "size = [1.0, 0.0]");
    assert!(e.contains("shapes[0]") && e.contains(":15:1"), "{e}");
}

#[test]
fn unknown_choices_list_the_valid_ones() {
    let e = error("model = \"ggx\"", "model = \"phong\"");
    assert!(
        e.contains("phong") && e.contains("ggx") && e.contains("measured_psd"),
        "{e}"
    );
    let e = error("metal = \"brass\"", "metal = \"unobtanium\"");
    assert!(
        e.contains("unknown metal `unobtanium`") && e.contains("stainless_steel"),
        "{e}"
    );
    let e = error("type = \"rectangle\"", "type = \"torus\"");
    assert!(e.contains("torus") && e.contains("sphere"), "{e}");
    let e = error("material = \"m\"", "material = \"gold\"");
    assert!(
        e.contains("unknown material `gold`") && e.contains("defined: m"),
        "{e}"
    );
    let e = error(
        "intensity = 1.0",
        "intensity = 1.0\nspectrum = \"sunlight\"",
    );
    assert!(e.contains("valid:") && e.contains("blackbody(T)"), "{e}");
}

#[test]
fn missing_files_are_named() {
    let e = error(
        "material = \"m\"\n",
        "material = \"m\"\n\n[[shapes]]\ntype = \"mesh\"\nfile = \"nope.obj\"\nmaterial = \"m\"\n",
    );
    assert!(e.contains("nope.obj") && e.contains("shapes[1]"), "{e}");
    let e = error("metal = \"brass\"", "nk_csv = \"missing_nk.csv\"");
    assert!(
        e.contains("missing_nk.csv") && e.contains("cannot read"),
        "{e}"
    );
    let e = error("alpha = 0.2", "alpha = 0.2\ninclude = \"no_such_fit.toml\"");
    assert!(e.contains("no_such_fit.toml"), "{e}");
    let e = render::load_scene(&PathBuf::from("/nonexistent/scene.toml"))
        .err()
        .unwrap()
        .to_string();
    assert!(
        e.contains("/nonexistent/scene.toml") && e.contains("cannot read"),
        "{e}"
    );
}

#[test]
fn camera_errors_point_at_the_key() {
    let e = error("look_at = [0.0, 0.0, 0.0]", "look_at = [0.0, 1.0, 2.0]");
    assert!(
        e.contains(":3:11") && e.contains("`look_at` must differ"),
        "{e}"
    );
    let e = error("look_from = [0.0, 1.0, 2.0]", "look_from = [0.0, 1.0, 0.0]");
    assert!(
        e.contains(":3:11") && e.contains("`up` must not be parallel"),
        "{e}"
    );
}

#[test]
fn two_scale_needs_beta() {
    let e = error(
        "model = \"ggx\"\nmetal = \"brass\"\nalpha = 0.2",
        "model = \"two_scale\"\nsigma_um = 0.1\nlc_um = 1.0\ngamma = 2.0\nmetal = \"brass\"",
    );
    assert!(e.contains("model `two_scale` needs `beta`"), "{e}");
    let e = error(
        "model = \"ggx\"\nmetal = \"brass\"\nalpha = 0.2",
        "model = \"two_scale\"\nsigma_um = 0.1\nlc_um = 1.0\ngamma = 2.0\nbeta = 0.1\ncoherent = \"both\"\nmetal = \"brass\"",
    );
    assert!(e.contains("macro_ndf") && e.contains("delta"), "{e}");
}

#[test]
fn wave_models_need_their_parameters() {
    let e = error(
        "model = \"ggx\"\nmetal = \"brass\"\nalpha = 0.2",
        "model = \"ghs\"\nmetal = \"brass\"",
    );
    assert!(e.contains("model `ghs` needs `sigma_um`"), "{e}");
    let e = error(
        "model = \"ggx\"\nmetal = \"brass\"\nalpha = 0.2",
        "model = \"ghs_ssa\"\nsigma_um = 0.1\nlc_um = 1.0\ngamma = 0.5\nmetal = \"brass\"",
    );
    assert!(e.contains("gamma"), "{e}");
    let e = error(
        "model = \"ggx\"\nmetal = \"brass\"\nalpha = 0.2",
        "model = \"measured_psd\"\nmetal = \"brass\"",
    );
    assert!(e.contains("psd_csv"), "{e}");
    let e = error(
        "model = \"ggx\"\nmetal = \"brass\"\nalpha = 0.2",
        "model = \"ghs\"\nsigma_um = 0.1\nlc_um = 1.0\ngamma = 2.0\nenergy = \"magic\"\nmetal = \"brass\"",
    );
    assert!(e.contains("magic") && e.contains("krywonos"), "{e}");
}

#[test]
fn keys_the_model_does_not_use_are_named() {
    // Switching a material's model and leaving its old parameters is an error naming them.
    let e = error(
        "model = \"ggx\"",
        "model = \"ghs\"\nsigma_um = 0.1\nlc_um = 1.0\ngamma = 2.0",
    );
    assert!(
        e.contains("[materials.m]") && e.contains("model `ghs` does not use `alpha`"),
        "{e}"
    );
}

#[test]
fn missing_sections_and_lights() {
    let e = error("[film]\nspp = 1\n", "");
    assert!(e.contains("missing field `film`"), "{e}");
    let e = error(
        "[[lights]]\ntype = \"point\"\nposition = [0.0, 1.0, 0.0]\nintensity = 1.0\n",
        "",
    );
    assert!(e.contains("no lights"), "{e}");
}

#[test]
fn garbage_never_panics() {
    for text in [
        "",
        "[[[",
        "camera = 3",
        "\u{0}\u{1}",
        "[camera]\nlook_from = [1e400, 0, 0]",
    ] {
        assert!(render::load_str(&path(), text).is_err(), "{text:?}");
    }
}

#[test]
fn hero_wavelengths_default_by_material_and_bad_counts_are_refused() {
    // Conductors only: sixteen per path; a wave-optical material: four;
    // `single`: one; an explicit count wins.
    let s = render::load_str(&path(), GOOD).unwrap();
    assert_eq!(s.settings.wavelengths_per_path(), 16, "{}", s.prepared);
    assert!(s.prepared.contains("16 per path"), "{}", s.prepared);
    let ssa = GOOD.replacen(
        "model = \"ggx\"\nmetal = \"brass\"\nalpha = 0.2",
        "model = \"ghs_ssa\"\nmetal = \"brass\"\nsigma_um = 0.02\nlc_um = 2.0\ngamma = 3.0",
        1,
    );
    assert_eq!(
        render::load_str(&path(), &ssa)
            .unwrap()
            .settings
            .wavelengths_per_path(),
        4
    );
    let single = with_integrator("wavelengths = \"single\"");
    assert_eq!(
        render::load_str(&path(), &single)
            .unwrap()
            .settings
            .wavelengths_per_path(),
        1
    );
    for n in [2, 7, 16] {
        let t = format!("{ssa}\n[integrator]\nhero_wavelengths = {n}\n");
        assert_eq!(
            render::load_str(&path(), &t)
                .unwrap()
                .settings
                .wavelengths_per_path(),
            n
        );
    }
    for bad in ["0", "1", "17", "1000"] {
        let e = integrator_error(&format!("hero_wavelengths = {bad}"));
        assert!(
            e.contains("hero_wavelengths") && e.contains("2..=16"),
            "{e}"
        );
    }
    let e = integrator_error("wavelengths = \"single\"\nhero_wavelengths = 8");
    assert!(e.contains("needs wavelengths = \"hero\""), "{e}");
}

#[test]
fn mis_light_weight_is_per_vertex_unless_set_and_bad_values_are_refused() {
    let s = render::load_str(&path(), GOOD).unwrap();
    assert_eq!(s.settings.mis_light_weight, None);
    let t = with_integrator("sampler = \"independent\"");
    let s = render::load_str(&path(), &t).unwrap();
    assert_eq!(s.settings.mis_light_weight, Some(1.0));
    for ok in ["0.001", "2", "2.5", "1000"] {
        let t = with_integrator(&format!("mis_light_weight = {ok}"));
        let s = render::load_str(&path(), &t).expect(ok);
        assert_eq!(
            s.settings.mis_light_weight,
            Some(ok.parse::<f64>().unwrap())
        );
    }
    // TOML has inf and nan literals; a string is refused by type.
    for bad in [
        "0.0", "-2.0", "inf", "-inf", "nan", "-0.0", "1e306", "1000.5", "0.00099", "1e-300",
    ] {
        let e = integrator_error(&format!("mis_light_weight = {bad}"));
        assert!(
            e.contains("mis_light_weight") && e.contains("0.001 to 1000") && e.contains(":26:"),
            "{bad}: {e}"
        );
    }
    let e = integrator_error("mis_light_weight = \"two\"");
    assert!(e.contains(":26:") && e.contains("expected f64"), "{e}");
}

/// A value that an `include`d fit file supplies is reported at its own file,
/// line and table, not at the scene's material table, which does not contain
/// it; a value the scene sets is still the scene's.
#[test]
fn an_invalid_value_from_an_include_is_located_in_the_include() {
    let dir = scene_fixtures::temp_dir("include-errors");
    let fit = "# written by lustre fit\n\
[provenance]\nfile = \"scan.x3p\"\n\n\
[material]\nmetal = \"cu\"\nmodel = \"ghs\"\nsigma_um = -3.0\nlc_um = 1.0\ngamma = 3.0\n\
alpha = 0.2\nalpha_beckmann = 0.2\n\n\
[two_scale.cutoff_50]\nbeta = 99.0\nsigma_um = 0.01\nlc_um = 1.0\ngamma = 3.0\n";
    std::fs::write(dir.join("fit.toml"), fit).unwrap();
    let load = |material: &str| {
        let text = GOOD.replacen(
            "model = \"ggx\"\nmetal = \"brass\"\nalpha = 0.2",
            material,
            1,
        );
        match render::load_str(&dir.join("scene.toml"), &text) {
            Ok(_) => panic!("`{material}` was accepted"),
            Err(e) => format!("{e:#}"),
        }
    };
    // σ of [material], line 8 of the include.
    let e = load("include = \"fit.toml\"");
    assert!(e.contains("fit.toml:8: [material]: `sigma_um`"), "{e}");
    assert!(e.contains("0 ≤ sigma_um ≤ 10"), "{e}");
    // β of the chosen split, line 15.
    let e = load("include = \"fit.toml\"\nmodel = \"two_scale\"\ncutoff = \"cutoff_50\"");
    assert!(
        e.contains("fit.toml:15: [two_scale.cutoff_50]: `beta`"),
        "{e}"
    );
    // The scene's own value is blamed on the scene.
    let e = load("include = \"fit.toml\"\nsigma_um = -1.0");
    assert!(!e.contains("fit.toml:"), "{e}");
    assert!(e.contains("`sigma_um`") && e.contains("-1"), "{e}");
    // So is a key of a group the scene replaces (alpha_x without alpha_y drops the
    // include's roughness group), and a key that neither file sets.
    let e = load("include = \"fit.toml\"\nsigma_um = 0.01\nmodel = \"ggx\"\nalpha_x = 0.1");
    assert!(!e.contains("fit.toml:") && e.contains("alpha"), "{e}");
    let e = load("include = \"fit.toml\"\nsigma_um = 0.01\nmodel = \"measured_psd\"");
    assert!(!e.contains("fit.toml:") && e.contains("psd_csv"), "{e}");
}
