//! GHS smooth-surface approximation of a measured 2-D PSD
//! ([`TabulatedPsd2d`], physics.md §15.4; `model = "measured_psd2d_ssa"`):
//!
//! ```text
//! f(i,o) = R_s A_s δ_ω(o − s)/cosθo + R · k² (1 − e^{−g(i,o)}) P₂(ζ)/σ²,
//! ζ = k(o⊥ + i⊥),  g = [kσ(cosθi + cosθo)]²,  A_s = e^{−(2kσ cosθi)²},
//! ```
//!
//! the SSA of §15 with the table in place of the stretched radial law; A_s, g,
//! the Fresnel angle and the polarisation factor are those of the other GHS
//! models. Sampling draws ζ from P₂/σ² exactly (the table's sampler), so the
//! glossy pdf is (1 − p_δ) k² cosθo P₂(ζ)/σ². Energy: `raw` only, as the
//! anisotropic models (§15): the renormalisations are tabulated over (θi, λ),
//! and this lobe depends on the incidence azimuth too.

use glam::DVec3;

use super::energy::{Energy, GhsOptions};
use super::ghs_ssa::{GhsCommon, LobeChoice};
use super::wavenumber;
use crate::BrdfError;
use crate::fresnel::Fresnel;
use crate::model::{Bxdf, BxdfSample, Specular, WAVELENGTH_MAX_NM, WAVELENGTH_MIN_NM};
use crate::numerics::math::finite_nonneg;
use crate::statistics::TabulatedPsd2d;

/// The GHS smooth-surface approximation of a tabulated 2-D PSD.
#[derive(Clone, Debug, PartialEq)]
pub struct GhsSsaPsd2d {
    table: TabulatedPsd2d,
    common: GhsCommon,
}

impl GhsSsaPsd2d {
    /// Builds the model; `opts.energy` must be [`Energy::Raw`].
    pub fn new(
        table: TabulatedPsd2d,
        fresnel: Fresnel,
        opts: GhsOptions,
    ) -> Result<Self, BrdfError> {
        fresnel.check_covers(WAVELENGTH_MIN_NM, WAVELENGTH_MAX_NM)?;
        if opts.energy != Energy::Raw {
            return Err(BrdfError::OutOfRange {
                name: "energy",
                value: f64::NAN,
                valid: "\"raw\" for a 2-D PSD (the krywonos and sigma_rel tables are over θi \
                        and λ, and this lobe depends on the incidence azimuth too)",
            });
        }
        let common = GhsCommon::new(
            fresnel,
            opts,
            table.sigma_um(),
            1.0 / table.step_rad_per_um(),
        );
        Ok(GhsSsaPsd2d { table, common })
    }

    /// The table.
    pub fn table(&self) -> &TabulatedPsd2d {
        &self.table
    }

    /// The options in use.
    pub fn options(&self) -> GhsOptions {
        self.common.opts
    }

    fn eval_pdf_impl(&self, wi: DVec3, wo: DVec3, lambda_nm: f64) -> (f64, f64) {
        let k = wavenumber(lambda_nm);
        if !(wi.z > 0.0 && wo.z > 0.0 && k > 0.0) {
            return (0.0, 0.0);
        }
        let (ci, co) = (wi.z.min(1.0), wo.z.min(1.0));
        let lobe = k * k * self.table.unit_psd(k * (wo.x + wi.x), k * (wo.y + wi.y));
        let (p_delta, _) = self.common.choice(ci, lambda_nm);
        let pdf = finite_nonneg((1.0 - p_delta) * co * lobe);
        let t = k * self.common.sigma * (ci + co);
        let f = -libm::expm1(-t * t) * lobe;
        if !(f > 0.0) {
            return (0.0, pdf);
        }
        (
            finite_nonneg(f * self.common.r_scatter(wi, wo, lambda_nm)),
            pdf,
        )
    }
}

impl Bxdf for GhsSsaPsd2d {
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
        if !(wi.z > 0.0) {
            return None;
        }
        if let LobeChoice::Delta(s) = self.common.choose_lobe(wi, lambda_nm, u[0]) {
            return s;
        }
        let k = wavenumber(lambda_nm);
        let (zx, zy) = self.table.sample_zeta(u[1], u[2]);
        if !(zx.is_finite() && zy.is_finite() && k > 0.0) {
            return None;
        }
        let wo = super::direction_from_offset(wi, zx / k, zy / k)?;
        super::glossy_sample(wo, self.eval_pdf_impl(wi, wo, lambda_nm))
    }

    fn specular(&self, wi: DVec3, lambda_nm: f64) -> Specular {
        self.common.specular(wi, lambda_nm)
    }
}
