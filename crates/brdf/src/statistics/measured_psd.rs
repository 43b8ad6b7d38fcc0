//! A measured, tabulated isotropic PSD (as `fit` produces) driving the GHS
//! models in place of a K-correlation fit.
//!
//! P(ζ) is interpolated log-log between the samples. Outside the band they
//! cover it is continued, by assumption, with P and its log-log slope
//! continuous: below the first sample by the K-correlation roll-off
//! (1 + (ζ/ζ_c)²)^{−β} with the table's fitted tail exponent, matched to the
//! first segment (see `low_rolloff`),
//! beyond the last one by the power law of the last segment, which must fall
//! faster than ζ⁻² so that σ² = ∫P d²ζ is finite. Radial sampling
//! inverts the exact CDF of that piecewise power law. For the full GHS the
//! covariance M(x) = C(r)/σ² is computed by an FFTLog Hankel transform of the
//! table (see [`TabulatedCorrelation`]).

use alloc::vec::Vec;
use core::f64::consts::PI;

use super::RadialPsd;
use super::matern::Matern;
use crate::BrdfError;
use crate::numerics::hankel::{Correlation, FftLog};
use crate::numerics::interp::lagrange4;

/// Steepest accepted last segment, d ln P/d ln ζ: the tail of a KC surface
/// with γ = [`GAMMA_MAX`](super::kc::GAMMA_MAX), ζ^−(γ+1). The tail sets the
/// Matérn smoothness ν_t = (−slope − 2)/2 of the covariance, whose
/// evaluation costs O(ν_t) and is called millions of times while the GHS
/// table is built (a segment falling as ζ^−7e6 would take minutes); past ν ≈ 50
/// the Matérn function is Gaussian to far below any measurable difference.
pub const TAIL_SLOPE_MIN: f64 = -(super::kc::GAMMA_MAX + 1.0);

/// Whether a last segment of log-log slope `slope` falls faster than
/// [`TAIL_SLOPE_MIN`] allows (false for NaN, which other checks refuse); the
/// relative slack admits a table written at exactly ζ^−101 whose logarithms
/// round past it.
pub fn tail_too_steep(slope: f64) -> bool {
    slope < TAIL_SLOPE_MIN * (1.0 + 1e-9)
}

/// Radial PSD given by samples (ζ_j in rad/µm, P_j in µm⁴).
#[derive(Clone, Debug, PartialEq)]
pub struct TabulatedPsd {
    ln_zeta: Vec<f64>,
    ln_p: Vec<f64>,
    /// d ln P/d ln ζ beyond the last sample (< −2).
    slope_hi: f64,
    /// The roll-off below the first sample ζ₀: P = P₀[(1 + t v)/(1 + t)]^{−β},
    /// v = (ζ/ζ₀)², as (t, β); t = 0 is a flat continuation.
    lo_t: f64,
    lo_beta: f64,
    sigma2: f64,
    /// Normalised radial mass inside each ζ_j (index 0: the flat disk).
    cum: Vec<f64>,
    /// L = 1/ζ_half: the median radial frequency sets the unit of u.
    length: f64,
}

