//! GGX ≡ K-correlation (`physics.md` §7): the γ = 3 KC spectrum is the GGX
//! normal distribution in disguise.
//!
//! Three mappings, each with its inverse:
//!
//! * **exact half-vector identity** (the paper's eq. 11 with cosθ_d = i·h):
//!   Lc² = (1−α²)/(4α²k²cos²θ_d), σ_h² = 4k²cos²θ_d/(1−α²), and then
//!   D_GGX(θ_h) ≡ P_KC(ζ) at ζ = 2k cosθ_d sinθ_h = k|(i+o)⊥| for every θ_h.
//!   Needs α < 1; σ_h² is a formal amplitude in µm⁻², not a height variance.
//! * **the paper's version**: the same formulas with cosθ_i (= i·n) in place of
//!   cosθ_d. Exact only at the mirror direction; [`paper_relative_error`]
//!   gives its error against D.
//! * **slope space** (valid for every α > 0): Lc = 1/(2kα cosθ_i). The GGX
//!   slope pdf is (2kγ_i)²P_KC(2kγ_i s)/σ² with γ = 3, so the SSA lobe
//!   k²P(ζ)/σ² equals D/(4cosθ_i cosθ_o) at the mirror direction.
//!
//! k = 2π/λ in rad/µm, lengths in µm, directions in the local frame (n = +z).

use crate::error::{BrdfError, check_range};
use core::f64::consts::PI;
use glam::DVec3;

/// The KC parameters (γ = 3) equivalent to a GGX roughness at one geometry.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct KcEquivalent {
    /// Correlation length Lc, µm.
    pub lc_um: f64,
    /// The PSD amplitude σ² that makes P_KC equal D (µm⁻² for the
    /// half-vector identities; any positive value for the slope-space form,
    /// where only P/σ² matters).
    pub sigma2: f64,
}

impl KcEquivalent {
    /// P_KC(ζ) with γ = 3: Lc²σ²/(π(1 + Lc²ζ²)²), evaluated without overflow.
    #[inline]
    pub fn psd(&self, zeta: f64) -> f64 {
        let u2 = self.lc_um * self.lc_um * zeta * zeta;
        let l2 = self.lc_um * self.lc_um;
        l2 * self.sigma2 / (PI * (1.0 + u2) * (1.0 + u2))
    }

    /// P_KC(ζ)/σ², the unit-mass spectrum.
    #[inline]
    pub fn unit_psd(&self, zeta: f64) -> f64 {
        let u2 = self.lc_um * self.lc_um * zeta * zeta;
        self.lc_um * self.lc_um / (PI * (1.0 + u2) * (1.0 + u2))
    }
}

fn check_alpha_below_one(alpha: f64) -> Result<f64, BrdfError> {
    if alpha.is_finite() && alpha > 0.0 && alpha < 1.0 {
        Ok(alpha)
    } else {
        Err(BrdfError::OutOfRange {
            name: "alpha",
            value: alpha,
            valid: "0 < alpha < 1 for the half-vector identity (use the slope-space form for α ≥ 1)",
        })
    }
}

fn check_k(k: f64) -> Result<f64, BrdfError> {
    check_range("k", k, 1e-12, 1e12, "wavenumber 1e-12 ≤ k ≤ 1e12 rad/µm")
}

fn check_cos(cos: f64) -> Result<f64, BrdfError> {
    if cos.is_finite() && cos > 0.0 && cos <= 1.0 {
        Ok(cos)
    } else {
        Err(BrdfError::OutOfRange {
            name: "cos_theta",
            value: cos,
            valid: "0 < cos_theta ≤ 1",
        })
    }
}

/// Half-vector identity (paper's eq. 11): the γ = 3 KC parameters that
/// reproduce GGX of roughness α < 1 at wavenumber `k` when `cos_theta` is
/// cosθ_d = i·h (exact everywhere) or cosθ_i (the paper's reading, exact at
/// the mirror only).
pub fn kc_from_ggx(alpha: f64, k: f64, cos_theta: f64) -> Result<KcEquivalent, BrdfError> {
    let a = check_alpha_below_one(alpha)?;
    let k = check_k(k)?;
    let c = check_cos(cos_theta)?;
    let one_minus_a2 = (1.0 - a) * (1.0 + a);
    let kc = k * c;
    Ok(KcEquivalent {
        lc_um: libm::sqrt(one_minus_a2) / (2.0 * a * kc),
        sigma2: 4.0 * kc * kc / one_minus_a2,
    })
}

