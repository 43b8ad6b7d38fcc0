//! Synthetic anisotropic Gaussian maps whose radial spectrum is NOT a K-correlation (a
//! two-slope power law, stretched along axes at φ₀ with areas kept: physics.md §15.2), run
//! through `fit` and `judge` as scans are: against each map's own explicit BRDF (the
//! estimator `lustre judge` uses), the stretched measured-PSD model (`measured_psd_aniso`)
//! is within the reference's noise and, for g up to ~2, beats the stretched K-correlation
//! (`ghs_aniso`), whose radial shape is wrong, and the isotropic measured PSD, which has no lay; for
//! ratios 2–10, several azimuths and g from 0.01 to ~12.

use fit::kc2d;
use serde_json::Value;

mod common;
use common::model;

const UM: f64 = 1e-6;

fn params(j: &Value, key: &str) -> Value {
    j["models"]
        .as_array()
        .unwrap()
        .iter()
        .find(|m| m["key"] == key)
        .map(|m| m["params"].clone())
        .unwrap_or(Value::Null)
}

/// The de-stretched radial law: flat below ρ₁, ρ^−2.5 to ρ₂, ρ^−5 beyond, σ = `sigma` [m].
fn two_slope(sigma: f64, rho1: f64, rho2: f64) -> impl Fn(f64) -> f64 {
    let shape = move |r: f64| {
        (1.0 + (r / rho1).powi(2)).powf(-1.25) * (1.0 + (r / rho2).powi(2)).powf(-1.25)
    };
    // ∫ shape d²ζ = 2π ∫ shape ρ dρ, on a log grid.
    let (n, lo, hi) = (20_000, (rho1 * 1e-4).ln(), (rho2 * 1e4).ln());
    let h = (hi - lo) / n as f64;
    let mass: f64 = (0..n)
        .map(|i| {
            let r = (lo + (i as f64 + 0.5) * h).exp();
            2.0 * std::f64::consts::PI * shape(r) * r * r * h
        })
        .sum();
    let c = sigma * sigma / mass;
    move |r| c * shape(r)
}

struct Case {
    sigma_um: f64,
    ratio: f64,
    angle_deg: f64,
    seed: u64,
    /// Whether the stretched measured model must beat the stretched KC here.
    beats_kc: bool,
}

fn judged(c: &Case) -> Value {
    let radial = two_slope(
        c.sigma_um * UM,
        2.0 * std::f64::consts::PI / (4.0 * UM),
        2.0 * std::f64::consts::PI / (0.4 * UM),
    );
    let (s, co) = c.angle_deg.to_radians().sin_cos();
    let (sa, sb) = (1.0 / c.ratio.sqrt(), c.ratio.sqrt());
    let psd = move |zx: f64, zy: f64| {
        let (za, zb) = (co * zx + s * zy, co * zy - s * zx);
        radial((sa * za).hypot(sb * zb))
    };
    // 20 µm, 256², as the two AFM scans of the corpus judge compares.
    let t = kc2d::synth_surface_with(256, 256, 20.0 * UM / 256.0, &psd, c.seed);
    common::judge_cu(t)
}

#[test]
fn the_elliptical_measured_model_beats_the_stretched_kc_on_non_kc_spectra() {
    // g = (2kσ)² at normal incidence (550 nm): 0.013, 0.21, 1.9, 0.21, 12.
    let cases = [
        Case {
            sigma_um: 0.005,
            ratio: 2.0,
            angle_deg: 0.0,
            seed: 3,
            beats_kc: true,
        },
        Case {
            sigma_um: 0.02,
            ratio: 3.0,
            angle_deg: 30.0,
            seed: 4,
            beats_kc: true,
        },
        Case {
            sigma_um: 0.06,
            ratio: 3.0,
            angle_deg: -75.0,
            seed: 5,
            beats_kc: true,
        },
        Case {
            sigma_um: 0.02,
            ratio: 10.0,
            angle_deg: 60.0,
            seed: 6,
            beats_kc: true,
        },
        // At g ≈ 12 the lobe is the slope distribution, set by the spectrum's top decade,
        // where the stretched KC fits as well: within the noise, not ranked against it.
        Case {
            sigma_um: 0.15,
            ratio: 6.0,
            angle_deg: 15.0,
            seed: 8,
            beats_kc: false,
        },
    ];
    let mut failures = Vec::new();
    for c in &cases {
        let j = judged(c);
        let noise = j["window"]["noise_floor_log10"].as_f64().unwrap();
        let e = model(&j, "measured_psd_aniso");
        let (kc, iso) = (model(&j, "ghs_aniso"), model(&j, "measured_psd"));
        let p = params(&j, "measured_psd_aniso");
        let skipped = &j["skipped"];
        eprintln!(
            "σ {} µm ratio {} φ₀ {}°: measured_psd_aniso {e:?}, ghs_aniso {kc:?}, \
             measured_psd {iso:?}, noise {noise:.3}; {p}",
            c.sigma_um, c.ratio, c.angle_deg
        );
        let Some(e) = e else {
            failures.push(format!("ratio {}: not ranked: {skipped}", c.ratio));
            continue;
        };
        let ratio = p["ly_um"].as_f64().unwrap() / p["lx_um"].as_f64().unwrap();
        let angle = p["angle_deg"].as_f64().unwrap();
        let turn = (angle - c.angle_deg).rem_euclid(180.0);
        // The axes are the stretched KC fit's, biased on a non-KC shape (8.3 for 10).
        if (ratio / c.ratio - 1.0).abs() > 0.2 || turn.min(180.0 - turn) > 3.0 {
            failures.push(format!(
                "ratio {}: axes Ly/Lx {ratio:.2} at {angle:.1}°, want {} at {}°",
                c.ratio, c.ratio, c.angle_deg
            ));
        }
        if e > 1.5 * noise {
            failures.push(format!("ratio {}: {e:.3} vs noise {noise:.3}", c.ratio));
        }
        if let Some(kc) = kc
            && c.beats_kc
            && e >= kc
        {
            failures.push(format!("ratio {}: {e:.3} vs ghs_aniso {kc:.3}", c.ratio));
        }
        if let Some(iso) = iso
            && c.ratio >= 3.0
            && e >= 0.7 * iso
        {
            failures.push(format!(
                "ratio {}: {e:.3} vs measured_psd {iso:.3}",
                c.ratio
            ));
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}