impl TabulatedPsd {
    /// From samples in the rad/µm convention: `zeta` strictly increasing and
    /// positive, `psd` positive and finite, at least 2 samples.
    pub fn new(zeta_rad_per_um: &[f64], psd_um4: &[f64]) -> Result<Self, BrdfError> {
        let n = zeta_rad_per_um.len();
        if n < 2 || psd_um4.len() != n {
            return Err(BrdfError::InvalidTable {
                reason: "need at least 2 (zeta, psd) samples and equally long columns",
                row: None,
            });
        }
        for j in 0..n {
            let (z, p) = (zeta_rad_per_um[j], psd_um4[j]);
            if !(z.is_finite() && z > 0.0) || (j > 0 && !(z > zeta_rad_per_um[j - 1])) {
                return Err(BrdfError::InvalidTable {
                    reason: "zeta must be finite, positive and strictly increasing (rad/µm)",
                    row: Some(j),
                });
            }
            if !(p.is_finite() && p > 0.0) {
                return Err(BrdfError::InvalidTable {
                    reason: "psd must be finite and positive (µm⁴); drop or floor zero bins",
                    row: Some(j),
                });
            }
        }
        let ln_zeta: Vec<f64> = zeta_rad_per_um
            .iter()
            .map(|z| crate::numerics::math::ln(*z))
            .collect();
        let ln_p: Vec<f64> = psd_um4
            .iter()
            .map(|p| crate::numerics::math::ln(*p))
            .collect();
        let slope_hi = (ln_p[n - 1] - ln_p[n - 2]) / (ln_zeta[n - 1] - ln_zeta[n - 2]);
        if !(slope_hi < -2.02) {
            return Err(BrdfError::InvalidTable {
                reason: "the last segment must fall faster than zeta^-2.02 (finite, normalisable \
                         tail); extend the table to higher frequencies or trim the noise floor",
                row: Some(n - 1),
            });
        }
        if tail_too_steep(slope_hi) {
            return Err(BrdfError::InvalidTable {
                reason: "the last segment falls faster than zeta^-101 (the tail of KC gamma = \
                         100, the steepest accepted): end the table before the roll-off or \
                         drop its last row",
                row: Some(n - 1),
            });
        }
        let (lo_t, lo_beta) = low_rolloff(
            (ln_p[1] - ln_p[0]) / (ln_zeta[1] - ln_zeta[0]),
            fitted_tail_slope(&ln_zeta, &ln_p, slope_hi),
        );
        let mut cum = Vec::with_capacity(n + 1);
        let z0 = zeta_rad_per_um[0];
        let mut acc = PI * z0 * z0 * psd_um4[0] * rolloff_mass(lo_t, lo_beta, 1.0);
        cum.push(acc);
        for j in 0..n - 1 {
            acc += seg_mass(ln_zeta[j], ln_p[j], ln_zeta[j + 1], ln_p[j + 1]);
            cum.push(acc);
        }
        let zl = zeta_rad_per_um[n - 1];
        acc += 2.0 * PI * psd_um4[n - 1] * zl * zl / (-(slope_hi + 2.0));
        let sigma2 = acc;
        if !(libm::sqrt(sigma2) <= super::kc::SIGMA_MAX_UM) {
            return Err(BrdfError::OutOfRange {
                name: "sigma_um of the tabulated PSD",
                value: libm::sqrt(sigma2),
                valid: "≤ 10 µm (the wave models' validated range; check the PSD's units: zeta in rad/µm, psd in µm⁴)",
            });
        }
        for c in cum.iter_mut() {
            *c /= sigma2;
        }
        let mut t = TabulatedPsd {
            ln_zeta,
            ln_p,
            slope_hi,
            lo_t,
            lo_beta,
            sigma2,
            cum,
            length: 1.0,
        };
        let half = t.sample_zeta(0.5);
        t.length = 1.0 / half;
        Ok(t)
    }

    /// From samples in the cycles/µm convention: ζ = 2πf, P = PSD_cyc/(2π)².
    pub fn from_cycles(f_cycles_per_um: &[f64], psd_cyc_um4: &[f64]) -> Result<Self, BrdfError> {
        let z: Vec<f64> = f_cycles_per_um.iter().map(|f| 2.0 * PI * f).collect();
        let p: Vec<f64> = psd_cyc_um4.iter().map(|p| p / (4.0 * PI * PI)).collect();
        Self::new(&z, &p)
    }

    /// rms height σ = sqrt(∫ P d²ζ), µm.
    pub fn sigma_um(&self) -> f64 {
        libm::sqrt(self.sigma2)
    }

    /// P(ζ), µm⁴.
    pub fn psd(&self, zeta: f64) -> f64 {
        if !(zeta > 0.0) {
            return self.rolloff(0.0);
        }
        let lz = crate::numerics::math::ln(zeta);
        let n = self.ln_zeta.len();
        if lz <= self.ln_zeta[0] {
            let z0 = crate::numerics::math::exp(self.ln_zeta[0]);
            return self.rolloff((zeta / z0) * (zeta / z0));
        }
        if lz >= self.ln_zeta[n - 1] {
            return crate::numerics::math::exp(
                self.ln_p[n - 1] + self.slope_hi * (lz - self.ln_zeta[n - 1]),
            );
        }
        let j = self.segment(lz);
        let t = (lz - self.ln_zeta[j]) / (self.ln_zeta[j + 1] - self.ln_zeta[j]);
        crate::numerics::math::exp(self.ln_p[j] + t * (self.ln_p[j + 1] - self.ln_p[j]))
    }

    /// P/σ², µm².
    pub fn unit_psd(&self, zeta: f64) -> f64 {
        self.psd(zeta) / self.sigma2
    }

    /// Segment j with ln ζ_j ≤ lz < ln ζ_{j+1}.
    fn segment(&self, lz: f64) -> usize {
        let (mut lo, mut hi) = (0usize, self.ln_zeta.len() - 1);
        while hi - lo > 1 {
            let mid = (lo + hi) / 2;
            if self.ln_zeta[mid] <= lz {
                lo = mid
            } else {
                hi = mid
            }
        }
        lo
    }

