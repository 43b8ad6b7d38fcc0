//! Normal distribution functions from measured slopes.
//!
//! A pixel of a height map covers the same projected area `dx·dy`, so each forward-difference
//! slope sample has equal weight. The projected-area fraction with normal polar angle in a
//! bin `[θ₀, θ₁)` equals `∫ D cosθ dω = D·π(sin²θ₁ − sin²θ₀)` for an isotropic NDF with
//! `∫ D (m·n) dω = 1`, which gives the histogram estimate (the angular Jacobian).
//! The binned mass is smoothed with a Gaussian kernel in θ (Dong et al. 2016 smooth
//! measured NDFs the same way to remove sampling noise); reflection at θ = 0 keeps mass.

use crate::Topography;
use std::f64::consts::PI;

/// Forward-difference slopes `(sx, sy)` on the common `(nx−1)×(ny−1)` region (as for Sdq).
/// For a profile, `sy` is empty.
pub fn slopes(t: &Topography) -> (Vec<f64>, Vec<f64>) {
    let (nx, ny, h) = (t.nx, t.ny, &t.heights);
    if ny == 1 {
        let sx = h
            .windows(2)
            .map(|w| (w[1] - w[0]) / t.dx)
            .filter(|v| v.is_finite())
            .collect();
        return (sx, Vec::new());
    }
    let mut sx = Vec::with_capacity((nx - 1) * (ny - 1));
    let mut sy = Vec::with_capacity((nx - 1) * (ny - 1));
    for y in 0..ny - 1 {
        for x in 0..nx - 1 {
            let i = y * nx + x;
            let (a, b) = ((h[i + 1] - h[i]) / t.dx, (h[i + nx] - h[i]) / t.dy);
            if a.is_finite() && b.is_finite() {
                sx.push(a);
                sy.push(b);
            }
        }
    }
    (sx, sy)
}

/// A tabulated isotropic NDF.
#[derive(Debug, Clone, PartialEq)]
pub struct Ndf {
    /// Bin centres θ [rad].
    pub theta: Vec<f64>,
    /// NDF value [sr⁻¹], normalised so that `∫ D cosθ dω = 1`.
    pub d: Vec<f64>,
    /// Projected-area fraction in each bin (after smoothing).
    pub mass: Vec<f64>,
    /// Bin width [rad].
    pub bin: f64,
}

/// NDF histogram of 2D slope samples with `nbins` bins up to `theta_max` [rad] and a
/// Gaussian smoothing of standard deviation `smooth` [rad] (0 = none).
pub fn histogram(sx: &[f64], sy: &[f64], nbins: usize, theta_max: f64, smooth: f64) -> Ndf {
    let bin = theta_max / nbins as f64;
    let mut mass = vec![0.0; nbins];
    let n = sx.len().max(1) as f64;
    for (a, b) in sx.iter().zip(sy) {
        let th = (a * a + b * b).sqrt().atan();
        let i = (th / bin) as usize;
        if i < nbins {
            mass[i] += 1.0 / n;
        }
    }
    if smooth > 0.0 {
        let s = smooth / bin;
        let reach = (4.0 * s).ceil() as isize;
        let mut out = vec![0.0; nbins];
        for (i, &m) in mass.iter().enumerate() {
            if m == 0.0 {
                continue;
            }
            let mut weights = Vec::new();
            let mut total = 0.0;
            for k in -reach..=reach {
                let mut j = i as isize + k;
                if j < 0 {
                    j = -j - 1; // reflect at θ = 0
                }
                if j as usize >= nbins {
                    continue;
                }
                let w = (-0.5 * (k as f64 / s).powi(2)).exp();
                weights.push((j as usize, w));
                total += w;
            }
            for (j, w) in weights {
                out[j] += m * w / total;
            }
        }
        mass = out;
    }
    let theta: Vec<f64> = (0..nbins).map(|i| (i as f64 + 0.5) * bin).collect();
    let d = (0..nbins)
        .map(|i| {
            let (t0, t1) = (i as f64 * bin, (i + 1) as f64 * bin);
            mass[i] / (PI * (t1.sin().powi(2) - t0.sin().powi(2)))
        })
        .collect();
    Ndf {
        theta,
        d,
        mass,
        bin,
    }
}

/// GGX (Trowbridge–Reitz) NDF.
pub fn ggx(alpha: f64, theta: f64) -> f64 {
    let (c, t2) = (theta.cos(), theta.tan().powi(2));
    let a2 = alpha * alpha;
    a2 / (PI * c.powi(4) * (a2 + t2).powi(2))
}

