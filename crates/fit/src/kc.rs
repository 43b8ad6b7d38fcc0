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
//! `ln σ` and logistic transforms of `ln ℓ` and `γ`, after a profiled grid search for the
//! start point, so the result always lies in the bounds the renderer accepts
//! ([`GAMMA_BOUNDS`], lengths within 10³ of the fitted band and within [`LC_BOUNDS_M`]).
//! A fit that does not converge, ends on a bound or is steeper than γ = 12 is kept as the
//! bounded best estimate and marked degenerate with its [`Degeneracy`]; the power law
//! through the top of the band ([`PowerLaw`]) is reported with every fit.

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

/// Which form of the model a fit uses: the 1D profile PSD or the radially averaged 2D
/// PSD.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PsdForm {
    /// One-sided 1D PSD of profiles or x-lines, x = f [cycles/m], P [m³].
    Profile1d,
    /// Radially averaged 2D PSD, x = ζ [rad/m], P [m⁴].
    Radial2d,
}

/// γ range of the fit: the range the renderer's K-correlation PSD accepts.
pub const GAMMA_BOUNDS: (f64, f64) = (1.001, 100.0);
/// Lc range of the fit [m]: the renderer's 1e-9 … 1e6 µm.
pub const LC_BOUNDS_M: (f64, f64) = (1e-15, 1.0);
/// Beyond this γ the band shows no power-law tail: the fit is called degenerate.
pub const GAMMA_STEEP: f64 = 12.0;

/// Why a K-correlation fit is not a meaningful description of the PSD.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Degeneracy {
    /// The minimiser did not converge.
    NotConverged,
    /// γ ended on a bound of [`GAMMA_BOUNDS`].
    GammaAtBound,
    /// The correlation length ended on a bound: the roll-off lies 10³ beyond the band.
    LengthAtBound,
    /// γ > 12: the band shows no power-law tail (a flat spectrum with peaks, noise).
    Steep,
    /// Too few PSD points to fit; the parameters are estimated from Sq and Sdq with
    /// γ = 4 assumed.
    TooFewPoints,
}

impl Degeneracy {
    /// One-line explanation.
    pub fn describe(self) -> &'static str {
        match self {
            Degeneracy::NotConverged => "the minimiser did not converge",
            Degeneracy::GammaAtBound => "γ ended on a bound of 1.001…100",
            Degeneracy::LengthAtBound => {
                "the correlation length ended on a bound: the roll-off lies far outside the \
                 measured band"
            }
            Degeneracy::Steep => {
                "γ > 12: the band shows no power-law tail (flat spectrum, peaks or noise)"
            }
            Degeneracy::TooFewPoints => {
                "too few PSD points to fit; σ = Sq, γ = 4 assumed, Lc from the rms slope"
            }
        }
    }
}

/// A power law `P = A·x^(−exponent)` fitted to the top of a band.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PowerLaw {
    /// Exponent (γ of the 1D form's high-frequency tail).
    pub exponent: f64,
    /// Prefactor A in SI units (P in m³ or m⁴, x in cycles/m or rad/m).
    pub prefactor: f64,
    /// Abscissa range used.
    pub range: (f64, f64),
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
    /// True when the optimum is not a meaningful K-correlation fit (see `reason`).
    pub degenerate: bool,
    /// Why, when degenerate.
    pub reason: Option<Degeneracy>,
    /// Power law through the top half (in log abscissa) of the fitted band.
    pub asymptote: Option<PowerLaw>,
    /// Form fitted.
    pub form: PsdForm,
}

fn ln_norm_1d(gamma: f64) -> f64 {
    2f64.ln() + libm::lgamma(gamma / 2.0) - 0.5 * PI.ln() - libm::lgamma((gamma - 1.0) / 2.0)
}

/// `ln P_model − 2 ln σ` for given ℓ (B or Lc) and γ, split as `c(γ) + a·ln ℓ − e(γ)·ln(1+u²)`.
fn shape_consts(form: PsdForm, gamma: f64) -> (f64, f64, f64) {
    match form {
        PsdForm::Profile1d => (ln_norm_1d(gamma), 1.0, gamma / 2.0),
        PsdForm::Radial2d => (
            (gamma - 1.0).ln() - (2.0 * PI).ln(),
            2.0,
            (gamma + 1.0) / 2.0,
        ),
    }
}

