//! K-correlation (ABC / Matérn) PSD model and its least-squares fit in log space.
//!
//! Two forms share the parameters `σ` (rms height), `Lc` (Matérn range, physics.md §2) and
//! `γ` (> 1):
//! * 2D isotropic, rad convention (physics.md §2.1):
//!   `P(ζ) = Lc²(γ−1)σ² / (2π (1 + Lc²ζ²)^{(γ+1)/2})`, `∫ P d²ζ = σ²`.
//! * 1D one-sided profile form in cycles (data README), the exact line integral of the 2D
//!   form: `P1(f) = 2σ²L Γ(γ/2)/(√π Γ((γ−1)/2)) (1 + L²f²)^{−γ/2}` with `L = 2π Lc`.
//!
//! The fit minimises `Σ (ln P_model − ln P_data)²` with Levenberg–Marquardt over
//! `(ln σ, ln ℓ, ln(γ−1))` after a profiled grid search for the start point.

use crate::FitError;
use levenberg_marquardt::{LeastSquaresProblem, LevenbergMarquardt};
use nalgebra::storage::Owned;
use nalgebra::{DVector, Dyn, OMatrix, U3, Vector3};
use std::f64::consts::PI;

/// K-correlation parameters in SI units.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct KcParams {
    /// Rms height σ [m].
    pub sigma: f64,
    /// Matérn range length Lc [m] (rad convention).
    pub lc: f64,
    /// Exponent γ (> 1).
    pub gamma: f64,
}

impl KcParams {
    /// The length of the README's 1D form, `L = 2π·Lc` [m].
    pub fn l_cycles(&self) -> f64 {
        2.0 * PI * self.lc
    }

    /// 2D isotropic PSD [m⁴] at `zeta` [rad/m] (physics.md convention).
    pub fn psd_2d(&self, zeta: f64) -> f64 {
        let u2 = (self.lc * zeta).powi(2);
        self.lc * self.lc * (self.gamma - 1.0) * self.sigma * self.sigma
            / (2.0 * PI * (1.0 + u2).powf((self.gamma + 1.0) / 2.0))
    }

    /// One-sided 1D profile PSD [m³] at `f` [cycles/m].
    pub fn psd_1d(&self, f: f64) -> f64 {
        let l = self.l_cycles();
        (ln_norm_1d(self.gamma) + 2.0 * self.sigma.ln() + l.ln()).exp()
            * (1.0 + (l * f).powi(2)).powf(-self.gamma / 2.0)
    }

    /// Total slope variance `⟨|∇h|²⟩ = 2σ²/(Lc²(γ−3))`; infinite for γ ≤ 3.
    pub fn slope_variance(&self) -> f64 {
        if self.gamma <= 3.0 {
            f64::INFINITY
        } else {
            2.0 * self.sigma * self.sigma / (self.lc * self.lc * (self.gamma - 3.0))
        }
    }
}

/// Which form of the model a fit uses.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Form {
    /// One-sided 1D PSD of profiles or x-lines, x = f [cycles/m], P [m³].
    Profile1d,
    /// Radially averaged 2D PSD, x = ζ [rad/m], P [m⁴].
    Radial2d,
}

/// Result of a K-correlation fit.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct KcFit {
    /// Best-fit parameters.
    pub params: KcParams,
    /// One-standard-error uncertainties (delta method on `s²(JᵀJ)⁻¹`).
    pub stderr: KcParams,
    /// Rms of the natural-log residuals (weighted when weights are given).
    pub rms_log_residual: f64,
    /// Number of PSD points fitted.
    pub points: usize,
    /// Abscissa range fitted (f in cycles/m or ζ in rad/m).
    pub range: (f64, f64),
    /// True when the optimum is not a meaningful K-correlation fit (γ > 12, a length
    /// outside the fitted band by 10³, or a failed minimisation).
    pub degenerate: bool,
    /// Form fitted.
    pub form: Form,
}

fn ln_norm_1d(gamma: f64) -> f64 {
    2f64.ln() + libm::lgamma(gamma / 2.0) - 0.5 * PI.ln() - libm::lgamma((gamma - 1.0) / 2.0)
}

