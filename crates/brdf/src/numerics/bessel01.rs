//! Modified Bessel functions of the second kind of integer order 0 and 1, and
//! the repeated integral Ki₁(x) = ∫ₓ^∞ K₀(t) dt, in f64 without `std`.
//!
//! They feed the closed-form Smith Λ of the exponential NDF (`physics.md`
//! §8.2). Two representations cover the whole positive axis:
//!
//! * `x < 1`: the ascending series (Abramowitz & Stegun 9.6.13, 9.6.11 and its
//!   term-by-term integral). Terms shrink like (x²/4)ᵏ/k!², so 12 terms reach
//!   round-off, and the only subtraction (the logarithm against the harmonic
//!   sums) loses less than one digit.
//! * `x ≥ 1`: the integral representations
//!   eˣK_ν(x) = ∫₀^∞ e^{−x(cosh t − 1)} cosh νt dt and
//!   eˣKi₁(x) = ∫₀^∞ e^{−x(cosh t − 1)} / cosh t dt,
//!   summed with the trapezoidal rule. The integrands are analytic in the strip
//!   |Im t| < d, so the rule converges like e^{−2πd/h}; d shrinks like
//!   √(2/x) for large x to keep the integrand bounded inside the strip, and the
//!   step follows it. Every term is positive: no cancellation.
//!
//! Accuracy: ≤ 3e−15 relative against 40-digit mpmath values (unit tests).

use core::f64::consts::{FRAC_PI_2, PI};

/// Euler–Mascheroni constant.
const EULER_GAMMA: f64 = 0.577_215_664_901_532_9;

/// Below this argument the ascending series is used.
const SERIES_MAX: f64 = 1.0;

/// Number of series terms; at x = 1 the 12th term is below 1e−20 of the sum.
const SERIES_TERMS: usize = 14;

/// Trapezoidal sum of `∫₀^∞ e^{−x(cosh t − 1)} w(t) dt` for `x ≥ 1`, where the
/// weight `w` grows at most like cosh 2t.
fn scaled_integral(x: f64, w: impl Fn(f64) -> f64) -> f64 {
    // Strip half-width: the integrand is bounded by e^{x(1 − cos d)} ≤ e inside
    // |Im t| < d, and 1/cosh t has its poles at ±iπ/2.
    let d = libm::sqrt(2.0 / x).min(1.2);
    // e^{−2πd/h} = e^{−40} ≈ 4e−18.
    let h = 2.0 * PI * d / 40.0;
    let mut sum = 0.5 * w(0.0);
    let mut j = 1.0;
    loop {
        let t = j * h;
        let sh = libm::sinh(0.5 * t);
        let term = libm::exp(-2.0 * x * sh * sh) * w(t);
        sum += term;
        if term <= 1e-18 * sum || j > 4000.0 {
            break;
        }
        j += 1.0;
    }
    sum * h
}

// K₀ and ∫K₀ serve only the tests, which check Ki₁ = π/2 − ∫₀ˣK₀ against them.
#[cfg(test)]
/// Returns (I₀-like sum Σ tᵏ/k!², Σ tᵏ/k!² Hₖ) with t = x²/4.
fn series_k0_parts(x: f64) -> (f64, f64) {
    let t = 0.25 * x * x;
    let (mut term, mut harmonic) = (1.0, 0.0);
    let (mut i0, mut h_sum) = (1.0, 0.0);
    for k in 1..SERIES_TERMS {
        let kf = k as f64;
        term *= t / (kf * kf);
        harmonic += 1.0 / kf;
        i0 += term;
        h_sum += term * harmonic;
    }
    (i0, h_sum)
}

#[cfg(test)]
/// K₀(x), x > 0. Returns +∞ at x = 0 and 0 for x ≥ ~745 (underflow); NaN
/// for negative or NaN input.
pub fn k0(x: f64) -> f64 {
    if x.is_nan() || x < 0.0 {
        return f64::NAN;
    }
    if x == 0.0 {
        return f64::INFINITY;
    }
    if x < SERIES_MAX {
        let (i0, h_sum) = series_k0_parts(x);
        return -(libm::log(0.5 * x) + EULER_GAMMA) * i0 + h_sum;
    }
    k0_scaled(x) * libm::exp(-x)
}

#[cfg(test)]
/// eˣ K₀(x), for x ≥ 1 through the integral, below through [`k0`].
pub fn k0_scaled(x: f64) -> f64 {
    if x.is_nan() || x < SERIES_MAX {
        return k0(x) * libm::exp(x);
    }
    if x == f64::INFINITY {
        return 0.0;
    }
    scaled_integral(x, |_| 1.0)
}

