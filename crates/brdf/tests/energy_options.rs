//! The energy-conserving options keep their promise over the accepted
//! domain: with R ≡ 1 the directional albedo — specular
//! weight plus ∫ f cosθo dωo by the independent adaptive cubature of
//! `brdf::testing::albedo_quadrature`, which never calls the model's own
//! tables or quadrature — is ≤ 1 + 1e−3 at every θi ≤ 89.5°:
//!
//! * GHS SSA and full GHS with `energy = "krywonos"` (and then also ≥ 1 − 1e−3
//!   wherever the raw lobe is not treated as absorbed) and `"sigma_rel"`;
//! * the two-scale model's reciprocal cap, both readings of the coherent part.
//!
//! σ 0–10 µm, Lc 0.03–1000 µm, γ 1.001 (full: 1.05)–100, β 1e−4–10,
//! λ 360–830 nm, θi 0–89.5° (a third of the angles beyond 85°), with fixed
//! seeds. CI runs a few dozen materials per model; `cargo test --release -p
//! brdf --test energy_options -- --ignored` runs 10× more. Three grazing
//! points where tables that stop short of grazing incidence exceed 1 are
//! pinned below.

use brdf::statistics::KcPsd;
use brdf::statistics::kc::{GAMMA_MIN, GAMMA_MIN_FULL};
use brdf::testing::albedo_quadrature;
use brdf::wave::two_scale::{CoherentPart, TwoScale, TwoScaleParams};
use brdf::wave::{Energy, GhsFull, GhsOptions, GhsSsa};
use brdf::{Bxdf, DVec3, Fresnel};
use proptest::prelude::*;
use proptest::test_runner::{Config, RngAlgorithm, TestRng, TestRunner};

/// The promise: the albedo exceeds 1 by at most this.
const EXCESS_MAX: f64 = 1e-3;
/// Absolute tolerance of the reference cubature (well inside the promise).
const CUBATURE_TOL: f64 = 2e-5;

fn dir(theta_deg: f64) -> DVec3 {
    let t = theta_deg.to_radians();
    DVec3::new(t.sin(), 0.0, t.cos())
}

fn runner(cases: u32, seed: u8) -> TestRunner {
    let config = Config {
        cases,
        failure_persistence: None,
        ..Config::default()
    };
    TestRunner::new_with_rng(
        config,
        TestRng::from_seed(RngAlgorithm::ChaCha, &[seed; 32]),
    )
}

fn log_uniform(lo: f64, hi: f64) -> impl Strategy<Value = f64> {
    (lo.ln()..=hi.ln()).prop_map(f64::exp)
}

/// σ: 0, the largest, or log-uniform from 1e−4 µm.
fn sigma() -> impl Strategy<Value = f64> {
    prop_oneof![
        1 => Just(0.0),
        1 => Just(10.0),
        14 => log_uniform(1e-4, 10.0),
    ]
}

/// γ − 1 log-uniform from `gamma_min` − 1 to 99.
fn gamma(gamma_min: f64) -> impl Strategy<Value = f64> {
    log_uniform(gamma_min - 1.0, 99.0).prop_map(|x| 1.0 + x)
}

/// θi in [0, 89.5°], a third of them beyond 85°.
fn theta() -> impl Strategy<Value = f64> {
    prop_oneof![2 => 0.0..85.0f64, 1 => 85.0..=89.5f64]
}

fn wavelength() -> impl Strategy<Value = f64> {
    prop_oneof![1 => Just(360.0), 1 => Just(830.0), 6 => 360.0..=830.0f64]
}

/// The albedo of `m` at (θi, λ) by the independent cubature.
fn albedo(m: &dyn Bxdf, theta_deg: f64, lambda_nm: f64) -> f64 {
    let q = albedo_quadrature(m, dir(theta_deg), lambda_nm, CUBATURE_TOL);
    assert!(q.converged, "cubature did not converge: {q:?}");
    q.value
}

/// A GHS model (SSA or full) under `energy`, and the same model raw.
fn ghs(psd: KcPsd, full: bool, energy: Energy) -> (Box<dyn Bxdf>, Box<dyn Bxdf>) {
    let opts = GhsOptions {
        energy,
        ..Default::default()
    };
    if full {
        (
            Box::new(GhsFull::with_options(psd, Fresnel::One, opts).unwrap()),
            Box::new(GhsFull::new(psd, Fresnel::One).unwrap()),
        )
    } else {
        (
            Box::new(GhsSsa::with_options(psd, Fresnel::One, opts).unwrap()),
            Box::new(GhsSsa::new(psd, Fresnel::One).unwrap()),
        )
    }
}