/// Inverse of [`kc_from_ggx`]: α = 1/sqrt(1 + 4k²cos²θ·Lc²) (always < 1).
pub fn ggx_alpha_from_kc(lc_um: f64, k: f64, cos_theta: f64) -> Result<f64, BrdfError> {
    let lc = check_range("lc_um", lc_um, 1e-12, 1e12, "1e-12 ≤ lc_um ≤ 1e12 (µm)")?;
    let w = 2.0 * check_k(k)? * check_cos(cos_theta)? * lc;
    Ok(1.0 / libm::hypot(1.0, w))
}

/// Slope-space identity: Lc = 1/(2kα cosθ_i), valid for every α > 0. The
/// returned σ² is 1: only P/σ² enters the SSA lobe.
pub fn kc_from_ggx_slope_space(
    alpha: f64,
    k: f64,
    cos_theta_i: f64,
) -> Result<KcEquivalent, BrdfError> {
    let a = check_range("alpha", alpha, 1e-12, 1e12, "alpha > 0")?;
    let kc = check_k(k)? * check_cos(cos_theta_i)?;
    Ok(KcEquivalent {
        lc_um: 1.0 / (2.0 * kc * a),
        sigma2: 1.0,
    })
}

/// Inverse of [`kc_from_ggx_slope_space`]: α = 1/(2k Lc cosθ_i).
pub fn ggx_alpha_from_kc_slope_space(
    lc_um: f64,
    k: f64,
    cos_theta_i: f64,
) -> Result<f64, BrdfError> {
    let lc = check_range("lc_um", lc_um, 1e-12, 1e12, "1e-12 ≤ lc_um ≤ 1e12 (µm)")?;
    Ok(1.0 / (2.0 * check_k(k)? * check_cos(cos_theta_i)? * lc))
}

/// Isotropic GGX D(h) = α²/(π(α²cos²θ_h + sin²θ_h)²) from the half vector's
/// components, free of the (α²−1)cos²+1 cancellation near the normal.
#[inline]
pub fn ggx_d(alpha: f64, h: DVec3) -> f64 {
    if !(h.z > 0.0) {
        return 0.0;
    }
    let a2 = alpha * alpha;
    let t = a2 * h.z * h.z + h.x * h.x + h.y * h.y;
    a2 / (PI * t * t)
}

/// ζ = k|(i + o)⊥| (rad/µm), which equals 2k cosθ_d sinθ_h exactly.
#[inline]
pub fn zeta(k: f64, wi: DVec3, wo: DVec3) -> f64 {
    k * libm::hypot(wi.x + wo.x, wi.y + wo.y)
}

/// Half vector and cosθ_d = i·h, or `None` for back-to-back directions.
#[inline]
pub fn half_vector(wi: DVec3, wo: DVec3) -> Option<(DVec3, f64)> {
    let s = wi + wo;
    let len = s.length();
    if !(len > 0.0) {
        return None;
    }
    let h = s / len;
    Some((h, 0.5 * len))
}

/// D_GGX(h) reconstructed as P_KC(ζ) through the exact identity (cosθ_d = i·h).
pub fn ggx_d_via_kc(alpha: f64, k: f64, wi: DVec3, wo: DVec3) -> Result<f64, BrdfError> {
    let (_, cos_d) = half_vector(wi, wo).ok_or(BrdfError::OutOfRange {
        name: "wo",
        value: -1.0,
        valid: "wo ≠ −wi",
    })?;
    Ok(kc_from_ggx(alpha, k, cos_d)?.psd(zeta(k, wi, wo)))
}

/// The paper's version: P_KC(ζ) with Lc and σ_h from cosθ_i = i·n, at the
/// physical ζ = k|(i+o)⊥|.
pub fn ggx_d_via_kc_paper(alpha: f64, k: f64, wi: DVec3, wo: DVec3) -> Result<f64, BrdfError> {
    Ok(kc_from_ggx(alpha, k, wi.z)?.psd(zeta(k, wi, wo)))
}

