//! Microfacet conductors: GGX (Trowbridge–Reitz) and Beckmann normal
//! distributions, height-correlated Smith shadowing, visible-normal sampling.
//!
//! Both distributions are written in their anisotropic form with roughness
//! `alpha_x`, `alpha_y` along the tangent axes; all formulas use the
//! tangential components of the half vector so that α → 0 stays exact.

mod beckmann;
mod conductor;
mod ggx;
mod rotated;
mod rows;

pub use conductor::{MicrofacetConductor, SmoothConductor};
pub use rotated::Rotated;

use crate::error::{BrdfError, check_range};
use glam::DVec3;

/// Smallest roughness accepted; below it the lobe is narrower than f64
/// evaluation can resolve reliably and a smooth conductor is the right model.
pub const ALPHA_MIN: f64 = 1e-4;
/// Largest roughness accepted.
pub const ALPHA_MAX: f64 = 1.0;
const ALPHA_VALID: &str = "1e-4 ≤ alpha ≤ 1 (use a smooth conductor below 1e-4)";

/// Directions with cosθ below this count as on the horizon, where the
/// microfacet conductors return f = pdf = 0 and no sample.
///
/// Above it the models return their analytic value, which is continuous up
/// to the horizon but not small there: with height-correlated Smith
/// shadowing, at a grazing mirror pair f ≈ D/(2α(cosθi + cosθo)) grows like
/// 1/cosθ while f·cosθi·cosθo stays below D/4. The threshold sits where the
/// products of two Smith terms (~(α cosθ)²) would reach subnormal numbers
/// and `eval`, `pdf` and `sample` would stop agreeing to round-off; no
/// direction a renderer or a degree-valued query produces comes near it
/// (cos 89.999999999999° = 1.7e−14).
pub const COS_HORIZON: f64 = 1e-100;

/// Which microfacet normal distribution.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum NdfKind {
    /// Trowbridge–Reitz / GGX: heavy-tailed slopes, `D ∝ (1 + s²/α²)^-2`.
    Ggx,
    /// Beckmann: Gaussian slopes with per-axis slope variance α²/2.
    Beckmann,
}

/// A microfacet normal distribution with its Smith shadowing and
/// visible-normal sampling.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Distribution {
    kind: NdfKind,
    alpha_x: f64,
    alpha_y: f64,
    /// 1/αx, 1/αy and 1/(π αx αy): evaluation multiplies instead of dividing.
    inv_alpha_x: f64,
    inv_alpha_y: f64,
    d_scale: f64,
}

impl Distribution {
    /// The largest value of D. GGX peaks at the normal, 1/(π αx αy) (the
    /// denominator's (h²/α²)-weighted length is ≥ 1 for α ≤ 1). Beckmann
    /// along an azimuth of roughness α, e^{−t/α²}(1 + t)²/(π αx αy) in
    /// t = tan²θ, peaks at the normal for α ≤ 1/√2 and at t = 2α² − 1 above,
    /// where it is 4α⁴ e^{1/α² − 2}/(π αx αy); the larger α bounds every
    /// azimuth.
    pub fn d_max(&self) -> f64 {
        let a = self.alpha_x.max(self.alpha_y);
        match self.kind {
            NdfKind::Beckmann if a * a > 0.5 => {
                let a2 = a * a;
                self.d_scale * 4.0 * a2 * a2 * crate::numerics::math::exp(1.0 / a2 - 2.0)
            }
            _ => self.d_scale,
        }
    }

    /// Builds a distribution; `alpha_x`, `alpha_y` in [1e-4, 1].
    pub fn new(kind: NdfKind, alpha_x: f64, alpha_y: f64) -> Result<Distribution, BrdfError> {
        let alpha_x = check_range("alpha_x", alpha_x, ALPHA_MIN, ALPHA_MAX, ALPHA_VALID)?;
        let alpha_y = check_range("alpha_y", alpha_y, ALPHA_MIN, ALPHA_MAX, ALPHA_VALID)?;
        Ok(Distribution {
            kind,
            alpha_x,
            alpha_y,
            inv_alpha_x: 1.0 / alpha_x,
            inv_alpha_y: 1.0 / alpha_y,
            d_scale: 1.0 / (core::f64::consts::PI * alpha_x * alpha_y),
        })
    }

