//! Synthetic Gaussian maps with two crossing lays (two stretched K-correlation spectra at
//! 0° and 70° summed: a 2-D PSD not constant on ellipses, physics.md §15.4) run through
//! `fit` and `judge` as scans are, at g ≤ 0.3 where the smooth-surface approximation holds:
//! `fit` flags the PSD as not elliptical and writes its grid, and against each map's own
//! explicit BRDF (the estimator `lustre judge` uses) the 2-D PSD model
//! (`measured_psd2d_ssa`) is within 2× the reference's noise (1.5–1.9× measured) and better than the
//! elliptical models (`measured_psd_aniso`, `ghs_aniso`), which hold one lay; at g ≈ 1–9 the
//! full GHS of the grid (`measured_psd2d`) is first.

use brdf::Metal;
use fit::kc2d::{self, AnisoKcParams};
use serde_json::Value;

mod common;
use common::model;

const UM: f64 = 1e-6;

/// "key error, …" of every ranked model, for the log.
fn ranking(j: &Value) -> String {
    let table: Vec<String> = (j["models"].as_array().unwrap().iter())
        .map(|m| {
            format!(
                "{} {:.3}",
                m["key"],
                m["log10_rms_error"].as_f64().unwrap_or(f64::NAN)
            )
        })
        .collect();
    table.join(", ")
}

struct Case {
    sigma_um: f64,
    /// Share of σ² in the lay at 0° (the rest at 70°).
    share: f64,
    seed: u64,
}

fn judged(c: &Case) -> Value {
    let s2 = (c.sigma_um * UM).powi(2);
    let a = AnisoKcParams {
        sigma: (c.share * s2).sqrt(),
        lx: 0.3 * UM,
        ly: 3.0 * UM,
        angle_rad: 0.0,
        gamma: 3.0,
    };
    let b = AnisoKcParams {
        sigma: ((1.0 - c.share) * s2).sqrt(),
        lx: 0.4 * UM,
        ly: 2.5 * UM,
        angle_rad: 70f64.to_radians(),
        gamma: 3.0,
    };
    let psd = move |zx: f64, zy: f64| a.psd(zx, zy) + b.psd(zx, zy);
    let t = kc2d::synth_surface_with(256, 256, 20.0 * UM / 256.0, &psd, c.seed);
    common::judge_cu(t)
}

/// The judge of `c`'s map (logged), and the error of `key` in it; a failure is noted
/// when `key` is not ranked or is more than `times_noise` × the reference's noise.
fn judged_within(
    c: &Case,
    key: &str,
    times_noise: f64,
    failures: &mut Vec<String>,
) -> Option<(Value, f64)> {
    let j = judged(c);
    let noise = j["window"]["noise_floor_log10"].as_f64().unwrap();
    eprintln!(
        "σ {} µm share {}: noise {noise:.3}; {}; skipped {}",
        c.sigma_um,
        c.share,
        ranking(&j),
        j["skipped"]
    );
    let Some(e) = model(&j, key) else {
        failures.push(format!("σ {}: not ranked: {}", c.sigma_um, j["skipped"]));
        return None;
    };
    if e > times_noise * noise {
        failures.push(format!("σ {}: {e:.3} vs noise {noise:.3}", c.sigma_um));
    }
    Some((j, e))
}

#[test]
fn the_2d_psd_model_beats_the_elliptical_ones_on_crossing_lays() {
    // g = (2kσ)² at normal incidence (550 nm): 0.034 and 0.21.
    let cases = [
        Case {
            sigma_um: 0.008,
            share: 0.6,
            seed: 11,
        },
        Case {
            sigma_um: 0.02,
            share: 0.7,
            seed: 12,
        },
    ];
    let mut failures = Vec::new();
    for c in &cases {
        let Some((j, e)) = judged_within(c, "measured_psd2d_ssa", 2.0, &mut failures) else {
            continue;
        };
        for other in ["measured_psd_aniso", "ghs_aniso", "measured_psd"] {
            if let Some(o) = model(&j, other)
                && e >= o
            {
                failures.push(format!("σ {}: {e:.3} vs {other} {o:.3}", c.sigma_um));
            }
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// The same crossing lays at g = (2kσ)² ≈ 1, 3.3 and 8.9 (normal incidence, 550 nm), where
/// the first order no longer holds: against each map's explicit BRDF the full GHS of the
/// grid (`measured_psd2d`) is first of every ranked model and within 2.5× the reference's
/// noise (1.7–2.0× measured; the SSA of the same grid 2.4–5.2×).
#[test]
fn the_full_2d_psd_model_at_g_1_to_10() {
    let cases = [
        Case {
            sigma_um: 0.044,
            share: 0.6,
            seed: 21,
        },
        Case {
            sigma_um: 0.08,
            share: 0.7,
            seed: 22,
        },
        Case {
            sigma_um: 0.13,
            share: 0.6,
            seed: 23,
        },
    ];
    let mut failures = Vec::new();
    for c in &cases {
        let Some((j, e)) = judged_within(c, "measured_psd2d", 2.5, &mut failures) else {
            continue;
        };
        for m in j["models"].as_array().unwrap() {
            let o = m["log10_rms_error"].as_f64().unwrap_or(f64::INFINITY);
            if m["key"] != "measured_psd2d" && e >= o {
                failures.push(format!("σ {}: {e:.3} vs {} {o:.3}", c.sigma_um, m["key"]));
            }
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// `corpus/mi-1.mi` (terraces whose straight edges streak the 2-D PSD, ellipse residual
/// 1.34): `fit` writes its grid and `judge` ranks the 2-D PSD model (Cu, 550 nm, θi 0°
/// and 45°, as physics.md §15.2's table of this scan).
#[test]
fn the_terraces_of_mi_1_are_ranked() {
    let path = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../data/surfaces/corpus/mi-1.mi");
    let bytes = fit::io::read_scan_file(&path).unwrap();
    let t = fit::io::read_bytes("mi-1.mi", &bytes, &fit::io::ReadOptions::default()).unwrap();
    let opts = judge::Options {
        metal: Some(Metal::Cu),
        lambda_nm: vec![550.0],
        theta_i_deg: vec![0.0, 45.0],
        ..judge::Options::default()
    };
    let j = judge::judge("mi-1.mi", t, &opts, &mut |_| {})
        .unwrap()
        .json();
    let noise = j["window"]["noise_floor_log10"].as_f64().unwrap();
    eprintln!(
        "mi-1: noise {noise:.3}; {}; skipped {}",
        ranking(&j),
        j["skipped"]
    );
    let Some(e) = model(&j, "measured_psd2d_ssa") else {
        panic!("not ranked: {}", j["skipped"]);
    };
    assert!(model(&j, "measured_psd2d").is_some(), "{}", j["skipped"]);
    // The streaks the elliptical table cannot hold are in the grid.
    let elliptical = model(&j, "measured_psd_aniso").unwrap();
    assert!(e < elliptical, "{e} vs measured_psd_aniso {elliptical}");
}