    /// Radial mass of P/σ² inside |ζ| ≤ zeta.
    pub fn cdf(&self, zeta: f64) -> f64 {
        if !(zeta > 0.0) {
            return 0.0;
        }
        let n = self.ln_zeta.len();
        let lz = crate::numerics::math::ln(zeta);
        if lz <= self.ln_zeta[0] {
            let z0 = crate::numerics::math::exp(self.ln_zeta[0]);
            let v = (zeta / z0) * (zeta / z0);
            return self.cum[0] * rolloff_mass(self.lo_t, self.lo_beta, v)
                / rolloff_mass(self.lo_t, self.lo_beta, 1.0);
        }
        if lz >= self.ln_zeta[n - 1] {
            let zl = crate::numerics::math::exp(self.ln_zeta[n - 1]);
            let b2 = self.slope_hi + 2.0;
            let m = 2.0
                * PI
                * crate::numerics::math::exp(self.ln_p[n - 1])
                * zl
                * zl
                * (libm::expm1(b2 * (lz - self.ln_zeta[n - 1])) / b2)
                / self.sigma2;
            return (self.cum[n - 1] + m).min(1.0);
        }
        let j = self.segment(lz);
        let m = seg_mass(
            self.ln_zeta[j],
            self.ln_p[j],
            lz,
            self.ln_p[j] + (lz - self.ln_zeta[j]) * self.seg_slope(j),
        );
        (self.cum[j] + m / self.sigma2).min(1.0)
    }

    fn seg_slope(&self, j: usize) -> f64 {
        (self.ln_p[j + 1] - self.ln_p[j]) / (self.ln_zeta[j + 1] - self.ln_zeta[j])
    }

    /// Inverse of [`TabulatedPsd::cdf`] for ξ ∈ [0, 1) (rad/µm; +∞ at ξ ≥ 1).
    pub fn sample_zeta(&self, xi: f64) -> f64 {
        if !(xi > 0.0) {
            return 0.0;
        }
        if xi >= 1.0 {
            return f64::INFINITY;
        }
        let n = self.ln_zeta.len();
        if xi < self.cum[0] {
            let target = rolloff_mass(self.lo_t, self.lo_beta, 1.0) * xi / self.cum[0];
            let v = rolloff_mass_inverse(self.lo_t, self.lo_beta, target).clamp(0.0, 1.0);
            return crate::numerics::math::exp(self.ln_zeta[0]) * libm::sqrt(v);
        }
        if xi >= self.cum[n - 1] {
            let zl = crate::numerics::math::exp(self.ln_zeta[n - 1]);
            let b2 = self.slope_hi + 2.0;
            let target = (xi - self.cum[n - 1]) * self.sigma2
                / (2.0 * PI * crate::numerics::math::exp(self.ln_p[n - 1]) * zl * zl);
            let z = 1.0 + b2 * target;
            return if z <= 0.0 {
                f64::INFINITY
            } else {
                zl * crate::numerics::math::exp(crate::numerics::math::ln(z) / b2)
            };
        }
        let (mut lo, mut hi) = (0usize, n - 1);
        while hi - lo > 1 {
            let mid = (lo + hi) / 2;
            if self.cum[mid] <= xi {
                lo = mid
            } else {
                hi = mid
            }
        }
        let j = lo;
        let zj = crate::numerics::math::exp(self.ln_zeta[j]);
        let b2 = self.seg_slope(j) + 2.0;
        let target = (xi - self.cum[j]) * self.sigma2
            / (2.0 * PI * crate::numerics::math::exp(self.ln_p[j]) * zj * zj);
        let ln_ratio = if libm::fabs(b2) < 1e-9 {
            target
        } else {
            libm::log1p(b2 * target) / b2
        };
        zj * crate::numerics::math::exp(ln_ratio.clamp(0.0, self.ln_zeta[j + 1] - self.ln_zeta[j]))
    }

    /// Exponent ν_t of the tail, P ∝ ζ^{−(2ν_t + 2)}.
    pub fn tail_nu(&self) -> f64 {
        0.5 * (-self.slope_hi - 2.0)
    }

    /// The band the samples cover, (first ζ, last ζ) in rad/µm: outside it
    /// P is the continuation of [`TabulatedPsd`]'s documentation, assumed
    /// rather than measured.
    pub fn band_rad_per_um(&self) -> (f64, f64) {
        let n = self.ln_zeta.len();
        (
            crate::numerics::math::exp(self.ln_zeta[0]),
            crate::numerics::math::exp(self.ln_zeta[n - 1]),
        )
    }

