//! GHS of an anisotropic K-correlation surface (`brdf::wave::GhsAnisotropic`,
//! physics.md §15): the isotropic models when Lx = Ly whatever the angle,
//! rotation covariance, reciprocity, chi-square of sampling against the pdf,
//! sampled = cubature albedo, and finiteness over the domain. Its agreement
//! with the explicit-surface BRDF of anisotropic Gaussian surfaces is
//! `crates/fit/tests/explicit_vs_anisotropic_ghs.rs`.

use std::f64::consts::PI;

use brdf::statistics::{AnisotropicKc, KcPsd};
use brdf::testing::{Chi2Config, albedo_quadrature, albedo_sampled, chi2_test, sidak};
use brdf::wave::{Energy, GhsAnisotropic, GhsFull, GhsOptions, GhsSsa};
use brdf::{Bxdf, DVec3, Fresnel, Ior, Metal};

fn dir(theta_deg: f64, phi_deg: f64) -> DVec3 {
    let (t, p) = (theta_deg.to_radians(), phi_deg.to_radians());
    DVec3::new(t.sin() * p.cos(), t.sin() * p.sin(), t.cos())
}

fn pairs() -> Vec<(DVec3, DVec3)> {
    let mut v = Vec::new();
    for (ti, pi) in [(0.0, 0.0), (30.0, 20.0), (60.0, 200.0), (85.0, 110.0)] {
        for (to, po) in [
            (0.0, 0.0),
            (ti, pi + 180.0),
            (ti + 2.0, pi + 181.0),
            (40.0, 75.0),
            (70.0, 300.0),
        ] {
            v.push((dir(ti, pi), dir(to.min(89.0), po)));
        }
    }
    v
}

fn aniso(s: f64, lx: f64, ly: f64, angle_deg: f64, g: f64) -> AnisotropicKc {
    AnisotropicKc::new(s, lx, ly, angle_deg.to_radians(), g).unwrap()
}

#[test]
fn equal_lengths_are_the_isotropic_models_at_any_angle() {
    let f = Fresnel::conductor(Ior::metal(Metal::Au));
    for (s, lc, g) in [(0.05, 2.0, 2.5), (0.3, 5.0, 3.5)] {
        let iso = KcPsd::new(s, lc, g).unwrap();
        let ssa = GhsSsa::new(iso, f.clone()).unwrap();
        let full = GhsFull::new(iso, f.clone()).unwrap();
        for angle in [0.0, 37.0, 90.0] {
            let a = aniso(s, lc, lc, angle, g);
            let assa = GhsAnisotropic::ssa(a, f.clone(), GhsOptions::default()).unwrap();
            let afull = GhsAnisotropic::full(a, f.clone(), GhsOptions::default()).unwrap();
            for (wi, wo) in pairs() {
                for lam in [400.0, 650.0] {
                    for (x, y) in [(&ssa as &dyn Bxdf, &assa as &dyn Bxdf), (&full, &afull)] {
                        let (fa, pa) = x.eval_pdf(wi, wo, lam);
                        let (fb, pb) = y.eval_pdf(wi, wo, lam);
                        assert!((fa - fb).abs() <= 1e-12 * fa.max(1e-300), "{fa} vs {fb}");
                        assert!((pa - pb).abs() <= 1e-12 * pa.max(1e-300), "{pa} vs {pb}");
                    }
                    assert_eq!(ssa.specular(wi, lam), assa.specular(wi, lam));
                }
            }
        }
    }
}

#[test]
fn rotating_surface_and_directions_together_changes_nothing() {
    let rot = |v: DVec3, d: f64| {
        let (s, c) = d.to_radians().sin_cos();
        DVec3::new(c * v.x - s * v.y, s * v.x + c * v.y, v.z)
    };
    for full in [false, true] {
        let make = |angle: f64| {
            let a = aniso(0.1, 0.5, 4.0, angle, 3.0);
            if full {
                GhsAnisotropic::full(a, Fresnel::One, GhsOptions::default()).unwrap()
            } else {
                GhsAnisotropic::ssa(a, Fresnel::One, GhsOptions::default()).unwrap()
            }
        };
        let (m0, m1) = (make(10.0), make(55.0));
        for (wi, wo) in pairs() {
            let a = m0.eval(wi, wo, 500.0);
            let b = m1.eval(rot(wi, 45.0), rot(wo, 45.0), 500.0);
            assert!(
                (a - b).abs() <= 1e-9 * a.max(1e-300),
                "full {full}: {a} vs {b}"
            );
            // Reciprocity (raw energy, halfway Fresnel angle).
            let c = m0.eval(wo, wi, 500.0);
            assert!(
                (a - c).abs() <= 1e-12 * a.max(1e-300),
                "full {full}: {a} vs {c}"
            );
        }
        // An anisotropic lobe: across the short length it is wider.
        let wi = dir(0.0, 0.0);
        let (along_a, along_b) = (dir(5.0, 10.0), dir(5.0, 100.0));
        assert!(m0.eval(wi, along_a, 500.0) > 2.0 * m0.eval(wi, along_b, 500.0));
    }
}

#[test]
fn renormalised_energy_is_refused_with_the_reason() {
    let opts = GhsOptions {
        energy: Energy::Krywonos,
        ..Default::default()
    };
    let e = GhsAnisotropic::ssa(aniso(0.1, 1.0, 2.0, 0.0, 3.0), Fresnel::One, opts).unwrap_err();
    assert!(e.to_string().contains("azimuth"), "{e}");
}

/// (σ, Lx, Ly, angle°, γ, θi°, φi°, λ).
type Set = (f64, f64, f64, f64, f64, f64, f64, f64);