/// `ln P_model − 2 ln σ` for given ℓ (B or Lc) and γ, split as `c(γ) + a·ln ℓ − e(γ)·ln(1+u²)`.
fn shape_consts(form: Form, gamma: f64) -> (f64, f64, f64) {
    match form {
        Form::Profile1d => (ln_norm_1d(gamma), 1.0, gamma / 2.0),
        Form::Radial2d => (
            (gamma - 1.0).ln() - (2.0 * PI).ln(),
            2.0,
            (gamma + 1.0) / 2.0,
        ),
    }
}

fn dshape_dgamma(form: Form, gamma: f64) -> (f64, f64) {
    // (d c/dγ, d e/dγ)
    match form {
        Form::Profile1d => {
            let h = 1e-5;
            (
                (ln_norm_1d(gamma + h) - ln_norm_1d(gamma - h)) / (2.0 * h),
                0.5,
            )
        }
        Form::Radial2d => (1.0 / (gamma - 1.0), 0.5),
    }
}

struct Problem<'a> {
    form: Form,
    lx: &'a [f64],
    ly: &'a [f64],
    sw: &'a [f64],
    q: Vector3<f64>,
}

impl Problem<'_> {
    fn unpack(&self) -> (f64, f64, f64) {
        (self.q[0], self.q[1].exp(), 1.0 + self.q[2].exp())
    }
}

impl LeastSquaresProblem<f64, Dyn, U3> for Problem<'_> {
    type ResidualStorage = Owned<f64, Dyn>;
    type JacobianStorage = Owned<f64, Dyn, U3>;
    type ParameterStorage = Owned<f64, U3>;

    fn set_params(&mut self, q: &Vector3<f64>) {
        self.q = *q;
    }

    fn params(&self) -> Vector3<f64> {
        self.q
    }

    fn residuals(&self) -> Option<DVector<f64>> {
        let (lns, l, g) = self.unpack();
        let (c, a, e) = shape_consts(self.form, g);
        let r = DVector::from_iterator(
            self.lx.len(),
            self.lx
                .iter()
                .zip(self.ly)
                .zip(self.sw)
                .map(|((&lx, &ly), &sw)| {
                    let u2 = (l * lx.exp()).powi(2);
                    sw * (c + 2.0 * lns + a * l.ln() - e * u2.ln_1p() - ly)
                }),
        );
        r.iter().all(|v| v.is_finite()).then_some(r)
    }

    fn jacobian(&self) -> Option<OMatrix<f64, Dyn, U3>> {
        let (_, l, g) = self.unpack();
        let (_, a, e) = shape_consts(self.form, g);
        let (dc, de) = dshape_dgamma(self.form, g);
        let mut j = OMatrix::<f64, Dyn, U3>::zeros(self.lx.len());
        for (i, (&lx, &sw)) in self.lx.iter().zip(self.sw).enumerate() {
            let u2 = (l * lx.exp()).powi(2);
            j[(i, 0)] = sw * 2.0;
            j[(i, 1)] = sw * (a - 2.0 * e * u2 / (1.0 + u2));
            j[(i, 2)] = sw * (g - 1.0) * (dc - de * u2.ln_1p());
        }
        j.iter().all(|v| v.is_finite()).then_some(j)
    }
}

/// Fit the K-correlation `form` to `(x, p)` restricted to `x_min ≤ x ≤ x_max`.
/// Non-positive or non-finite points are ignored.
pub fn fit(form: Form, x: &[f64], p: &[f64], x_min: f64, x_max: f64) -> Result<KcFit, FitError> {
    fit_weighted(form, x, p, None, x_min, x_max)
}