/// Beckmann NDF.
pub fn beckmann(alpha: f64, theta: f64) -> f64 {
    let (c, t2) = (theta.cos(), theta.tan().powi(2));
    let a2 = alpha * alpha;
    (-t2 / a2).exp() / (PI * a2 * c.powi(4))
}

/// Fit `alpha` of `model` to the NDF: minimises `Σ mass·(ln D − ln D_model)²` over bins
/// holding mass, by a log-spaced scan then golden-section refinement on ln α ∈ [1e-4, 4].
/// Returns `(alpha, weighted rms log residual)`.
pub fn fit_alpha(ndf: &Ndf, model: fn(f64, f64) -> f64) -> (f64, f64) {
    let cost = |la: f64| -> f64 {
        let a = la.exp();
        let (mut s, mut w) = (0.0, 0.0);
        for ((&th, &d), &m) in ndf.theta.iter().zip(&ndf.d).zip(&ndf.mass) {
            if m > 0.0 && d > 0.0 {
                let r = d.ln() - model(a, th).ln();
                let r = if r.is_finite() { r } else { 50.0 };
                s += m * r * r;
                w += m;
            }
        }
        if w > 0.0 { s / w } else { f64::INFINITY }
    };
    let (lo, hi) = (1e-4f64.ln(), 4f64.ln());
    let steps = 200;
    let mut best = (f64::INFINITY, lo);
    for i in 0..=steps {
        let la = lo + (hi - lo) * i as f64 / steps as f64;
        let c = cost(la);
        if c < best.0 {
            best = (c, la);
        }
    }
    let h = (hi - lo) / steps as f64;
    let (mut a, mut b) = (best.1 - h, best.1 + h);
    let g = (5f64.sqrt() - 1.0) / 2.0;
    for _ in 0..60 {
        let (c, d) = (b - g * (b - a), a + g * (b - a));
        if cost(c) < cost(d) {
            b = d;
        } else {
            a = c;
        }
    }
    let la = 0.5 * (a + b);
    (la.exp(), cost(la).sqrt())
}

/// Maximum-likelihood β of the exponential slope distribution `p(s) = e^{−|s|/β}/(2πβ²)`:
/// `|s|` is Gamma(2, β) distributed, so `β = mean|s| / 2`.
pub fn exponential_beta(sx: &[f64], sy: &[f64]) -> f64 {
    let n = sx.len().max(1) as f64;
    sx.iter()
        .zip(sy)
        .map(|(a, b)| (a * a + b * b).sqrt())
        .sum::<f64>()
        / n
        / 2.0
}

/// Bin range for a slope set: up to 1.5× the 99.9 % quantile of the polar angle, ≤ 89°.
pub fn theta_max_for(sx: &[f64], sy: &[f64]) -> f64 {
    let mut th: Vec<f64> = sx
        .iter()
        .zip(sy)
        .map(|(a, b)| (a * a + b * b).sqrt().atan())
        .collect();
    if th.is_empty() {
        return 89f64.to_radians();
    }
    let k = ((th.len() as f64 * 0.999) as usize).min(th.len() - 1);
    let (_, q, _) = th.select_nth_unstable_by(k, f64::total_cmp);
    (1.5 * *q).clamp(0.5f64.to_radians(), 89f64.to_radians())
}

/// Slope marginal of GGX along one axis: `α² / (2(α² + s²)^{3/2})`.
pub fn ggx_marginal(alpha: f64, s: f64) -> f64 {
    let a2 = alpha * alpha;
    a2 / (2.0 * (a2 + s * s).powf(1.5))
}

/// Slope marginal of Beckmann along one axis: normal with variance `α²/2`.
pub fn beckmann_marginal(alpha: f64, s: f64) -> f64 {
    (-(s * s) / (alpha * alpha)).exp() / (alpha * PI.sqrt())
}

/// Fit α of a 1D slope marginal (profiles): histogram of `s` over ±`s_max` in `nbins`
/// bins, mass-weighted least squares in log space as in [`fit_alpha`].
pub fn fit_alpha_marginal(
    s: &[f64],
    nbins: usize,
    s_max: f64,
    model: fn(f64, f64) -> f64,
) -> (f64, f64) {
    let bin = 2.0 * s_max / nbins as f64;
    let mut mass = vec![0.0; nbins];
    for &v in s {
        let i = ((v + s_max) / bin).floor();
        if i >= 0.0 && (i as usize) < nbins {
            mass[i as usize] += 1.0 / s.len() as f64;
        }
    }
    let ndf = Ndf {
        theta: (0..nbins)
            .map(|i| -s_max + (i as f64 + 0.5) * bin)
            .collect(),
        d: mass.iter().map(|m| m / bin).collect(),
        mass,
        bin,
    };
    fit_alpha(&ndf, model)
}
