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
///
/// Returns the normal up to a positive factor. The stretched view direction
/// s = (αx x, αy y, z) is not normalised: with L = |s| and A = L + s_z, the
/// cap point scaled by L has height Lz = (1 − u)A − s_z, so the normal's
/// height is Lz + s_z = (1 − u)A and the cap radius is
/// L sinθ = √((L − Lz)(L + Lz)) = √(uA (2L − uA)): one square root and no
/// division before the normal (the sampler's critical path), and no
/// cancellation near the cap's edges.
#[inline]
pub(super) fn sample_visible_unnormalised(wi: DVec3, ax: f64, ay: f64, u: [f64; 2]) -> DVec3 {
    let s = DVec3::new(ax * wi.x, ay * wi.y, wi.z);
    let l = libm::sqrt(s.length_squared());
    let a = l + s.z;
    let ua = u[1] * a;
    let l_sin = libm::sqrt((ua * (2.0 * l - ua)).max(0.0));
    let (sp, cp) = crate::numerics::math::sincos_2pi(u[0]);
    DVec3::new(
        ax * (l_sin * cp + s.x),
        ay * (l_sin * sp + s.y),
        ((1.0 - u[1]) * a).max(0.0),
    )
}
