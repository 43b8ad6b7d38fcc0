//! Rayleigh–Rice (`brdf::wave::RayleighRice`, physics.md §13):
//!
//! * against NIST SCATMECH's `Microroughness_BRDF_Model`
//!   (`data/reference/scatmech_rayleigh_rice.json`, made by the script beside
//!   it): unpolarised M₀₀ and s- and p-incident BRDFs, 1050 geometries (in-plane
//!   forward and back, out of plane, θ to 89°) on five metals at seven
//!   wavelengths, to 1e−6 relative;
//! * sampling against the pdf (chi-square), the delta lobe, reciprocity;
//! * energy: the sampled albedo equals the cubature albedo, and for a smooth
//!   surface with a narrow lobe the total is R_s(θi) to O(g_s²);
//! * a tabulated PSD gives the formula with its own P(ζ).

use std::f64::consts::PI;

use brdf::statistics::{KcPsd, RadialPsd, TabulatedPsd};
use brdf::testing::{Chi2Config, albedo_quadrature, albedo_sampled, chi2_test, sidak};
use brdf::wave::{Polarization, RayleighRice};
use brdf::{Bxdf, DVec3, Fresnel, Ior, Metal};
use serde_json::Value;

fn reference() -> Value {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../data/reference/scatmech_rayleigh_rice.json"
    );
    serde_json::from_str(&std::fs::read_to_string(path).expect("reference json")).expect("parse")
}

fn num(v: &Value, k: &str) -> f64 {
    v[k].as_f64().unwrap_or_else(|| panic!("field {k}"))
}

fn dir(theta_deg: f64, phi_deg: f64) -> DVec3 {
    let (t, p) = (theta_deg.to_radians(), phi_deg.to_radians());
    DVec3::new(t.sin() * p.cos(), t.sin() * p.sin(), t.cos())
}

const POLS: [(Polarization, &str); 3] = [
    (Polarization::Unpolarized, "m00"),
    (Polarization::S, "s"),
    (Polarization::P, "p"),
];

#[test]
fn equals_scatmech_to_1e6_everywhere() {
    let r = reference();
    let rows = r["rows"].as_array().unwrap();
    assert!(rows.len() >= 1000, "{} rows", rows.len());
    let mut worst = 0.0f64;
    let mut seen = std::collections::BTreeSet::new();
    for row in rows {
        let lam = num(row, "lambda_nm");
        let metal = Metal::from_name(row["metal"].as_str().unwrap()).unwrap();
        let (n, k) = (num(row, "n"), num(row, "k"));
        // The reference's n, k are rows of the built-in table.
        assert_eq!(Ior::metal(metal).at(lam), (n, k), "{row}");
        seen.insert((row["metal"].as_str().unwrap().to_string(), lam.to_bits()));
        let psd = KcPsd::new(num(row, "sigma_um"), num(row, "lc_um"), num(row, "gamma")).unwrap();
        let wi = dir(num(row, "theta_i_deg"), 0.0);
        let wo = dir(num(row, "theta_s_deg"), num(row, "phi_s_deg") + 180.0);
        for (pol, key) in POLS {
            let m =
                RayleighRice::with_polarization(psd, Fresnel::conductor(Ior::metal(metal)), pol)
                    .unwrap();
            let got = m.eval(wi, wo, lam);
            let want = num(row, key);
            let e = (got / want - 1.0).abs();
            worst = worst.max(e);
            assert!(
                e < 1e-6,
                "{key}: {got} vs SCATMECH {want} ({e:.1e}) at {row}"
            );
        }
    }
    assert!(seen.len() >= 7, "{seen:?}");
    println!(
        "{} rows × 3 polarisations: max relative deviation {worst:.2e}",
        rows.len()
    );
}

