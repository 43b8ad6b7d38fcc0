//! `lustre brdf eval` end to end: JSON lines in, JSON lines out, through the
//! built binary.

use std::io::Write;
use std::process::{Command, Stdio};

use serde_json::Value;

fn run(input: &str) -> Vec<Value> {
    run_in(&std::env::current_dir().unwrap(), input)
}

/// [`run`] with `dir` as the working directory (relative file names).
fn run_in(dir: &std::path::Path, input: &str) -> Vec<Value> {
    let mut child = Command::new(env!("CARGO_BIN_EXE_lustre"))
        .args(["brdf", "eval"])
        .current_dir(dir)
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("run lustre");
    child
        .stdin
        .take()
        .unwrap()
        .write_all(input.as_bytes())
        .unwrap();
    let out = child.wait_with_output().unwrap();
    assert!(
        out.status.success(),
        "stderr: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8(out.stdout)
        .unwrap()
        .lines()
        .map(|l| serde_json::from_str(l).expect("each output line is JSON"))
        .collect()
}

fn rel(a: f64, b: f64) -> f64 {
    ((a - b) / b).abs()
}

fn ggx_lambda(alpha: f64, theta: f64) -> f64 {
    let t = alpha * theta.tan();
    0.5 * (-1.0 + (1.0 + t * t).sqrt())
}

#[test]
fn microfacet_values_and_errors_in_one_stream() {
    let input = r#"{"model": "ggx", "alpha": 0.2, "lambda_nm": 550, "theta_i_deg": 30, "theta_o_deg": 30, "phi_o_deg": 180, "fresnel": "none"}
not json
{"model": "ggx", "alpha": 0.2, "lambda_nm": 550, "theta_i_deg": 30, "theta_o_deg": 30, "phi_o_deg": 180}
{"model": "beckmann", "alpha": 0.3, "lambda_nm": 550, "theta_i_deg": 0, "theta_o_deg": 0, "phi_o_deg": 0, "fresnel": "none"}
{"model": "ggx", "alpha": -1, "lambda_nm": 550, "theta_i_deg": 30, "theta_o_deg": 30, "phi_o_deg": 180, "fresnel": "none"}
{"model": "ggx", "alpha": 0.2, "lambda_nm": 550, "theta_i_deg": 95, "theta_o_deg": 30, "phi_o_deg": 180, "fresnel": "none"}
{"model": "phong", "lambda_nm": 550, "theta_i_deg": 30, "theta_o_deg": 30, "phi_o_deg": 180, "fresnel": "none"}
{"model": "ggx", "alpha": 0.2, "lambda_nm": 550, "theta_i_deg": 30, "theta_o_deg": 30, "phi_o_deg": 180, "fresnel": "unobtainium"}
{"model": "ggx", "alpha": 0.2, "theta_i_deg": 30, "theta_o_deg": 30, "phi_o_deg": 180, "fresnel": "none"}
{"model": "ggx", "alpha": 0.2, "lambda_nm": 550, "theta_i_deg": 30, "theta_o_deg": 30, "phi_o_deg": 180, "metal": "cu"}
{"model": "ghs_ssa", "sigma_um": 0.1, "lc_um": 5, "gamma": 0.5, "lambda_nm": 550, "theta_i_deg": 0, "theta_o_deg": 0, "phi_o_deg": 0, "fresnel": "none"}
{"model": "ghs_ssa", "sigma_um": 0.1, "lc_um": 5, "gamma": 2, "energy": "magic", "lambda_nm": 550, "theta_i_deg": 0, "theta_o_deg": 0, "phi_o_deg": 0, "fresnel": "none"}
"#;
    let out = run(input);
    assert_eq!(out.len(), 12, "{out:?}");

    // GGX at the mirror, R = 1: D = 1/(πα²) at h = n, G₂ = 1/(1 + 2Λ).
    let (a, t) = (0.2f64, 30f64.to_radians());
    let want = 1.0
        / (std::f64::consts::PI * a * a)
        / (1.0 + 2.0 * ggx_lambda(a, t))
        / (4.0 * t.cos() * t.cos());
    let f = out[0]["f"].as_f64().unwrap();
    assert!(rel(f, want) < 1e-12, "{f} vs {want}");
    assert_eq!(out[0]["specular_weight"].as_f64().unwrap(), 0.0);
    assert!(out[0]["pdf"].as_f64().unwrap() > 0.0);

    let field = |i: usize| out[i]["field"].as_str().unwrap_or("<none>").to_string();
    assert!(out[1]["error"].is_string());
    assert_eq!(field(1), "line");
    assert_eq!(field(2), "fresnel", "no fresnel and no metal: {:?}", out[2]);
    // Beckmann at normal incidence and the mirror: D = 1/(πα²), Λ = 0.
    let want = 1.0 / (std::f64::consts::PI * 0.09) / 4.0;
    assert!(rel(out[3]["f"].as_f64().unwrap(), want) < 1e-12);
    assert_eq!(field(4), "alpha");
    assert_eq!(field(5), "theta_i_deg");
    assert_eq!(field(6), "model");
    assert_eq!(field(7), "fresnel");
    assert_eq!(field(8), "lambda_nm");
    // Copper Fresnel through the `metal` field: below the R = 1 value.
    let cu = out[9]["f"].as_f64().unwrap();
    assert!(cu > 0.3 * f && cu < 0.9 * f, "{cu} vs {f}");
    assert_eq!(field(10), "gamma");
    assert_eq!(field(11), "energy");
}

/// Reference rows of `data/reference/ghs_reference.json` → GHS values.
#[test]
fn ghs_values_match_reference_rows() {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/data/reference/ghs_reference.json"
    );
    let r: Value = serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap();
    let rows: Vec<&Value> = r["brdf"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|row| {
            let s = row["surface"].as_str().unwrap();
            (s == "S138" || s == "S027") && row["brdf_full"].as_f64().unwrap() > 1e-8
        })
        .collect();
    assert!(rows.len() >= 8);
    let mut input = String::new();
    for row in &rows {
        for model in ["ghs", "ghs_ssa"] {
            input.push_str(
                &serde_json::json!({
                    "model": model,
                    "sigma_um": row["sigma_um"], "lc_um": row["Lc_um"], "gamma": row["gamma"],
                    "lambda_nm": row["lambda_um"].as_f64().unwrap() * 1000.0,
                    "theta_i_deg": row["theta_i_deg"], "theta_o_deg": row["theta_o_deg"],
                    "phi_o_deg": row["phi_o_deg"], "fresnel": "none", "energy": "raw",
                })
                .to_string(),
            );
            input.push('\n');
        }
    }
    let out = run(&input);
    assert_eq!(out.len(), 2 * rows.len());
    let mut worst = [0.0f64; 2];
    for (j, row) in rows.iter().enumerate() {
        for (m, key) in ["brdf_full", "brdf_ssa"].iter().enumerate() {
            let got = &out[2 * j + m];
            let f = got["f"].as_f64().unwrap_or_else(|| panic!("{got}"));
            let want = row[key].as_f64().unwrap();
            worst[m] = worst[m].max(rel(f, want));
            assert!(rel(f, want) < 1e-3, "{key} row {row}: {f}");
            // Specular weight at this θi: A_s = exp(−(2kσ cosθi)²).
            let k = 2.0 * std::f64::consts::PI / row["lambda_um"].as_f64().unwrap();
            let x = 2.0
                * k
                * row["sigma_um"].as_f64().unwrap()
                * row["theta_i_deg"].as_f64().unwrap().to_radians().cos();
            let a_s = (-x * x).exp();
            let sw = got["specular_weight"].as_f64().unwrap();
            assert!((sw - a_s).abs() <= 1e-9 + 1e-6 * a_s, "{sw} vs {a_s}");
        }
    }
    eprintln!(
        "brdf eval vs reference: full {:.2e}, ssa {:.2e}",
        worst[0], worst[1]
    );
}

