//! A model turned about the surface normal: its anisotropic frame (αx along
//! the axis at `angle_deg` from the tangent x towards y, the convention of
//! `ghs_aniso`'s φ₀) instead of the tangent axes.
//!
//! f'(wi, wo) = f(R(−φ) wi, R(−φ) wo); a sample of the inner model is turned
//! back by R(φ). A rotation about the normal keeps cosθ and solid angle, so
//! the pdf and the Monte Carlo weight are the inner model's.

use glam::DVec3;

use crate::error::BrdfError;
use crate::model::{Bxdf, BxdfSample, Specular};

/// `inner` with its tangent frame turned by φ about the normal.
#[derive(Clone, Debug, PartialEq)]
pub struct Rotated<B> {
    inner: B,
    angle_rad: f64,
    /// cos φ, sin φ
    cs: (f64, f64),
}

impl<B: Bxdf> Rotated<B> {
    /// Turns `inner`'s frame by `angle_rad` (finite) from the tangent x towards y.
    pub fn new(inner: B, angle_rad: f64) -> Result<Self, BrdfError> {
        crate::statistics::anisotropic::check_angle(angle_rad)?;
        Ok(Rotated {
            inner,
            angle_rad,
            cs: (libm::cos(angle_rad), libm::sin(angle_rad)),
        })
    }

    /// The model in its own frame.
    pub fn inner(&self) -> &B {
        &self.inner
    }

    /// φ, radians from the tangent x towards y.
    pub fn angle_rad(&self) -> f64 {
        self.angle_rad
    }

    /// R(−φ) v: a tangent-frame direction in the inner model's frame.
    #[inline]
    fn to_inner(&self, v: DVec3) -> DVec3 {
        let (c, s) = self.cs;
        DVec3::new(c * v.x + s * v.y, c * v.y - s * v.x, v.z)
    }

    /// R(φ) v.
    #[inline]
    fn to_tangent(&self, v: DVec3) -> DVec3 {
        let (c, s) = self.cs;
        DVec3::new(c * v.x - s * v.y, s * v.x + c * v.y, v.z)
    }
}

impl<B: Bxdf> Bxdf for Rotated<B> {
    fn eval(&self, wi: DVec3, wo: DVec3, lambda_nm: f64) -> f64 {
        self.inner
            .eval(self.to_inner(wi), self.to_inner(wo), lambda_nm)
    }

    fn pdf(&self, wi: DVec3, wo: DVec3, lambda_nm: f64) -> f64 {
        self.inner
            .pdf(self.to_inner(wi), self.to_inner(wo), lambda_nm)
    }

    fn eval_pdf(&self, wi: DVec3, wo: DVec3, lambda_nm: f64) -> (f64, f64) {
        self.inner
            .eval_pdf(self.to_inner(wi), self.to_inner(wo), lambda_nm)
    }

    fn eval_pdf_many(&self, wi: DVec3, wo: DVec3, lambdas: &[f64], out: &mut [(f64, f64)]) {
        self.inner
            .eval_pdf_many(self.to_inner(wi), self.to_inner(wo), lambdas, out)
    }

    fn sample(&self, wi: DVec3, lambda_nm: f64, u: [f64; 3]) -> Option<BxdfSample> {
        let s = self.inner.sample(self.to_inner(wi), lambda_nm, u)?;
        Some(BxdfSample {
            wo: self.to_tangent(s.wo),
            ..s
        })
    }

    fn specular(&self, wi: DVec3, lambda_nm: f64) -> Specular {
        self.inner.specular(self.to_inner(wi), lambda_nm)
    }

    fn uses_lobe_choice(&self) -> bool {
        self.inner.uses_lobe_choice()
    }

    fn lobe_peak_pdf(&self, wi: DVec3) -> Option<f64> {
        self.inner.lobe_peak_pdf(self.to_inner(wi))
    }
}