    /// The continuation below the band: (ζ_c, β) of P ∝ (1 + (ζ/ζ_c)²)^{−β}
    /// (ζ_c in rad/µm; +∞ when the table starts flat or rising and is
    /// continued flat).
    pub fn low_rolloff(&self) -> (f64, f64) {
        let z0 = crate::numerics::math::exp(self.ln_zeta[0]);
        if self.lo_t > 0.0 {
            (z0 / libm::sqrt(self.lo_t), self.lo_beta)
        } else {
            (f64::INFINITY, self.lo_beta)
        }
    }

    /// The log-log slope d ln P/d ln ζ of the continuation above the band.
    pub fn high_slope(&self) -> f64 {
        self.slope_hi
    }

    /// P at v = (ζ/ζ₀)² ≤ 1, below the first sample.
    fn rolloff(&self, v: f64) -> f64 {
        let p0 = crate::numerics::math::exp(self.ln_p[0]);
        if !(self.lo_t > 0.0) {
            return p0;
        }
        let t = self.lo_t;
        p0 * crate::numerics::math::exp(-self.lo_beta * (libm::log1p(t * v) - libm::log1p(t)))
    }
}

/// The least-squares log-log slope of the top third of a table (in ln ζ; at
/// least its last two samples): its fitted high-frequency tail, less
/// sensitive than the last segment to a noise floor trimmed at the end.
/// `slope_hi` where the fit does not fall faster than ζ⁻² (then no
/// K-correlation has that tail).
fn fitted_tail_slope(ln_zeta: &[f64], ln_p: &[f64], slope_hi: f64) -> f64 {
    let n = ln_zeta.len();
    let from = ln_zeta[0] + (ln_zeta[n - 1] - ln_zeta[0]) * 2.0 / 3.0;
    let first = ln_zeta
        .iter()
        .position(|&z| z >= from)
        .unwrap_or(0)
        .min(n - 2);
    let (x, y) = (&ln_zeta[first..], &ln_p[first..]);
    let m = x.len() as f64;
    let (mx, my) = (x.iter().sum::<f64>() / m, y.iter().sum::<f64>() / m);
    let (mut sxx, mut sxy) = (0.0, 0.0);
    for (a, b) in x.iter().zip(y) {
        sxx += (a - mx) * (a - mx);
        sxy += (a - mx) * (b - my);
    }
    let s = sxy / sxx;
    if s < -2.0 && s.is_finite() {
        s
    } else {
        slope_hi
    }
}

/// The roll-off below a table's first sample ζ₀, (t, β) of
/// P = P₀[(1 + t(ζ/ζ₀)²)/(1 + t)]^{−β}: the K-correlation shape, flat at
/// ζ → 0, with the exponent β = max(−s_t/2, −s₀) (the K-correlation whose
/// tail s_t is the table's fitted one, [`fitted_tail_slope`], steepened if
/// the first segment is steeper still) and t such that the log-slope at ζ₀, −2βt/(1 + t), is the
/// first segment's s₀. P and d ln P/d ln ζ are continuous at ζ₀: a table
/// held flat below ζ₀ has a kink there whose slowly decaying, oscillating
/// covariance the transforms of the full GHS cannot resolve (the table
/// and the direct transform would disagree by 7–69 %). A first segment that is
/// flat or rising is continued flat (t = 0), and so is one so steep that
/// the roll-off would rise more than [`ROLLOFF_RISE_MAX`] above P₀ (a C¹
/// continuation of a ζ^{s₀} segment to a plateau rises by 2^{−s₀} when
/// β = −s₀): there the table's low end is not a spectrum flattening out,
/// and inventing three decades of power below it would be worse than the
/// kink.
fn low_rolloff(s0: f64, tail_slope: f64) -> (f64, f64) {
    let beta = (-0.5 * tail_slope).max(-s0);
    if !(s0 < 0.0) || !(beta > 0.0) {
        return (0.0, beta.max(1.0));
    }
    let t = -s0 / (2.0 * beta + s0);
    if beta * libm::log1p(t) > crate::numerics::math::ln(ROLLOFF_RISE_MAX) {
        return (0.0, beta);
    }
    (t, beta)
}

/// Largest factor by which the continuation below a table may rise above
/// its first sample (reached for a first segment near ζ^{−10}).
pub const ROLLOFF_RISE_MAX: f64 = 1e3;