fn dshape_dgamma(form: PsdForm, gamma: f64) -> (f64, f64) {
    // (d c/dγ, d e/dγ)
    match form {
        PsdForm::Profile1d => {
            let h = 1e-5;
            (
                (ln_norm_1d(gamma + h) - ln_norm_1d(gamma - h)) / (2.0 * h),
                0.5,
            )
        }
        PsdForm::Radial2d => (1.0 / (gamma - 1.0), 0.5),
    }
}

struct Problem<'a> {
    form: PsdForm,
    lx: &'a [f64],
    ly: &'a [f64],
    sw: &'a [f64],
    q: Vector3<f64>,
    /// ln ℓ bounds.
    ll: (f64, f64),
    /// γ bounds.
    gb: (f64, f64),
}

fn sigmoid(u: f64) -> f64 {
    if u >= 0.0 {
        1.0 / (1.0 + (-u).exp())
    } else {
        let e = u.exp();
        e / (1.0 + e)
    }
}

fn logit(s: f64) -> f64 {
    let s = s.clamp(1e-12, 1.0 - 1e-12);
    (s / (1.0 - s)).ln()
}

impl Problem<'_> {
    /// (ln σ, ℓ, γ) and the derivatives d lnℓ/du, dγ/dv.
    fn unpack_full(&self) -> (f64, f64, f64, f64, f64) {
        let (su, sv) = (sigmoid(self.q[1]), sigmoid(self.q[2]));
        let ln_l = self.ll.0 + (self.ll.1 - self.ll.0) * su;
        let g = self.gb.0 + (self.gb.1 - self.gb.0) * sv;
        (
            self.q[0],
            ln_l.exp(),
            g,
            (self.ll.1 - self.ll.0) * su * (1.0 - su),
            (self.gb.1 - self.gb.0) * sv * (1.0 - sv),
        )
    }

    fn unpack(&self) -> (f64, f64, f64) {
        let (a, b, c, _, _) = self.unpack_full();
        (a, b, c)
    }

    fn pack(&self, ln_sigma: f64, l: f64, g: f64) -> Vector3<f64> {
        Vector3::new(
            ln_sigma,
            logit((l.ln() - self.ll.0) / (self.ll.1 - self.ll.0)),
            logit((g - self.gb.0) / (self.gb.1 - self.gb.0)),
        )
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
        let (_, l, g, dl, dg) = self.unpack_full();
        let (_, a, e) = shape_consts(self.form, g);
        let (dc, de) = dshape_dgamma(self.form, g);
        let mut j = OMatrix::<f64, Dyn, U3>::zeros(self.lx.len());
        for (i, (&lx, &sw)) in self.lx.iter().zip(self.sw).enumerate() {
            let u2 = (l * lx.exp()).powi(2);
            j[(i, 0)] = sw * 2.0;
            j[(i, 1)] = sw * (a - 2.0 * e * u2 / (1.0 + u2)) * dl;
            j[(i, 2)] = sw * (dc - de * u2.ln_1p()) * dg;
        }
        j.iter().all(|v| v.is_finite()).then_some(j)
    }
}

/// Fit the K-correlation `form` to `(x, p)` restricted to `x_min ≤ x ≤ x_max`.
/// Non-positive or non-finite points are ignored.
pub fn fit(form: PsdForm, x: &[f64], p: &[f64], x_min: f64, x_max: f64) -> Result<KcFit, FitError> {
    fit_weighted(form, x, p, None, x_min, x_max)
}

/// As [`fit`], with per-point weights (e.g. the number of periodogram samples averaged in
/// a radial bin: the variance of a log-averaged periodogram is ≈ 1/count).
pub fn fit_weighted(
    form: PsdForm,
    x: &[f64],
    p: &[f64],
    weights: Option<&[f64]>,
    x_min: f64,
    x_max: f64,
) -> Result<KcFit, FitError> {
    let (lx, ly, lw) = log_points(x, p, weights, x_min, x_max);
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
    let ll = ln_length_bounds(form, xlo, xhi)?;
    let gb = GAMMA_BOUNDS;
    let mut problem = Problem {
        form,
        lx: &lx,
        ly: &ly,
        sw: &sw,
        q: Vector3::zeros(),
        ll,
        gb,
    };
    let (ln_sigma, l, g) = grid_start(form, &lx, &ly, &lw, ll, gb);
    problem.q = problem.pack(ln_sigma, l, g);
    let (problem, res, converged) = refine(problem)?;
    let (lns, l, g) = problem.unpack();
    let ssr = res.norm_squared();
    let sigma = lns.exp();
    let lc = match form {
        PsdForm::Profile1d => l / (2.0 * PI),
        PsdForm::Radial2d => l,
    };
    // On a bound: within 0.1 % of the transformed range.
    let at = |v: f64, (a, b): (f64, f64)| (v - a) <= 1e-3 * (b - a) || (b - v) <= 1e-3 * (b - a);
    let reason = if !converged {
        Some(Degeneracy::NotConverged)
    } else if at(g, gb) {
        Some(Degeneracy::GammaAtBound)
    } else if at(l.ln(), ll) {
        Some(Degeneracy::LengthAtBound)
    } else if g > GAMMA_STEEP {
        Some(Degeneracy::Steep)
    } else {
        None
    };
    let stderr = match reason {
        None => standard_errors(&problem, ssr, sigma, lc),
        Some(_) => KcParams {
            sigma: f64::NAN,
            lc: f64::NAN,
            gamma: f64::NAN,
        },
    };
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
        degenerate: reason.is_some(),
        reason,
        asymptote: power_law(&lx, &ly),
        form,
    })
}