/// Relative error (P_paper − D)/D of the paper's (i·n) version against GGX.
///
/// It does not depend on k: with u = Lcζ the ratio is
/// [(1 + q s²)/(1 + q s² cos²θ_d/cos²θ_i)]², q = (1−α²)/α², s = sinθ_h.
pub fn paper_relative_error(alpha: f64, wi: DVec3, wo: DVec3) -> Result<f64, BrdfError> {
    let a = check_alpha_below_one(alpha)?;
    check_cos(wi.z)?;
    let (h, cos_d) = half_vector(wi, wo).ok_or(BrdfError::OutOfRange {
        name: "wo",
        value: -1.0,
        valid: "wo ≠ −wi",
    })?;
    let q = (1.0 - a) * (1.0 + a) / (a * a);
    let s2 = h.x * h.x + h.y * h.y;
    let r = cos_d / wi.z;
    // (1+qs²)/(1+qs²r²) − 1 = qs²(1−r)(1+r)/(1+qs²r²): no cancellation near r = 1.
    let x = q * s2 * (1.0 - r) * (1.0 + r) / (1.0 + q * s2 * r * r);
    Ok(x * (2.0 + x))
}

/// The SSA lobe k²P(ζ)/σ² with the slope-space Lc (γ = 3), in sr⁻¹; equals the
/// GGX BRDF D/(4cosθ_i cosθ_o) with F = G = 1 at the mirror direction.
pub fn ssa_lobe_slope_space(alpha: f64, k: f64, wi: DVec3, wo: DVec3) -> Result<f64, BrdfError> {
    let kc = kc_from_ggx_slope_space(alpha, k, wi.z)?;
    Ok(k * k * kc.unit_psd(zeta(k, wi, wo)))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::frame::spherical;

    #[test]
    fn inverses_round_trip() {
        for &a in &[1e-4, 0.02, 0.3, 0.9, 0.999] {
            for &c in &[1e-3, 0.5, 1.0] {
                let k = 2.0 * PI / 0.55;
                let kc = kc_from_ggx(a, k, c).unwrap();
                let back = ggx_alpha_from_kc(kc.lc_um, k, c).unwrap();
                assert!(((back - a) / a).abs() < 1e-13, "{a} {c}: {back}");
                let s = kc_from_ggx_slope_space(a, k, c).unwrap();
                let back = ggx_alpha_from_kc_slope_space(s.lc_um, k, c).unwrap();
                assert!(((back - a) / a).abs() < 1e-14);
            }
        }
        // Lc_paper² = (1 − α²) Lc_slope².
        let (a, k, c) = (0.3, 11.0, 0.7);
        let p = kc_from_ggx(a, k, c).unwrap().lc_um;
        let s = kc_from_ggx_slope_space(a, k, c).unwrap().lc_um;
        assert!((p * p / (s * s) - (1.0 - a * a)).abs() < 1e-14);
    }

    #[test]
    fn rejects_alpha_at_or_above_one_for_the_paper_identity() {
        assert!(kc_from_ggx(1.0, 10.0, 1.0).is_err());
        assert!(kc_from_ggx(1.5, 10.0, 1.0).is_err());
        assert!(kc_from_ggx(f64::NAN, 10.0, 1.0).is_err());
        assert!(kc_from_ggx(0.5, 10.0, 0.0).is_err());
        assert!(kc_from_ggx_slope_space(1.5, 10.0, 0.5).is_ok());
    }

    #[test]
    fn half_vector_identity_holds_off_peak() {
        let k = 2.0 * PI / 0.55;
        let wi = spherical(0.7, 0.0);
        for &a in &[0.01, 0.1, 0.5, 0.95] {
            for j in 0..50 {
                let wo = spherical(0.03 * j as f64, 2.0 + 0.1 * j as f64);
                let (h, _) = half_vector(wi, wo).unwrap();
                let d = ggx_d(a, h);
                let p = ggx_d_via_kc(a, k, wi, wo).unwrap();
                assert!(((p - d) / d).abs() < 1e-12, "α {a} j {j}: {p} vs {d}");
            }
        }
    }
}