/// Metals and surfaces for the sampling and energy tests.
fn models() -> Vec<(String, RayleighRice, f64, f64)> {
    let mut out = Vec::new();
    for (i, (s, lc, g, th, lam)) in [
        (0.002, 10.0, 3.5, 0.0, 550.0),
        (0.01, 2.0, 2.0, 45.0, 450.0),
        (0.005, 0.5, 1.5, 70.0, 650.0),
        (0.02, 5.0, 3.0, 85.0, 400.0),
        (0.1, 50.0, 4.0, 80.0, 700.0),
    ]
    .into_iter()
    .enumerate()
    {
        let metal = [Metal::Au, Metal::Al, Metal::Cu, Metal::Ag, Metal::Cr][i];
        let pol = POLS[i % 3].0;
        let m = RayleighRice::with_polarization(
            KcPsd::new(s, lc, g).unwrap(),
            Fresnel::conductor(Ior::metal(metal)),
            pol,
        )
        .unwrap();
        out.push((format!("{metal:?} σ {s} Lc {lc} γ {g} {pol:?}"), m, th, lam));
    }
    out
}

#[test]
fn sampling_matches_the_pdf() {
    let ms = models();
    let alpha = sidak(0.01, ms.len());
    let mut failures = Vec::new();
    for (i, (name, m, th, lam)) in ms.iter().enumerate() {
        let cfg = Chi2Config {
            samples: 120_000,
            pilot_samples: 30_000,
            seed: 77 + i as u64,
            ..Default::default()
        };
        let rep = chi2_test(m, dir(*th, 0.0), *lam, &cfg);
        println!(
            "{name} θi {th}: χ² {:.1} dof {} p {:.3}",
            rep.statistic, rep.dof, rep.p_value
        );
        if !rep.passes(alpha) {
            failures.push(format!("{name}: {}", rep.check(alpha).unwrap_err()));
        }
        // Enough glossy samples that the test can fail.
        assert!(rep.dof >= 5, "{name}: {} degrees of freedom", rep.dof);
    }
    assert!(failures.is_empty(), "{}", failures.join("\n\n"));
}

#[test]
fn unpolarised_rayleigh_rice_is_reciprocal() {
    let m = RayleighRice::new(
        KcPsd::new(0.01, 2.0, 2.5).unwrap(),
        Fresnel::conductor(Ior::metal(Metal::Au)),
    )
    .unwrap();
    let mut worst = 0.0f64;
    for ti in [0.0, 20.0, 55.0, 80.0, 89.0] {
        for (to, po) in [
            (0.0, 0.0),
            (15.0, 180.0),
            (40.0, 30.0),
            (75.0, 250.0),
            (88.0, 100.0),
        ] {
            for lam in [380.0, 560.0, 800.0] {
                let (wi, wo) = (dir(ti, 10.0), dir(to, po));
                let (a, b) = (m.eval(wi, wo, lam), m.eval(wo, wi, lam));
                assert!(a > 0.0);
                worst = worst.max((a / b - 1.0).abs());
            }
        }
    }
    assert!(worst < 1e-12, "{worst}");
}

#[test]
fn specular_lobe_is_the_polarised_fresnel_reflectance_times_a_s() {
    let (s, lam, th) = (0.01, 500.0, 60.0f64);
    let au = Ior::metal(Metal::Au);
    let (n, k) = au.at(lam);
    let (rs, rp) = {
        // The textbook complex form, written out here.
        let c = th.to_radians().cos();
        let e = (n * n - k * k, 2.0 * n * k);
        let (ar, ai) = csqrt(e.0 - (1.0 - c * c), e.1);
        let r = |num: (f64, f64), den: (f64, f64)| {
            (num.0 * num.0 + num.1 * num.1) / (den.0 * den.0 + den.1 * den.1)
        };
        let ec = (e.0 * c, e.1 * c);
        (
            r((c - ar, -ai), (c + ar, ai)),
            r((ec.0 - ar, ec.1 - ai), (ec.0 + ar, ec.1 + ai)),
        )
    };
    let a_s = (-(4.0 * PI * s * th.to_radians().cos() / (lam / 1000.0)).powi(2)).exp();
    for (pol, r) in [
        (Polarization::S, rs),
        (Polarization::P, rp),
        (Polarization::Unpolarized, 0.5 * (rs + rp)),
    ] {
        let m = RayleighRice::with_polarization(
            KcPsd::new(s, 2.0, 3.0).unwrap(),
            Fresnel::conductor(au.clone()),
            pol,
        )
        .unwrap();
        let w = m.specular(dir(th, 0.0), lam).weight;
        assert!(
            (w / (r * a_s) - 1.0).abs() < 1e-12,
            "{pol:?}: {w} vs {}",
            r * a_s
        );
    }
}

