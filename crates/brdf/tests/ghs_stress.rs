//! proptest stress of the GHS models over the hazards of physics.md §11:
//! γ → 1 (SSA down to 1.001, full down to 1.05) and large γ, g → 0 and
//! g ≫ 1, grazing angles, tiny and huge Lc, σ → 0 (and σ = 0), extreme λ.
//! Every eval/pdf/sample/specular must be finite, ≥ 0 and never panic.

use std::f64::consts::{FRAC_PI_2, TAU};
use std::sync::{Arc, OnceLock};

use brdf::statistics::KcPsd;
use brdf::statistics::matern::Matern;
use brdf::wave::ghs::hemisphere_u_max;
use brdf::wave::ghs_table::{GhsTable, TableResolution};
use brdf::wave::{Energy, GhsFull, GhsOptions, GhsSsa};
use brdf::{Bxdf, DVec3, Fresnel, Ior, Metal};
use proptest::prelude::*;

/// γ values with a prebuilt table (sized for Lc ≤ 1e3 µm).
const GAMMAS: [f64; 5] = [1.05, 1.3, 3.0, 6.0, 40.0];
const LC_MAX: f64 = 1e3;

fn tables() -> &'static Vec<Arc<GhsTable>> {
    static T: OnceLock<Vec<Arc<GhsTable>>> = OnceLock::new();
    T.get_or_init(|| {
        GAMMAS
            .iter()
            .map(|g| {
                let m = Matern::new((g - 1.0) / 2.0);
                Arc::new(
                    GhsTable::build(&m, hemisphere_u_max(LC_MAX), TableResolution::default())
                        .unwrap(),
                )
            })
            .collect()
    })
}

fn dir(theta: f64, phi: f64) -> DVec3 {
    DVec3::new(
        theta.sin() * phi.cos(),
        theta.sin() * phi.sin(),
        theta.cos(),
    )
}

fn check(m: &dyn Bxdf, wi: DVec3, wo: DVec3, lam: f64, u: [f64; 3]) -> Result<(), TestCaseError> {
    let f = m.eval(wi, wo, lam);
    let p = m.pdf(wi, wo, lam);
    prop_assert!(f.is_finite() && f >= 0.0, "eval {f}");
    prop_assert!(p.is_finite() && p >= 0.0, "pdf {p}");
    let s = m.specular(wi, lam);
    prop_assert!(
        s.weight.is_finite() && (0.0..=1.0 + 1e-12).contains(&s.weight),
        "spec {s:?}"
    );
    prop_assert!((0.0..=1.0).contains(&s.probability), "spec {s:?}");
    if let Some(x) = m.sample(wi, lam, u) {
        prop_assert!(x.weight.is_finite() && x.weight >= 0.0, "sample {x:?}");
        prop_assert!(x.pdf.is_finite() && x.pdf > 0.0, "sample {x:?}");
        prop_assert!(
            x.wo.is_finite() && (x.wo.length() - 1.0).abs() < 1e-9 && x.wo.z > 0.0,
            "sample {x:?}"
        );
    }
    Ok(())
}

fn sigma_strategy() -> impl Strategy<Value = f64> {
    prop_oneof![Just(0.0), (-9.0f64..1.0).prop_map(|e| 10f64.powf(e))]
}

