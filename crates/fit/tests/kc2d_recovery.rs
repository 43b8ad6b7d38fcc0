//! The stretched K-correlation fit (`fit::kc2d`) recovers the parameters of synthetic
//! anisotropic Gaussian maps whose PSD is known (spectral synthesis, `kc2d::synth_surface`):
//! anisotropy ratios 1–10, axis angles over the half turn, γ 1.5–6; the fitted angle turns
//! with the map (a transposed map has φ₀ → 90° − φ₀). Fixed seeds.

use fit::kc2d::{self, AnisoKcParams, wrap_half_turn};
use proptest::prelude::*;

const UM: f64 = 1e-6;

/// 512² map, 1 µm pixels: the band is 0.037…1.57 rad/µm, so lengths of 1.2–13 µm have
/// their roll-off inside it.
fn recover(ratio: f64, angle_deg: f64, gamma: f64, seed: u64) -> (AnisoKcParams, kc2d::AnisoKcFit) {
    let lg = 4.0 * UM;
    let truth = AnisoKcParams {
        sigma: 0.05 * UM,
        lx: lg / ratio.sqrt(),
        ly: lg * ratio.sqrt(),
        angle_rad: angle_deg.to_radians(),
        gamma,
    };
    let t = kc2d::synth_surface(512, 512, UM, truth, seed);
    let f = kc2d::fit(&t, 0.0).expect("fit");
    (truth.normalised(), f)
}

fn angle_err_deg(a: f64, b: f64) -> f64 {
    wrap_half_turn(a - b).to_degrees().abs()
}

fn check(ratio: f64, angle_deg: f64, gamma: f64, seed: u64) {
    let (t, f) = recover(ratio, angle_deg, gamma, seed);
    let p = f.params;
    let rel = |a: f64, b: f64| (a / b - 1.0).abs();
    let msg = format!(
        "ratio {ratio} angle {angle_deg} γ {gamma}: fitted σ {:.4e} Lx {:.3e} Ly {:.3e} φ {:.2}° γ {:.3} \
         (rms {:.3}, iso {:.3}, {:?})",
        p.sigma,
        p.lx,
        p.ly,
        p.angle_rad.to_degrees(),
        p.gamma,
        f.rms_log_residual,
        f.rms_log_residual_isotropic,
        f.problem
    );
    eprintln!("{msg}");
    assert!(f.problem.is_none(), "{msg}");
    // One 512² realisation: σ and the lengths trade off along the roll-off (most at low γ),
    // their ratio and the angle are set by the whole band.
    assert!(rel(p.sigma, t.sigma) < 0.12, "σ: {msg}");
    assert!(
        rel(p.lx, t.lx) < 0.25 && rel(p.ly, t.ly) < 0.25,
        "lengths: {msg}"
    );
    // A known limit of the fit, measured: past a ratio of 5 the narrow axis's roll-off
    // nears the band's edge and the fitted ratio runs high, most at heavy tails (γ 1.5:
    // 11.3–11.9 for 9.72 at 44°; 10.96 for 9.87). Within 10 % below a ratio of 5.
    let ratio_tol = if ratio > 5.0 { 0.25 } else { 0.1 };
    assert!(rel(p.ratio(), t.ratio()) < ratio_tol, "ratio: {msg}");
    assert!((p.gamma - t.gamma).abs() < 0.1 * t.gamma, "γ: {msg}");
    if ratio >= 1.5 {
        assert!(
            angle_err_deg(p.angle_rad, t.angle_rad) < 3.0,
            "angle: {msg}"
        );
    }
    // Cell means of n ≥ 12 windowed periodogram bins scatter by ≈ 0.2–0.3 in ln; a wrong
    // model (the isotropic one on an anisotropic map) is far above that.
    assert!(f.rms_log_residual < 0.35, "residual: {msg}");
    if ratio >= 3.0 {
        assert!(
            f.rms_log_residual_isotropic > 1.5 * f.rms_log_residual,
            "{msg}"
        );
    }
}

#[test]
fn recovers_ratios_and_angles() {
    for (i, &(ratio, angle, gamma)) in [
        (1.0, 0.0, 2.5),
        (3.0, 0.0, 2.5),
        (3.0, 30.0, 4.0),
        (10.0, 75.0, 2.5),
        (10.0, -45.0, 4.0),
        (6.0, 90.0, 1.8),
    ]
    .iter()
    .enumerate()
    {
        check(ratio, angle, gamma, 11 + i as u64);
    }
    // A map longer along x than along y.
    let truth = AnisoKcParams {
        sigma: 0.05 * UM,
        lx: 1.5 * UM,
        ly: 4.5 * UM,
        angle_rad: 60f64.to_radians(),
        gamma: 3.0,
    };
    let t = kc2d::synth_surface(512, 256, UM, truth, 21);
    let p = kc2d::fit(&t, 0.0).unwrap().params;
    eprintln!("512 × 256: {p:?}");
    assert!(angle_err_deg(p.angle_rad, truth.angle_rad) < 3.0, "{p:?}");
    assert!((p.ratio() / 3.0 - 1.0).abs() < 0.1, "{p:?}");
}

#[test]
fn isotropic_map_fits_equal_lengths() {
    let (_, f) = recover(1.0, 20.0, 3.0, 5);
    assert!(f.params.ratio() < 1.1, "ratio {}", f.params.ratio());
}

