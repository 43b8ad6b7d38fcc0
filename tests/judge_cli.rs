//! `lustre judge` end to end: on a Gaussian K-correlation surface (whose right answer is full
//! GHS) the GHS models rank first and the microfacet models far behind; `--reference` ranks
//! the model that generated the reference first with zero error; bad reference files are
//! reported with file, line and column; all outputs are written.

use std::path::{Path, PathBuf};
use std::process::Command;

use brdf::statistics::KcPsd;

use brdf::wave::GhsFull;
use brdf::{Bxdf, Fresnel};
use fit::kc::KcParams;
use fit::sampled_kc::PointSampledKc;
use serde_json::Value;

fn lustre() -> Command {
    Command::new(env!("CARGO_BIN_EXE_lustre"))
}

fn scratch(name: &str) -> PathBuf {
    let dir =
        Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("judge-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// A point-sampled Gaussian KC map as a Gwyddion text matrix (heights in m).
fn write_kc_map(path: &Path, n: usize, dx_um: f64, sigma_um: f64, lc_um: f64, gamma: f64) {
    let t = PointSampledKc::new(
        n,
        n,
        dx_um * 1e-6,
        KcParams {
            sigma: sigma_um * 1e-6,
            lc: lc_um * 1e-6,
            gamma,
        },
    )
    .realise(2024);
    let w = n as f64 * dx_um;
    let mut s =
        format!("# Channel: synthetic\n# Width: {w} µm\n# Height: {w} µm\n# Value units: m\n");
    for row in t.heights.chunks(n) {
        let line: Vec<String> = row.iter().map(|h| format!("{h:.6e}")).collect();
        s.push_str(&line.join("\t"));
        s.push('\n');
    }
    std::fs::write(path, s).unwrap();
}

fn run_json(args: &[&str]) -> Value {
    let out = lustre().args(args).output().expect("running lustre judge");
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "lustre judge failed: {err}");
    serde_json::from_slice(&out.stdout).unwrap_or_else(|e| panic!("not JSON ({e}): {err}"))
}

fn model<'a>(j: &'a Value, key: &str) -> &'a Value {
    j["models"]
        .as_array()
        .unwrap()
        .iter()
        .find(|m| m["key"] == key)
        .unwrap_or_else(|| panic!("no model {key} in {}", j["models"]))
}

#[test]
fn gaussian_kc_surface_is_judged_full_ghs() {
    let dir = scratch("kc");
    let map = dir.join("kc.txt");
    // σ 0.05 µm, Lc 0.3 µm, γ 4: g ≈ 1.3 at 550 nm, normal incidence; lobe Δsinθ ≈ 0.3.
    write_kc_map(&map, 512, 0.05, 0.05, 0.3, 4.0);
    let out = dir.join("out");
    let j = run_json(&[
        "judge",
        map.to_str().unwrap(),
        "--lambda",
        "550",
        "--theta-i",
        "0,45",
        "--angles",
        "60",
        "--json",
        "--no-surrogate",
        "-o",
        out.to_str().unwrap(),
    ]);
    let models = j["models"].as_array().unwrap();
    let errs: Vec<f64> = models
        .iter()
        .map(|m| m["log10_rms_error"].as_f64().unwrap_or(f64::INFINITY))
        .collect();
    assert!(
        errs.windows(2).all(|w| w[0] <= w[1]),
        "not best first: {errs:?}"
    );
    for m in models {
        println!(
            "{:<40} {:.3} (excess {:.3})",
            m["label"].as_str().unwrap(),
            m["log10_rms_error"].as_f64().unwrap_or(f64::NAN),
            m["log10_excess_over_noise"].as_f64().unwrap_or(f64::NAN)
        );
        assert_eq!(m["per_angle"].as_array().unwrap().len(), 2);
    }
    let noise = j["window"]["noise_floor_log10"].as_f64().unwrap();
    let ghs = model(&j, "ghs")["log10_rms_error"].as_f64().unwrap();
    let ggx = model(&j, "ggx")["log10_rms_error"].as_f64().unwrap();
    let top: Vec<&str> = models[..2]
        .iter()
        .map(|m| m["model"].as_str().unwrap())
        .collect();
    println!("noise floor {noise:.3}");
    // The right theory is within the reference's own noise (plus the KC fit's error); the
    // microfacet lobe is not.
    assert!(
        top.contains(&"ghs") || top.contains(&"measured_psd"),
        "top two: {top:?}"
    );
    assert!(
        ghs < 1.5 * noise + 0.05,
        "full GHS error {ghs} vs noise {noise}"
    );
    assert!(ggx > 2.0 * ghs, "GGX {ggx} vs GHS {ghs}");
    let w = &j["window"]["per_angle"][0];
    assert!(w["resolution_dsin"].as_f64().unwrap() > 0.0);
    assert!(w["by_validity"]["valid"].as_u64().unwrap() > 20);
    for f in [
        "judge.json",
        "judge_table.md",
        "judge_points.csv",
        "judge_slices.png",
        "judge_errors.png",
    ] {
        let m = std::fs::metadata(out.join(f)).unwrap_or_else(|e| panic!("{f}: {e}"));
        assert!(m.len() > 100, "{f} is empty");
    }
    let table = std::fs::read_to_string(out.join("judge_table.md")).unwrap();
    assert!(table.contains("Valid window") && table.contains("full GHS, KC fit"));
}