fn csqrt(re: f64, im: f64) -> (f64, f64) {
    let r = re.hypot(im);
    let a = (0.5 * (r + re)).sqrt();
    (a, 0.5 * im / a)
}

#[test]
fn energy_sampled_equals_quadrature_and_smooth_limit_is_fresnel() {
    for (name, m, th, lam) in models() {
        let wi = dir(th, 0.0);
        let q = albedo_quadrature(&m, wi, lam, 1e-7);
        let s = albedo_sampled(&m, wi, lam, 400_000, 5);
        let e = (s.mean - q.value).abs();
        assert!(
            e < 5.0 * s.std_error + 1e-6,
            "{name} θi {th}: sampled {} ± {} vs cubature {}",
            s.mean,
            s.std_error,
            q.value
        );
    }
    // σ 1 nm, Lc 50 µm (the lobe within 1° of the mirror), θi ≤ 60°:
    // g_s ≤ 2e−3 and Q/R, the obliquity and the disk cut all 1 to
    // O(lobe width), so the total is R_s to a few 1e−6.
    for th in [0.0, 30.0, 60.0] {
        for metal in [Metal::Au, Metal::Al] {
            let f = Fresnel::conductor(Ior::metal(metal));
            let m = RayleighRice::new(KcPsd::new(0.001, 50.0, 4.0).unwrap(), f.clone()).unwrap();
            let lam = 550.0;
            let wi = dir(th, 0.0);
            let total = albedo_quadrature(&m, wi, lam, 1e-9).value;
            let r = f.reflectance(wi.z, lam);
            let g = (4.0 * PI * 0.001 * wi.z / 0.55f64).powi(2);
            assert!(
                (total / r - 1.0).abs() < g * g + 2e-4 * g,
                "{metal:?} θi {th}: total {total} vs R {r} (g_s {g:.1e})"
            );
        }
    }
}

#[test]
fn a_tabulated_psd_enters_through_its_own_p() {
    let kc = KcPsd::new(0.01, 2.0, 2.5).unwrap();
    let zeta: Vec<f64> = (0..200).map(|i| 1e-3 * 1.08f64.powi(i)).collect();
    let p: Vec<f64> = zeta.iter().map(|&z| kc.psd(z)).collect();
    let tab = TabulatedPsd::new(&zeta, &p).unwrap();
    let f = Fresnel::conductor(Ior::metal(Metal::Cu));
    let m = RayleighRice::new(tab.clone(), f.clone()).unwrap();
    let mk = RayleighRice::new(kc, f).unwrap();
    let lam = 600.0;
    let k = 2000.0 * PI / lam;
    for (wi, wo) in [
        (dir(30.0, 0.0), dir(35.0, 180.0)),
        (dir(70.0, 0.0), dir(20.0, 90.0)),
    ] {
        let zeta = k * ((wi.x + wo.x).powi(2) + (wi.y + wo.y).powi(2)).sqrt();
        let (l, s) = (tab.length_um(), tab.sigma_um());
        let p_tab = s * s * l * l * tab.unit_psd_u(l * zeta);
        let (a, b) = (m.eval(wi, wo, lam), mk.eval(wi, wo, lam));
        assert!(
            (a / b - p_tab / kc.psd(zeta)).abs() < 1e-12,
            "{a} {b} {p_tab} {}",
            kc.psd(zeta)
        );
        assert!((a / b - 1.0).abs() < 1e-2, "{a} vs {b}");
    }
}

