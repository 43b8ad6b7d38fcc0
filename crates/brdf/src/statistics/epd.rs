//! The exponential normal distribution (EPD with p = ½, `physics.md` §8.1):
//! the macro-scale NDF of the Holzschuch–Pacanowski two-scale model.
//!
//! Its slope pdf is e^{−|s|/β}/(2πβ²), so in terms of half-vector angles
//!
//! ```text
//! D(h) = exp(−tanθ/β) / (2π β² cos⁴θ),      ∫ D cosθ dω = 1,
//! Λ(w) = [2K₁(x) − Ki₁(x)]/π,  x = 1/(β tanθ_w),
//! ```
//!
//! and the radius r = |s|/β of a slope drawn from D cosθ follows a Gamma(2, 1)
//! law: P(2, r) = 1 − (1 + r)e^{−r}. Sampling inverts that CDF (the p = ½ case
//! of HP17 Eqs. 49–50, with P⁻¹(2, ξ) in place of scipy's `gammaincinv`).

use crate::error::{BrdfError, check_range};
use crate::numerics::bessel01::smith_lambda_exp;
use core::f64::consts::PI;
use glam::DVec3;

/// Isotropic exponential NDF of scale β (the slope pdf's mean radius is 2β).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ExponentialNdf {
    beta: f64,
}

/// Smallest accepted β: below it the lobe is a mirror for every practical purpose.
pub const BETA_MIN: f64 = 1e-4;
/// Largest accepted β.
pub const BETA_MAX: f64 = 10.0;

impl ExponentialNdf {
    /// An exponential NDF with scale `beta`, in [1e−4, 10].
    pub fn new(beta: f64) -> Result<ExponentialNdf, BrdfError> {
        check_range("beta", beta, BETA_MIN, BETA_MAX, "1e-4 ≤ beta ≤ 10")?;
        Ok(ExponentialNdf { beta })
    }

    /// The scale β.
    pub fn beta(&self) -> f64 {
        self.beta
    }

    /// D as a function of tanθ and cosθ of the half vector (cosθ > 0).
    #[inline]
    pub(crate) fn d_tan_cos(&self, tan_t: f64, cos_t: f64) -> f64 {
        let r = tan_t / self.beta;
        // Beyond r = 700 the exponential is below 1e−304 while 1/cos⁴θ may
        // overflow; the product is 0 to double precision (cos⁴ ≥ (β r)^{−4}).
        if !(r < 700.0) || cos_t <= 0.0 {
            return 0.0;
        }
        let c2 = cos_t * cos_t;
        crate::numerics::math::exp(-r) / (2.0 * PI * self.beta * self.beta * c2 * c2)
    }

    /// D(h) in sr⁻¹ for a unit half vector `h` (0 below the horizon).
    #[inline]
    pub fn d(&self, h: DVec3) -> f64 {
        if !(h.z > 0.0) {
            return 0.0;
        }
        let sin_t = libm::sqrt(h.x * h.x + h.y * h.y);
        self.d_tan_cos(sin_t / h.z, h.z)
    }

    /// D at polar angle θ ∈ [0, π/2].
    #[inline]
    pub fn d_theta(&self, theta: f64) -> f64 {
        let (s, c) = libm::sincos(theta);
        if !(c > 0.0) {
            return 0.0;
        }
        self.d_tan_cos(s / c, c)
    }

    /// Smith Λ(w) for a direction `w` (0 at the normal, +∞ at the horizon).
    #[inline]
    pub fn lambda(&self, w: DVec3) -> f64 {
        let sin_t = libm::sqrt(w.x * w.x + w.y * w.y);
        if sin_t == 0.0 {
            return 0.0;
        }
        // tanθ = sinθ / max(cosθ, 1e−12) (physics.md §11 grazing row).
        let tan_t = sin_t / w.z.max(1e-12);
        smith_lambda_exp(1.0 / (self.beta * tan_t))
    }

    /// Smith masking G₁(w) = 1/(1 + Λ(w)); 0 for directions below the horizon.
    #[inline]
    pub fn g1(&self, w: DVec3) -> f64 {
        if !(w.z > 0.0) {
            return 0.0;
        }
        1.0 / (1.0 + self.lambda(w))
    }

    /// Height-correlated Smith masking–shadowing 1/(1 + Λ(i) + Λ(o)).
    #[inline]
    pub fn g2(&self, wi: DVec3, wo: DVec3) -> f64 {
        if !(wi.z > 0.0 && wo.z > 0.0) {
            return 0.0;
        }
        1.0 / (1.0 + self.lambda(wi) + self.lambda(wo))
    }

    /// Draws a half vector from the density D(h) cosθ_h (solid angle) using
    /// two uniform numbers in [0, 1).
    pub fn sample(&self, u: [f64; 2]) -> DVec3 {
        let r = inverse_gamma2_cdf(u[0]);
        let tan_t = self.beta * r;
        let cos_t = 1.0 / libm::sqrt(1.0 + tan_t * tan_t);
        let sin_t = tan_t * cos_t;
        let (sp, cp) = libm::sincos(2.0 * PI * u[1]);
        DVec3::new(sin_t * cp, sin_t * sp, cos_t)
    }

