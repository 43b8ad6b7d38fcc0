//! `lustre brdf plot` and `lustre compare`: the figures have the requested
//! pixel size, and every CSV value equals a direct evaluation of the model
//! built here with the `brdf` crate from the parameters in that CSV row.

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::process::Command;

use brdf::statistics::KcPsd;
use brdf::wave::two_scale::{CoherentPart, TableResolution, TwoScale, TwoScaleParams};
use brdf::wave::{Energy, GhsFull, GhsOptions, GhsSsa};
use brdf::{Bxdf, DVec3, Distribution, Fresnel, Ior, Metal, MicrofacetConductor};

fn lustre() -> Command {
    Command::new(env!("CARGO_BIN_EXE_lustre"))
}

fn scratch(name: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join(format!("figures-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn run(cmd: &mut Command) -> String {
    let out = cmd.output().expect("running lustre");
    let err = String::from_utf8_lossy(&out.stderr).into_owned();
    assert!(out.status.success(), "lustre failed: {err}");
    err
}

/// Width and height from a PNG's IHDR chunk.
fn png_size(path: &Path) -> (u32, u32) {
    let b = std::fs::read(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    assert_eq!(
        &b[..8],
        b"\x89PNG\r\n\x1a\n",
        "{} is not a PNG",
        path.display()
    );
    assert_eq!(&b[12..16], b"IHDR");
    let be = |i: usize| u32::from_be_bytes([b[i], b[i + 1], b[i + 2], b[i + 3]]);
    (be(16), be(20))
}

/// RFC 4180 fields of one line (quotes only around fields that need them).
fn fields(line: &str) -> Vec<String> {
    let (mut out, mut cur, mut quoted, mut chars) =
        (Vec::new(), String::new(), false, line.chars().peekable());
    while let Some(c) = chars.next() {
        match (c, quoted) {
            ('"', true) if chars.peek() == Some(&'"') => {
                cur.push('"');
                chars.next();
            }
            ('"', _) => quoted = !quoted,
            (',', false) => out.push(std::mem::take(&mut cur)),
            _ => cur.push(c),
        }
    }
    out.push(cur);
    out
}

/// Rows of a CSV as column-name → text maps.
fn read_csv(path: &Path) -> Vec<HashMap<String, String>> {
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text.lines();
    let head = fields(lines.next().unwrap());
    lines
        .map(|l| head.iter().cloned().zip(fields(l)).collect())
        .collect()
}

fn num(row: &HashMap<String, String>, k: &str) -> f64 {
    row[k]
        .parse()
        .unwrap_or_else(|e| panic!("column {k} = {:?}: {e}", row[k]))
}

/// The model of a CSV row, built directly with the `brdf` crate.
fn model(row: &HashMap<String, String>) -> Box<dyn Bxdf> {
    let fresnel = match row["fresnel"].as_str() {
        "none" => Fresnel::One,
        m => Fresnel::conductor(Ior::metal(Metal::from_name(m).unwrap())),
    };
    let psd = || KcPsd::new(num(row, "sigma_um"), num(row, "lc_um"), num(row, "gamma")).unwrap();
    let raw = GhsOptions {
        energy: Energy::Raw,
        ..GhsOptions::default()
    };
    match row["model"].as_str() {
        "ggx" => {
            let a = num(row, "alpha");
            Box::new(MicrofacetConductor::new(Distribution::ggx(a, a).unwrap(), fresnel).unwrap())
        }
        "beckmann" => {
            let a = num(row, "alpha");
            Box::new(
                MicrofacetConductor::new(Distribution::beckmann(a, a).unwrap(), fresnel).unwrap(),
            )
        }
        "ghs_ssa" => Box::new(GhsSsa::with_options(psd(), fresnel, raw).unwrap()),
        "ghs" => Box::new(GhsFull::with_options(psd(), fresnel, raw).unwrap()),
        "two_scale" => Box::new(
            TwoScale::new(TwoScaleParams {
                beta: num(row, "beta"),
                sigma_um: num(row, "sigma_um"),
                lc_um: num(row, "lc_um"),
                gamma: num(row, "gamma"),
                fresnel,
                coherent: CoherentPart::MacroNdf,
                resolution: TableResolution::default(),
            })
            .unwrap(),
        ),
        other => panic!("unexpected model {other}"),
    }
}

fn dir(theta_deg: f64, phi_deg: f64) -> DVec3 {
    brdf::frame::spherical(theta_deg.to_radians(), phi_deg.to_radians())
}

fn assert_rel(got: f64, want: f64, what: &str) {
    let scale = got.abs().max(want.abs());
    assert!(
        got == want || (got - want).abs() <= 1e-12 * scale,
        "{what}: CSV {got:e} vs brdf {want:e}"
    );
}

#[test]
fn brdf_plot_pngs_have_the_requested_size_and_csv_equals_brdf() {
    let out = scratch("plot");
    run(lustre()
        .args([
            "brdf",
            "plot",
            "--samples",
            "S027",
            "--theta-i",
            "30,80",
            "--points",
            "24",
            "--albedo-angles",
            "3",
            "--size",
            "700x450",
            "--quiet",
            "--out",
        ])
        .arg(&out));
    for f in ["s027_slices.png", "s027_albedo.png"] {
        assert_eq!(png_size(&out.join(f)), (700, 450), "{f}");
    }
    assert!(
        !out.join("panel.png").exists(),
        "one surface needs no panel"
    );

    let rows = read_csv(&out.join("s027_slices.csv"));
    let mut cache: HashMap<String, Box<dyn Bxdf>> = HashMap::new();
    let mut per_model: HashMap<String, usize> = HashMap::new();
    for row in &rows {
        // Two GGX rows (slope-based and identity α) share the model name.
        let m = cache
            .entry(row["label"].clone())
            .or_insert_with(|| model(row));
        let wi = dir(num(row, "theta_i_deg"), 0.0);
        let wo = dir(num(row, "theta_o_deg"), num(row, "phi_o_deg"));
        let want = m.eval(wi, wo, num(row, "lambda_nm"));
        assert_rel(
            num(row, "brdf_per_sr"),
            want,
            &format!("{} at θo {}", row["model"], row["theta_o_deg"]),
        );
        // β − β0 is the direction-cosine offset from the mirror direction.
        let db = -wo.x - wi.x;
        assert!((num(row, "beta_minus_beta0") - db).abs() <= 1e-15);
        *per_model.entry(row["model"].clone()).or_default() += 1;
    }
    let mut models: Vec<_> = per_model.keys().cloned().collect();
    models.sort();
    assert_eq!(models, ["ggx", "ghs", "ghs_ssa", "two_scale"]);
    assert!(per_model.values().all(|&n| n >= 2 * 20), "{per_model:?}");
    // The mirror direction itself is on every slice.
    for t in [30.0f64, 80.0] {
        assert!(
            rows.iter()
                .any(|r| num(r, "theta_i_deg") == t && num(r, "beta_minus_beta0").abs() < 1e-15)
        );
    }

    let rows = read_csv(&out.join("s027_albedo.csv"));
    assert_eq!(rows.len(), 5 * 3);
    for row in &rows {
        let m = &cache[&row["label"]];
        let lambda = num(row, "lambda_nm");
        let wi = dir(num(row, "theta_i_deg"), 0.0);
        let scattered = brdf::wave::energy::hemispherical_integral(wi, num(row, "lobe_rho"), |o| {
            m.eval(wi, o, lambda)
        });
        let spec = m.specular(wi, lambda).weight;
        let what = format!("{} at θi {}", row["model"], row["theta_i_deg"]);
        assert_rel(num(row, "scattered_albedo"), scattered, &what);
        assert_rel(num(row, "specular_weight"), spec, &what);
        assert_rel(num(row, "total_albedo"), scattered + spec, &what);
        let total = num(row, "total_albedo");
        assert!(total > 0.0 && total < 1.02, "{what}: total albedo {total}");
    }
}

#[test]
fn brdf_plot_panel_has_one_row_per_sample() {
    let out = scratch("panel");
    run(lustre()
        .args([
            "brdf",
            "plot",
            "--samples",
            "S027,S280",
            "--models",
            "ggx,ghs_ssa",
            "--theta-i",
            "45",
            "--points",
            "16",
            "--albedo-angles",
            "2",
            "--size",
            "600x400",
            "--x",
            "beta",
            "--quiet",
            "--out",
        ])
        .arg(&out));
    for f in [
        "s027_slices.png",
        "s280_slices.png",
        "s027_albedo.png",
        "s280_albedo.png",
    ] {
        assert_eq!(png_size(&out.join(f)), (600, 400), "{f}");
    }
    let (w, h) = png_size(&out.join("panel.png"));
    assert!((2 * 600..2 * 600 + 100).contains(&w), "panel width {w}");
    assert!((2 * 400..2 * 400 + 100).contains(&h), "panel height {h}");
}

#[test]
fn brdf_plot_rejects_bad_input_with_a_named_option() {
    for (args, needle) in [
        (vec!["--samples", "S999"], "S808"),
        (vec!["--lambda-nm", "100"], "--lambda-nm"),
        (vec!["--theta-i", "95"], "--theta-i"),
        (vec!["--size", "10"], "WIDTHxHEIGHT"),
        (vec!["--models", "phong"], "phong"),
    ] {
        let out = lustre()
            .args(["brdf", "plot", "--out"])
            .arg(scratch("bad"))
            .args(&args)
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success(), "{args:?} should fail");
        assert!(err.contains(needle), "{args:?}: {err}");
    }
}

#[test]
fn compare_grid_has_one_cell_per_model_and_view() {
    let out = scratch("compare");
    let png = out.join("grid.png");
    run(lustre()
        .args([
            "compare",
            "--sample",
            "S027",
            "--cutoffs",
            "100",
            "--views",
            "0,80",
            "--size",
            "40x30",
            "--spp",
            "1",
            "--threads",
            "2",
            "--quiet",
            "--out",
        ])
        .arg(&png));
    let (w, h) = png_size(&png);
    let cells = read_csv(&out.join("grid.cells.csv"));
    // GGX (slope α), GGX (KC identity α), GHS SSA, full GHS, one two-scale
    // row; two views.
    assert_eq!(cells.len(), 5 * 2);
    let labels: Vec<&str> = cells
        .iter()
        .filter(|c| c["col"] == "0")
        .map(|c| c["model"].as_str())
        .collect();
    assert!(labels[0].starts_with("GGX, slope α"), "{labels:?}");
    assert!(labels[1].starts_with("GGX, KC identity α"), "{labels:?}");
    assert!(
        labels[2] == "GHS SSA" && labels[3] == "full GHS",
        "{labels:?}"
    );
    assert!(labels[4].starts_with("two-scale 100λ"), "{labels:?}");
    for c in &cells {
        assert_eq!(
            (num(c, "grid_width") as u32, num(c, "grid_height") as u32),
            (w, h)
        );
        let (x0, y0, x1, y1) = (num(c, "x0"), num(c, "y0"), num(c, "x1"), num(c, "y1"));
        assert_eq!((x1 - x0, y1 - y0), (40.0, 30.0), "cell size");
        // Each cell's unclipped linear image.
        let (ew, eh, rgb) = render::output::read_exr(Path::new(&c["exr"])).unwrap();
        assert_eq!((ew, eh), (40, 30), "{}", c["exr"]);
        assert!(rgb.iter().flatten().all(|v| v.is_finite() && *v >= 0.0));
        assert!(x0 >= 0.0 && y0 >= 0.0 && x1 <= f64::from(w) && y1 <= f64::from(h));
    }
    let views: Vec<f64> = cells
        .iter()
        .filter(|c| c["row"] == "0")
        .map(|c| num(c, "view_deg"))
        .collect();
    assert_eq!(views, [0.0, 80.0]);
}

/// A fit file of a scan flagged anisotropic and non-elliptical (corpus/mi-1) offers the
/// anisotropic and measured-PSD models too, and `compare --material` draws every one:
/// a row per offered model, in the file's order, then its two-scale splits.
#[test]
fn compare_of_a_fit_file_has_a_row_per_offered_model() {
    let out = scratch("compare_fit");
    let file = out.join("mi1.toml");
    run(lustre()
        .args([
            "fit",
            "data/surfaces/corpus/mi-1.mi",
            "--metal",
            "cu",
            "--no-plots",
            "-o",
        ])
        .arg(&file));
    let png = out.join("mi1.png");
    run(lustre()
        .args([
            "compare", "--views", "30", "--size", "16x12", "--spp", "1", "--quiet",
        ])
        .arg("--material")
        .arg(&file)
        .arg("--out")
        .arg(&png));
    let cells = read_csv(&out.join("mi1.cells.csv"));
    let labels: Vec<String> = cells
        .iter()
        .map(|c| c["model"].replace('\n', " "))
        .collect();
    let doc: brdf::spec::MaterialFile =
        toml::from_str(&std::fs::read_to_string(&file).unwrap()).unwrap();
    let offered: Vec<_> = doc
        .offered()
        .into_iter()
        .filter(|o| o.model.is_some())
        .collect();
    assert_eq!(labels.len(), offered.len(), "{labels:?}");
    for want in [
        "Beckmann",
        "full GHS, anisotropic KC",
        "full GHS, measured PSD",
        "GHS SSA, 2-D PSD grid",
        "full GHS, 2-D PSD grid",
    ] {
        assert!(labels.iter().any(|l| l == want), "{want}: {labels:?}");
    }
    assert!(
        labels.last().unwrap().starts_with("two-scale"),
        "{labels:?}"
    );
    for c in &cells {
        let (_, _, rgb) = render::output::read_exr(Path::new(&c["exr"])).unwrap();
        assert!(
            rgb.iter().flatten().all(|v| v.is_finite() && *v >= 0.0),
            "{}",
            c["model"]
        );
    }
}