#[test]
fn two_scale_queries_share_one_model() {
    let q = |th_o: f64| {
        format!(
            r#"{{"model": "two_scale", "beta": 0.1, "sigma_um": 0.05, "lc_um": 2, "gamma": 2.5, "lambda_nm": 500, "theta_i_deg": 30, "theta_o_deg": {th_o}, "phi_o_deg": 180, "fresnel": "au", "coherent": "delta"}}"#
        )
    };
    let input: String = (0..40).map(|j| q(j as f64) + "\n").collect();
    let out = run(&input);
    assert_eq!(out.len(), 40);
    for o in &out {
        assert!(
            o["f"].as_f64().unwrap() >= 0.0 && o["pdf"].as_f64().unwrap() >= 0.0,
            "{o}"
        );
        assert!(o["specular_weight"].as_f64().unwrap() > 0.0);
    }
    // The lobe peaks at the mirror (θo = 30°).
    let f: Vec<f64> = out.iter().map(|o| o["f"].as_f64().unwrap()).collect();
    let peak = f.iter().cloned().fold(0.0, f64::max);
    assert!((f[30] - peak).abs() <= 0.2 * peak, "{f:?}");
}

/// `angle_deg` turns a microfacet material's axes: at normal incidence (which a turn
/// leaves in place) the material turned by 40° at φo is the unturned one at φo − 40°, and
/// a bad angle names the key.
#[test]
fn angle_deg_turns_the_microfacet_axes() {
    let input = r#"{"model": "ggx", "alpha_x": 0.1, "alpha_y": 0.3, "angle_deg": 40, "lambda_nm": 550, "theta_i_deg": 0, "theta_o_deg": 20, "phi_o_deg": 70, "metal": "cu"}
{"model": "ggx", "alpha_x": 0.1, "alpha_y": 0.3, "lambda_nm": 550, "theta_i_deg": 0, "theta_o_deg": 20, "phi_o_deg": 30, "metal": "cu"}
{"model": "beckmann", "alpha_x": 0.1, "alpha_y": 0.3, "angle_deg": -25, "lambda_nm": 450, "theta_i_deg": 0, "theta_o_deg": 35, "phi_o_deg": 200, "fresnel": "one"}
{"model": "beckmann", "alpha_x": 0.1, "alpha_y": 0.3, "lambda_nm": 450, "theta_i_deg": 0, "theta_o_deg": 35, "phi_o_deg": 225, "fresnel": "one"}
{"model": "ggx", "alpha_x": 0.1, "alpha_y": 0.3, "lambda_nm": 550, "theta_i_deg": 0, "theta_o_deg": 20, "phi_o_deg": 70, "metal": "cu"}
{"model": "ggx", "alpha": 0.1, "angle_deg": 1e300, "lambda_nm": 550, "theta_i_deg": 0, "theta_o_deg": 20, "phi_o_deg": 70, "metal": "cu"}
{"model": "smooth", "angle_deg": 10, "lambda_nm": 550, "theta_i_deg": 0, "theta_o_deg": 0, "phi_o_deg": 0, "metal": "cu"}
"#;
    let out = run(input);
    assert_eq!(out.len(), 7, "{out:?}");
    let f = |i: usize| out[i]["f"].as_f64().unwrap();
    assert!(rel(f(0), f(1)) < 1e-12, "{} vs {}", f(0), f(1));
    assert!(rel(f(2), f(3)) < 1e-12, "{} vs {}", f(2), f(3));
    // The turn matters: unturned at 70° is another value.
    assert!(rel(f(4), f(0)) > 0.1, "{} vs {}", f(4), f(0));
    for i in [5, 6] {
        assert_eq!(out[i]["field"].as_str(), Some("angle_deg"), "{:?}", out[i]);
    }
}

