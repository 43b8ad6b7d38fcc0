//! The RGL format's angle parameterisation and the small geometry around it.
//!
//! A direction's elevation θ ∈ [0, π/2] is stored as u = √(2θ/π) (dense
//! nodes near the normal, where specular lobes live) and its azimuth
//! φ ∈ [−π, π] as (φ + π)/2π, exactly as Mitsuba 3's and pbrt-v4's
//! `measured` readers map them.

use brdf::DVec3;
use core::f64::consts::{FRAC_2_PI, FRAC_PI_2, PI, TAU};

/// u of an elevation θ (radians).
pub fn theta_to_u(theta: f64) -> f64 {
    (theta * FRAC_2_PI).max(0.0).sqrt()
}

/// Elevation θ (radians) of u.
pub fn u_to_theta(u: f64) -> f64 {
    u * u * FRAC_PI_2
}

/// u of an azimuth φ (radians, −π..π).
pub fn phi_to_u(phi: f64) -> f64 {
    (phi + PI) / TAU
}

/// Azimuth φ (radians) of u.
pub fn u_to_phi(u: f64) -> f64 {
    (2.0 * u - 1.0) * PI
}

/// Elevation of a unit vector, accurate near the normal (the readers' form:
/// twice the arcsine of half the chord to +z).
pub fn elevation(d: DVec3) -> f64 {
    let chord = (d.x * d.x + d.y * d.y + (d.z - 1.0) * (d.z - 1.0)).sqrt();
    2.0 * (0.5 * chord).clamp(-1.0, 1.0).asin()
}

/// The unit vector of (θ, φ).
pub fn direction(theta: f64, phi: f64) -> DVec3 {
    let (st, ct) = theta.sin_cos();
    let (sp, cp) = phi.sin_cos();
    DVec3::new(st * cp, st * sp, ct)
}

/// Node k of n nodes spread evenly over [0, 1].
pub fn node(k: usize, n: usize) -> f64 {
    k as f64 / (n - 1) as f64
}

/// ∫₀^{2π} max(0, ω·m) dφ_m for ω at elevation `theta` and m at `theta_m`:
/// the azimuthal part of a projected area, in closed form.
pub fn azimuthal_cosine_integral(theta: f64, theta_m: f64) -> f64 {
    let a = theta.cos() * theta_m.cos();
    let b = theta.sin() * theta_m.sin();
    if b <= a.abs() {
        TAU * a.max(0.0)
    } else {
        let phi0 = (-a / b).clamp(-1.0, 1.0).acos();
        2.0 * (a * phi0 + b * phi0.sin())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn maps_invert() {
        for k in 0..=100 {
            let u = k as f64 / 100.0;
            assert!((theta_to_u(u_to_theta(u)) - u).abs() < 1e-15);
            assert!((phi_to_u(u_to_phi(u)) - u).abs() < 1e-15);
        }
        for &t in &[0.0, 1e-9, 0.3, 1.2, FRAC_PI_2] {
            assert!((elevation(direction(t, 0.7)) - t).abs() < 1e-15);
        }
    }

    #[test]
    fn azimuthal_integral_matches_quadrature() {
        for &(t, tm) in &[
            (0.0, 0.4),
            (0.5, 0.3),
            (1.2, 0.9),
            (1.5, 1.5),
            (FRAC_PI_2, 0.2),
        ] {
            let n = 200_000;
            let w = direction(t, 0.0);
            let q: f64 = (0..n)
                .map(|i| {
                    let phi = (i as f64 + 0.5) / n as f64 * TAU;
                    w.dot(direction(tm, phi)).max(0.0)
                })
                .sum::<f64>()
                * TAU
                / n as f64;
            let c = azimuthal_cosine_integral(t, tm);
            assert!((q - c).abs() < 1e-8, "{t} {tm}: {q} vs {c}");
        }
    }
}
