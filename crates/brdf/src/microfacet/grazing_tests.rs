//! The microfacet conductors at and near the horizon.
//!
//! The grazing limit, as defined here and documented on
//! [`super::MicrofacetConductor`]: a direction with cosθ ≤ 0 (on or below
//! the horizon) gives f = pdf = 0 and no sample. For cosθ > 0, however
//! small, the models return their analytic value for the directions as
//! given. That value is continuous up to the horizon but not small there:
//! with height-correlated Smith shadowing G₂ ≈ 2 cosθi cosθo /
//! (α(cosθi + cosθo)) when both are grazing, so at the mirror pair f ≈ D /
//! (2α (cosθi + cosθo)) grows like 1/cosθ while f·cosθo stays bounded: for
//! θi = θo = 90° in f64, cos(π/2) = 6.1e−17 is a round-off distance above the
//! horizon and f is 5e14, which is why the CLI places 90° exactly on it.
//!
//! Checked at exactly 0, at cosines from 1e−300 to 1e−3 (including
//! cos(π/2) in f64 and the cosine of 90° − 1e−12°), for wi and wo, GGX and
//! Beckmann, isotropic and anisotropic, Fresnel 1 and copper: finite and
//! non-negative; equal to an independent evaluation from the textbook
//! formulas wherever that evaluation does not underflow; reciprocal;
//! `eval_pdf_many` equal to `eval_pdf`; and every sample's weight and pdf
//! equal to f·cosθo/pdf and `pdf()` at the sampled direction.

extern crate std;

use super::{Distribution, MicrofacetConductor, NdfKind};
use crate::{Bxdf, Fresnel, Ior, Metal};
use core::f64::consts::PI;
use glam::DVec3;
use std::string::String;
use std::vec::Vec;
use std::{eprintln, format};

/// Cosines of the polar angle tried for each direction.
const COSINES: [f64; 11] = [
    0.0,
    1e-300,
    1e-200,
    9.9e-101, // just below COS_HORIZON
    1e-100,
    6.123_233_995_736_766e-17, // cos(π/2) in f64: "θ = 90°" through radians
    1.745_329_251_994_329_6e-14, // cos(90° − 1e−12°)
    1e-8,
    1e-5,
    1e-3,
    0.5,
];

fn models() -> Vec<(String, MicrofacetConductor)> {
    let mut v = Vec::new();
    for kind in [NdfKind::Ggx, NdfKind::Beckmann] {
        for (ax, ay) in [
            (1e-4, 1e-4),
            (0.01, 0.01),
            (0.1, 0.1),
            (0.5, 0.5),
            (1.0, 1.0),
            (0.05, 0.6),
        ] {
            for (fname, fresnel) in [
                ("one", Fresnel::One),
                ("cu", Fresnel::conductor(Ior::metal(Metal::Cu))),
            ] {
                let d = Distribution::new(kind, ax, ay).unwrap();
                v.push((
                    format!("{kind:?} α=({ax},{ay}) F={fname}"),
                    MicrofacetConductor::new(d, fresnel).unwrap(),
                ));
            }
        }
    }
    v
}

/// A unit direction with polar cosine `c` at azimuth `phi`.
fn dir(c: f64, phi: f64) -> DVec3 {
    let s = libm::sqrt((1.0 - c * c).max(0.0));
    DVec3::new(s * libm::cos(phi), s * libm::sin(phi), c)
}

/// f from the textbook formulas, written independently of the model code:
/// h = (wi + wo)/|wi + wo|, D from tan²θh and the azimuth, Smith Λ from
/// tan²θ along each direction's azimuth, G₂ = 1/(1 + Λi + Λo),
/// f = F(i·h) D G₂ / (4 cosθi cosθo). `None` where these naive products
/// underflow or overflow (the comparison would test the reference).
fn reference(m: &MicrofacetConductor, wi: DVec3, wo: DVec3, lambda: f64) -> Option<f64> {
    let d = m.distribution();
    let (ax, ay) = (d.alpha_x(), d.alpha_y());
    let h = (wi + wo).normalize();
    let cos2 = h.z * h.z;
    let tan2_aniso = (h.x * h.x / (ax * ax) + h.y * h.y / (ay * ay)) / cos2;
    let dval = match d.kind() {
        NdfKind::Ggx => 1.0 / (PI * ax * ay * cos2 * cos2 * (1.0 + tan2_aniso).powi(2)),
        NdfKind::Beckmann => libm::exp(-tan2_aniso) / (PI * ax * ay * cos2 * cos2),
    };
    let lambda_smith = |w: DVec3| {
        // α² tan²θ along w's azimuth.
        let t = (ax * ax * w.x * w.x + ay * ay * w.y * w.y) / (w.z * w.z);
        match d.kind() {
            NdfKind::Ggx => (libm::sqrt(1.0 + t) - 1.0) / 2.0,
            NdfKind::Beckmann => {
                let a = 1.0 / libm::sqrt(t);
                (libm::exp(-a * a) / (a * libm::sqrt(PI)) - libm::erfc(a)) / 2.0
            }
        }
    };
    let g2 = 1.0 / (1.0 + lambda_smith(wi) + lambda_smith(wo));
    let fr = m.fresnel().reflectance(wi.dot(h).clamp(0.0, 1.0), lambda);
    let f = fr * dval * g2 / (4.0 * wi.z * wo.z);
    (f.is_finite() && f > 1e-250 && dval > 1e-250 && g2 > 1e-250).then_some(f)
}

