//! The Matérn correlation M(x) = 2^{1−ν}/Γ(ν) · x^ν K_ν(x), M(0) = 1: the
//! normalised autocovariance C(r)/σ² of the K-correlation surface at
//! x = r/Lc (physics.md §2.3).
//!
//! Both M and 1 − M are provided. The full GHS kernel needs 1 − M to full
//! relative accuracy at small x (g(1 − M) with g up to 1e4), which the
//! cancellation-free series of §2.3 gives for non-integer ν.

use crate::numerics::hankel::Correlation;
use crate::numerics::special::{EULER_GAMMA, bessel_k_pair_scaled};

/// Below this distance from an integer, ν is treated with the Bessel form
/// (the series' Γ(1 − ν) pole makes its terms cancel).
const NEAR_INTEGER: f64 = 1e-3;
/// The small-x series is used for x below this.
const SERIES_MAX_X: f64 = 1.0;

/// Matérn correlation for a fixed smoothness ν, with the constants that
/// depend only on ν precomputed.
#[derive(Clone, Copy, Debug)]
pub struct Matern {
    nu: f64,
    /// (1 − ν) ln 2 − ln Γ(ν)
    log_norm: f64,
    /// Γ(1 − ν) for the series (unused near integers).
    gamma_1m_nu: f64,
    /// ln Γ(1 + ν) and Γ(2 − ν), the series' other constants: evaluated
    /// per call they would be most of its cost (the S̃ tables call it millions of
    /// times).
    lgamma_1p_nu: f64,
    gamma_2m_nu: f64,
    near_integer: bool,
}

impl Matern {
    /// Matérn correlation with smoothness `nu` > 0.
    pub fn new(nu: f64) -> Self {
        let near_integer = libm::fabs(nu - libm::round(nu)) < NEAR_INTEGER;
        Matern {
            nu,
            log_norm: (1.0 - nu) * core::f64::consts::LN_2 - libm::lgamma(nu),
            gamma_1m_nu: if near_integer {
                0.0
            } else {
                libm::tgamma(1.0 - nu)
            },
            lgamma_1p_nu: libm::lgamma(1.0 + nu),
            gamma_2m_nu: libm::tgamma(2.0 - nu),
            near_integer,
        }
    }

    /// The smoothness ν.
    pub fn nu(&self) -> f64 {
        self.nu
    }

    /// M(x) for x ≥ 0 (M(0) = 1, M → 0 without underflow trouble).
    pub fn value(&self, x: f64) -> f64 {
        if x.is_nan() || x <= 0.0 {
            return 1.0;
        }
        if x < SERIES_MAX_X {
            return 1.0 - self.one_minus(x);
        }
        self.bessel_form(x)
    }

    /// 1 − M(x), accurate in relative terms for small x.
    pub fn one_minus(&self, x: f64) -> f64 {
        if x.is_nan() || x <= 0.0 {
            return 0.0;
        }
        if x >= SERIES_MAX_X {
            return 1.0 - self.bessel_form(x);
        }
        if !self.near_integer {
            return self.series(x);
        }
        if x < 1e-3 {
            return self.leading_term_near_integer(x);
        }
        (1.0 - self.bessel_form(x)).max(0.0)
    }

    /// exp(log_norm + ν ln x + ln K_ν(x)) with K from Temme + upward recurrence
    /// done on the Matérn functions themselves (no overflow for large ν).
    fn bessel_form(&self, x: f64) -> f64 {
        let nu = self.nu;
        if x > 745.0 + 2.0 * nu * crate::numerics::math::ln(x.max(1.0)) + 50.0 {
            return 0.0;
        }
        if nu < 1.5 {
            let (mu, which) = if nu <= 0.5 { (nu, 0) } else { (nu - 1.0, 1) };
            let (k0, k1) = bessel_k_pair_scaled(mu, x);
            let k = if which == 0 { k0 } else { k1 };
            return crate::numerics::math::exp(
                self.log_norm + nu * crate::numerics::math::ln(x) + crate::numerics::math::ln(k)
                    - x,
            );
        }
        // a ∈ [½, 3/2): M_a and M_{a+1} directly, then
        // M_{μ+1} = M_μ + x²/(4μ(μ−1)) M_{μ−1}, a sum of positive terms.
        let n = libm::floor(nu - 0.5);
        let a = nu - n;
        let (mu, which) = if a <= 0.5 { (a, 0) } else { (a - 1.0, 1) };
        let (k0, k1) = bessel_k_pair_scaled(mu, x);
        let (ka, ka1) = if which == 0 {
            (k0, k1)
        } else {
            (k1, 2.0 * (mu + 1.0) / x * k1 + k0)
        };
        let lx = crate::numerics::math::ln(x);
        let m_of = |order: f64, k: f64| {
            crate::numerics::math::exp(
                (1.0 - order) * core::f64::consts::LN_2 - libm::lgamma(order)
                    + order * lx
                    + crate::numerics::math::ln(k)
                    - x,
            )
        };
        let mut m0 = m_of(a, ka);
        let mut m1 = m_of(a + 1.0, ka1);
        let mut order = a + 1.0;
        let x2 = 0.25 * x * x;
        while order + 0.5 < nu {
            let m2 = m1 + x2 / (order * (order - 1.0)) * m0;
            m0 = m1;
            m1 = m2;
            order += 1.0;
        }
        if n < 1.0 { m0 } else { m1 }
    }

