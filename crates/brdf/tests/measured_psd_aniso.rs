//! GHS (SSA and full) of a measured radial PSD stretched along two axes
//! (`brdf::statistics::EllipticalPsd<TabulatedPsd>`, `model = "measured_psd_aniso"`,
//! physics.md §15.2): the isotropic measured-PSD models at ratio 1 whatever the angle;
//! the anisotropic K-correlation when the radial law is the KC of Lc = √(Lx Ly);
//! rotation covariance, reciprocity, chi-square of sampling against the pdf on a
//! radial law that is not a K-correlation (two power laws), sampled = cubature
//! albedo, finiteness over a sweep. Its agreement with the explicit-surface BRDF of
//! anisotropic Gaussian surfaces is `crates/judge/tests/anisotropic_synthetic.rs`.

use std::f64::consts::PI;

use brdf::statistics::{AnisotropicKc, EllipticalPsd, KcPsd, RadialPsd, TabulatedPsd};
use brdf::testing::{Chi2Config, albedo_quadrature, albedo_sampled, chi2_test, sidak};
use brdf::wave::{GhsAnisotropic, GhsFull, GhsOptions, GhsSsa};
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

/// A radial PSD that is not a K-correlation: flat below ζ₁, ζ^−2.5 to ζ₂, ζ^−5 beyond
/// (a two-slope power law with rounded knees), scaled to rms height `sigma_um`, sampled
/// at 120 log-spaced nodes over the band of a scan (0.05…60 rad/µm).
fn two_slope(sigma_um: f64, z1: f64, z2: f64) -> TabulatedPsd {
    let shape =
        |z: f64| (1.0 + (z / z1).powi(2)).powf(-1.25) * (1.0 + (z / z2).powi(2)).powf(-1.25);
    let zeta: Vec<f64> = (0..120)
        .map(|i| 0.05 * (1200.0f64).powf(i as f64 / 119.0))
        .collect();
    let p: Vec<f64> = zeta.iter().map(|&z| shape(z)).collect();
    let unit = TabulatedPsd::new(&zeta, &p).unwrap();
    let scale = sigma_um * sigma_um / (unit.sigma_um() * unit.sigma_um());
    let p: Vec<f64> = p.iter().map(|v| v * scale).collect();
    TabulatedPsd::new(&zeta, &p).unwrap()
}

fn ell<P: RadialPsd>(p: P, lx: f64, ly: f64, angle_deg: f64) -> EllipticalPsd<P> {
    EllipticalPsd::new(p, lx, ly, angle_deg.to_radians()).unwrap()
}

fn close(a: f64, b: f64, rel: f64) -> bool {
    (a - b).abs() <= rel * a.abs().max(b.abs()) || a.max(b) < 1e-300
}

#[test]
fn equal_lengths_are_the_isotropic_measured_models_at_any_angle() {
    let f = Fresnel::conductor(Ior::metal(Metal::Au));
    let t = two_slope(0.05, 0.5, 5.0);
    let ssa = GhsSsa::new(t.clone(), f.clone()).unwrap();
    let full = GhsFull::new(t.clone(), f.clone()).unwrap();
    for angle in [0.0, 37.0, 90.0] {
        let e = ell(t.clone(), 2.0, 2.0, angle);
        let assa = GhsAnisotropic::ssa(e.clone(), f.clone(), GhsOptions::default()).unwrap();
        let afull = GhsAnisotropic::full(e, f.clone(), GhsOptions::default()).unwrap();
        for (wi, wo) in pairs() {
            for lam in [400.0, 650.0] {
                for (x, y) in [(&ssa as &dyn Bxdf, &assa as &dyn Bxdf), (&full, &afull)] {
                    let (fa, pa) = x.eval_pdf(wi, wo, lam);
                    let (fb, pb) = y.eval_pdf(wi, wo, lam);
                    assert!(close(fa, fb, 1e-12), "angle {angle}: {fa} vs {fb}");
                    assert!(close(pa, pb, 1e-12), "angle {angle}: {pa} vs {pb}");
                }
                assert_eq!(ssa.specular(wi, lam), assa.specular(wi, lam));
            }
        }
    }
}