fn close(a: f64, b: f64, rel: f64) -> bool {
    (a - b).abs() <= rel * a.abs().max(b.abs()) || (a == 0.0 && b == 0.0)
}

#[test]
fn horizon_is_zero_and_near_horizon_values_are_the_analytic_ones() {
    let lambda = 550.0;
    let mut compared = 0;
    let mut worst = 0.0f64;
    for (name, m) in models() {
        for &ci in &COSINES {
            for &co in &COSINES {
                for phi in [0.0, PI / 2.0, PI, 0.65] {
                    let wi = dir(ci, 0.0);
                    let wo = dir(co, phi);
                    let (f, pdf) = m.eval_pdf(wi, wo, lambda);
                    let ctx = format!("{name} cosθi={ci:e} cosθo={co:e} φ={phi}");
                    assert!(f.is_finite() && f >= 0.0, "{ctx}: f = {f}");
                    assert!(pdf.is_finite() && pdf >= 0.0, "{ctx}: pdf = {pdf}");
                    assert_eq!(f, m.eval(wi, wo, lambda), "{ctx}");
                    assert!(close(pdf, m.pdf(wi, wo, lambda), 1e-12), "{ctx}");
                    let mut many = [(7.0, 7.0); 2];
                    m.eval_pdf_many(wi, wo, &[lambda, lambda], &mut many);
                    assert_eq!(many, [(f, pdf); 2], "{ctx}");
                    if ci < super::COS_HORIZON || co < super::COS_HORIZON {
                        assert_eq!((f, pdf), (0.0, 0.0), "{ctx}: on the horizon");
                        continue;
                    }
                    // Reciprocity holds to round-off everywhere above it.
                    let fr = m.eval(wo, wi, lambda);
                    assert!(close(f, fr, 1e-9), "{ctx}: f(i,o) {f} ≠ f(o,i) {fr}");
                    // f may grow like 1/cosθ, but f cosθi cosθo = F D(h) G2/4 ≤ D(h)/4.
                    let dh = m.distribution().d((wi + wo).normalize());
                    assert!(f * ci * co <= 0.25 * dh * (1.0 + 1e-9), "{ctx}: f = {f}");
                    if ci >= 1e-20
                        && co >= 1e-20
                        && let Some(want) = reference(&m, wi, wo, lambda)
                    {
                        let rel = (f - want).abs() / want;
                        worst = worst.max(rel);
                        // Beckmann's Λ formula cancels for small a = cotθ/α in the reference.
                        assert!(rel < 1e-7, "{ctx}: f = {f}, reference {want}");
                        compared += 1;
                    }
                }
            }
        }
    }
    assert!(compared > 1500, "only {compared} comparisons");
    eprintln!(
        "{compared} near-horizon values vs textbook formulas: worst relative error {worst:.1e}"
    );
}