/// K₁(x), x > 0. Returns +∞ at x = 0 and 0 for large x (underflow).
pub fn k1(x: f64) -> f64 {
    if x.is_nan() || x < 0.0 {
        return f64::NAN;
    }
    if x == 0.0 {
        return f64::INFINITY;
    }
    if x < SERIES_MAX {
        let t = 0.25 * x * x;
        // ψ(k+1) + ψ(k+2) = −2γ + H_k + H_{k+1}.
        let mut term = 1.0; // tᵏ/(k!(k+1)!)
        let mut h_k = 0.0;
        let mut i1_sum = 1.0;
        let mut psi_sum = -2.0 * EULER_GAMMA + 1.0;
        for k in 1..SERIES_TERMS {
            let kf = k as f64;
            term *= t / (kf * (kf + 1.0));
            h_k += 1.0 / kf;
            let h_k1 = h_k + 1.0 / (kf + 1.0);
            i1_sum += term;
            psi_sum += term * (-2.0 * EULER_GAMMA + h_k + h_k1);
        }
        let i1 = 0.5 * x * i1_sum;
        return 1.0 / x + libm::log(0.5 * x) * i1 - 0.25 * x * psi_sum;
    }
    k1_scaled(x) * libm::exp(-x)
}

/// eˣ K₁(x).
pub fn k1_scaled(x: f64) -> f64 {
    if x.is_nan() || x < SERIES_MAX {
        return k1(x) * libm::exp(x);
    }
    if x == f64::INFINITY {
        return 0.0;
    }
    scaled_integral(x, libm::cosh)
}

/// ∫₀ˣ K₀(t) dt for 0 ≤ x < 1 by the integrated ascending series.
fn int_k0_series(x: f64) -> f64 {
    let t = 0.25 * x * x;
    let log_term = -libm::log(0.5 * x) - EULER_GAMMA;
    let mut term = 1.0; // (x/2)^{2k}/k!²
    let mut harmonic = 0.0;
    let mut sum = log_term + 1.0;
    for k in 1..SERIES_TERMS {
        let kf = k as f64;
        term *= t / (kf * kf);
        harmonic += 1.0 / kf;
        let odd = 2.0 * kf + 1.0;
        sum += term / odd * (log_term + 1.0 / odd + harmonic);
    }
    x * sum
}

/// Ki₁(x) = ∫ₓ^∞ K₀(t) dt = π/2 − ∫₀ˣ K₀(t) dt, x ≥ 0.
pub fn ki1(x: f64) -> f64 {
    if x.is_nan() || x < 0.0 {
        return f64::NAN;
    }
    if x == 0.0 {
        return FRAC_PI_2;
    }
    if x < SERIES_MAX {
        return FRAC_PI_2 - int_k0_series(x);
    }
    ki1_scaled(x) * libm::exp(-x)
}

/// eˣ Ki₁(x).
pub fn ki1_scaled(x: f64) -> f64 {
    if x.is_nan() || x < SERIES_MAX {
        return ki1(x) * libm::exp(x);
    }
    if x == f64::INFINITY {
        return 0.0;
    }
    scaled_integral(x, |t| 1.0 / libm::cosh(t))
}

#[cfg(test)]
/// ∫₀ˣ K₀(t) dt (scipy's `iti0k0(x)[1]`), x ≥ 0.
pub fn int_k0(x: f64) -> f64 {
    if x.is_nan() || x < 0.0 {
        return f64::NAN;
    }
    if x < SERIES_MAX {
        return int_k0_series(x);
    }
    FRAC_PI_2 - ki1(x)
}

/// [2K₁(x) − Ki₁(x)]/π, the Smith Λ of the exponential NDF at x = 1/(β tanθ)
/// (`physics.md` §8.2), accurate in relative terms for every x > 0.
///
/// For x ≥ 1 both terms share the kernel e^{−x cosh t}, and
/// 2 cosh t − 1/cosh t = cosh 2t / cosh t > 0, so the difference is one
/// integral of a positive function: no cancellation even where Λ ≈ 1e−300.
pub fn smith_lambda_exp(x: f64) -> f64 {
    if x.is_nan() || x < 0.0 {
        return f64::NAN;
    }
    if x == 0.0 {
        return f64::INFINITY;
    }
    if x < SERIES_MAX {
        return (2.0 * k1(x) - ki1(x)) / PI;
    }
    if x > 800.0 {
        return 0.0;
    }
    let scaled = scaled_integral(x, |t| libm::cosh(2.0 * t) / libm::cosh(t));
    scaled * libm::exp(-x) / PI
}

#[cfg(test)]
mod tests {
    use super::*;