fn angle_strategy() -> impl Strategy<Value = f64> {
    prop_oneof![
        0.0..FRAC_PI_2,
        Just(0.0),
        (1.0f64..9.0).prop_map(|e| FRAC_PI_2 - 10f64.powf(-e)),
    ]
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 400, ..ProptestConfig::default() })]

    #[test]
    fn full_model_is_finite_and_nonnegative(
        gi in 0usize..GAMMAS.len(),
        sigma in sigma_strategy(),
        lc_exp in -1.5f64..3.0,
        th_i in angle_strategy(),
        th_o in angle_strategy(),
        phi in 0.0f64..TAU,
        lam in 360.0f64..830.0,
        u in prop::array::uniform3(0.0f64..1.0),
    ) {
        let psd = KcPsd::new(sigma, 10f64.powf(lc_exp), GAMMAS[gi]).unwrap();
        let m = GhsFull::with_table(psd, Fresnel::conductor(Ior::metal(Metal::Au)), GhsOptions::default(), tables()[gi].clone()).unwrap();
        let (wi, wo) = (dir(th_i, 0.0), dir(th_o, phi));
        check(&m, wi, wo, lam, u)?;
        check(&m, wi, DVec3::new(-wi.x, -wi.y, wi.z), lam, u)?; // exact mirror (ζ = 0)
    }

    #[test]
    fn ssa_model_is_finite_and_nonnegative(
        gamma in prop_oneof![Just(1.001), 1.001f64..100.0],
        sigma in prop_oneof![Just(0.0), Just(10.0), (-9.0f64..1.0).prop_map(|e| 10f64.powf(e))],
        lc_exp in -1.5f64..3.0,
        th_i in angle_strategy(),
        th_o in angle_strategy(),
        phi in 0.0f64..TAU,
        lam in 360.0f64..830.0,
        u in prop::array::uniform3(0.0f64..1.0),
    ) {
        let psd = KcPsd::new(sigma, 10f64.powf(lc_exp), gamma).unwrap();
        let m = GhsSsa::new(psd, Fresnel::One).unwrap();
        let (wi, wo) = (dir(th_i, 0.0), dir(th_o, phi));
        check(&m, wi, wo, lam, u)?;
        check(&m, wi, DVec3::new(-wi.x, -wi.y, wi.z), lam, u)?;
    }
}

/// The renormalised options at the extremes (their (θi, λ) tables cost
/// ~10⁷ lobe evaluations each, so a handful of surfaces, not proptest).
#[test]
fn renormalised_options_at_extremes() {
    for (gi, sigma, lc) in [
        (0usize, 0.3, 0.03),
        (1, 1e-7, 1e3),
        (3, 5.0, 0.03),
        (4, 0.0, 1.0),
        (2, 0.5, 1e3),
    ] {
        let psd = KcPsd::new(sigma, lc, GAMMAS[gi]).unwrap();
        for energy in [Energy::Krywonos, Energy::SigmaRel] {
            let opts = GhsOptions {
                energy,
                ..Default::default()
            };
            let full = GhsFull::with_table(psd, Fresnel::One, opts, tables()[gi].clone()).unwrap();
            let ssa = GhsSsa::with_options(psd, Fresnel::One, opts).unwrap();
            for m in [&full as &dyn Bxdf, &ssa] {
                for th_i in [0.0, 0.7, 1.5, FRAC_PI_2 - 1e-6] {
                    for th_o in [0.0, 0.3, 1.2, FRAC_PI_2 - 1e-5] {
                        for lam in [360.0, 555.0, 830.0] {
                            check(m, dir(th_i, 0.0), dir(th_o, 2.0), lam, [0.3, 0.6, 0.9]).unwrap();
                        }
                    }
                }
            }
        }
    }
}

#[test]
fn bad_inputs_never_panic() {
    let psd = KcPsd::new(0.1, 2.0, 3.0).unwrap();
    let full = GhsFull::with_table(
        psd,
        Fresnel::One,
        GhsOptions::default(),
        tables()[2].clone(),
    )
    .unwrap();
    let ssa = GhsSsa::new(psd, Fresnel::One).unwrap();
    let bad = [
        DVec3::new(0.0, 0.0, -1.0),
        DVec3::new(f64::NAN, 0.0, 1.0),
        DVec3::new(1.0, 0.0, 0.0),
        DVec3::ZERO,
        DVec3::new(0.0, 0.0, f64::INFINITY),
    ];
    for m in [&full as &dyn Bxdf, &ssa] {
        for &a in &bad {
            for lam in [f64::NAN, -1.0, 0.0, 550.0, 1e9] {
                let f =
                    m.eval(a, DVec3::Z, lam) + m.eval(DVec3::Z, a, lam) + m.pdf(a, DVec3::Z, lam);
                assert!(f.is_finite() && f >= 0.0);
                let s = m.specular(a, lam);
                assert!(s.weight.is_finite() && s.probability.is_finite());
                if let Some(x) = m.sample(a, lam, [0.5, 0.5, 0.5]) {
                    assert!(x.weight.is_finite() && x.pdf.is_finite());
                }
            }
        }
    }
    // γ < 1.05 is rejected by the full model's table with a clear error.
    let e = GhsFull::new(KcPsd::new(0.1, 1.0, 1.01).unwrap(), Fresnel::One).unwrap_err();
    assert!(e.to_string().contains("gamma"), "{e}");
}