/// A `lustre fit` material file through `include` (relative to the working
/// directory), with the query's keys over it, gives the same bits as the
/// same material written out in the query; a missing file is named, and a bad key
/// over the file is named as that key.
#[test]
fn include_reads_a_fit_material_file() {
    let dir = std::env::temp_dir().join(format!("lustre-eval-include-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(
        dir.join("fit.toml"),
        "[provenance]\nfile = \"scan.x3p\"\nsha256 = \"00\"\ntool = \"lustre fit\"\n\n\
         [material]\nmetal = \"brass\"\nmodel = \"ghs\"\nsigma_um = 0.1\nlc_um = 2.0\n\
         gamma = 2.5\nalpha = 0.05\nalpha_beckmann = 0.06\n",
    )
    .unwrap();
    let geometry = r#""lambda_nm": 550, "theta_i_deg": 30, "theta_o_deg": 25, "phi_o_deg": 170"#;
    let input = [
        format!(r#"{{"include": "fit.toml", {geometry}}}"#),
        format!(
            r#"{{"model": "ghs", "metal": "brass", "sigma_um": 0.1, "lc_um": 2.0, "gamma": 2.5, {geometry}}}"#
        ),
        format!(r#"{{"include": "fit.toml", "model": "ggx", {geometry}}}"#),
        format!(r#"{{"model": "ggx", "alpha": 0.05, "metal": "brass", {geometry}}}"#),
        format!(r#"{{"include": "fit.toml", "model": "ggx", "alpha": 0.2, {geometry}}}"#),
        format!(r#"{{"include": "missing.toml", {geometry}}}"#),
        format!(r#"{{"include": "fit.toml", "sigma_um": -1.0, {geometry}}}"#),
    ]
    .join("\n");
    let out = run_in(&dir, &input);
    let _ = std::fs::remove_dir_all(&dir);
    assert_eq!(out.len(), 7, "{out:?}");
    let bits = |i: usize, k: &str| {
        out[i][k]
            .as_f64()
            .unwrap_or_else(|| panic!("line {i}: {:?}", out[i]))
            .to_bits()
    };
    for k in ["f", "pdf"] {
        assert_eq!(bits(0, k), bits(1, k), "{k}: {:?} vs {:?}", out[0], out[1]);
        assert_eq!(bits(2, k), bits(3, k), "{k}: {:?} vs {:?}", out[2], out[3]);
    }
    // The query's alpha is over the file's.
    assert_ne!(bits(4, "f"), bits(2, "f"));
    assert_eq!(out[5]["field"].as_str(), Some("include"), "{:?}", out[5]);
    assert!(
        out[5]["error"].as_str().unwrap().contains("missing.toml"),
        "{:?}",
        out[5]
    );
    assert_eq!(out[6]["field"].as_str(), Some("sigma_um"), "{:?}", out[6]);
}
