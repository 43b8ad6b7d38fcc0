//! Scene inputs that used to panic, hang, render silently wrong or explain
//! themselves badly: each is refused with a message that names the file,
//! the place and the fix, and the inputs at the accepted limits still load.

use render::scene::load;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// A scene with `material` as `[materials.m]`, `shape` as its one shape and
/// `film` appended to `[film]`.
fn scene(material: &str, shape: &str, film: &str) -> String {
    format!(
        r#"
[camera]
look_from = [0.0, 0.7, 0.7]
look_at = [0.0, 0.0, 0.0]
fov_deg = 40.0
resolution = [4, 4]

[film]
spp = 1
{film}

[materials.m]
{material}

{shape}

[[lights]]
type = "environment"
radiance = 1.0
"#
    )
}

const PLATE: &str = r#"[[shapes]]
type = "rectangle"
size = [0.5, 0.5]
material = "m"
transform = { rotate_deg = [-90.0, 0.0, 0.0] }"#;

const GGX: &str = "model = \"ggx\"\nmetal = \"cu\"\nalpha = 0.2";

/// A fresh directory holding `files` and `scene.toml` = `text`; the load's
/// error message, or `None` when the scene loads.
fn try_load(tag: &str, text: &str, files: &[(&str, &[u8])]) -> Option<String> {
    let dir = std::env::temp_dir().join(format!("lustre-limits-{tag}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    for (name, bytes) in files {
        std::fs::write(dir.join(name), bytes).unwrap();
    }
    let path: PathBuf = dir.join("scene.toml");
    std::fs::write(&path, text).unwrap();
    let r = load(Path::new(&path)).err().map(|e| e.to_string());
    let _ = std::fs::remove_dir_all(&dir);
    r
}

fn refused(tag: &str, text: &str, files: &[(&str, &[u8])]) -> String {
    try_load(tag, text, files).unwrap_or_else(|| panic!("{tag}: the scene loaded"))
}

fn loads(tag: &str, text: &str, files: &[(&str, &[u8])]) {
    if let Some(e) = try_load(tag, text, files) {
        panic!("{tag}: {e}");
    }
}

const QUAD: &[u8] = b"v -0.5 0 -0.5\nv 0.5 0 -0.5\nv 0.5 0 0.5\nv -0.5 0 0.5\nf 1 3 2\nf 1 4 3\n";

fn mesh(transform: &str) -> String {
    format!(
        "[[shapes]]\ntype = \"mesh\"\nfile = \"q.obj\"\nmaterial = \"m\"\ntransform = {transform}"
    )
}

#[test]
fn a_mesh_beyond_the_bvh_range_is_refused_not_a_panic() {
    let e = refused(
        "mesh-huge",
        &scene(GGX, &mesh("{ scale = 1e20 }"), ""),
        &[("q.obj", QUAD)],
    );
    assert!(
        e.contains("shapes[0]") && e.contains("q.obj") && e.contains("transform.scale"),
        "{e}"
    );
    let e = refused(
        "mesh-collapsed",
        &scene(GGX, &mesh("{ scale = 1e-300 }"), ""),
        &[("q.obj", QUAD)],
    );
    assert!(e.contains("degenerate") && e.contains("transform"), "{e}");
    loads(
        "mesh-large",
        &scene(GGX, &mesh("{ scale = 2e12 }"), ""),
        &[("q.obj", QUAD)],
    );
}

#[test]
fn a_steep_psd_tail_is_refused_and_the_steepest_accepted_sets_up_quickly() {
    let psd = |csv: &str| {
        scene(
            "model = \"measured_psd\"\nmetal = \"cu\"\npsd_csv = \"p.csv\"",
            PLATE,
            "",
        )
        .replace("p.csv", csv)
    };
    let start = Instant::now();
    let e = refused(
        "psd-steep",
        &psd("p.csv"),
        &[("p.csv", b"1,1e-3\n1.0001,1e-300\n")],
    );
    assert!(
        e.contains("p.csv") && e.contains("lines 1–2") && e.contains("-101"),
        "{e}"
    );
    assert!(start.elapsed().as_secs_f64() < 5.0);
    // ζ^−101 exactly: accepted, and the full GHS table builds in bounded
    // time (ζ^−1000 needed seconds, ζ^−7e6 over two minutes).
    let bound = format!("1,1e-3\n2,{:e}\n", 1e-3 * 2f64.powf(-101.0));
    let start = Instant::now();
    loads("psd-bound", &psd("p.csv"), &[("p.csv", bound.as_bytes())]);
    let secs = start.elapsed().as_secs_f64();
    assert!(secs < 20.0, "{secs} s");
}

#[test]
fn nk_csv_values_get_the_bounds_of_nk_and_a_units_hint() {
    let nk = scene(
        "model = \"ggx\"\nnk_csv = \"nk.csv\"\nalpha = 0.2",
        PLATE,
        "",
    );
    let e = refused(
        "nk-huge",
        &nk,
        &[("nk.csv", b"wavelength_nm,n,k\n300,0.2,3\n900,1e77,1e77\n")],
    );
    assert!(
        e.contains("nk.csv") && e.contains("line 3") && e.contains("1e6"),
        "{e}"
    );
    let e = refused(
        "nk-um",
        &nk,
        &[("nk.csv", b"wavelength_um,n,k\n0.3,0.2,3\n0.9,0.2,3\n")],
    );
    assert!(e.contains("micrometres") && e.contains("nm"), "{e}");
    // Headerless with a BOM: both rows are data (the first was taken for
    // a header, leaving one row).
    loads(
        "nk-bom",
        &nk,
        &[("nk.csv", "\u{feff}300,0.2,3\n900,0.2,3\n".as_bytes())],
    );
}

#[test]
fn exposure_is_bounded() {
    for bad in ["127", "-61", "1e300"] {
        let e = refused(
            "exposure",
            &scene(GGX, PLATE, &format!("exposure = {bad}")),
            &[],
        );
        assert!(
            e.contains("exposure") && e.contains("60") && e.contains(":10:"),
            "{e}"
        );
    }
    loads("exposure-60", &scene(GGX, PLATE, "exposure = -60"), &[]);
}

#[test]
fn the_camera_says_what_is_wrong() {
    let far = scene(GGX, PLATE, "").replace(
        "look_from = [0.0, 0.7, 0.7]",
        "look_from = [0.0, 1e300, 1e300]",
    );
    let e = refused("camera-far", &far, &[]);
    assert!(!e.contains("must differ") && e.contains("apart"), "{e}");
}

#[test]
fn conflicting_material_keys_are_refused() {
    for (tag, m, keys) in [
        (
            "alpha-xy",
            "model = \"ggx\"\nmetal = \"cu\"\nalpha = 0.2\nalpha_x = 0.1\nalpha_y = 0.3",
            ["`alpha`", "`alpha_x`"],
        ),
        (
            "fresnel-one",
            "model = \"ggx\"\nfresnel = \"one\"\nmetal = \"cu\"\nalpha = 0.2",
            ["fresnel = \"one\"", "`metal`"],
        ),
        (
            "fresnel-one-nk",
            "model = \"ggx\"\nfresnel = \"one\"\nnk = [0.2, 3.0]\nalpha = 0.2",
            ["fresnel = \"one\"", "`nk`"],
        ),
    ] {
        let e = refused(tag, &scene(m, PLATE, ""), &[]);
        assert!(
            e.contains("[materials.m]") && keys.iter().all(|k| e.contains(k)),
            "{tag}: {e}"
        );
    }
}

#[test]
fn wrong_brackets_get_the_fix() {
    let text = scene(GGX, PLATE, "");
    let e = refused(
        "mat-array",
        &text.replace("[materials.m]", "[[materials.m]]"),
        &[],
    );
    assert!(e.contains("[materials.NAME]"), "{e}");
    let e = refused("shapes-table", &text.replace("[[shapes]]", "[shapes]"), &[]);
    assert!(e.contains("[[shapes]]"), "{e}");
}

/// The 1-based line of the `n`-th (0-based) line equal to `header` in `text`.
fn line_of(text: &str, header: &str, n: usize) -> usize {
    text.lines()
        .enumerate()
        .filter(|(_, l)| l.trim() == header)
        .nth(n)
        .map(|(i, _)| i + 1)
        .unwrap_or_else(|| panic!("no {n}-th `{header}`"))
}

/// Two `[lights]` (or `[shapes]`) tables where `[[lights]]` was meant: toml
/// reports only "duplicate key" at the second header. The message names the
/// key and the brackets to write, at that header's line.
#[test]
fn a_repeated_table_that_should_be_an_array_of_tables_gets_the_fix() {
    const POINT: &str = "type = \"point\"\nposition = [0.0, 1.0, 0.0]\nintensity = 1.0\n";
    let two_lights = format!(
        "{}\n[lights]\n{POINT}",
        scene(GGX, PLATE, "").replace("[[lights]]", "[lights]")
    );
    let e = refused("two-lights", &two_lights, &[]);
    println!("{e}");
    let line = line_of(&two_lights, "[lights]", 1);
    assert!(e.contains(&format!("scene.toml:{line}:2: ")), "{e}");
    assert!(
        e.contains(
            "duplicate key `lights` (lights are an array of tables: write [[lights]] (two \
             brackets) for each light)"
        ),
        "{e}"
    );

    let two_shapes = format!(
        "{}\n[shapes]\n{}",
        scene(GGX, PLATE, "").replace("[[shapes]]", "[shapes]"),
        PLATE.replace("[[shapes]]\n", "")
    );
    let e = refused("two-shapes", &two_shapes, &[]);
    println!("{e}");
    let line = line_of(&two_shapes, "[shapes]", 1);
    assert!(e.contains(&format!("scene.toml:{line}:2: ")), "{e}");
    assert!(
        e.contains("write [[shapes]] (two brackets) for each shape"),
        "{e}"
    );

    // One `[[lights]]` and then a `[lights]`: the same fix.
    let mixed = format!("{}\n[lights]\n{POINT}", scene(GGX, PLATE, ""));
    let e = refused("mixed-lights", &mixed, &[]);
    let line = line_of(&mixed, "[lights]", 0);
    assert!(e.contains(&format!("scene.toml:{line}:2: ")), "{e}");
    assert!(
        e.contains("write [[lights]] (two brackets) for each light"),
        "{e}"
    );

    // A key repeated inside a table is another mistake: toml's own message.
    let twice = scene(GGX, PLATE, "").replace("radiance = 1.0", "radiance = 1.0\nradiance = 2.0");
    let e = refused("key-twice", &twice, &[]);
    assert!(e.contains("duplicate key") && !e.contains("[["), "{e}");
    // Two tables of a kind that is not an array keep the bare message too.
    let two_cameras = format!("{}\n[camera]\nfov_deg = 30.0\n", scene(GGX, PLATE, ""));
    let e = refused("two-cameras", &two_cameras, &[]);
    assert!(e.contains("duplicate key") && !e.contains("[["), "{e}");
}
