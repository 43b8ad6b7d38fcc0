//! Beckmann distribution.

use crate::numerics::math::exp;
use core::f64::consts::PI;
use glam::DVec3;

const SQRT_PI: f64 = 1.772_453_850_905_516;

/// D(h) for h.z > 0: exp(−tan²θ (cos²φ/αx² + sin²φ/αy²)) / (π αx αy cos⁴θ).
#[inline]
pub(super) fn d(h: DVec3, ax: f64, ay: f64) -> f64 {
    let z2 = h.z * h.z;
    let x = h.x / ax;
    let y = h.y / ay;
    let e = (x * x + y * y) / z2;
    let num = exp(-e);
    // Near the horizon cos⁴θ underflows before e^{−tan²θ/α²} does not:
    // the limit is 0, not 0/0.
    if num == 0.0 {
        return 0.0;
    }
    num / (PI * ax * ay * z2 * z2)
}

/// Λ from t = α² tan²θ, with a = 1/√t: (e^{−a²}/(a√π) − erfc a)/2.
#[inline]
pub(super) fn lambda(t: f64) -> f64 {
    if t.is_infinite() {
        return f64::INFINITY;
    }
    if t <= 0.0 {
        return 0.0;
    }
    let a = 1.0 / libm::sqrt(t);
    if a > 26.0 {
        // Both terms underflow together; Λ < 1e-290.
        return 0.0;
    }
    (0.5 * (exp(-a * a) / (a * SQRT_PI) - libm::erfc(a))).max(0.0)
}

/// Visible-normal sampling: stretch to unit roughness, draw the slope along
/// the view azimuth from its visible marginal by inverting its CDF, draw the
/// orthogonal slope from the (independent) Gaussian marginal, unstretch.
pub(super) fn sample_visible(wi: DVec3, ax: f64, ay: f64, u: [f64; 2]) -> DVec3 {
    let ws = DVec3::new(ax * wi.x, ay * wi.y, wi.z).normalize();
    let sin_t = libm::sqrt((ws.x * ws.x + ws.y * ws.y).min(1.0));
    let (cos_phi, sin_phi) = if sin_t > 0.0 {
        (ws.x / sin_t, ws.y / sin_t)
    } else {
        (1.0, 0.0)
    };
    let (sx, sy) = sample_slopes_unit(ws.z, sin_t, u);
    // Rotate back to the view azimuth and unstretch; the normal is (−s, 1).
    let rx = cos_phi * sx - sin_phi * sy;
    let ry = sin_phi * sx + cos_phi * sy;
    super::normalize_or_none(DVec3::new(-rx * ax, -ry * ay, 1.0)).unwrap_or(DVec3::Z)
}

