//! Trowbridge–Reitz (GGX) distribution.

use glam::DVec3;

/// D(h) for h.z > 0: 1 / (π αx αy (hx²/αx² + hy²/αy² + hz²)²).
#[inline]
pub(super) fn d(h: DVec3, inv_ax: f64, inv_ay: f64, d_scale: f64) -> f64 {
    let x = h.x * inv_ax;
    let y = h.y * inv_ay;
    let s = x * x + y * y + h.z * h.z;
    d_scale / (s * s)
}

/// Λ from t = α² tan²θ: (√(1+t) − 1)/2, written without cancellation.
#[inline]
pub(super) fn lambda(t: f64) -> f64 {
    if t.is_infinite() {
        return f64::INFINITY;
    }
    t / (2.0 * (1.0 + libm::sqrt(1.0 + t)))
}

/// Visible-normal sampling by the spherical-cap construction (Dupuy &
/// Benyoub 2023): in the stretched configuration the visible normals are the
/// normalised sum of the view direction and a uniform point on the spherical
/// cap below it, which needs no branch and no tangent frame.
#[inline]
pub(super) fn sample_visible(wi: DVec3, ax: f64, ay: f64, u: [f64; 2]) -> DVec3 {
    let ws = DVec3::new(ax * wi.x, ay * wi.y, wi.z).normalize();
    let z = (1.0 - u[1]) * (1.0 + ws.z) - ws.z;
    let sin_t = libm::sqrt((1.0 - z * z).max(0.0));
    let (sp, cp) = crate::math::sincos_2pi(u[0]);
    let hs = DVec3::new(sin_t * cp, sin_t * sp, z) + ws;
    let h = DVec3::new(ax * hs.x, ay * hs.y, hs.z.max(0.0));
    super::normalize_or_none(h).unwrap_or(DVec3::Z)
}