#[test]
fn reference_file_ranks_the_model_that_made_it_first() {
    let dir = scratch("ref");
    let scan = Path::new(env!("CARGO_MANIFEST_DIR")).join("data/surfaces/di-3.di");
    let base = [
        "judge",
        scan.to_str().unwrap(),
        "--lambda",
        "550",
        "--theta-i",
        "30",
        "--angles",
        "24",
        "--no-surrogate",
        "--no-plots",
        "--json",
    ];
    let out = dir.join("a");
    let mut args: Vec<&str> = base.to_vec();
    args.extend(["-o", out.to_str().unwrap()]);
    let j = run_json(&args);
    let p = &model(&j, "ghs")["params"];
    let ghs = GhsFull::new(
        KcPsd::new(
            p["sigma_um"].as_f64().unwrap(),
            p["lc_um"].as_f64().unwrap(),
            p["gamma"].as_f64().unwrap(),
        )
        .unwrap(),
        Fresnel::One,
    )
    .unwrap();
    // Columns in another order than documented, plus a comment and a zero row.
    let mut csv =
        String::from("# made by the test\nlambda_nm,brdf,theta_i_deg,phi_o_deg,theta_o_deg\n");
    for lambda in [480.0, 620.0] {
        for ti in [0.0f64, 40.0] {
            for to in [5.0f64, 20.0, 35.0, 60.0] {
                for po in [0.0f64, 90.0, 180.0] {
                    let wi = brdf::frame::spherical(ti.to_radians(), 0.0);
                    let wo = brdf::frame::spherical(to.to_radians(), po.to_radians());
                    let f = ghs.eval(wi, wo, lambda);
                    csv.push_str(&format!("{lambda},{f:e},{ti},{po},{to}\n"));
                }
            }
        }
    }
    csv.push_str("550,0,10,180,10\n");
    let reference = dir.join("ref.csv");
    std::fs::write(&reference, csv).unwrap();
    let out = dir.join("b");
    let mut args: Vec<&str> = base.to_vec();
    args.extend([
        "-o",
        out.to_str().unwrap(),
        "--reference",
        reference.to_str().unwrap(),
    ]);
    let j = run_json(&args);
    let r = &j["reference"];
    assert_eq!(r["rows"], 49);
    assert_eq!(r["skipped_rows"], 1);
    let ranked = r["models"].as_array().unwrap();
    assert_eq!(ranked[0]["key"], "ghs", "{ranked:?}");
    assert!(ranked[0]["log10_rms_error"].as_f64().unwrap() < 1e-9);
    assert_eq!(ranked[0]["points"], 48);
    assert!(ranked[1]["log10_rms_error"].as_f64().unwrap() > 1e-3);
}