/// Slopes of the visible normals of a unit-roughness Beckmann surface, for a
/// view at cosθ = `c`, sinθ = `s` along +x. The x-slope density is
/// ∝ (cotθ − x) e^{−x²} on x < cotθ, with CDF
/// C(x) = [cotθ (1 + erf x) + e^{−x²}/√π] / 2; y is Gaussian with variance ½.
fn sample_slopes_unit(c: f64, s: f64, u: [f64; 2]) -> (f64, f64) {
    if s < 1e-7 {
        // Normal view: the visible slope density is the isotropic Gaussian.
        let r = libm::sqrt(-libm::log1p(-u[0]));
        let (sp, cp) = libm::sincos(2.0 * PI * u[1]);
        return (r * cp, r * sp);
    }
    // Per-axis slope variance ½ at unit roughness: erfinv of a uniform on (−1, 1).
    let sy = erfinv(2.0 * u[1] - 1.0);
    let cot = c / s;
    // 1 + erf(cotθ), once for the total mass and the starting point.
    let one_plus_erf = libm::erfc(-cot);
    let total = 0.5 * (cot * one_plus_erf + exp(-cot * cot) / SQRT_PI);
    let target = u[0] * total;
    // Safeguarded Halley iteration on C(x) = target over (lo, cot].
    // C(x) < 1e-30 below −8 for every cotθ, so the root lies in (−8, cotθ].
    let mut lo = (-8.0f64).min(cot - 1.0);
    let mut hi = cot;
    // Start from the exact inverse of the cotθ → ∞ limit (the Gaussian CDF
    // rescaled to the mass below cotθ); Newton then needs a few steps only.
    // Newton polishes the start, so Giles' approximation is enough here.
    let mut x = erfinv_approx(u[0] * one_plus_erf - 1.0);
    if !(x > lo && x < hi) {
        x = 0.5 * (lo + hi);
    }
    // Slopes to 1e-11 relative are far below any visible or statistical
    // effect; asking for more makes Newton chase round-off in C(x) − target.
    for _ in 0..40 {
        let e = exp(-x * x) / SQRT_PI;
        let f = 0.5 * (cot * libm::erfc(-x) + e) - target;
        if f == 0.0 {
            break;
        }
        if f > 0.0 {
            hi = x;
        } else {
            lo = x;
        }
        // Halley's step (cubic convergence; C'' = −(1 + 2x(cotθ − x)) e^{−x²}/√π
        // comes free with C'), which saves about one erfc and one exp per
        // sample over Newton.
        let dens = (cot - x) * e;
        let curv = -(1.0 + 2.0 * x * (cot - x)) * e;
        let denom = 2.0 * dens * dens - f * curv;
        let mut next = if dens > 0.0 && denom > 0.0 {
            x - 2.0 * f * dens / denom
        } else {
            f64::NAN
        };
        if !(next > lo && next < hi) {
            next = 0.5 * (lo + hi);
        }
        let done = (next - x).abs() <= 1e-11 * (1.0 + x.abs());
        x = next;
        if done || hi - lo <= 1e-12 * (1.0 + x.abs()) {
            break;
        }
    }
    (x, sy)
}

/// Inverse error function to full f64 accuracy: Giles' single-precision
/// approximation (relative error below 3e-7 over (−1, 1)) refined by one
/// Newton step on libm's erf, which squares that error (a second step
/// changed nothing the tests can see and cost an erf and an exp).
fn erfinv(y: f64) -> f64 {
    let x = erfinv_approx(y);
    if y <= -1.0 || y >= 1.0 {
        return x;
    }
    let err = libm::erf(x) - y;
    x - err / (2.0 / SQRT_PI * exp(-x * x))
}

/// Giles' approximation of erfinv alone (relative error below 3e-7 over
/// (−1, 1)); ±6 at and beyond ±1.
fn erfinv_approx(y: f64) -> f64 {
    if y <= -1.0 {
        return -6.0;
    }
    if y >= 1.0 {
        return 6.0;
    }
    let w = -libm::log((1.0 - y) * (1.0 + y));
    if w < 5.0 {
        let w = w - 2.5;
        let mut p = 2.810_226_36e-08;
        p = 3.432_739_39e-07 + p * w;
        p = -3.523_387_7e-06 + p * w;
        p = -4.391_506_54e-06 + p * w;
        p = 0.000_218_580_87 + p * w;
        p = -0.001_253_725_03 + p * w;
        p = -0.004_177_681_64 + p * w;
        p = 0.246_640_727 + p * w;
        p = 1.501_409_41 + p * w;
        p * y
    } else {
        let w = libm::sqrt(w) - 3.0;
        let mut p = -0.000_200_214_257;
        p = 0.000_100_950_558 + p * w;
        p = 0.001_349_343_22 + p * w;
        p = -0.003_673_428_44 + p * w;
        p = 0.005_739_507_73 + p * w;
        p = -0.007_622_461_3 + p * w;
        p = 0.009_438_870_47 + p * w;
        p = 1.001_674_06 + p * w;
        p = 2.832_976_82 + p * w;
        p * y
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn erfinv_inverts_erf() {
        for i in 1..2000 {
            let y = -1.0 + i as f64 / 1000.0;
            let x = erfinv(y);
            assert!((libm::erf(x) - y).abs() < 1e-14, "y={y}");
            // The approximation that starts the slope inversion.
            let a = erfinv_approx(y);
            assert!(
                (a - x).abs() <= 3e-7 * x.abs().max(1e-3),
                "y={y}: {a} vs {x}"
            );
        }
    }
}