/// ∫₀^v [(1 + t v')/(1 + t)]^{−β} dv' (the roll-off's mass inside v =
/// (ζ/ζ₀)², in units of πζ₀²P₀), without cancellation for small t.
fn rolloff_mass(t: f64, beta: f64, v: f64) -> f64 {
    if !(t > 0.0) {
        return v;
    }
    let scale = crate::numerics::math::exp(beta * libm::log1p(t));
    let x = t * v;
    let l = libm::log1p(x);
    let raw = if libm::fabs(beta - 1.0) < 1e-12 {
        l / t
    } else {
        -libm::expm1((1.0 - beta) * l) / (t * (beta - 1.0))
    };
    scale * raw
}

/// v with [`rolloff_mass`](t, β, v) = m.
fn rolloff_mass_inverse(t: f64, beta: f64, m: f64) -> f64 {
    if !(t > 0.0) {
        return m;
    }
    let raw = m / crate::numerics::math::exp(beta * libm::log1p(t));
    let x = if libm::fabs(beta - 1.0) < 1e-12 {
        libm::expm1(raw * t)
    } else {
        let arg = -raw * t * (beta - 1.0);
        if !(arg > -1.0) {
            return f64::INFINITY;
        }
        libm::expm1(libm::log1p(arg) / (1.0 - beta))
    };
    x / t
}

/// 2π ∫ P ζ dζ over a log-log-linear segment.
fn seg_mass(lz0: f64, lp0: f64, lz1: f64, lp1: f64) -> f64 {
    let d = lz1 - lz0;
    if !(d > 0.0) {
        return 0.0;
    }
    let b2 = (lp1 - lp0) / d + 2.0;
    let base = 2.0 * PI * crate::numerics::math::exp(lp0 + 2.0 * lz0);
    if libm::fabs(b2 * d) < 1e-12 {
        base * d
    } else {
        base * libm::expm1(b2 * d) / b2
    }
}

impl RadialPsd for TabulatedPsd {
    fn sigma_um(&self) -> f64 {
        TabulatedPsd::sigma_um(self)
    }
    fn length_um(&self) -> f64 {
        self.length
    }
    fn unit_psd_u(&self, u: f64) -> f64 {
        let l = self.length;
        self.unit_psd(u / l) / (l * l)
    }
    fn cdf_u(&self, u: f64) -> f64 {
        self.cdf(u / self.length)
    }
    fn sample_u(&self, xi: f64) -> f64 {
        self.sample_zeta(xi) * self.length
    }
}

/// Normalised covariance of a [`TabulatedPsd`] in x = r/L.
///
/// The tail of p(u) (a power law B u^{−2ν_t−2} beyond the last sample) sets
/// the cusp of 1 − M at small x, which a numerical transform cannot resolve
/// to the relative accuracy g(1 − M) needs. So p is split as
/// p = c·p₁(u; ν_t) + r(u), with c = πB/ν_t the K-correlation (Lc = 1) of
/// the same tail: the Matérn part is exact, and the remainder r, whose tail
/// falls two powers faster, is transformed by FFTLog (bias ½, 8192 points
/// over 44 decades) and interpolated (cubic in ln x); where the remainder
/// is below 1e−6 its quadratic small-x form x²m₂/4 is used instead:
/// 1 − M = c(1 − M_ν(x)) + [(1 − c) − M_r(x)]. Beyond the last separation
/// where |M| > 1e−6, M is faded smoothly to 0 over a factor 2 in x, removing
/// the transform's noise floor. The transforms of the full GHS subtract the
/// cusp with the Matérn part alone (its transform is exact), and stop
/// integrating where an envelope of |M| has decayed (M goes negative).
///
/// The first order of S̃ is p itself, added exactly by the table and the
/// direct transform, because this M reproduces p to only ~2e−3 near the
/// band's low end, where P changes slope fastest.
#[derive(Clone, Debug)]
pub struct TabulatedCorrelation {
    p: TabulatedPsd,
    matern: Matern,
    c: f64,
    /// 1/Lc' of the tail-matching KC (1 unless the tail is steep and late).
    inv_lc_tail: f64,
    t0: f64,
    dt: f64,
    m_r: Vec<f64>,
    m2: f64,
    x_switch: f64,
    /// M is faded smoothly to 0 from `x_fade` to `x_cut` and ≡ 0 beyond.
    x_fade: f64,
    x_cut: f64,
    /// max |M(y)| over y ≥ x_i on the transform's grid (× a small margin for
    /// the interpolation between grid points): M oscillates and goes
    /// negative, and the transforms must not stop at its first zero.
    envelope: Vec<f64>,
}