#[test]
fn bad_reference_is_reported_with_line_and_column() {
    let dir = scratch("bad");
    let scan = Path::new(env!("CARGO_MANIFEST_DIR")).join("data/surfaces/di-3.di");
    let cases = [
        (
            "theta_i_deg,theta_o_deg,phi_o_deg,lambda_nm,brdf\n0,10,180,550,0.1\n0,20,180,550,abc\n",
            "ref.csv:3: column `brdf`",
        ),
        (
            "theta_i_deg,theta_o_deg,lambda_nm,brdf\n0,10,550,0.1\n",
            "no column `phi_o_deg`",
        ),
        (
            "theta_i_deg,theta_o_deg,phi_o_deg,lambda_nm,brdf\n0,10,180,2000,0.1\n",
            "ref.csv:2: lambda_nm must lie in",
        ),
    ];
    for (text, want) in cases {
        let reference = dir.join("ref.csv");
        std::fs::write(&reference, text).unwrap();
        let out = lustre()
            .args([
                "judge",
                scan.to_str().unwrap(),
                "--theta-i",
                "0",
                "--lambda",
                "550",
                "--angles",
                "8",
                "--no-surrogate",
                "--no-plots",
                "-o",
                dir.join("o").to_str().unwrap(),
                "--reference",
                reference.to_str().unwrap(),
            ])
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success());
        assert!(err.contains(want), "expected {want:?} in: {err}");
    }
}

#[test]
fn a_scan_too_short_for_any_direction_is_refused() {
    // An 8-point stylus profile: no direction of its explicit BRDF can be
    // compared, which gave a ranking of nothing and then a plot error.
    let dir = scratch("short");
    let scan = Path::new(env!("CARGO_MANIFEST_DIR")).join("data/surfaces/corpus/csv-1.csv");
    let out = lustre()
        .args([
            "judge",
            scan.to_str().unwrap(),
            "--no-plots",
            "-o",
            dir.join("o").to_str().unwrap(),
        ])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success(), "{err}");
    assert!(
        err.contains("csv-1.csv") && err.contains("no direction"),
        "{err}"
    );
    assert!(!dir.join("o/judge.json").exists());
}

#[test]
fn flags_that_would_run_for_minutes_or_misreport_are_refused_up_front() {
    // `--angles 100000` and `--upsample 16` on a 512 × 512 map each ran past 5 minutes;
    // `--crop 100000` was clamped to the map while the report said "central 100000 px";
    // a missing `--reference` was noticed only after the whole analysis.
    let dir = scratch("extremes");
    let scan = dir.join("kc.txt");
    write_kc_map(&scan, 64, 0.05, 0.01, 0.2, 3.0);
    let di6 = Path::new(env!("CARGO_MANIFEST_DIR")).join("data/surfaces/di-6.di");
    let (kc, di6) = (scan.to_str().unwrap(), di6.to_str().unwrap());
    for (file, flags, want) in [
        (
            kc,
            vec!["--angles", "100000"],
            "--angles 100000: must lie in 8..=1000",
        ),
        (
            kc,
            vec!["--crop", "100000"],
            "--crop 100000: larger than the scan (64 × 64 points)",
        ),
        (di6, vec!["--upsample", "16"], "--upsample 16 would"),
        (
            kc,
            vec!["--reference", "no/such.csv"],
            "--reference no/such.csv: no such file",
        ),
    ] {
        let start = std::time::Instant::now();
        let mut args = vec!["judge", file, "--no-plots", "-o", dir.to_str().unwrap()];
        args.extend(flags.iter().copied());
        let out = lustre().args(&args).output().unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success(), "{flags:?}: {err}");
        assert!(err.contains(want), "{flags:?}: {err}");
        if flags[0] != "--angles" && flags[0] != "--reference" {
            assert!(
                err.contains(file) && err.contains("Fix:"),
                "{flags:?}: {err}"
            );
        }
        assert!(start.elapsed().as_secs() < 30, "{flags:?}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}
