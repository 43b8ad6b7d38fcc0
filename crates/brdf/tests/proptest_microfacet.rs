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

/// Any direction, including below the horizon, at the horizon, unnormalised
/// and (rarely) non-finite: `eval_pdf_rows` must treat each row as
/// `eval_pdf` does.
fn any_direction() -> impl Strategy<Value = DVec3> {
    prop_oneof![
        8 => direction(THETA_MAX),
        2 => (0.0..=std::f64::consts::PI, 0.0..std::f64::consts::TAU)
            .prop_map(|(t, p)| spherical(t, p)),
        1 => (-2.0f64..2.0, -2.0f64..2.0, -2.0f64..2.0).prop_map(|(x, y, z)| DVec3::new(x, y, z)),
        1 => Just(DVec3::new(1.0, 0.0, 0.0)),
        1 => Just(DVec3::new(0.0, 0.0, f64::NAN)),
    ]
}

fn any_fresnel() -> impl Strategy<Value = Fresnel> {
    prop_oneof![
        Just(Fresnel::One),
        (0..Metal::ALL.len()).prop_map(|m| Fresnel::conductor(Ior::metal(Metal::ALL[m]))),
        (0.05f64..4.0, 0.0f64..8.0)
            .prop_map(|(n, k)| Fresnel::conductor(Ior::constant(n, k).unwrap())),
        (0.05f64..4.0, 0.0f64..8.0).prop_map(|(n, k)| Fresnel::conductor(
            Ior::table(vec![
                [300.0, n, k],
                [600.0, n + 0.5, 0.5 * k],
                [900.0, 1.0, k]
            ])
            .unwrap()
        )),
    ]
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 500, ..config(0x726f_7773) })]

    /// The array path (SIMD lanes for GGX) is bit-identical to `eval_pdf`
    /// row by row, for every row count (whole blocks and a remainder).
    #[test]
    fn eval_pdf_rows_is_eval_pdf_bit_for_bit(
        kind in prop_oneof![Just(NdfKind::Ggx), Just(NdfKind::Beckmann)],
        ax in alpha(),
        ay in alpha(),
        fresnel in any_fresnel(),
        rows in prop::collection::vec((any_direction(), any_direction(), wavelength()), 0..23),
    ) {
        let m = MicrofacetConductor::new(Distribution::new(kind, ax, ay).unwrap(), fresnel).unwrap();
        let wi: Vec<DVec3> = rows.iter().map(|r| r.0).collect();
        let wo: Vec<DVec3> = rows.iter().map(|r| r.1).collect();
        let lambda: Vec<f64> = rows.iter().map(|r| r.2).collect();
        let (mut f, mut pdf) = (vec![-1.0; rows.len()], vec![-1.0; rows.len()]);
        m.eval_pdf_rows(&wi, &wo, &lambda, &mut f, &mut pdf);
        for (i, &(a, b, l)) in rows.iter().enumerate() {
            let (f1, p1) = m.eval_pdf(a, b, l);
            prop_assert_eq!((f[i].to_bits(), pdf[i].to_bits()), (f1.to_bits(), p1.to_bits()),
                "row {} of {}: wi {:?} wo {:?} λ {}", i, rows.len(), a, b, l);
        }
    }
}