    /// GGX with roughness `alpha_x`, `alpha_y`.
    pub fn ggx(alpha_x: f64, alpha_y: f64) -> Result<Distribution, BrdfError> {
        Distribution::new(NdfKind::Ggx, alpha_x, alpha_y)
    }

    /// Beckmann with roughness `alpha_x`, `alpha_y`.
    pub fn beckmann(alpha_x: f64, alpha_y: f64) -> Result<Distribution, BrdfError> {
        Distribution::new(NdfKind::Beckmann, alpha_x, alpha_y)
    }

    /// The distribution family.
    pub fn kind(&self) -> NdfKind {
        self.kind
    }

    /// Roughness along the tangent x axis.
    pub fn alpha_x(&self) -> f64 {
        self.alpha_x
    }

    /// Roughness along the tangent y axis.
    pub fn alpha_y(&self) -> f64 {
        self.alpha_y
    }

    /// Normal distribution D(h) in sr⁻¹, normalised so that ∫ D(h) cosθh dω = 1.
    /// Zero for `h` in the lower hemisphere.
    #[inline]
    pub fn d(&self, h: DVec3) -> f64 {
        if h.z <= 0.0 {
            return 0.0;
        }
        match self.kind {
            NdfKind::Ggx => ggx::d(h, self.inv_alpha_x, self.inv_alpha_y, self.d_scale),
            NdfKind::Beckmann => beckmann::d(h, self.alpha_x, self.alpha_y),
        }
    }

    /// D at the half vector of `wi` and `wo` (both with z > 0), and
    /// cos²θd = (wi·h)² = |wi + wo|²/4 (exact, never 0/0 at grazing).
    ///
    /// GGX is homogeneous of degree 0 in h up to the factor |v|⁴, so it is
    /// evaluated on the unnormalised v = wi + wo, and Fresnel takes cos²θd
    /// (as the ratio |v|²/4): no square root on the path.
    #[inline]
    pub(crate) fn d_half(&self, wi: DVec3, wo: DVec3) -> Option<(f64, f64)> {
        let v = wi + wo;
        let len2 = v.length_squared();
        if !(len2 > 0.0 && len2.is_finite() && v.z > 0.0) {
            return None;
        }
        Some((self.d_unnormalised(v, len2), 0.25 * len2))
    }

    /// D(v/|v|) for v with v.z > 0 and `len2` = |v|² > 0.
    #[inline]
    pub(crate) fn d_unnormalised(&self, v: DVec3, len2: f64) -> f64 {
        match self.kind {
            NdfKind::Ggx => {
                let (num, den) = self.ggx_d_fraction(v, len2);
                num / den
            }
            NdfKind::Beckmann => {
                let (num, den) = self.beckmann_d_fraction(v, len2);
                num / den
            }
        }
    }

    /// [`Distribution::d_unnormalised`] for a Beckmann distribution, as an
    /// unformed fraction: e^{−tan²θ/α²} / (π αx αy cos⁴θ) with tan²θ/α² =
    /// (vx²/αx² + vy²/αy²)/vz² and cos²θ = vz²/|v|², both invariant under the
    /// scale of v, so v needs no normalisation (a square root and a division
    /// fewer). Where cos⁴θ underflows, e^{−tan²θ/α²} has underflowed first
    /// for every α ≤ 1 (it is positive only for tan²θ < 745 α²), so the
    /// fraction is 0/0 there, which the callers' `finite_nonneg` turns into
    /// the limit 0.
    #[inline(always)]
    pub(crate) fn beckmann_d_fraction(&self, v: DVec3, len2: f64) -> (f64, f64) {
        let x = v.x * self.inv_alpha_x;
        let y = v.y * self.inv_alpha_y;
        let z2 = v.z * v.z;
        let cos2 = z2 / len2;
        (
            crate::numerics::math::exp(-(x * x + y * y) / z2),
            core::f64::consts::PI * self.alpha_x * self.alpha_y * (cos2 * cos2),
        )
    }