    /// 1 − M = Γ(1−ν)[Σ_{k≥0} t^{k+ν}/(k!Γ(k+1+ν)) − Σ_{k≥1} t^k/(k!Γ(k+1−ν))], t = x²/4.
    fn series(&self, x: f64) -> f64 {
        let nu = self.nu;
        let t = 0.25 * x * x;
        // first sum
        let mut term =
            crate::numerics::math::exp(nu * crate::numerics::math::ln(t) - self.lgamma_1p_nu);
        let mut s1 = term;
        let mut k = 1.0;
        while k < 60.0 {
            term *= t / (k * (k + nu));
            s1 += term;
            if term.abs() < 1e-17 * s1.abs() {
                break;
            }
            k += 1.0;
        }
        // second sum: t^k/(k! Γ(k+1−ν)) via the recurrence of 1/Γ.
        let mut term2 = t / self.gamma_2m_nu;
        let mut s2 = term2;
        let mut k = 2.0;
        while k < 60.0 {
            term2 *= t / (k * (k - nu));
            s2 += term2;
            if term2.abs() < 1e-17 * s2.abs().max(1e-300) {
                break;
            }
            k += 1.0;
        }
        (self.gamma_1m_nu * (s1 - s2)).max(0.0)
    }

    /// Leading small-x behaviour of 1 − M for ν within 1e−3 of an integer n,
    /// used below x = 1e−3: exact limit for ν = n (next term O(x² ln x)); for
    /// ν = n ± δ its relative error is about 2δ·ln(1/x).
    fn leading_term_near_integer(&self, x: f64) -> f64 {
        let n = libm::round(self.nu);
        let x2 = x * x;
        if n <= 1.0 {
            0.25 * x2 * (crate::numerics::math::ln(4.0 / x2) + 1.0 - 2.0 * EULER_GAMMA)
        } else {
            x2 / (4.0 * (self.nu - 1.0))
        }
    }
}

/// The K-correlation surface: Matérn covariance and p₁.
impl Correlation for Matern {
    fn m(&self, x: f64) -> f64 {
        self.value(x)
    }
    fn one_minus_m(&self, x: f64) -> f64 {
        self.one_minus(x)
    }
    fn unit_psd_u(&self, u: f64) -> f64 {
        super::kc::p1(self.nu(), u)
    }
    fn cusp_nu(&self) -> f64 {
        self.nu()
    }
    fn identity(&self) -> Option<crate::numerics::hankel::CorrelationKey> {
        Some(crate::numerics::hankel::CorrelationKey {
            family: "matern",
            params: [self.nu().to_bits(), 0],
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn closed_forms() {
        for &x in &[1e-8, 1e-3, 0.2, 0.999, 1.0, 1.5, 4.0, 20.0, 200.0] {
            let e = crate::numerics::math::exp(-x);
            let m12 = Matern::new(0.5);
            let m32 = Matern::new(1.5);
            let m52 = Matern::new(2.5);
            assert!((m12.value(x) / e - 1.0).abs() < 1e-13, "{x}");
            assert!((m32.value(x) / ((1.0 + x) * e) - 1.0).abs() < 1e-13, "{x}");
            assert!(
                (m52.value(x) / ((1.0 + x + x * x / 3.0) * e) - 1.0).abs() < 1e-13,
                "{x}"
            );
            // 1 − M against -expm1 for ν = ½ (relative)
            let om = -libm::expm1(-x);
            assert!((m12.one_minus(x) / om - 1.0).abs() < 1e-13, "{x}");
            // ν = 3/2: 1 − (1+x)e^{−x}
            let om32 = -libm::expm1(-x) - x * e;
            assert!(
                (m32.one_minus(x) / om32 - 1.0).abs() < 1e-11 || om32 < 1e-14,
                "{x}"
            );
        }
        // ν = 1: M = x K₁(x); K₁(1) = 0.6019072301972346
        assert!((Matern::new(1.0).value(1.0) - 0.601_907_230_197_234_6).abs() < 1e-14);
    }

    #[test]
    fn series_and_bessel_forms_agree() {
        for &nu in &[0.01, 0.25, 0.6, 0.9, 1.25, 2.2, 3.7, 12.3, 49.5] {
            let m = Matern::new(nu);
            for &x in &[0.3, 0.7, 0.99] {
                let a = m.series(x);
                let b = 1.0 - m.bessel_form(x);
                assert!((a / b - 1.0).abs() < 1e-11, "nu={nu} x={x}: {a} vs {b}");
            }
            assert_eq!(m.value(0.0), 1.0);
            // monotone decreasing, within [0, 1]
            let mut prev = 1.0;
            for i in 1..400 {
                let x = 1e-4 * libm::pow(1.05, i as f64);
                let v = m.value(x);
                assert!(v <= prev + 1e-15 && v >= 0.0, "nu={nu} x={x}");
                prev = v;
            }
        }
    }

    #[test]
    fn cusp_leading_term() {
        // 1 − M ≈ Γ(1−ν)/Γ(1+ν) (x/2)^{2ν} for ν < 1; x²/(4(ν−1)) for ν > 1.
        let x = 1e-6;
        for &nu in &[0.1, 0.25, 0.75] {
            let want =
                libm::tgamma(1.0 - nu) / libm::tgamma(1.0 + nu) * libm::pow(x / 2.0, 2.0 * nu);
            let got = Matern::new(nu).one_minus(x);
            assert!((got / want - 1.0).abs() < 1e-3, "{nu}");
        }
        for &nu in &[1.5, 2.0, 3.0, 5.5] {
            let got = Matern::new(nu).one_minus(x);
            assert!(
                (got / (x * x / (4.0 * (nu - 1.0))) - 1.0).abs() < 1e-3,
                "{nu}"
            );
        }
    }
}