/// Random points over the whole accepted domain (σ 0–10 µm, Lc 0.03–1000 µm,
/// γ 1.001–100, every metal, the perfect conductor and extreme constant
/// indices, every polarisation, θ to 90° − 1e−9, λ 360–830 nm): Rayleigh–Rice
/// and the SSA with Q are finite, ≥ 0, and their samples carry
/// f·cosθo/pdf.
#[test]
fn finite_over_the_domain() {
    use brdf::wave::{GhsOptions, GhsSsa, PolarizationFactor};
    use proptest::prelude::*;
    use proptest::test_runner::{Config, RngAlgorithm, TestRng, TestRunner};
    let log_uniform = |lo: f64, hi: f64| (lo.ln()..=hi.ln()).prop_map(f64::exp);
    let theta = prop_oneof![
        4 => 0.0..90.0f64,
        1 => (1.0..9.0f64).prop_map(|e| 90.0 - 10f64.powf(-e).to_degrees()),
    ];
    let fresnel = prop_oneof![
        Just(Fresnel::One),
        (0..Metal::ALL.len()).prop_map(|i| Fresnel::conductor(Ior::metal(Metal::ALL[i]))),
        Just(Fresnel::conductor(Ior::constant(1e-3, 1e3).unwrap())),
        Just(Fresnel::conductor(Ior::constant(1.0, 1e-6).unwrap())),
    ];
    let strategy = (
        prop_oneof![Just(0.0), log_uniform(1e-5, 10.0)],
        log_uniform(0.03, 1000.0),
        log_uniform(1e-3, 99.0).prop_map(|x| 1.0 + x),
        fresnel,
        0..3usize,
        (theta.clone(), theta, 0.0..360.0f64, 360.0..=830.0f64),
        [0.0..1.0f64, 0.0..1.0f64, 0.0..1.0f64],
    );
    let mut runner = TestRunner::new_with_rng(
        Config {
            cases: 4000,
            failure_persistence: None,
            ..Config::default()
        },
        TestRng::from_seed(RngAlgorithm::ChaCha, &[35; 32]),
    );
    runner
        .run(&strategy, |(s, lc, g, f, p, (ti, to, po, lam), u)| {
            let psd = KcPsd::new(s, lc, g).unwrap();
            let pol = POLS[p].0;
            let rr = RayleighRice::with_polarization(psd, f.clone(), pol).unwrap();
            let opts = GhsOptions {
                polarization: pol,
                polarization_factor: PolarizationFactor::Q,
                ..Default::default()
            };
            let ssa = GhsSsa::with_options(psd, f, opts).unwrap();
            let (wi, wo) = (dir(ti, 0.0), dir(to, po));
            for m in [&rr as &dyn Bxdf, &ssa] {
                let (fv, pdf) = m.eval_pdf(wi, wo, lam);
                prop_assert!(fv.is_finite() && fv >= 0.0 && pdf.is_finite() && pdf >= 0.0);
                let sp = m.specular(wi, lam);
                prop_assert!((0.0..=1.0).contains(&sp.weight), "{sp:?}");
                if let Some(x) = m.sample(wi, lam, u) {
                    prop_assert!(x.weight.is_finite() && x.weight >= 0.0, "{x:?}");
                    if !x.is_delta {
                        let (f2, p2) = m.eval_pdf(wi, x.wo, lam);
                        let w = f2 * x.wo.z / p2;
                        prop_assert!((x.weight - w).abs() <= 1e-9 * w.max(1e-300), "{x:?} {w}");
                    }
                }
            }
            Ok(())
        })
        .unwrap();
}