impl TabulatedCorrelation {
    /// Transforms the PSD once.
    pub fn new(p: &TabulatedPsd) -> Self {
        let n = 1 << 15;
        let dt = 0.003125;
        let nu = p.tail_nu();
        let nl = p.ln_zeta.len();
        // tail amplitude in u: p(u) = B u^{slope} for u ≥ u_last
        let u_last = crate::numerics::math::exp(p.ln_zeta[nl - 1]) * p.length;
        let b = p.unit_psd_u_inner(u_last)
            * crate::numerics::math::exp(-p.slope_hi * crate::numerics::math::ln(u_last));
        // The KC of the same tail with Lc = 1 has mass πB/ν. A last segment
        // far steeper than the body (a roll-off appended past the data)
        // makes that astronomically large, and r = p − c·p₁ then cancels
        // to nothing; there the tail is matched by a unit-mass KC of a
        // shorter length instead: Lc'^{−2ν} = πB/ν.
        let tail_mass = PI * b / nu;
        let (c, lc_tail) = if tail_mass <= 1.0 {
            (tail_mass, 1.0)
        } else {
            (
                1.0,
                crate::numerics::math::exp(-crate::numerics::math::ln(tail_mass) / (2.0 * nu)),
            )
        };
        let plan = FftLog::with_bias(n, dt, 0.5);
        let tu0 = -51.0;
        let f: Vec<f64> = (0..n)
            .map(|i| {
                let u = crate::numerics::math::exp(tu0 + i as f64 * dt);
                let tail = c * lc_tail * lc_tail * super::kc::p1(nu, lc_tail * u);
                2.0 * PI * (p.unit_psd_u_inner(u) - tail)
            })
            .collect();
        let (mut re, mut im) = (Vec::new(), Vec::new());
        plan.transform(tu0, &f, &mut re, &mut im);
        let t0 = -(tu0 + (n - 1) as f64 * dt);
        // Second moment of r (finite: r falls like u^{slope−2}), for the
        // small-x form (1 − c) − M_r ≈ x² m₂/4 where the transform's
        // absolute error (~1e−9, from the kinks of the log-log table)
        // would dominate.
        let mut m2 = 0.0;
        for (i, fi) in f.iter().enumerate() {
            let u = crate::numerics::math::exp(tu0 + i as f64 * dt);
            if u > u_last {
                break;
            }
            m2 += fi * u * u * u * u * dt;
        }
        // r ≈ B(ν + 1)u^{slope−2}/Lc'² beyond the last sample.
        m2 += 2.0 * PI * b * (nu + 1.0) / (lc_tail * lc_tail)
            * crate::numerics::math::exp((p.slope_hi + 2.0) * crate::numerics::math::ln(u_last))
            / (-(p.slope_hi + 2.0));
        // switch where the quadratic form reaches 1e−6
        let x_switch = libm::sqrt(4e-6 / m2.abs().max(1e-300));
        let mut t = TabulatedCorrelation {
            p: p.clone(),
            matern: Matern::new(nu),
            c,
            inv_lc_tail: 1.0 / lc_tail,
            t0,
            dt,
            m_r: re,
            m2,
            x_switch,
            x_fade: f64::INFINITY,
            x_cut: f64::INFINITY,
            envelope: Vec::new(),
        };
        // The transform leaves ~1e−9 of noise where M has decayed; cut M to
        // zero beyond the last point where |M| > 1e−6 (×2 margin) so the
        // kernel e^{−g}(e^{gM} − 1) really vanishes at large separations.
        let mut x_fade = crate::numerics::math::exp(t0);
        for i in (0..n).rev() {
            let x = crate::numerics::math::exp(t0 + i as f64 * dt);
            if libm::fabs(t.m_full(x)) > 1e-6 {
                x_fade = x;
                break;
            }
        }
        let x_cut = 2.0 * x_fade;
        t.x_fade = x_fade;
        t.x_cut = x_cut;
        let mut envelope = alloc::vec![0.0; n];
        let mut running = 0.0f64;
        for i in (0..n).rev() {
            let x = crate::numerics::math::exp(t0 + i as f64 * dt);
            if x <= x_cut {
                running = running.max(libm::fabs(t.m(x)));
            }
            envelope[i] = (ENVELOPE_MARGIN * running).min(1.0);
        }
        t.envelope = envelope;
        t
    }

    /// [`Correlation::m_envelope`] from the grid: the bound at the grid point
    /// at or below x covers every y ≥ x.
    fn envelope_at(&self, x: f64) -> f64 {
        if !(x > 0.0) {
            return 1.0;
        }
        if x > self.x_cut {
            return 0.0;
        }
        let pos = (crate::numerics::math::ln(x) - self.t0) / self.dt;
        if !(pos >= 0.0) {
            return 1.0;
        }
        let i = libm::floor(pos) as usize;
        self.envelope.get(i).copied().unwrap_or(0.0)
    }