    /// (x, K₀, K₁, Ki₁) from mpmath: `besselk` at 30 digits; Ki₁ as
    /// π/2 − (πx/2)[K₀L₋₁ + K₁L₀] (modified Struve functions) at 400 digits,
    /// which agrees with the quadrature of e^{−x cosh t}/cosh t to 1e−17.
    // 20 significant digits as mpmath printed them.
    #[allow(clippy::excessive_precision)]
    const REF: &[(f64, f64, f64, f64)] = &[
        (
            1e-08,
            1.8536612259610778388e+1,
            9.9999999999999902725e+7,
            1.5707961314287740231,
        ),
        (
            0.0001,
            9.326271913450274873,
            9.999999508686404478e+3,
            1.5697636996052448592,
        ),
        (
            0.01,
            4.7212447301610949443,
            9.9973894118296245561e+1,
            1.5135848052401720667,
        ),
        (
            0.1,
            2.4270690247020165578,
            9.8538447808706055744,
            1.2286318830369222187,
        ),
        (
            0.5,
            9.2441907122766586178e-1,
            1.6564411200033008937,
            6.4369380586374754578e-1,
        ),
        (
            0.999,
            4.2162685730813515851e-1,
            6.0293127632301203684e-1,
            3.2870780373355560702e-1,
        ),
        (
            1.0,
            4.2102443824070833334e-1,
            6.0190723019723457474e-1,
            3.2828647817111835301e-1,
        ),
        (
            1.5,
            2.1380556264752573672e-1,
            2.7738780045684381609e-1,
            1.7621386306217573045e-1,
        ),
        (
            2.0,
            1.1389387274953343565e-1,
            1.3986588181652242728e-1,
            9.7120592478067936717e-2,
        ),
        (
            3.0,
            3.4739504386279248072e-2,
            4.0156431128194184377e-2,
            3.084823672701536016e-2,
        ),
        (
            5.0,
            3.6910983340425942747e-3,
            4.0446134454521642084e-3,
            3.4089360665305699256e-3,
        ),
        (
            10.0,
            1.7780062316167651811e-5,
            1.8648773453825584597e-5,
            1.7015178917759400094e-5,
        ),
        (
            20.0,
            5.7412378153365242927e-10,
            5.8830579695570381777e-10,
            5.6088163165514969967e-10,
        ),
        (
            50.0,
            3.4101677497894955139e-23,
            3.4441022267175556126e-23,
            3.3771991805743436873e-23,
        ),
        (
            100.0,
            4.6566282291759020189e-45,
            4.6798537356369092866e-45,
            4.633741870050395952e-45,
        ),
        (
            300.0,
            3.7236948548891432633e-132,
            3.7298958583323726986e-132,
            3.71752457576934734e-132,
        ),
        (
            700.0,
            4.669776431685376881e-306,
            4.6731107967079661091e-306,
            4.6664491838110553133e-306,
        ),
    ];

    fn rel(a: f64, b: f64) -> f64 {
        ((a - b) / b).abs()
    }

    #[test]
    fn matches_mpmath() {
        let mut worst = [0.0f64; 3];
        for &(x, k0r, k1r, ki1r) in REF {
            let e = [rel(k0(x), k0r), rel(k1(x), k1r), rel(ki1(x), ki1r)];
            for j in 0..3 {
                worst[j] = worst[j].max(e[j]);
            }
            assert!(e.iter().all(|&v| v < 1e-13), "x = {x}: rel errors {e:?}");
        }
        // Keep the documented bound honest.
        assert!(worst.iter().all(|&v| v < 3e-15), "worst {worst:?}");
    }

    #[test]
    fn scaled_forms_continue_across_the_switch() {
        for &x in &[0.999_999_9, 1.0, 1.000_000_1] {
            assert!(rel(k0_scaled(x), k0(x) * libm::exp(x)) < 1e-14);
            assert!(rel(k1_scaled(x), k1(x) * libm::exp(x)) < 1e-14);
        }
        assert!(rel(k0(1.0 - 1e-12), k0(1.0)) < 1e-11);
        assert!(rel(ki1(1.0 - 1e-12), ki1(1.0)) < 1e-11);
        assert!(rel(int_k0(2.0) + ki1(2.0), FRAC_PI_2) < 1e-15);
    }

    #[test]
    fn lambda_combination_equals_difference() {
        for &x in &[1.0, 1.7, 3.0, 8.0] {
            let direct = (2.0 * k1(x) - ki1(x)) / PI;
            assert!(rel(smith_lambda_exp(x), direct) < 1e-14, "x = {x}");
        }
        // Grazing limit Λ ≈ 2/(πx) − 1/2.
        let x = 1e-9;
        assert!((smith_lambda_exp(x) - (2.0 / (PI * x) - 0.5)).abs() < 1e-6);
        assert!(smith_lambda_exp(1e-300).is_finite());
        assert_eq!(smith_lambda_exp(1e4), 0.0);
    }

    #[test]
    fn edge_inputs() {
        assert_eq!(k0(0.0), f64::INFINITY);
        assert_eq!(k1(0.0), f64::INFINITY);
        assert_eq!(ki1(0.0), FRAC_PI_2);
        assert!(k0(-1.0).is_nan() && k1(f64::NAN).is_nan());
        assert_eq!(k0(1e6), 0.0);
        assert_eq!(k1_scaled(f64::INFINITY), 0.0);
    }
}