/// `(ln x, ln p, weight)` of the points in `[x_min, x_max]` with positive finite x, p and
/// weight (a missing weight is 0).
fn log_points(
    x: &[f64],
    p: &[f64],
    weights: Option<&[f64]>,
    x_min: f64,
    x_max: f64,
) -> (Vec<f64>, Vec<f64>, Vec<f64>) {
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
    (lx, ly, lw)
}

/// Bounds of ln ℓ for the band `xlo … xhi`: lengths within 10³ of the band and in the
/// renderer's Lc range.
fn ln_length_bounds(form: PsdForm, xlo: f64, xhi: f64) -> Result<(f64, f64), FitError> {
    let to_l = |lc: f64| match form {
        PsdForm::Profile1d => 2.0 * PI * lc,
        PsdForm::Radial2d => lc,
    };
    let l_lo = (1e-3 / xhi).max(to_l(LC_BOUNDS_M.0));
    let l_hi = (1e3 / xlo).min(to_l(LC_BOUNDS_M.1));
    if l_lo.partial_cmp(&l_hi) != Some(std::cmp::Ordering::Less) {
        return Err(FitError::data(
            "K-correlation fit",
            format!("the band {xlo:e}…{xhi:e} lies outside the lengths the renderer accepts"),
        ));
    }
    Ok((l_lo.ln(), l_hi.ln()))
}

/// The starting point `(ln σ, ℓ, γ)` of the least-squares fit: a grid search over ℓ and γ
/// inside the bounds, with σ profiled out (it enters additively in log space).
fn grid_start(
    form: PsdForm,
    lx: &[f64],
    ly: &[f64],
    lw: &[f64],
    ll: (f64, f64),
    gb: (f64, f64),
) -> (f64, f64, f64) {
    let n = lx.len();
    let mut best = (f64::INFINITY, 0.0, 0.0, 0.0);
    let nl = 60;
    let ng = 48;
    let (gl, gh) = (gb.0 + 0.02, 15.0f64.min(gb.1));
    for il in 0..nl {
        let l = (ll.0 + (ll.1 - ll.0) * (0.02 + 0.96 * il as f64 / (nl - 1) as f64)).exp();
        let lg: Vec<f64> = lx.iter().map(|&v| (l * v.exp()).powi(2).ln_1p()).collect();
        for ig in 0..ng {
            let g = gl * (gh / gl).powf(ig as f64 / (ng - 1) as f64);
            let (c, a, e) = shape_consts(form, g);
            let base = c + a * l.ln();
            let mean = ly
                .iter()
                .zip(&lg)
                .zip(lw)
                .map(|((y, t), w)| w * (y - (base - e * t)))
                .sum::<f64>()
                / n as f64;
            let ssr: f64 = ly
                .iter()
                .zip(&lg)
                .zip(lw)
                .map(|((y, t), w)| w * (y - (base - e * t) - mean).powi(2))
                .sum();
            if ssr < best.0 {
                best = (ssr, mean / 2.0, l, g);
            }
        }
    }
    (best.1, best.2, best.3)
}

/// Levenberg–Marquardt from the problem's start; the fitted problem, its residuals and
/// whether it converged. A fit that leaves the region where the model is finite keeps the
/// start (not converged).
fn refine(problem: Problem<'_>) -> Result<(Problem<'_>, DVector<f64>, bool), FitError> {
    let start = problem.q;
    let (mut problem, report) = LevenbergMarquardt::new()
        .with_patience(400)
        .minimize(problem);
    let mut converged = report.termination.was_successful();
    let res = match problem.residuals() {
        Some(r) => r,
        None => {
            converged = false;
            problem.q = start;
            problem.residuals().ok_or_else(|| {
                FitError::data(
                    "K-correlation fit",
                    "the model is not finite anywhere near the data",
                )
            })?
        }
    };
    Ok((problem, res, converged))
}

