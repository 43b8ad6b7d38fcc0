//! The full GHS of a measured 2-D PSD ([`TabulatedPsd2d`], physics.md §15.4;
//! `model = "measured_psd2d"`):
//!
//! ```text
//! f(i,o) = R_s A_s δ_ω(o − s)/cosθo + R · k² S̃(ζ; g(i,o)),
//! ζ = k(o⊥ + i⊥),  g = [kσ(cosθi + cosθo)]²,  A_s = e^{−(2kσ cosθi)²},
//! ```
//!
//! S̃ all diffraction orders of P₂ ([`Psd2dGhsTable`]); A_s, g, the Fresnel
//! angle and the polarisation factor are those of the other GHS models, and
//! as g → 0 the lobe is that of [`GhsSsaPsd2d`](super::GhsSsaPsd2d). Sampling:
//! the delta with the probability of the other GHS models, else ζ from the
//! table's proposal at g_s = (2kσ cosθi)² (the first order P₂/σ² and the
//! slices bracketing g_s, mixed by their shares); the glossy pdf is
//! (1 − p_δ) k² cosθo q(ζ; g_s) exactly. Energy: `raw` only, as the other
//! anisotropic models (§15).

use alloc::sync::Arc;

use glam::DVec3;

use super::energy::{Energy, GhsOptions};
use super::ghs::hemisphere_g_max;
use super::ghs_psd2d_table::{Psd2dGhsTable, Psd2dResolution};
use super::ghs_ssa::{GhsCommon, LobeChoice};
use super::wavenumber;
use crate::BrdfError;
use crate::fresnel::Fresnel;
use crate::model::{Bxdf, BxdfSample, Specular, WAVELENGTH_MAX_NM, WAVELENGTH_MIN_NM};
use crate::numerics::math::finite_nonneg;
use crate::statistics::TabulatedPsd2d;

/// The full GHS of a tabulated 2-D PSD.
#[derive(Clone, Debug)]
pub struct GhsPsd2d {
    table: Arc<Psd2dGhsTable>,
    common: GhsCommon,
}

impl GhsPsd2d {
    /// Builds the model and its table (slices up to the g the surface reaches
    /// at 360 nm); `opts.energy` must be [`Energy::Raw`].
    pub fn new(psd: TabulatedPsd2d, fresnel: Fresnel, opts: GhsOptions) -> Result<Self, BrdfError> {
        Self::with_resolution(psd, fresnel, opts, Psd2dResolution::default())
    }

    /// As [`new`](Self::new) at a given table resolution.
    pub fn with_resolution(
        psd: TabulatedPsd2d,
        fresnel: Fresnel,
        opts: GhsOptions,
        res: Psd2dResolution,
    ) -> Result<Self, BrdfError> {
        Self::check(&fresnel, opts)?;
        let g_max = hemisphere_g_max(psd.sigma_um());
        let table = Psd2dGhsTable::with_resolution(psd, g_max, res)?;
        Self::with_table(Arc::new(table), fresnel, opts)
    }

    /// The model on a table already built (shared between materials).
    pub fn with_table(
        table: Arc<Psd2dGhsTable>,
        fresnel: Fresnel,
        opts: GhsOptions,
    ) -> Result<Self, BrdfError> {
        Self::check(&fresnel, opts)?;
        let psd = table.psd();
        let common = GhsCommon::new(fresnel, opts, psd.sigma_um(), 1.0 / psd.step_rad_per_um());
        Ok(GhsPsd2d { table, common })
    }

    /// What the model accepts besides its table: a Fresnel term over the
    /// visible range and `raw` energy.
    fn check(fresnel: &Fresnel, opts: GhsOptions) -> Result<(), BrdfError> {
        fresnel.check_covers(WAVELENGTH_MIN_NM, WAVELENGTH_MAX_NM)?;
        if opts.energy != Energy::Raw {
            return Err(BrdfError::OutOfRange {
                name: "energy",
                value: f64::NAN,
                valid: "\"raw\" for a 2-D PSD (the krywonos and sigma_rel tables are over θi \
                        and λ, and this lobe depends on the incidence azimuth too)",
            });
        }
        Ok(())
    }

    /// The table.
    pub fn table(&self) -> &Psd2dGhsTable {
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
        let (zx, zy) = (k * (wo.x + wi.x), k * (wo.y + wi.y));
        let (p_delta, gs) = self.common.choice(ci, lambda_nm);
        let t = k * self.common.sigma * (ci + co);
        let (s, q) = self.table.s_tilde_and_proposal(zx, zy, t * t, gs);
        let pdf = finite_nonneg((1.0 - p_delta) * k * k * co * q);
        let f = k * k * s;
        if !(f > 0.0) {
            return (0.0, pdf);
        }
        (
            finite_nonneg(f * self.common.r_scatter(wi, wo, lambda_nm)),
            pdf,
        )
    }
}

impl Bxdf for GhsPsd2d {
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
        let (v, gs) = match self.common.choose_lobe(wi, lambda_nm, u[0]) {
            LobeChoice::Delta(s) => return s,
            LobeChoice::Glossy { v, gs } => (v, gs),
        };
        let k = wavenumber(lambda_nm);
        let (zx, zy) = self.table.proposal_sample(gs, v, u[1], u[2]);
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