    /// [`Distribution::d_unnormalised`] for a GGX distribution, as an unformed
    /// fraction (numerator, denominator > 0).
    #[inline(always)]
    pub(crate) fn ggx_d_fraction(&self, v: DVec3, len2: f64) -> (f64, f64) {
        let x = v.x * self.inv_alpha_x;
        let y = v.y * self.inv_alpha_y;
        let s = x * x + y * y + v.z * v.z;
        (self.d_scale * (len2 * len2), s * s)
    }

    /// Smith Λ(w) as a fraction (num, den), Λ = num/den with den > 0 for
    /// w.z > 0, so that callers combine Λi, Λo, G1 and G2 with one division.
    /// GGX: Λ = (√(1 + a/z²) − 1)/2 with a = αx²x² + αy²y², rationalised to
    /// a / (2z(z + √(a + z²))): no cancellation, no division. Both parts are
    /// homogeneous of degree 2 in w, so for GGX `w` need not be normalised.
    ///
    /// Beckmann: Λ(a) < 3.3·10⁻¹³ for a = 1/(α tanθ) ≥ 4.7 (mpmath), and the
    /// conductor formulas use Λ only in sums with 1 (G1 = 1/(1 + Λ),
    /// G2 = 1/(1 + Λi + Λo)): there it is taken as 0 (G1 and G2 within
    /// 6.6·10⁻¹³ relative, to the last bit from a = 5.8 on), without the exp
    /// and erfc. Near the normal, and for every direction of a smooth surface
    /// (α ≤ 0.05 up to 77°), that is most calls.
    #[inline]
    pub(crate) fn lambda_frac(&self, w: DVec3) -> (f64, f64) {
        match self.kind {
            NdfKind::Ggx => self.ggx_lambda_frac(w),
            NdfKind::Beckmann => {
                let ax = self.alpha_x * w.x;
                let ay = self.alpha_y * w.y;
                // a² = z² / (αx²x² + αy²y²) ≥ 4.7².
                const A2: f64 = beckmann::LAMBDA_NEGLIGIBLE_A * beckmann::LAMBDA_NEGLIGIBLE_A;
                let q = ax * ax + ay * ay;
                if w.z > 0.0 && q * A2 <= w.z * w.z {
                    return (0.0, 1.0);
                }
                (beckmann::lambda_qz(q, w.z), 1.0)
            }
        }
    }

    /// [`Distribution::lambda_frac`] for a GGX distribution.
    #[inline(always)]
    pub(crate) fn ggx_lambda_frac(&self, w: DVec3) -> (f64, f64) {
        let ax = self.alpha_x * w.x;
        let ay = self.alpha_y * w.y;
        let a = ax * ax + ay * ay;
        let z = w.z;
        (a, 2.0 * z * (z + libm::sqrt(a + z * z)))
    }

    /// Smith Λ(w): G1(w) = 1 / (1 + Λ(w)). Infinite at and below the horizon.
    #[inline]
    pub fn lambda(&self, w: DVec3) -> f64 {
        if w.z <= 0.0 {
            return f64::INFINITY;
        }
        // α² tan²θ along w's azimuth, from tangential components (exact as α → 0).
        let t = (self.alpha_x * self.alpha_x * w.x * w.x + self.alpha_y * self.alpha_y * w.y * w.y)
            / (w.z * w.z);
        match self.kind {
            NdfKind::Ggx => ggx::lambda(t),
            NdfKind::Beckmann => beckmann::lambda(t),
        }
    }