/// As [`fit`], with per-point weights (e.g. the number of periodogram samples averaged in
/// a radial bin: the variance of a log-averaged periodogram is ≈ 1/count).
pub fn fit_weighted(
    form: Form,
    x: &[f64],
    p: &[f64],
    weights: Option<&[f64]>,
    x_min: f64,
    x_max: f64,
) -> Result<KcFit, FitError> {
    let mut lx = Vec::new();
    let mut ly = Vec::new();
    let mut lw = Vec::new();
    for (i, (&x, &p)) in x.iter().zip(p).enumerate() {
        let w = weights.map_or(1.0, |w| w.get(i).copied().unwrap_or(0.0));
        if x.is_finite()
            && p.is_finite()
            && x > 0.0
            && p > 0.0
            && x >= x_min
            && x <= x_max
            && w > 0.0
            && w.is_finite()
        {
            lx.push(x.ln());
            ly.push(p.ln());
            lw.push(w);
        }
    }
    let n = lx.len();
    if n < 6 {
        return Err(FitError::data(
            "K-correlation fit",
            format!("only {n} usable PSD points in the fit range; need ≥ 6"),
        ));
    }
    // Normalise weights to mean 1 so residual scales stay comparable.
    let wmean = lw.iter().sum::<f64>() / n as f64;
    let sw: Vec<f64> = lw.iter().map(|w| (w / wmean).sqrt()).collect();
    let lw: Vec<f64> = lw.iter().map(|w| w / wmean).collect();
    let (xlo, xhi) = (lx[0].min(lx[n - 1]).exp(), lx[0].max(lx[n - 1]).exp());

    // Profiled grid search: σ enters additively in log space.
    let mut best = (f64::INFINITY, 0.0, 0.0, 0.0);
    let nl = 60;
    let ng = 48;
    for il in 0..nl {
        let l = (0.1 / xhi) * (1000.0 * xhi / xlo).powf(il as f64 / (nl - 1) as f64);
        let lg: Vec<f64> = lx.iter().map(|&v| (l * v.exp()).powi(2).ln_1p()).collect();
        for ig in 0..ng {
            let g = 1.0 + 0.03 * (14.0f64 / 0.03).powf(ig as f64 / (ng - 1) as f64);
            let (c, a, e) = shape_consts(form, g);
            let base = c + a * l.ln();
            let mean = ly
                .iter()
                .zip(&lg)
                .zip(&lw)
                .map(|((y, t), w)| w * (y - (base - e * t)))
                .sum::<f64>()
                / n as f64;
            let ssr: f64 = ly
                .iter()
                .zip(&lg)
                .zip(&lw)
                .map(|((y, t), w)| w * (y - (base - e * t) - mean).powi(2))
                .sum();
            if ssr < best.0 {
                best = (ssr, mean / 2.0, l, g);
            }
        }
    }
    let start = Vector3::new(best.1, best.2.ln(), (best.3 - 1.0).ln());
    let problem = Problem {
        form,
        lx: &lx,
        ly: &ly,
        sw: &sw,
        q: start,
    };
    let (problem, report) = LevenbergMarquardt::new()
        .with_patience(400)
        .minimize(problem);
    let (lns, l, g) = problem.unpack();
    let res = problem.residuals().ok_or_else(|| {
        FitError::data(
            "K-correlation fit",
            "the minimiser left the valid parameter region",
        )
    })?;
    let ssr = res.norm_squared();
    let sigma = lns.exp();
    let lc = match form {
        Form::Profile1d => l / (2.0 * PI),
        Form::Radial2d => l,
    };
    let mut stderr = KcParams {
        sigma: f64::NAN,
        lc: f64::NAN,
        gamma: f64::NAN,
    };
    if let Some(j) = problem.jacobian()
        && n > 3
        && let Some(inv) = (j.transpose() * &j).try_inverse()
    {
        let s2 = ssr / (n - 3) as f64;
        let var = |i: usize| (s2 * inv[(i, i)]).max(0.0).sqrt();
        stderr = KcParams {
            sigma: sigma * var(0),
            lc: lc * var(1),
            gamma: (g - 1.0) * var(2),
        };
    }
    let degenerate =
        !report.termination.was_successful() || g > 12.0 || l * xhi < 1e-3 || l * xlo > 1e3;
    Ok(KcFit {
        params: KcParams {
            sigma,
            lc,
            gamma: g,
        },
        stderr,
        rms_log_residual: (ssr / n as f64).sqrt(),
        points: n,
        range: (xlo, xhi),
        degenerate,
        form,
    })
}

/// Fit the 1D form to a line PSD on the raw bins `k_lo ..= k_hi` (README: 3 ..= nx/4).
pub fn fit_bins(psd: &crate::psd::Psd1d, k_lo: usize, k_hi: usize) -> Result<KcFit, FitError> {
    let hi = k_hi.min(psd.f.len().saturating_sub(1));
    if k_lo >= hi {
        return Err(FitError::data("K-correlation fit", "empty bin range"));
    }
    fit(
        Form::Profile1d,
        &psd.f,
        &psd.p,
        psd.f[k_lo] * (1.0 - 1e-9),
        psd.f[hi] * (1.0 + 1e-9),
    )
}