#[test]
fn the_angle_turns_with_the_map() {
    let truth = AnisoKcParams {
        sigma: 0.05 * UM,
        lx: 2.0 * UM,
        ly: 8.0 * UM,
        angle_rad: 20f64.to_radians(),
        gamma: 3.0,
    };
    let t = kc2d::synth_surface(512, 512, UM, truth, 3);
    let a = kc2d::fit(&t, 0.0).unwrap().params;
    let b = kc2d::fit(&fit::anisotropy::transpose(&t), 0.0)
        .unwrap()
        .params;
    // Transposing swaps x and y: a direction at φ goes to 90° − φ.
    let want = wrap_half_turn(0.5 * std::f64::consts::PI - a.angle_rad);
    assert!(angle_err_deg(b.angle_rad, want) < 0.5, "{a:?} {b:?}");
    assert!(angle_err_deg(a.angle_rad, truth.angle_rad) < 3.0, "{a:?}");
}

proptest! {
    #![proptest_config(ProptestConfig {
        cases: 8,
        rng_seed: proptest::test_runner::RngSeed::Fixed(0x6b63_3264),
        failure_persistence: None,
        ..ProptestConfig::default()
    })]
    #[test]
    fn recovers_over_the_domain(ratio in 1.0f64..10.0, angle in -90.0f64..90.0, gamma in 1.5f64..6.0, seed in 0u64..1000) {
        check(ratio, angle, gamma, seed);
    }
}

/// The two corpus AFM scans flagged anisotropic: the stretched fit exists, lies in the
/// renderer's range, and describes their 2-D PSD at least as well as the isotropic one
/// (it contains it). The numbers are the ones physics.md §15 quotes.
#[test]
fn corpus_scans_flagged_anisotropic() {
    for name in ["nid-1.nid", "mi-1.mi"] {
        let path = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR"))
            .join("../../data/surfaces/corpus")
            .join(name);
        let t = fit::io::read_path(&path, &Default::default()).unwrap();
        let a = fit::pipeline::analyse(t, None, &Default::default()).unwrap();
        let an = a.anisotropy.as_ref().unwrap();
        let f = an.kc.as_ref().expect("flagged").as_ref().unwrap();
        let p = f.params;
        eprintln!(
            "{name}: slope ratio {:.2} at {:.1}°; 2-D fit σ {:.3} nm Lx {:.3} µm Ly {:.3} µm \
             φ₀ {:.1}° γ {:.2} noise {:.2e} m⁴, ln rms {:.3} (isotropic {:.3}), {} cells, {:?}",
            an.ratio,
            an.slope_direction_deg,
            p.sigma * 1e9,
            p.lx * 1e6,
            p.ly * 1e6,
            p.angle_rad.to_degrees(),
            p.gamma,
            f.noise_m4,
            f.rms_log_residual,
            f.rms_log_residual_isotropic,
            f.cells,
            f.problem
        );
        assert!(f.problem.is_none(), "{name}: {:?}", f.problem);
        assert!(f.rms_log_residual <= f.rms_log_residual_isotropic + 1e-9);
    }
}

/// What flags nid-1: the slope covariance of the whole map against that of the map
/// without its first 16 rows (a 40 nm artefact where the scan starts).
#[test]
fn nid1_slope_ratio_comes_from_its_first_rows() {
    let path = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../data/surfaces/corpus/nid-1.nid");
    let t = fit::io::read_path(&path, &Default::default()).unwrap();
    let ratio = |t: fit::Topography| {
        let (t, _) = fit::pipeline::prepare(t).unwrap();
        let psd = fit::psd::welch(&t, &Default::default()).unwrap();
        let an = fit::anisotropy::analyse(&t, psd).unwrap();
        (an.ratio, an.slope_direction_deg)
    };
    let mut cut = t.clone();
    cut.heights.drain(..16 * t.nx);
    cut.ny -= 16;
    let (whole, cropped) = (ratio(t), ratio(cut));
    eprintln!("nid-1 slope ratio {whole:?}, without the first 16 rows {cropped:?}");
    assert!(whole.0 > 5.0 && cropped.0 < 0.5 * whole.0);
}

/// Maps the fit cannot use are refused with an error naming the fit, never a panic.
#[test]
fn unusable_maps_are_refused() {
    let map = |nx: usize, ny: usize, h: f64| fit::Topography {
        nx,
        ny,
        dx: UM,
        dy: UM,
        heights: vec![h; nx * ny],
        channel: "test".into(),
        format: "synthetic",
    };
    let mut nan = kc2d::synth_surface(64, 64, UM, isotropic(), 1);
    nan.heights[100] = f64::NAN;
    for (what, t) in [
        ("profile", map(512, 1, 0.0)),
        ("tiny", map(8, 8, 0.0)),
        ("flat", map(64, 64, 1e-9)),
        ("invalid points", nan),
    ] {
        let e = kc2d::fit(&t, 0.0).expect_err(what).to_string();
        assert!(e.contains("anisotropic K-correlation fit"), "{what}: {e}");
    }
}

fn isotropic() -> AnisoKcParams {
    AnisoKcParams {
        sigma: 0.05 * UM,
        lx: 4.0 * UM,
        ly: 4.0 * UM,
        angle_rad: 0.0,
        gamma: 2.5,
    }
}