/// g_s from ~1e−3 to ~100, ratios 1–10.
const SETS: [Set; 8] = [
    (0.002, 2.0, 2.0, 0.0, 3.0, 0.0, 0.0, 550.0),
    (0.05, 0.5, 5.0, 30.0, 2.5, 30.0, 0.0, 450.0),
    (0.1, 1.0, 3.0, 90.0, 3.5, 60.0, 45.0, 600.0),
    (0.3, 2.0, 20.0, 10.0, 4.0, 0.0, 0.0, 500.0),
    (0.02, 10.0, 1.0, 135.0, 2.0, 80.0, 120.0, 700.0),
    (0.5, 3.0, 9.0, 60.0, 3.0, 45.0, 300.0, 400.0),
    (1.0, 5.0, 50.0, 0.0, 3.5, 20.0, 90.0, 550.0),
    (0.08, 0.3, 1.5, 75.0, 1.5, 70.0, 10.0, 650.0),
];

#[test]
fn sampling_matches_the_pdf() {
    let alpha = sidak(0.01, 2 * SETS.len());
    let mut failures = Vec::new();
    for (i, &(s, lx, ly, ang, g, ti, pi, lam)) in SETS.iter().enumerate() {
        let a = aniso(s, lx, ly, ang, g);
        for (name, m) in [
            (
                "ssa",
                GhsAnisotropic::ssa(a, Fresnel::One, GhsOptions::default()).unwrap(),
            ),
            (
                "full",
                GhsAnisotropic::full(a, Fresnel::One, GhsOptions::default()).unwrap(),
            ),
        ] {
            let cfg = Chi2Config {
                samples: 120_000,
                pilot_samples: 30_000,
                seed: 500 + i as u64,
                ..Default::default()
            };
            let rep = chi2_test(&m, dir(ti, pi), lam, &cfg);
            println!(
                "{name} set {i}: χ² {:.1} dof {} p {:.3}",
                rep.statistic, rep.dof, rep.p_value
            );
            if !rep.passes(alpha) {
                failures.push(format!("{name} set {i}: {}", rep.check(alpha).unwrap_err()));
            }
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n\n"));
}

#[test]
fn sampled_albedo_equals_the_cubature() {
    for &(s, lx, ly, ang, g, ti, pi, lam) in SETS.iter().skip(1).step_by(2) {
        let a = aniso(s, lx, ly, ang, g);
        let m = GhsAnisotropic::full(
            a,
            Fresnel::conductor(Ior::metal(Metal::Cu)),
            GhsOptions::default(),
        )
        .unwrap();
        let wi = dir(ti, pi);
        let q = albedo_quadrature(&m, wi, lam, 1e-6);
        let sm = albedo_sampled(&m, wi, lam, 300_000, 9);
        assert!(
            (sm.mean - q.value).abs() < 5.0 * sm.std_error + 1e-5,
            "σ {s} Lx {lx} Ly {ly}: sampled {} ± {} vs {}",
            sm.mean,
            sm.std_error,
            q.value
        );
    }
}

#[test]
fn finite_and_bounded_over_the_domain() {
    use brdf::testing::Pcg32;
    let mut rng = Pcg32::new(35, 3);
    let lu = |rng: &mut Pcg32, lo: f64, hi: f64| (lo.ln() + rng.next_f64() * (hi / lo).ln()).exp();
    for _ in 0..60 {
        let s = if rng.next_u32().is_multiple_of(8) {
            0.0
        } else {
            lu(&mut rng, 1e-4, 10.0)
        };
        let (lx, ly) = (lu(&mut rng, 0.03, 1000.0), lu(&mut rng, 0.03, 1000.0));
        let g = 1.0 + lu(&mut rng, 0.05, 99.0);
        let a = aniso(s, lx, ly, 360.0 * rng.next_f64(), g);
        let full = GhsAnisotropic::full(a, Fresnel::One, GhsOptions::default()).unwrap();
        let ssa = GhsAnisotropic::ssa(a, Fresnel::One, GhsOptions::default()).unwrap();
        for _ in 0..200 {
            let ti = if rng.next_u32().is_multiple_of(4) {
                90.0 - 10f64.powf(-8.0 * rng.next_f64())
            } else {
                90.0 * rng.next_f64()
            };
            let wi = dir(ti, 360.0 * rng.next_f64());
            let wo = dir(90.0 * rng.next_f64(), 360.0 * rng.next_f64());
            let lam = 360.0 + 470.0 * rng.next_f64();
            // p_m ≤ p₁(0) = ν/π, so f ≤ k² Lx Ly (1 − e^{−g}) ν/π (+ the table's 1e−3).
            let k = 2000.0 * PI / lam;
            let t = k * s * (wi.z + wo.z);
            let bound =
                k * k * lx * ly * -(-t * t).exp_m1() * (g - 1.0) / (2.0 * PI) * (1.0 + 1e-3);
            for m in [&full, &ssa] {
                let (f, p) = m.eval_pdf(wi, wo, lam);
                assert!(
                    f.is_finite() && f >= 0.0 && f <= bound,
                    "{f} > {bound}: {a:?}"
                );
                assert!(p.is_finite() && p >= 0.0);
                if let Some(x) = m.sample(wi, lam, rng.uniform3()) {
                    assert!(
                        x.weight.is_finite() && x.weight >= 0.0 && x.pdf > 0.0,
                        "{x:?}"
                    );
                    assert!((x.wo.length() - 1.0).abs() < 1e-9 && x.wo.z >= 0.0);
                }
            }
        }
    }
}