/// Krywonos and σ_rel at three random (θi, λ) each for one random surface.
fn ghs_energy_suite(cases: u32, full: bool, seed: u8) {
    let gamma_min = if full { GAMMA_MIN_FULL } else { GAMMA_MIN };
    let points = proptest::collection::vec((theta(), wavelength()), 3);
    let strategy = (
        sigma(),
        log_uniform(0.03, 1000.0),
        gamma(gamma_min),
        prop_oneof![Just(Energy::Krywonos), Just(Energy::SigmaRel)],
        points,
    );
    runner(cases, seed)
        .run(&strategy, |(s, lc, g, energy, points)| {
            let psd = KcPsd::new(s, lc, g).unwrap();
            let (m, raw) = ghs(psd, full, energy);
            for (th, lam) in points {
                let total = albedo(&*m, th, lam);
                let what = format!(
                    "{} σ {s} µm, Lc {lc} µm, γ {g}, {energy:?}, θi {th}°, λ {lam} nm",
                    if full { "full" } else { "SSA" }
                );
                prop_assert!(total <= 1.0 + EXCESS_MAX, "{what}: albedo {total}");
                if energy == Energy::Krywonos {
                    // By construction A_s + K a_s = 1, unless the raw lobe is
                    // (nearly) all evanescent and treated as absorbed.
                    let a_s = m.specular(dir(th), lam).weight;
                    let a_raw = albedo(&*raw, th, lam) - a_s;
                    if a_raw > 1e-4 * (1.0 - a_s) {
                        prop_assert!(total >= 1.0 - EXCESS_MAX, "{what}: albedo {total}");
                    }
                }
            }
            Ok(())
        })
        .unwrap();
}

fn two_scale_suite(cases: u32, seed: u8) {
    let points = proptest::collection::vec((theta(), wavelength()), 3);
    let strategy = (
        log_uniform(1e-4, 10.0),
        sigma(),
        log_uniform(0.03, 1000.0),
        gamma(GAMMA_MIN),
        prop_oneof![Just(CoherentPart::MacroNdf), Just(CoherentPart::Delta)],
        points,
    );
    runner(cases, seed)
        .run(&strategy, |(beta, s, lc, g, coherent, points)| {
            let m = TwoScale::new(TwoScaleParams {
                beta,
                sigma_um: s,
                lc_um: lc,
                gamma: g,
                fresnel: Fresnel::One,
                coherent,
                resolution: Default::default(),
            })
            .unwrap();
            for (th, lam) in points {
                let total = albedo(&m, th, lam);
                prop_assert!(
                    total <= 1.0 + EXCESS_MAX,
                    "β {beta}, σ {s} µm, Lc {lc} µm, γ {g}, {coherent:?}, θi {th}°, λ {lam} nm: \
                     albedo {total}"
                );
            }
            Ok(())
        })
        .unwrap();
}

#[test]
fn ssa_energy_options_never_exceed_one() {
    ghs_energy_suite(24, false, 1);
}

#[test]
fn full_ghs_energy_options_never_exceed_one() {
    ghs_energy_suite(12, true, 2);
}

#[test]
fn two_scale_cap_never_exceeds_one() {
    two_scale_suite(16, 3);
}

// The long suites are separate tests so that a failure in one does not
// hide the other's result.
#[test]
#[ignore = "long: 10x the materials; run with --release -- --ignored"]
fn energy_options_never_exceed_one_long() {
    ghs_energy_suite(240, false, 11);
    ghs_energy_suite(120, true, 12);
}

#[test]
#[ignore = "long (≈6 min): 10x the materials; run with --release -- --ignored"]
fn two_scale_cap_never_exceeds_one_long() {
    two_scale_suite(160, 13);
}

/// Three points near grazing incidence where tables that stop short of it
/// give albedos of 1.026 (Krywonos), 1.007 (σ_rel) and 1.035 (two-scale).
#[test]
fn three_grazing_points_conserve_energy() {
    let s808 = KcPsd::new(0.808, 10.0, 3.5).unwrap();
    for energy in [Energy::Krywonos, Energy::SigmaRel] {
        let (m, _) = ghs(s808, true, energy);
        let total = albedo(&*m, 89.0, 400.0);
        assert!(total <= 1.0 + EXCESS_MAX, "{energy:?}: {total}");
        if energy == Energy::Krywonos {
            assert!((total - 1.0).abs() <= EXCESS_MAX, "{energy:?}: {total}");
        }
    }
    let narrow = TwoScale::new(TwoScaleParams {
        beta: 1.2e-4,
        sigma_um: 0.027,
        lc_um: 1.0,
        gamma: 4.0,
        fresnel: Fresnel::One,
        coherent: CoherentPart::MacroNdf,
        resolution: Default::default(),
    })
    .unwrap();
    assert!(narrow.is_energy_capped());
    for th in [89.0, 89.5] {
        let total = albedo(&narrow, th, 550.0);
        assert!(total <= 1.0 + EXCESS_MAX, "two-scale θi {th}°: {total}");
    }
}