    /// M faded to 0 between `x_fade` and `x_cut` by a quintic smoothstep in
    /// ln x: cut off abruptly, the step (~1e−6) rings through the FFTLog rows
    /// of large g, whose subtracted cusp A·M(x/ε) puts it at x = ε·x_cut
    /// (3 % at g 200 on a synthetic 512² map).
    fn m_faded(&self, x: f64) -> f64 {
        if x <= self.x_fade {
            return self.m_full(x);
        }
        if x >= self.x_cut {
            return 0.0;
        }
        let s = crate::numerics::math::ln(x / self.x_fade) / core::f64::consts::LN_2;
        let w = 1.0 - s * s * s * (10.0 - 15.0 * s + 6.0 * s * s);
        self.m_full(x) * w
    }

    fn m_full(&self, x: f64) -> f64 {
        self.c * self.matern.value(x * self.inv_lc_tail) + self.m_r(x)
    }

    fn m_r(&self, x: f64) -> f64 {
        let n = self.m_r.len();
        let pos = (crate::numerics::math::ln(x) - self.t0) / self.dt;
        if pos >= (n - 2) as f64 {
            return 0.0;
        }
        // below the window M_r is flat at its x → 0 value 1 − c
        let pos = pos.max(1.0);
        let i = (libm::floor(pos) as usize).clamp(1, n - 3);
        let w = lagrange4(pos - i as f64);
        (0..4).map(|k| w[k] * self.m_r[i - 1 + k]).sum()
    }
}

impl TabulatedPsd {
    fn unit_psd_u_inner(&self, u: f64) -> f64 {
        <Self as RadialPsd>::unit_psd_u(self, u)
    }
}

impl Correlation for TabulatedCorrelation {
    fn m(&self, x: f64) -> f64 {
        if !(x > 0.0) {
            return 1.0;
        }
        if x < self.x_switch {
            return 1.0 - self.one_minus_m(x);
        }
        self.m_faded(x).clamp(-1.0, 1.0)
    }
    fn one_minus_m(&self, x: f64) -> f64 {
        if !(x > 0.0) {
            return 0.0;
        }
        if x > self.x_fade {
            return (1.0 - self.m_faded(x)).clamp(0.0, 2.0);
        }
        let rem = if x < self.x_switch {
            0.25 * x * x * self.m2
        } else {
            (1.0 - self.c) - self.m_r(x)
        };
        let v = self.c * self.matern.one_minus(x * self.inv_lc_tail) + rem;
        v.clamp(0.0, 2.0)
    }
    fn unit_psd_u(&self, u: f64) -> f64 {
        <TabulatedPsd as RadialPsd>::unit_psd_u(&self.p, u)
    }
    fn cusp_nu(&self) -> f64 {
        self.p.tail_nu()
    }
    fn separate_first_order(&self) -> bool {
        true
    }
    fn m_envelope(&self, x: f64) -> f64 {
        self.envelope_at(x)
    }
    // The cusp is the Matérn part's, whose transform is known in closed
    // form: subtracting M itself would add back p where only the numerical
    // transform of p was subtracted.
    fn cusp_m(&self, x: f64) -> f64 {
        self.matern.value(x * self.inv_lc_tail)
    }
    fn cusp_psd_u(&self, u: f64) -> f64 {
        let s = self.inv_lc_tail;
        super::kc::p1(self.p.tail_nu(), u / s) / (s * s)
    }
    fn cusp_m_envelope(&self, x: f64) -> f64 {
        self.cusp_m(x)
    }
    fn cusp_weight(&self) -> f64 {
        self.c
    }
}

/// Relative margin of the grid envelope over the grid values: the cubic
/// interpolation between points 0.003 apart in ln x moves |M| by far less.
const ENVELOPE_MARGIN: f64 = 1.01;

#[cfg(test)]
mod tests {
    use super::super::KcPsd;
    use super::*;

    fn kc_samples(k: &KcPsd, n: usize, lo: f64, hi: f64) -> (Vec<f64>, Vec<f64>) {
        let z: Vec<f64> = (0..n)
            .map(|i| {
                crate::numerics::math::exp(
                    crate::numerics::math::ln(lo)
                        + (crate::numerics::math::ln(hi) - crate::numerics::math::ln(lo))
                            * i as f64
                            / (n - 1) as f64,
                )
            })
            .collect();
        let p = z.iter().map(|z| k.psd(*z)).collect();
        (z, p)
    }

