//! Rayleigh–Rice: first-order vector perturbation theory for a conductor
//! (physics.md §13):
//!
//! ```text
//! f(i,o) = R_s A_s δ_ω(o − s)/cosθo + 4k⁴ cosθi cosθo Q(i,o) P(ζ),
//! A_s = exp(−(2kσ cosθi)²),  ζ = k(o⊥ + i⊥),
//! ```
//!
//! the Mueller element M₀₀ of the microroughness BRDF for unpolarised
//! incidence, or its s- or p-incident value ([`Polarization`]), both
//! detected polarisations summed; Q is [`super::polarization`]'s, R_s the
//! Fresnel reflectance of the incident polarisation at θi. In cycles this is
//! the familiar (16π²/λ⁴) cosθi cosθo Q PSD_cyc(f). The specular lobe is the
//! SSA's.
//!
//! The theory is first order in (kσ)²: its scattered albedo at small g_s is
//! R g_s × (the lobe's in-disk fraction, obliquity and Q/R averaged over it),
//! so R_s A_s + scattered exceeds R_s by O(g_s²) and is not bounded when
//! g_s ≳ 1, where the theory does not apply (use `ghs` there).
//!
//! **Sampling.** The scattered frequency is drawn from P/σ² exactly (as in
//! the SSA), so the pdf is k² cosθo P(ζ)/σ² and the weight
//! 4k²σ² cosθi cosθo Q (over the glossy probability); the delta lobe is
//! chosen as in the SSA.

use glam::DVec3;

use super::Geometry;
use super::energy::GhsOptions;
use super::ghs_ssa::GhsCommon;
use super::polarization::{Medium, Polarization};
use crate::BrdfError;
use crate::fresnel::Fresnel;
use crate::model::{Bxdf, BxdfSample, Specular, WAVELENGTH_MAX_NM, WAVELENGTH_MIN_NM};
use crate::numerics::math::finite_nonneg;
use crate::statistics::{KcPsd, RadialPsd};

/// Rayleigh–Rice BRDF of a conductor driven by a radial PSD.
#[derive(Clone, Debug, PartialEq)]
pub struct RayleighRice<P: RadialPsd = KcPsd> {
    psd: P,
    common: GhsCommon,
}

impl<P: RadialPsd> RayleighRice<P> {
    /// Unpolarised incidence.
    pub fn new(psd: P, fresnel: Fresnel) -> Result<Self, BrdfError> {
        Self::with_polarization(psd, fresnel, Polarization::Unpolarized)
    }

    /// For incident polarisation `pol` (both scattered polarisations
    /// summed). Fresnel data must cover 360–830 nm; [`Fresnel::One`] is the
    /// perfect conductor.
    pub fn with_polarization(
        psd: P,
        fresnel: Fresnel,
        pol: Polarization,
    ) -> Result<Self, BrdfError> {
        fresnel.check_covers(WAVELENGTH_MIN_NM, WAVELENGTH_MAX_NM)?;
        let opts = GhsOptions {
            polarization: pol,
            ..GhsOptions::default()
        };
        let common = GhsCommon::new(fresnel, opts, psd.sigma_um(), psd.length_um());
        Ok(RayleighRice { psd, common })
    }

    /// The surface PSD.
    pub fn psd(&self) -> &P {
        &self.psd
    }

    /// The incident polarisation.
    pub fn polarization(&self) -> Polarization {
        self.common.opts.polarization
    }

    /// (f, pdf) at one pair of directions.
    #[inline]
    fn eval_pdf_impl(&self, wi: DVec3, wo: DVec3, lambda_nm: f64) -> (f64, f64) {
        let Some(geo) = Geometry::new(wi, wo, lambda_nm, self.common.length) else {
            return (0.0, 0.0);
        };
        let (p_delta, _) = self.common.choice(geo.ci, lambda_nm);
        let kl = geo.k * self.common.length;
        // k²L² p(u) = k² P(ζ)/σ².
        let lobe = kl * kl * self.psd.unit_psd_u(libm::sqrt(geo.u2));
        let pdf = finite_nonneg((1.0 - p_delta) * geo.co * lobe);
        let q = Medium::of(&self.common.fresnel, lambda_nm).q_factor(
            wi,
            wo,
            self.common.opts.polarization,
        );
        let ks = geo.k * self.common.sigma;
        let f = finite_nonneg(4.0 * ks * ks * geo.ci * geo.co * q * lobe);
        (f, pdf)
    }
}

impl<P: RadialPsd> Bxdf for RayleighRice<P> {
    fn eval(&self, wi: DVec3, wo: DVec3, lambda_nm: f64) -> f64 {
        self.eval_pdf_impl(wi, wo, lambda_nm).0
    }

    fn pdf(&self, wi: DVec3, wo: DVec3, lambda_nm: f64) -> f64 {
        self.eval_pdf_impl(wi, wo, lambda_nm).1
    }

    fn eval_pdf(&self, wi: DVec3, wo: DVec3, lambda_nm: f64) -> (f64, f64) {
        self.eval_pdf_impl(wi, wo, lambda_nm)
    }

    fn sample(&self, wi: DVec3, lambda_nm: f64, u: [f64; 3]) -> Option<BxdfSample> {
        self.common
            .sample_first_order(&self.psd, wi, lambda_nm, u, |wo| {
                self.eval_pdf_impl(wi, wo, lambda_nm)
            })
    }

    fn specular(&self, wi: DVec3, lambda_nm: f64) -> Specular {
        self.common.specular(wi, lambda_nm)
    }
}