    /// Smith masking G1(w).
    #[inline]
    pub fn g1(&self, w: DVec3) -> f64 {
        1.0 / (1.0 + self.lambda(w))
    }

    /// Height-correlated Smith masking-shadowing G2(wi, wo) = 1/(1 + Λi + Λo).
    #[inline]
    pub fn g2(&self, wi: DVec3, wo: DVec3) -> f64 {
        1.0 / (1.0 + self.lambda(wi) + self.lambda(wo))
    }

    /// Samples a microfacet normal from the distribution of normals visible
    /// from `wi`, D_wi(h) = G1(wi) max(0, wi·h) D(h) / cosθi. `wi.z > 0`.
    #[inline]
    pub fn sample_visible(&self, wi: DVec3, u: [f64; 2]) -> DVec3 {
        match self.kind {
            NdfKind::Ggx => normalize_or_none(ggx::sample_visible_unnormalised(
                wi,
                self.alpha_x,
                self.alpha_y,
                u,
            ))
            .unwrap_or(DVec3::Z),
            NdfKind::Beckmann => beckmann::sample_visible(wi, self.alpha_x, self.alpha_y, u),
        }
    }

    /// [`Distribution::sample_visible`] for a Beckmann distribution, up to a
    /// positive factor (h.z = 1, no normalisation: a square root and a
    /// division fewer), with Smith Λ(wi), which the inversion computes on
    /// the way, and e^{−|s|²} of the sampled stretched slopes s, from which
    /// [`Distribution::beckmann_d_from_slopes`] gives D without another
    /// division.
    #[inline]
    pub(crate) fn beckmann_sample_visible_with_lambda(
        &self,
        wi: DVec3,
        u: [f64; 2],
    ) -> (DVec3, f64, f64) {
        beckmann::sample_visible_with_lambda(wi, self.alpha_x, self.alpha_y, u)
    }

    /// Beckmann D(h/|h|) for h = (−αx sx, −αy sy, 1), the normal of the
    /// stretched slopes s, from `exp_minus_s2` = e^{−|s|²} and `len2` = |h|²:
    /// tan²θ/α² along h's azimuth is |s|² and cos²θ = 1/|h|², so
    /// D = e^{−|s|²} |h|⁴ / (π αx αy).
    #[inline(always)]
    pub(crate) fn beckmann_d_from_slopes(&self, exp_minus_s2: f64, len2: f64) -> f64 {
        exp_minus_s2 * (len2 * len2) * self.d_scale
    }

    /// [`Distribution::sample_visible`] for a GGX distribution, up to a
    /// positive factor (z ≥ 0, may be zero for degenerate input): no
    /// normalisation, two divisions and a square root fewer.
    #[inline(always)]
    pub(crate) fn ggx_sample_visible_unnormalised(&self, wi: DVec3, u: [f64; 2]) -> DVec3 {
        ggx::sample_visible_unnormalised(wi, self.alpha_x, self.alpha_y, u)
    }

    /// Density (per solid angle of `h`) of [`Distribution::sample_visible`].
    #[inline]
    pub fn pdf_visible(&self, wi: DVec3, h: DVec3) -> f64 {
        if wi.z <= 0.0 {
            return 0.0;
        }
        let cos_ih = wi.dot(h);
        if cos_ih <= 0.0 {
            return 0.0;
        }
        self.g1(wi) * cos_ih * self.d(h) / wi.z
    }
}

/// Normalises a vector, returning `None` for zero length or non-finite input.
#[inline]
pub(crate) fn normalize_or_none(v: DVec3) -> Option<DVec3> {
    let l2 = v.length_squared();
    if l2 > 0.0 && l2.is_finite() {
        Some(v * (1.0 / libm::sqrt(l2)))
    } else {
        None
    }
}

#[cfg(test)]
mod grazing_tests;