/// A very steep surface (σ/Lc ≈ 46) whose two-scale albedo exceeds 1 at normal
/// incidence (1.0087 at 360 nm) and not at the grazing angles the cap used to screen
/// alone: found by `energy_options_never_exceed_one_long`.
#[test]
fn two_scale_cap_screens_normal_incidence() {
    let m = TwoScale::new(TwoScaleParams {
        beta: 1.97e-3,
        sigma_um: 10.0,
        lc_um: 0.217,
        gamma: 7.45,
        fresnel: Fresnel::One,
        coherent: CoherentPart::MacroNdf,
        resolution: Default::default(),
    })
    .unwrap();
    for (th, lam) in [(0.0, 360.0), (0.0, 830.0), (30.0, 360.0), (89.0, 550.0)] {
        let total = albedo(&m, th, lam);
        assert!(
            total <= 1.0 + EXCESS_MAX,
            "θi {th}°, λ {lam} nm: albedo {total}"
        );
    }
}

/// A steep surface (σ/Lc 6.5) whose raw full-GHS lobe peaks all along the
/// horizon (g ∝ (cosθi + cosθo)² is smallest there) as well as at the mirror
/// direction: the build quadrature of the Krywonos table missed that band
/// near grazing incidence and left the albedo at 1.0039 (86.8°, 830 nm; up to
/// 1.0065 at 87°, 700 nm) and 0.9924 (89°, 830 nm). Found by
/// `energy_options_never_exceed_one_long`; its neighbours in θi and λ too.
#[test]
fn krywonos_steep_surface_near_grazing() {
    let psd = KcPsd::new(6.51, 1.0, 2.0).unwrap();
    let (m, _) = ghs(psd, true, Energy::Krywonos);
    for lam in [700.0, 780.0, 830.0] {
        for th in [86.0, 86.8, 87.5, 89.0] {
            let total = albedo(&*m, th, lam);
            assert!(
                (total - 1.0).abs() <= EXCESS_MAX,
                "θi {th}°, λ {lam} nm: albedo {total}"
            );
        }
    }
}

/// A raw albedo that changes by 10× per degree near the rim (σ 3 µm, Lc 1 µm,
/// γ 1.1: 1.2e−6 at 85°, 7.4e−6 at 86°, 700 nm): interpolated as a cubic in a,
/// not in ln a, its Krywonos albedo was 1.0014 at 85°, 700 nm. Found by
/// `krywonos_steep_grazing_sweep`.
#[test]
fn krywonos_albedo_steep_in_theta() {
    let psd = KcPsd::new(3.0, 1.0, 1.1).unwrap();
    let (m, _) = ghs(psd, true, Energy::Krywonos);
    for (th, lam) in [(85.0, 700.0), (85.0, 750.0), (86.0, 650.0), (86.0, 700.0)] {
        let total = albedo(&*m, th, lam);
        assert!(
            (total - 1.0).abs() <= EXCESS_MAX,
            "θi {th}°, λ {lam} nm: albedo {total}"
        );
    }
}

/// Steep surfaces near grazing incidence, where the raw lobe's band along the
/// horizon carries most of its albedo: full GHS under Krywonos on a grid of
/// σ 1–10 µm, Lc 0.3–3 µm, γ 1.1–8, θi 80–89.9°, λ 360–830 nm stays within
/// 1 ± EXCESS_MAX (wherever the raw lobe is not treated as absorbed).
#[test]
#[ignore = "long: 48 surfaces × 28 points; run with --release -- --ignored"]
fn krywonos_steep_grazing_sweep() {
    let (mut lo, mut hi) = ((f64::INFINITY, String::new()), (0.0, String::new()));
    for s in [1.0, 3.0, 6.51, 10.0] {
        for lc in [0.3, 1.0, 3.0] {
            for g in [1.1, 2.0, 4.0, 8.0] {
                let psd = KcPsd::new(s, lc, g).unwrap();
                let (m, raw) = ghs(psd, true, Energy::Krywonos);
                for th in [80.0, 85.0, 86.8, 88.0, 89.0, 89.5, 89.9] {
                    for lam in [360.0, 550.0, 700.0, 830.0] {
                        let total = albedo(&*m, th, lam);
                        let what = format!("σ {s} µm, Lc {lc} µm, γ {g}, θi {th}°, λ {lam} nm");
                        if total > hi.0 {
                            hi = (total, what.clone());
                        }
                        let a_s = m.specular(dir(th), lam).weight;
                        if albedo(&*raw, th, lam) - a_s > 1e-4 * (1.0 - a_s) && total < lo.0 {
                            lo = (total, what);
                        }
                    }
                }
            }
        }
    }
    println!(
        "largest albedo {} at {}; smallest {} at {}",
        hi.0, hi.1, lo.0, lo.1
    );
    assert!(hi.0 <= 1.0 + EXCESS_MAX, "albedo {} at {}", hi.0, hi.1);
    assert!(lo.0 >= 1.0 - EXCESS_MAX, "albedo {} at {}", lo.0, lo.1);
}