/// A KC radial law of Lc = √(Lx Ly) stretched by Ly/Lx is the anisotropic KC: exactly
/// in the SSA (the same p₁), to the S̃ tables' accuracy in the full GHS (tables built
/// over different u ranges).
#[test]
fn a_stretched_kc_is_the_anisotropic_kc() {
    for (s, lx, ly, ang, g) in [(0.05, 0.5, 5.0, 30.0, 2.5), (0.3, 2.0, 6.0, -70.0, 3.5)] {
        let a = AnisotropicKc::new(s, lx, ly, f64::to_radians(ang), g).unwrap();
        let e = ell(KcPsd::new(s, (lx * ly).sqrt(), g).unwrap(), lx, ly, ang);
        let f = Fresnel::conductor(Ior::metal(Metal::Cu));
        let o = GhsOptions::default();
        let pairs_of = [
            (
                GhsAnisotropic::ssa(a, f.clone(), o).unwrap().eval_pdf_fn(),
                GhsAnisotropic::ssa(e.clone(), f.clone(), o)
                    .unwrap()
                    .eval_pdf_fn(),
                1e-12,
            ),
            (
                GhsAnisotropic::full(a, f.clone(), o).unwrap().eval_pdf_fn(),
                GhsAnisotropic::full(e.clone(), f.clone(), o)
                    .unwrap()
                    .eval_pdf_fn(),
                3e-3,
            ),
        ];
        for (x, y, tol) in &pairs_of {
            for (wi, wo) in pairs() {
                let (fa, pa) = x(wi, wo, 550.0);
                let (fb, pb) = y(wi, wo, 550.0);
                assert!(close(fa, fb, *tol), "{fa} vs {fb} ({tol})");
                assert!(close(pa, pb, *tol), "{pa} vs {pb} ({tol})");
            }
        }
    }
}

/// `eval_pdf` as a boxed closure, so models of different surface types share a list.
trait EvalPdfFn {
    fn eval_pdf_fn(self) -> Box<dyn Fn(DVec3, DVec3, f64) -> (f64, f64)>;
}

impl<B: Bxdf + 'static> EvalPdfFn for B {
    fn eval_pdf_fn(self) -> Box<dyn Fn(DVec3, DVec3, f64) -> (f64, f64)> {
        Box::new(move |wi, wo, lam| self.eval_pdf(wi, wo, lam))
    }
}

#[test]
fn rotation_covariance_reciprocity_and_the_lay() {
    let rot = |v: DVec3, d: f64| {
        let (s, c) = d.to_radians().sin_cos();
        DVec3::new(c * v.x - s * v.y, s * v.x + c * v.y, v.z)
    };
    let t = two_slope(0.1, 0.3, 4.0);
    for full in [false, true] {
        let make = |angle: f64| {
            let e = ell(t.clone(), 0.5, 4.0, angle);
            if full {
                GhsAnisotropic::full(e, Fresnel::One, GhsOptions::default()).unwrap()
            } else {
                GhsAnisotropic::ssa(e, Fresnel::One, GhsOptions::default()).unwrap()
            }
        };
        let (m0, m1) = (make(10.0), make(55.0));
        for (wi, wo) in pairs() {
            let a = m0.eval(wi, wo, 500.0);
            let b = m1.eval(rot(wi, 45.0), rot(wo, 45.0), 500.0);
            assert!(close(a, b, 1e-9), "full {full}: {a} vs {b}");
            let c = m0.eval(wo, wi, 500.0);
            assert!(close(a, c, 1e-12), "full {full}: {a} vs {c}");
        }
        // Across the short length (along a, at 10°) the lobe is wider.
        let wi = dir(0.0, 0.0);
        let (along_a, along_b) = (dir(5.0, 10.0), dir(5.0, 100.0));
        assert!(m0.eval(wi, along_a, 500.0) > 2.0 * m0.eval(wi, along_b, 500.0));
    }
}

/// (σ µm, knee ζ₁, knee ζ₂ rad/µm, Lx, Ly, angle°, θi°, φi°, λ nm): g_s ~1e−3 to ~60,
/// ratios 1–10.
type Set = (f64, f64, f64, f64, f64, f64, f64, f64, f64);

const SETS: [Set; 6] = [
    (0.002, 0.5, 5.0, 2.0, 2.0, 0.0, 0.0, 0.0, 550.0),
    (0.05, 0.3, 3.0, 0.5, 5.0, 30.0, 30.0, 0.0, 450.0),
    (0.1, 1.0, 8.0, 1.0, 3.0, 90.0, 60.0, 45.0, 600.0),
    (0.3, 0.2, 2.0, 2.0, 20.0, 10.0, 0.0, 0.0, 500.0),
    (0.02, 0.5, 20.0, 10.0, 1.0, 135.0, 80.0, 120.0, 700.0),
    (0.5, 0.3, 1.0, 3.0, 9.0, 60.0, 45.0, 300.0, 400.0),
];