    #[test]
    fn rejects_bad_tables() {
        assert!(TabulatedPsd::new(&[1.0], &[1.0]).is_err());
        assert!(TabulatedPsd::new(&[1.0, 1.0], &[1.0, 0.1]).is_err());
        assert!(TabulatedPsd::new(&[1.0, 2.0], &[1.0, 0.0]).is_err());
        assert!(TabulatedPsd::new(&[1.0, 2.0], &[1.0, 0.5]).is_err()); // tail too shallow
        assert!(TabulatedPsd::new(&[1.0, 2.0], &[1.0, 0.1]).is_ok());
    }

    #[test]
    fn a_too_rough_table_names_the_units_in_one_clean_line() {
        // σ = sqrt(π·1²·1e4 + tail) ≫ 10 µm. The message went out (material files'
        // [reliability].psd, scene errors) with 25 spaces in the middle of a sentence.
        extern crate std;
        use std::string::ToString;
        let e = TabulatedPsd::new(&[1.0, 2.0], &[1e4, 1e3]).unwrap_err();
        let msg = e.to_string();
        assert!(msg.contains("units: zeta in rad/µm, psd in µm⁴"), "{msg}");
        assert!(!msg.contains("  "), "{msg}");
    }

    #[test]
    fn the_steepest_accepted_tail_sets_up_in_bounded_time() {
        // Rows 1,1e-3 / 1.0001,1e-300 (slope −6.9e6) would take hours to set up.
        let steep = TabulatedPsd::new(&[1.0, 1.0001], &[1e-3, 1e-300]);
        assert!(
            matches!(steep, Err(BrdfError::InvalidTable { row: Some(1), .. })),
            "{steep:?}"
        );
        let just_past = 2f64.powf(TAIL_SLOPE_MIN - 1e-5);
        assert!(TabulatedPsd::new(&[1.0, 2.0], &[1e-3, 1e-3 * just_past]).is_err());
        // The worst accepted table: the transform and the covariance at the
        // number of separations a GHS table asks for (a ζ^−1000 segment
        // would need ~2 s for this).
        extern crate std;
        let start = std::time::Instant::now();
        let t = TabulatedPsd::new(&[1.0, 2.0], &[1e-3, 1e-3 * 2f64.powf(TAIL_SLOPE_MIN)]).unwrap();
        assert!((t.tail_nu() - 49.5).abs() < 1e-9, "{}", t.tail_nu());
        let c = TabulatedCorrelation::new(&t);
        let mut acc = 0.0;
        for i in 0..200_000 {
            let x = crate::numerics::math::exp(-20.0 + 30.0 * i as f64 / 200_000.0);
            acc += c.m(x) + c.one_minus_m(x);
        }
        assert!(acc.is_finite());
        let secs = start.elapsed().as_secs_f64();
        assert!(secs < 5.0, "{secs} s");
    }

    #[test]
    fn reproduces_kc_sigma_cdf_and_sampling() {
        let k = KcPsd::new(0.2, 2.0, 3.5).unwrap();
        let (z, p) = kc_samples(&k, 300, 1e-3, 1e3);
        let t = TabulatedPsd::new(&z, &p).unwrap();
        assert!((t.sigma_um() / 0.2 - 1.0).abs() < 2e-4, "{}", t.sigma_um());
        for &zz in &[0.01, 0.3, 1.0, 10.0] {
            assert!((t.psd(zz) / k.psd(zz) - 1.0).abs() < 1e-3);
            assert!((t.cdf(zz) - k.cdf(zz)).abs() < 1e-3);
        }
        for i in 1..50 {
            let xi = i as f64 / 50.0;
            let zz = t.sample_zeta(xi);
            assert!((t.cdf(zz) - xi).abs() < 1e-12, "{xi}");
        }
    }

    #[test]
    fn covariance_matches_matern() {
        let k = KcPsd::new(0.2, 2.0, 2.5).unwrap();
        let (z, p) = kc_samples(&k, 400, 1e-4, 1e4);
        let t = TabulatedPsd::new(&z, &p).unwrap();
        let c = TabulatedCorrelation::new(&t);
        let mat = super::super::matern::Matern::new(k.nu());
        // x is in units of the table's L; Matérn in units of Lc.
        let scale = t.length / 2.0;
        for &x in &[1e-8, 1e-6, 1e-4, 1e-2, 0.1, 0.5, 1.0, 3.0] {
            let a = c.one_minus_m(x);
            let b = mat.one_minus(x * scale);
            assert!((a / b - 1.0).abs() < 3e-3, "x={x}: {a} vs {b}");
        }
    }
}
