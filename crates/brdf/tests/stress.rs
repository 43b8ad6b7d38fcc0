//! Numerical stress suite: random parameter points over the whole valid
//! range of every model, with fixed seeds. Every value must be finite and
//! ≥ 0, sampled directions must have pdf > 0 wherever f > 0 and a weight
//! consistent with eval·cos/pdf, and nothing may panic.
//!
//! CI runs `STRESS_CASES` (10⁴) points per model; the `#[ignore]`d variants
//! run 10⁶ (`cargo test --release -p brdf --test stress -- --ignored`).
//! Every failure found becomes a named regression case at the bottom.

use brdf::frame::spherical;
use brdf::microfacet::{Distribution, MicrofacetConductor, NdfKind};
use brdf::{Bxdf, Fresnel, Ior, Metal, SmoothConductor};
use proptest::prelude::*;
use proptest::test_runner::{Config, RngAlgorithm, TestRng, TestRunner};

const STRESS_CASES: u32 = 10_000;
const LONG_CASES: u32 = 1_000_000;

/// θ up to 89.999°, azimuth anywhere, λ over the visible range, random numbers.
fn geometry() -> impl Strategy<Value = (f64, f64, f64, f64, f64, [f64; 3])> {
    (
        0.0..89.999f64,
        0.0..89.999f64,
        0.0..360.0f64,
        360.0..830.0f64,
        0.0..360.0f64,
        [0.0..1.0f64, 0.0..1.0f64, 0.0..1.0f64],
    )
        .prop_map(|(ti, to, po, l, pi, u)| (ti, to, po, l, pi, u))
}

/// Log-uniform value in [lo, hi].
fn log_uniform(lo: f64, hi: f64) -> impl Strategy<Value = f64> {
    (lo.ln()..=hi.ln()).prop_map(f64::exp)
}

fn metal() -> impl Strategy<Value = Fresnel> {
    prop_oneof![
        Just(Fresnel::One),
        (0..Metal::ALL.len()).prop_map(|i| Fresnel::conductor(Ior::metal(Metal::ALL[i]))),
    ]
}

/// The invariants every model must keep at one geometry.
pub fn check_model<B: Bxdf + ?Sized>(
    model: &B,
    (ti, to, po, lambda, pi, u): (f64, f64, f64, f64, f64, [f64; 3]),
) -> Result<(), TestCaseError> {
    let wi = spherical(ti.to_radians(), pi.to_radians());
    let wo = spherical(to.to_radians(), (pi + po).to_radians());
    let f = model.eval(wi, wo, lambda);
    let p = model.pdf(wi, wo, lambda);
    prop_assert!(f.is_finite() && f >= 0.0, "eval = {f}");
    prop_assert!(p.is_finite() && p >= 0.0, "pdf = {p}");
    let spec = model.specular(wi, lambda);
    prop_assert!(
        spec.weight.is_finite() && spec.weight >= 0.0,
        "specular weight {}",
        spec.weight
    );
    prop_assert!(
        (0.0..=1.0).contains(&spec.probability),
        "specular probability {}",
        spec.probability
    );
    if let Some(s) = model.sample(wi, lambda, u) {
        prop_assert!(
            s.wo.is_finite() && (s.wo.length() - 1.0).abs() < 1e-9,
            "wo {:?}",
            s.wo
        );
        prop_assert!(
            s.weight.is_finite() && s.weight >= 0.0,
            "weight {}",
            s.weight
        );
        prop_assert!(s.pdf.is_finite() && s.pdf > 0.0, "sample pdf {}", s.pdf);
        if !s.is_delta {
            let fs = model.eval(wi, s.wo, lambda);
            let ps = model.pdf(wi, s.wo, lambda);
            prop_assert!(fs.is_finite() && fs >= 0.0);
            if fs > 0.0 {
                prop_assert!(ps > 0.0, "f = {fs} > 0 but pdf = 0 at a sampled direction");
            }
            // The returned pdf is the one pdf() reports (to round-off).
            prop_assert!(
                (ps - s.pdf).abs() <= 1e-6 * ps.max(s.pdf),
                "pdf {ps} vs sample pdf {}",
                s.pdf
            );
        }
    }
    Ok(())
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

fn microfacet_suite(cases: u32) {
    let strategy = (
        prop_oneof![Just(NdfKind::Ggx), Just(NdfKind::Beckmann)],
        log_uniform(1e-4, 1.0),
        log_uniform(1e-4, 1.0),
        metal(),
        geometry(),
    );
    runner(cases, 1)
        .run(&strategy, |(kind, ax, ay, fresnel, geo)| {
            let model = MicrofacetConductor::new(Distribution::new(kind, ax, ay).unwrap(), fresnel)
                .unwrap();
            check_model(&model, geo)
        })
        .unwrap();
}

fn smooth_suite(cases: u32) {
    runner(cases, 2)
        .run(&(metal(), geometry()), |(fresnel, geo)| {
            check_model(&SmoothConductor::new(fresnel).unwrap(), geo)
        })
        .unwrap();
}

#[test]
fn microfacet_stress() {
    microfacet_suite(STRESS_CASES);
}

#[test]
fn smooth_stress() {
    smooth_suite(STRESS_CASES);
}

#[test]
#[ignore = "long: 10^6 points per model; run with --release -- --ignored"]
fn microfacet_stress_long() {
    microfacet_suite(LONG_CASES);
}

#[test]
#[ignore = "long: 10^6 points per model; run with --release -- --ignored"]
fn smooth_stress_long() {
    smooth_suite(LONG_CASES);
}

/// Exact edge cases that random sampling hits with probability zero.
#[test]
fn microfacet_edges() {
    for kind in [NdfKind::Ggx, NdfKind::Beckmann] {
        for a in [1e-4, 1.0] {
            let m = MicrofacetConductor::new(Distribution::new(kind, a, a).unwrap(), Fresnel::One)
                .unwrap();
            for ti in [0.0, 45.0, 89.999, 90.0] {
                for to in [0.0, 89.999, 90.0] {
                    for po in [0.0, 180.0] {
                        for u in [[0.0; 3], [0.999_999_999_999; 3], [0.5; 3]] {
                            check_model(&m, (ti, to, po, 550.0, 0.0, u)).unwrap();
                        }
                    }
                }
            }
        }
    }
}
