//! Local shading frame helpers: normal = +z, directions point away from the surface.

use glam::DVec3;

/// Unit vector with polar angle `theta` from +z and azimuth `phi` from +x.
#[inline]
pub fn spherical(theta: f64, phi: f64) -> DVec3 {
    let (st, ct) = crate::numerics::math::sincos(theta);
    let (sp, cp) = crate::numerics::math::sincos(phi);
    DVec3::new(st * cp, st * sp, ct)
}

/// Mirror direction of `w` about the normal +z.
#[inline]
pub fn reflect_z(w: DVec3) -> DVec3 {
    DVec3::new(-w.x, -w.y, w.z)
}

/// Two unit tangents `(t, b)` so that `(t, b, n)` is right-handed and
/// orthonormal, for a unit `n`. Branch-free construction of Duff et al. 2017,
/// continuous everywhere except across the z = 0 sign flip.
#[inline]
pub fn orthonormal_basis(n: DVec3) -> (DVec3, DVec3) {
    let sign = 1.0f64.copysign(n.z);
    let a = -1.0 / (sign + n.z);
    let b = n.x * n.y * a;
    (
        DVec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x),
        DVec3::new(b, sign + n.y * n.y * a, -n.y),
    )
}

/// Half vector h = (i + o)/|i + o| and cosθd = i·h = |i + o|/2, or `None`
/// when i and o are opposite. The length form of cosθd stays exact at
/// grazing incidence, where the tangential parts of i + o cancel and i·h
/// computed from the normalised h would lose every digit.
#[inline]
pub fn half_vector(wi: DVec3, wo: DVec3) -> Option<(DVec3, f64)> {
    let v = wi + wo;
    let len = v.length();
    (len > 0.0 && len.is_finite()).then(|| (v / len, 0.5 * len))
}

/// sin²θ of a unit direction from its tangential components, without the
/// cancellation of 1 − cos²θ near the normal.
#[inline]
pub fn sin2_theta(w: DVec3) -> f64 {
    (w.x * w.x + w.y * w.y).min(1.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn basis_is_orthonormal() {
        for i in 0..200 {
            let th = (i as f64 / 199.0) * core::f64::consts::PI;
            let n = spherical(th, i as f64 * 0.7);
            let (t, b) = orthonormal_basis(n);
            assert!((t.length() - 1.0).abs() < 1e-12 && (b.length() - 1.0).abs() < 1e-12);
            assert!(t.dot(n).abs() < 1e-12 && b.dot(n).abs() < 1e-12 && t.dot(b).abs() < 1e-12);
            assert!((t.cross(b) - n).length() < 1e-12);
        }
    }
}