#[test]
fn sampling_at_the_horizon_is_consistent_with_eval_and_pdf() {
    let lambda = 600.0;
    for (name, m) in models() {
        for &ci in &COSINES {
            let wi = dir(ci, 0.3);
            let n = 256;
            let mut got = 0;
            for k in 0..n {
                let u = [
                    (k as f64 + 0.5) / n as f64,
                    ((k * 37 % n) as f64 + 0.5) / n as f64,
                    ((k * 101 % n) as f64 + 0.5) / n as f64,
                ];
                let Some(s) = m.sample(wi, lambda, u) else {
                    continue;
                };
                let ctx = format!("{name} cosθi={ci:e} u={u:?}");
                assert!(ci >= super::COS_HORIZON, "{ctx}: a sample from the horizon");
                got += 1;
                assert!(
                    s.wo.z >= super::COS_HORIZON && (s.wo.length() - 1.0).abs() < 1e-12,
                    "{ctx}: {s:?}"
                );
                assert!(s.weight.is_finite() && s.weight > 0.0, "{ctx}: {s:?}");
                // Visible-normal sampling: weight = F G2/G1 ≤ 1.
                assert!(s.weight <= 1.0 + 1e-12, "{ctx}: {s:?}");
                let (f, pdf) = m.eval_pdf(wi, s.wo, lambda);
                // `eval` recomputes the half vector from the rounded wo: its
                // tangential part (wi + wo)⊥ carries an absolute error of a
                // few ulps, relative error ~1e−16/|(wi + wo)⊥| (1e−8 for a
                // 1e−4 lobe at grazing incidence), which D amplifies up to 4×.
                let v = wi + s.wo;
                let tol = 1e-9 + 2e-15 / libm::hypot(v.x, v.y).max(1e-300);
                assert!(
                    close(pdf, s.pdf, tol),
                    "{ctx}: pdf {pdf} vs sample {}",
                    s.pdf
                );
                let w = f * s.wo.z / pdf;
                assert!(
                    close(w, s.weight, tol),
                    "{ctx}: f cos/pdf {w} vs weight {}",
                    s.weight
                );
            }
            if ci >= 1e-8 {
                assert!(got > n / 2, "{name} cosθi={ci:e}: {got} of {n} samples");
            }
        }
    }
}

/// Beckmann's `lambda_frac` returns Λ = 0 from a = 1/(α tanθ) ≥ 4.7 on
/// (Λ < 3.3e−13); the sums with 1 the conductor formulas form must then be
/// those of the exact Λ within that, and to the last bit from a = 5.8 on
/// (Λ < 1.8e−18), on both sides of the cut and for anisotropic α.
#[test]
fn beckmann_lambda_cut_moves_g1_and_g2_by_less_than_the_cut() {
    let (mut cut, mut exact_bits) = (0, 0);
    for (ax, ay) in [(0.05, 0.05), (0.2, 0.2), (0.01, 0.3), (1.0, 0.5)] {
        let d = Distribution::beckmann(ax, ay).unwrap();
        for i in 0..600 {
            // a from 4 to 7 along several azimuths.
            let a = 4.0 + 3.0 * (i as f64 + 0.5) / 600.0;
            let phi = 0.37 * i as f64;
            let (c, s) = (libm::cos(phi), libm::sin(phi));
            let alpha = libm::sqrt(ax * ax * c * c + ay * ay * s * s);
            let tan = 1.0 / (a * alpha);
            let w = DVec3::new(tan * c, tan * s, 1.0).normalize();
            let (l_frac, one) = d.lambda_frac(w);
            let exact = d.lambda(w);
            assert_eq!(one, 1.0);
            if a >= 4.7 + 1e-9 {
                assert_eq!(l_frac, 0.0, "a = {a}");
                assert!(exact < 3.26e-13, "Λ({a}) = {exact}");
                cut += 1;
            } else {
                assert!(l_frac > 0.0, "a = {a}");
            }
            for other in [0.0, exact, 1e-3, 0.4, 7.0] {
                let (g1, g1_exact) = (1.0 / (1.0 + l_frac), 1.0 / (1.0 + exact));
                let (g2, g2_exact) = (1.0 / (1.0 + l_frac + other), 1.0 / (1.0 + exact + other));
                assert!((g1 - g1_exact).abs() <= 3.3e-13 * g1_exact, "G1 at a = {a}");
                assert!(
                    (g2 - g2_exact).abs() <= 3.3e-13 * g2_exact,
                    "G2 at a = {a}, other Λ {other}"
                );
                if a >= 5.8 + 1e-9 {
                    assert_eq!((1.0 + l_frac).to_bits(), (1.0 + exact).to_bits());
                    assert_eq!(
                        (1.0 + l_frac + other).to_bits(),
                        (1.0 + exact + other).to_bits(),
                        "G2 at a = {a}, other Λ {other}"
                    );
                    assert_eq!(
                        (1.0 + other + l_frac).to_bits(),
                        (1.0 + other + exact).to_bits()
                    );
                    exact_bits += 1;
                }
            }
        }
    }
    assert!(cut > 1500 && exact_bits > 4000, "{cut} {exact_bits}");
}