    /// Solid-angle density of [`ExponentialNdf::sample`]: D(h) cosθ_h.
    #[inline]
    pub fn pdf(&self, h: DVec3) -> f64 {
        self.d(h) * h.z.max(0.0)
    }
}

/// r − ln(1 + r), with a series below r = 0.1 where the difference cancels.
fn r_minus_log1p(r: f64) -> f64 {
    if r < 0.1 {
        // Σ_{k≥2} (−1)^k r^k / k; 16 terms reach 1e−17 relative at r = 0.1.
        let mut term = r * r;
        let mut sum = 0.0;
        for k in 2..18 {
            let t = term / k as f64;
            sum += if k % 2 == 0 { t } else { -t };
            term *= r;
        }
        sum
    } else {
        r - libm::log1p(r)
    }
}

/// Inverse of the regularized lower incomplete gamma P(2, r) = 1 − (1 + r)e^{−r}.
///
/// With L = −ln(1 − ξ), the equation is φ(r) = r − ln(1 + r) = L, where φ is
/// increasing and convex on r ≥ 0 (φ' = r/(1+r)). Newton steps from a start
/// right of the root converge monotonically; near r = 0 the start comes from
/// φ ≈ r²/2 − r³/3 and the iteration is done in the variable r itself with φ
/// evaluated by the cancellation-free series. Returns +∞ for ξ ≥ 1 and 0 for
/// ξ ≤ 0 or NaN.
pub(crate) fn inverse_gamma2_cdf(xi: f64) -> f64 {
    if !(xi > 0.0) {
        return 0.0;
    }
    if xi >= 1.0 {
        return f64::INFINITY;
    }
    let l = -libm::log1p(-xi);
    // Start: small-L root of r²/2 − r³/3 = L, large-L root of r = L + ln(1+r).
    let mut r = if l < 0.5 {
        let s = libm::sqrt(2.0 * l);
        s + s * s / 3.0
    } else {
        let r0 = l + libm::log1p(l);
        l + libm::log1p(r0) + 0.1
    };
    for _ in 0..40 {
        let f = r_minus_log1p(r) - l;
        let dfdr = r / (1.0 + r);
        if !(dfdr > 0.0) {
            break;
        }
        let step = f / dfdr;
        let next = (r - step).max(0.5 * r);
        if (next - r).abs() <= 1e-16 * r {
            r = next;
            break;
        }
        r = next;
    }
    r
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn inverse_gamma_cdf_is_an_inverse() {
        for i in 0..=2000 {
            let xi = (i as f64 / 2000.0).powi(3).min(1.0 - 1e-16);
            let r = inverse_gamma2_cdf(xi);
            // Residual in the log variable, relative.
            let l = -libm::log1p(-xi);
            let res = if l > 0.0 {
                (r_minus_log1p(r) - l).abs() / l
            } else {
                r
            };
            assert!(res < 1e-13, "xi = {xi}: r = {r}, residual {res}");
        }
        for xi in [1e-300, 1e-20, 1e-10] {
            // φ(r) = r²/2 − r³/3 + … = ξ + O(ξ²).
            let r = inverse_gamma2_cdf(xi);
            let phi = r * r / 2.0 - r * r * r / 3.0 + r * r * r * r / 4.0;
            assert!((phi / xi - 1.0).abs() < 1e-9, "{xi} -> {r}");
        }
        assert_eq!(inverse_gamma2_cdf(1.0), f64::INFINITY);
        assert_eq!(inverse_gamma2_cdf(f64::NAN), 0.0);
    }

    /// ∫ D cosθ dω over the hemisphere, by Gauss–Legendre in the slope radius.
    fn projected_mass(ndf: &ExponentialNdf) -> f64 {
        // Simpson's rule in the slope radius r = tanθ/β on [0, 60], mapped
        // back to θ so that d_theta and the Jacobian dθ/dr are exercised.
        let n = 20000;
        let h = 60.0 / n as f64;
        let f = |r: f64| {
            let theta = libm::atan(ndf.beta * r);
            let c = libm::cos(theta);
            let dtheta_dr = ndf.beta * c * c;
            ndf.d_theta(theta) * c * libm::sin(theta) * dtheta_dr * 2.0 * PI
        };
        let mut sum = f(0.0) + f(60.0);
        for j in 1..n {
            sum += f(j as f64 * h) * if j % 2 == 1 { 4.0 } else { 2.0 };
        }
        sum * h / 3.0
    }

    #[test]
    fn normalised() {
        for beta in [0.01, 0.1, 0.5, 2.0] {
            let ndf = ExponentialNdf::new(beta).unwrap();
            let m = projected_mass(&ndf);
            assert!((m - 1.0).abs() < 1e-10, "β = {beta}: ∫D cos = {m}");
        }
    }
}