#[test]
fn sampling_matches_the_pdf() {
    let alpha = sidak(0.01, 2 * SETS.len());
    let mut failures = Vec::new();
    for (i, &(s, z1, z2, lx, ly, ang, ti, pi, lam)) in SETS.iter().enumerate() {
        let e = ell(two_slope(s, z1, z2), lx, ly, ang);
        for (name, m) in [
            (
                "ssa",
                GhsAnisotropic::ssa(e.clone(), Fresnel::One, GhsOptions::default()).unwrap(),
            ),
            (
                "full",
                GhsAnisotropic::full(e.clone(), Fresnel::One, GhsOptions::default()).unwrap(),
            ),
        ] {
            let cfg = Chi2Config {
                samples: 120_000,
                pilot_samples: 30_000,
                seed: 700 + i as u64,
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
    for &(s, z1, z2, lx, ly, ang, ti, pi, lam) in SETS.iter().skip(1).step_by(2) {
        let e = ell(two_slope(s, z1, z2), lx, ly, ang);
        let m = GhsAnisotropic::full(
            e,
            Fresnel::conductor(Ior::metal(Metal::Cu)),
            GhsOptions::default(),
        )
        .unwrap();
        let wi = dir(ti, pi);
        let q = albedo_quadrature(&m, wi, lam, 1e-6);
        let sm = albedo_sampled(&m, wi, lam, 300_000, 9);
        println!(
            "σ {s} Lx {lx} Ly {ly}: sampled {:.5} ± {:.5}, cubature {:.5}",
            sm.mean, sm.std_error, q.value
        );
        assert!(
            (sm.mean - q.value).abs() < 5.0 * sm.std_error + 1e-5,
            "σ {s} Lx {lx} Ly {ly}: sampled {} ± {} vs {}",
            sm.mean,
            sm.std_error,
            q.value
        );
    }
}

/// Random surfaces (σ, knees, ratio 1/30…30, any angle) and directions: finite,
/// non-negative, the pdf positive wherever f is, and below the order bound
/// k² |det A| (1 − e^{−g}) max p (the full GHS: + the table's 1e−3).
#[test]
fn finite_and_bounded_over_a_sweep() {
    use brdf::testing::Pcg32;
    let mut rng = Pcg32::new(36, 5);
    let lu = |rng: &mut Pcg32, lo: f64, hi: f64| (lo.ln() + rng.next_f64() * (hi / lo).ln()).exp();
    for _ in 0..12 {
        let s = lu(&mut rng, 1e-3, 1.0);
        let z1 = lu(&mut rng, 0.1, 3.0);
        let t = two_slope(s, z1, z1 * lu(&mut rng, 2.0, 20.0));
        let (lx, ly) = (lu(&mut rng, 0.1, 30.0), lu(&mut rng, 0.1, 30.0));
        let e = ell(t.clone(), lx, ly, 360.0 * rng.next_f64());
        let p_max = (0..2000)
            .map(|i| t.unit_psd_u(1e-4 * 1e7f64.powf(i as f64 / 1999.0)))
            .fold(t.unit_psd_u(0.0), f64::max);
        let area = t.length_um().powi(2);
        let full = GhsAnisotropic::full(e.clone(), Fresnel::One, GhsOptions::default()).unwrap();
        let ssa = GhsAnisotropic::ssa(e, Fresnel::One, GhsOptions::default()).unwrap();
        for _ in 0..200 {
            let wi = dir(90.0 * rng.next_f64(), 360.0 * rng.next_f64());
            let wo = dir(90.0 * rng.next_f64(), 360.0 * rng.next_f64());
            let lam = 360.0 + 470.0 * rng.next_f64();
            let k = 2000.0 * PI / lam;
            let tq = k * s * (wi.z + wo.z);
            let bound = k * k * area * -(-tq * tq).exp_m1() * p_max * (1.0 + 1e-2);
            for (name, m) in [("full", &full), ("ssa", &ssa)] {
                let (f, p) = m.eval_pdf(wi, wo, lam);
                assert!(f.is_finite() && f >= 0.0, "{name}: {f}");
                assert!(p.is_finite() && p >= 0.0, "{name}: {p}");
                if name == "ssa" {
                    assert!(f <= bound, "{name}: {f} > {bound}");
                }
                if f > 0.0 {
                    assert!(p > 0.0, "{name}: f {f} with pdf 0");
                }
            }
        }
    }
}
