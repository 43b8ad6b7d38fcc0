//! What the tests of the 2-D PSD models share: directions, a grid of a PSD's
//! half-plane nodes, and the crossing-lay PSD they are tested on.

use std::f64::consts::PI;

use brdf::statistics::{AnisotropicKc, EllipticalPsd, TabulatedPsd, TabulatedPsd2d};
use brdf::testing::{Pcg32, albedo_quadrature};
use brdf::{Bxdf, DVec3};

pub fn dir(theta_deg: f64, phi_deg: f64) -> DVec3 {
    let (t, p) = (theta_deg.to_radians(), phi_deg.to_radians());
    DVec3::new(t.sin() * p.cos(), t.sin() * p.sin(), t.cos())
}

/// The half-plane nodes of `f` on a grid of half sizes (mx, my) and steps (dx, dy).
pub fn table(
    mx: usize,
    my: usize,
    dx: f64,
    dy: f64,
    alpha: f64,
    angle_deg: f64,
    f: impl Fn(f64, f64) -> f64,
) -> TabulatedPsd2d {
    let mut v = Vec::with_capacity((2 * mx + 1) * (my + 1));
    for j in 0..=my {
        for i in 0..=2 * mx {
            v.push(f((i as f64 - mx as f64) * dx, j as f64 * dy));
        }
    }
    TabulatedPsd2d::new(mx, my, dx, dy, &v, alpha, angle_deg.to_radians()).unwrap()
}

/// Two stretched K-correlation lays (γ 3, tails ζ^−4) crossing at 0° and 70°.
pub fn crossing_lays(sigma_um: f64) -> impl Fn(f64, f64) -> f64 {
    let a = AnisotropicKc::new(sigma_um * 0.8, 0.3, 3.0, 0.0, 3.0).unwrap();
    let b = AnisotropicKc::new(sigma_um * 0.6, 0.4, 2.5, 70f64.to_radians(), 3.0).unwrap();
    move |x, y| a.psd(x, y) + b.psd(x, y)
}

/// An elliptical PSD (axes 1 and 3 at 40°) whose radial law is a table of
/// `amplitude`·(1 + (ζ/0.5)²)^−1.25 (1 + (ζ/4)²)^−1.25 over 0.05–60 rad/µm.
pub fn elliptical(amplitude: f64) -> EllipticalPsd<TabulatedPsd> {
    let zeta: Vec<f64> = (0..120)
        .map(|i| 0.05 * (1200.0f64).powf(i as f64 / 119.0))
        .collect();
    let p: Vec<f64> = zeta
        .iter()
        .map(|&z| {
            amplitude
                * (1.0 + (z / 0.5f64).powi(2)).powf(-1.25)
                * (1.0 + (z / 4.0f64).powi(2)).powf(-1.25)
        })
        .collect();
    let radial = TabulatedPsd::new(&zeta, &p).unwrap();
    EllipticalPsd::new(radial, 1.0, 3.0, 40f64.to_radians()).unwrap()
}

/// `m` against `reference` at 550 nm from three incidences: the worst relative
/// difference of f over 20 exit directions each where |ζ| ≥ 1.5 rad/µm (near the
/// mirror a grid's bilinear cells differ most), and each incidence's (θi, wi, albedo
/// of `m`, albedo of `reference`) by cubature.
pub fn against(m: &dyn Bxdf, reference: &dyn Bxdf) -> (f64, Vec<(f64, DVec3, f64, f64)>) {
    let mut worst: f64 = 0.0;
    let mut albedos = Vec::new();
    for (ti, pi) in [(0.0, 0.0), (30.0, 20.0), (60.0, 200.0)] {
        let wi = dir(ti, pi);
        for to in [10.0, 25.0, 45.0, 70.0, 85.0] {
            for po in [0.0, 50.0, 130.0, 250.0] {
                let wo = dir(to, po);
                let z = 2.0 * PI / 0.55 * ((wo.x + wi.x).hypot(wo.y + wi.y));
                if z < 1.5 {
                    continue;
                }
                let (a, b) = (m.eval(wi, wo, 550.0), reference.eval(wi, wo, 550.0));
                worst = worst.max((a / b - 1.0).abs());
            }
        }
        let qa = albedo_quadrature(m, wi, 550.0, 1e-6).value;
        let qb = albedo_quadrature(reference, wi, 550.0, 1e-6).value;
        albedos.push((ti, wi, qa, qb));
    }
    (worst, albedos)
}

/// A grid as the property tests draw it: half sizes `half`, steps 10^`log_steps` rad/µm,
/// values 10^`lscale`·u with a fifth of them zero and one at 10^`lscale`.
pub fn random_grid(
    rng: &mut Pcg32,
    (mx, my): (usize, usize),
    (ldx, ldy): (f64, f64),
    alpha: f64,
    angle_deg: f64,
    lscale: f64,
) -> TabulatedPsd2d {
    let n = (2 * mx + 1) * (my + 1);
    let mut v: Vec<f64> = (0..n)
        .map(|_| {
            let u = rng.next_f64();
            if u < 0.2 { 0.0 } else { 10f64.powf(lscale) * u }
        })
        .collect();
    v[rng.next_u32() as usize % n] = 10f64.powf(lscale);
    TabulatedPsd2d::new(
        mx,
        my,
        10f64.powf(ldx),
        10f64.powf(ldy),
        &v,
        alpha,
        angle_deg.to_radians(),
    )
    .unwrap()
}

/// Over `n` random direction pairs (θ to 89.5°) and wavelengths (360–830 nm): f and pdf
/// finite and ≥ 0, pdf > 0 wherever f > 0, f reciprocal to 1e−9, and a glossy sample with
/// a finite weight above the horizon where the pdf is positive; the first failure.
pub fn sound_over_random_directions(m: &dyn Bxdf, rng: &mut Pcg32, n: usize) -> Result<(), String> {
    for _ in 0..n {
        let [a, b, c] = rng.uniform3();
        let [d, e, _] = rng.uniform3();
        let (wi, wo) = (dir(89.5 * a, 360.0 * b), dir(89.5 * d, 360.0 * e));
        let lam = 360.0 + 470.0 * c;
        let (f, pdf) = m.eval_pdf(wi, wo, lam);
        if !(f.is_finite() && f >= 0.0 && pdf.is_finite() && pdf >= 0.0) {
            return Err(format!("f {f} pdf {pdf}"));
        }
        if !(f == 0.0 || pdf > 0.0) {
            return Err(format!("f {f} pdf {pdf}"));
        }
        let back = m.eval(wo, wi, lam);
        let reciprocal = (f - back).abs() <= 1e-9 * f.max(back);
        if !reciprocal {
            return Err(format!("{f} vs {back}"));
        }
        if let Some(s) = m.sample(wi, lam, rng.uniform3())
            && !s.is_delta
        {
            if !(s.weight.is_finite() && s.weight >= 0.0 && s.wo.z > 0.0) {
                return Err(format!("{s:?}"));
            }
            let reached = m.pdf(wi, s.wo, lam) > 0.0;
            if !reached {
                return Err(format!("{s:?}"));
            }
        }
    }
    Ok(())
}