/// Standard errors of σ, Lc and γ from the Jacobian at the optimum (NaN where it is
/// singular or there are no more points than parameters).
fn standard_errors(problem: &Problem<'_>, ssr: f64, sigma: f64, lc: f64) -> KcParams {
    let n = problem.lx.len();
    if let Some(j) = problem.jacobian()
        && n > 3
        && let Some(inv) = (j.transpose() * &j).try_inverse()
    {
        let (_, _, _, dl, dg) = problem.unpack_full();
        let s2 = ssr / (n - 3) as f64;
        let var = |i: usize| (s2 * inv[(i, i)]).max(0.0).sqrt();
        return KcParams {
            sigma: sigma * var(0),
            lc: lc * dl * var(1),
            gamma: dg * var(2),
        };
    }
    KcParams {
        sigma: f64::NAN,
        lc: f64::NAN,
        gamma: f64::NAN,
    }
}

/// Power law through the points in the upper half of the log-abscissa range (at least
/// the last three).
fn power_law(lx: &[f64], ly: &[f64]) -> Option<PowerLaw> {
    let n = lx.len();
    if n < 3 {
        return None;
    }
    let (lo, hi) = (lx[0].min(lx[n - 1]), lx[0].max(lx[n - 1]));
    let mid = 0.5 * (lo + hi);
    let mut idx: Vec<usize> = (0..n).filter(|&i| lx[i] >= mid).collect();
    if idx.len() < 3 {
        let mut all: Vec<usize> = (0..n).collect();
        all.sort_by(|&a, &b| lx[b].total_cmp(&lx[a]));
        idx = all[..3].to_vec();
    }
    let m = idx.len() as f64;
    let mx = idx.iter().map(|&i| lx[i]).sum::<f64>() / m;
    let my = idx.iter().map(|&i| ly[i]).sum::<f64>() / m;
    let sxx: f64 = idx.iter().map(|&i| (lx[i] - mx).powi(2)).sum();
    let sxy: f64 = idx.iter().map(|&i| (lx[i] - mx) * (ly[i] - my)).sum();
    if sxx <= 0.0 {
        return None;
    }
    let slope = sxy / sxx;
    let (a, b) = idx
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &i| {
            (a.min(lx[i]), b.max(lx[i]))
        });
    Some(PowerLaw {
        exponent: -slope,
        prefactor: (my - slope * mx).exp(),
        range: (a.exp(), b.exp()),
    })
}

/// Parameters when there are too few PSD points to fit: σ = Sq, γ = 4, and Lc from the
/// K-correlation slope variance `2σ²/(Lc²(γ − 3))` = Sdq² (or the scan length when the
/// surface is flat); clamped to the renderer's ranges.
pub fn estimate_from_stats(sq: f64, rms_slope: f64, scan_length: f64, form: PsdForm) -> KcFit {
    let gamma = 4.0;
    let lc = if rms_slope > 0.0 && sq > 0.0 {
        (2.0f64 / (gamma - 3.0)).sqrt() * sq / rms_slope
    } else {
        scan_length / (2.0 * PI)
    };
    let nan = KcParams {
        sigma: f64::NAN,
        lc: f64::NAN,
        gamma: f64::NAN,
    };
    KcFit {
        params: KcParams {
            sigma: sq.max(0.0),
            lc: lc.clamp(LC_BOUNDS_M.0, LC_BOUNDS_M.1),
            gamma,
        },
        stderr: nan,
        rms_log_residual: f64::NAN,
        points: 0,
        range: (f64::NAN, f64::NAN),
        degenerate: true,
        reason: Some(Degeneracy::TooFewPoints),
        asymptote: None,
        form,
    }
}

/// Fit the 1D form to a line PSD on the raw bins `k_lo ..= k_hi` (README: 3 ..= nx/4).
pub fn fit_bins(psd: &crate::psd::Psd1d, k_lo: usize, k_hi: usize) -> Result<KcFit, FitError> {
    let hi = k_hi.min(psd.f.len().saturating_sub(1));
    if k_lo >= hi {
        return Err(FitError::data("K-correlation fit", "empty bin range"));
    }
    fit(
        PsdForm::Profile1d,
        &psd.f,
        &psd.p,
        psd.f[k_lo] * (1.0 - 1e-9),
        psd.f[hi] * (1.0 + 1e-9),
    )
}
