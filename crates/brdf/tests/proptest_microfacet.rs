//! Property sweeps over the whole parameter space of the microfacet
//! conductors: α ∈ [1e-4, 1] (log-uniform, independently per axis),
//! θ up to 89.99°, λ over 360–830 nm, every built-in metal. Fixed seeds.

use brdf::frame::spherical;
use brdf::microfacet::{Distribution, MicrofacetConductor, NdfKind};
use brdf::{Bxdf, DVec3, Fresnel, Ior, Metal};
use proptest::prelude::*;
use proptest::test_runner::RngSeed;

const THETA_MAX: f64 = 89.99 * std::f64::consts::PI / 180.0;

fn config(seed: u64) -> ProptestConfig {
    ProptestConfig {
        cases: 2000,
        rng_seed: RngSeed::Fixed(seed),
        failure_persistence: None,
        ..ProptestConfig::default()
    }
}

fn alpha() -> impl Strategy<Value = f64> {
    (-4.0f64..=0.0).prop_map(|e| 10f64.powf(e).clamp(1e-4, 1.0))
}

fn model() -> impl Strategy<Value = MicrofacetConductor> {
    (
        prop_oneof![Just(NdfKind::Ggx), Just(NdfKind::Beckmann)],
        alpha(),
        alpha(),
        0..Metal::ALL.len(),
    )
        .prop_map(|(kind, ax, ay, m)| {
            MicrofacetConductor::new(
                Distribution::new(kind, ax, ay).unwrap(),
                Fresnel::conductor(Ior::metal(Metal::ALL[m])),
            )
            .unwrap()
        })
}

/// Directions with θ ∈ [0, θmax], φ ∈ [0, 2π).
fn direction(theta_max: f64) -> impl Strategy<Value = DVec3> {
    (0.0..=theta_max, 0.0..std::f64::consts::TAU).prop_map(|(t, p)| spherical(t, p))
}

fn wavelength() -> impl Strategy<Value = f64> {
    360.0f64..=830.0
}

fn rel(a: f64, b: f64) -> f64 {
    if a == b {
        0.0
    } else {
        (a - b).abs() / a.abs().max(b.abs())
    }
}

proptest! {
    #![proptest_config(config(0x6b72_6466))]

    /// eval and pdf are finite and ≥ 0 for any pair of directions (including
    /// below the horizon), f > 0 implies pdf > 0, and f is reciprocal.
    #[test]
    fn eval_and_pdf_are_finite_nonnegative_reciprocal(
        m in model(),
        wi in direction(THETA_MAX),
        wo in direction(std::f64::consts::PI),
        l in wavelength(),
    ) {
        let f = m.eval(wi, wo, l);
        let p = m.pdf(wi, wo, l);
        prop_assert!(f.is_finite() && f >= 0.0, "f = {}", f);
        prop_assert!(p.is_finite() && p >= 0.0, "pdf = {}", p);
        if f > 0.0 {
            prop_assert!(p > 0.0, "f = {} > 0 but pdf = 0", f);
        }
        let back = m.eval(wo, wi, l);
        prop_assert!(rel(f, back) < 1e-5, "f(i,o) = {}, f(o,i) = {}", f, back);
    }

    /// Every sample is a finite unit direction above the horizon with a
    /// finite weight in [0, 1] (F ≤ 1 and G2 ≤ G1), a positive pdf equal to
    /// pdf(), and weight = f cosθo / pdf.
    #[test]
    fn samples_are_valid_and_consistent(
        m in model(),
        wi in direction(THETA_MAX),
        l in wavelength(),
        u in (0.0f64..1.0, 0.0f64..1.0, 0.0f64..1.0),
    ) {
        if let Some(s) = m.sample(wi, l, [u.0, u.1, u.2]) {
            prop_assert!(!s.is_delta);
            prop_assert!(s.wo.is_finite() && (s.wo.length() - 1.0).abs() < 1e-12 && s.wo.z > 0.0, "{:?}", s);
            prop_assert!(s.weight.is_finite() && s.weight >= 0.0 && s.weight <= 1.0 + 1e-12, "{:?}", s);
            prop_assert!(s.pdf.is_finite() && s.pdf > 0.0, "{:?}", s);
            let p = m.pdf(wi, s.wo, l);
            let f = m.eval(wi, s.wo, l);
            prop_assert!(p > 0.0, "sampled where pdf = 0: {:?}", s);
            if f > 0.0 {
                prop_assert!(p > 0.0);
            }
            prop_assert!(rel(p, s.pdf) < 1e-5, "pdf() = {} vs sample pdf {}", p, s.pdf);
            prop_assert!(rel(f * s.wo.z / p, s.weight) < 1e-5, "f cos/pdf = {} vs weight {}", f * s.wo.z / p, s.weight);
        }
    }
}
