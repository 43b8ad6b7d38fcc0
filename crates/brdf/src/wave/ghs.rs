//! Full GHS: all diffraction orders (physics.md §3–4, §9).
//!
//! f(i,o) = R_s A_s δ_ω(o − s)/cosθo + R·k²L²·S̃(L|ζ|; g(i,o)),
//! S̃(u; g) = Σ_{m≥1} w_m(g) p_m(u) = (1/2π)∫[e^{−g(1−M)} − e^{−g}] J₀(ux) x dx,
//! read from a per-surface [`GhsTable`] built when the model is made.
//!
//! **Sampling.** The exact law of the scattered frequency for the specular
//! g_s = (2kσ cosθi)² is S̃(u; g_s)/(1 − e^{−g_s}): an order m ~ Pois(g_s | m ≥ 1)
//! followed by a sum of m independent p₁ samples (see
//! [`GhsFull::sample_orders_exact`], O(g_s) per draw). The renderer's
//! sampler is the O(log n) fast path: it draws u from the table's own radial
//! CDF of S̃(·; g_s) (a piecewise power law in w between columns, the two
//! rows bracketing ln g_s mixed linearly), mixed defensively with p₁
//! (weight 5 %, which has exactly the true u^{−(γ+1)} tail shape). `pdf()`
//! is the density of exactly that mixture, so the estimator is unbiased
//! whatever the table error; the table error only moves the proposal away
//! from the exact law (measured in tests/ghs_sampling.rs). For g_s < 1e−4
//! the lobe is p₁ to O(g_s) and p₁ is sampled exactly.

use alloc::sync::Arc;

use glam::DVec3;

use super::energy::{GhsOptions, hemispherical_integral};
use super::ghs_ssa::{GhsCommon, LobeChoice};
use super::ghs_table::{G_MIN, GhsTable, TableResolution};
use super::{Geometry, direction_from_u, wavenumber};
use crate::fresnel::Fresnel;
use crate::model::{Bxdf, BxdfSample, Specular, WAVELENGTH_MAX_NM, WAVELENGTH_MIN_NM};
use crate::numerics::math::finite_nonneg;
use crate::statistics::matern::Matern;
use crate::statistics::measured_psd::TabulatedCorrelation;
use crate::statistics::{KcPsd, RadialPsd, TabulatedPsd};
use crate::{BrdfError, frame};

/// A surface PSD whose full-GHS table this module can build. The statistics
/// types (`kc`, `measured_psd`) describe a surface; which correlation each
/// has, and how its S̃(u; g) table is built, is the model's business, so they
/// do not depend on the table builder.
pub trait TableSource: RadialPsd {
    /// The S̃(u; g) table for u ≤ `u_max` and g ≤ `g_max`.
    fn build_table(
        &self,
        u_max: f64,
        g_max: f64,
        res: TableResolution,
    ) -> Result<GhsTable, BrdfError>;
}

impl TableSource for KcPsd {
    fn build_table(
        &self,
        u_max: f64,
        g_max: f64,
        res: TableResolution,
    ) -> Result<GhsTable, BrdfError> {
        GhsTable::build_up_to(&Matern::new(self.nu()), u_max, g_max, res)
    }
}

impl TableSource for TabulatedPsd {
    fn build_table(
        &self,
        u_max: f64,
        g_max: f64,
        res: TableResolution,
    ) -> Result<GhsTable, BrdfError> {
        let c = TabulatedCorrelation::new(self);
        GhsTable::build_up_to(&c, u_max, g_max, res)
    }
}

/// Probability of drawing from p₁ instead of the tabulated S̃ CDF.
pub(crate) const DEFENSIVE_WEIGHT: f64 = 0.05;

/// Full GHS model driven by a radial PSD and its S̃ table.
#[derive(Clone, Debug)]
pub struct GhsFull<P: TableSource = KcPsd> {
    psd: P,
    common: GhsCommon,
    table: Arc<GhsTable>,
}

/// u_max covering the hemisphere at the shortest supported wavelength.
pub fn hemisphere_u_max(length_um: f64) -> f64 {
    2.0 * wavenumber(WAVELENGTH_MIN_NM) * length_um * 1.001
}

/// The largest g = (kσ(cosθi + cosθo))² a surface of rms height `sigma_um`
/// reaches at the shortest supported wavelength, (2 k_max σ)² (with the
/// same 0.1 % margin as [`hemisphere_u_max`]).
pub fn hemisphere_g_max(sigma_um: f64) -> f64 {
    let x = 2.0 * wavenumber(WAVELENGTH_MIN_NM) * sigma_um * 1.001;
    x * x
}

impl<P: TableSource> GhsFull<P> {
    /// Raw energy, halfway Fresnel angle, default table resolution.
    pub fn new(psd: P, fresnel: Fresnel) -> Result<Self, BrdfError> {
        Self::with_options(psd, fresnel, GhsOptions::default())
    }

    /// With explicit options and the default table resolution.
    pub fn with_options(psd: P, fresnel: Fresnel, opts: GhsOptions) -> Result<Self, BrdfError> {
        Self::with_resolution(psd, fresnel, opts, TableResolution::default())
    }

    /// With an explicit table resolution (benches/ghs.rs measures the
    /// error/time trade-off).
    pub fn with_resolution(
        psd: P,
        fresnel: Fresnel,
        opts: GhsOptions,
        res: TableResolution,
    ) -> Result<Self, BrdfError> {
        let table = psd.build_table(
            hemisphere_u_max(psd.length_um()),
            hemisphere_g_max(psd.sigma_um()),
            res,
        )?;
        Self::with_table(psd, fresnel, opts, Arc::new(table))
    }

    /// Shares an existing table (it depends only on the correlation shape and
    /// the u and g ranges, not on σ, Lc or λ). Fails if the table does not
    /// cover the hemisphere, or the g range, of this surface.
    pub fn with_table(
        psd: P,
        fresnel: Fresnel,
        opts: GhsOptions,
        table: Arc<GhsTable>,
    ) -> Result<Self, BrdfError> {
        fresnel.check_covers(WAVELENGTH_MIN_NM, WAVELENGTH_MAX_NM)?;
        let need = hemisphere_u_max(psd.length_um()) / 1.001;
        if table.u_max() < need {
            return Err(BrdfError::OutOfRange {
                name: "table u_max",
                value: table.u_max(),
                valid: "≥ 2·k(360 nm)·L of the surface: build the table for this surface",
            });
        }
        let need_g = hemisphere_g_max(psd.sigma_um()) / 1.002;
        if table.g_max() < need_g.min(super::ghs_table::G_MAX) {
            return Err(BrdfError::OutOfRange {
                name: "table g_max",
                value: table.g_max(),
                valid: "≥ (2·k(360 nm)·σ)² of the surface: build the table for this σ or larger",
            });
        }
        let common = GhsCommon::new(fresnel, opts, psd.sigma_um(), psd.length_um());
        let mut model = GhsFull { psd, common, table };
        let mut common = model.common.clone();
        common.build_table(
            |u| model.psd.cdf_u(u),
            |c, th, lam| {
                let wi = frame::spherical(th, 0.0);
                let kl = wavenumber(lam) * c.length;
                hemispherical_integral(wi, 1.0 / kl, |o| {
                    model.raw_lobe(c, wi, o, lam) * c.r_scatter(wi, o, lam)
                })
            },
        );
        model.common = common;
        Ok(model)
    }

    /// The surface PSD.
    pub fn psd(&self) -> &P {
        &self.psd
    }

    /// The S̃ table.
    pub fn table(&self) -> &Arc<GhsTable> {
        &self.table
    }

    /// The options in use.
    pub fn options(&self) -> GhsOptions {
        self.common.opts
    }

    /// S̃(u; g): the table for g ≥ 1e−4, (1 − e^{−g})·p(u) below.
    #[inline]
    pub fn s_tilde(&self, u: f64, g: f64) -> f64 {
        if !(g > 0.0) {
            return 0.0;
        }
        self.s_tilde_at(ln_or_neg_inf(u), u, g)
    }

    /// R = 1, unrenormalised scattered BRDF k²L² S̃.
    #[inline]
    fn raw_lobe(&self, c: &GhsCommon, wi: DVec3, wo: DVec3, lambda_nm: f64) -> f64 {
        match Geometry::new(wi, wo, lambda_nm, c.length) {
            Some(geo) => self.raw_lobe_at(c, &geo, lambda_nm, Self::ln_u(&geo)),
            None => 0.0,
        }
    }

    #[inline]
    fn ln_u(geo: &Geometry) -> f64 {
        0.5 * ln_or_neg_inf(geo.u2)
    }

    #[inline]
    fn raw_lobe_at(&self, c: &GhsCommon, geo: &Geometry, lambda_nm: f64, ln_u: f64) -> f64 {
        let s = c.sigma_eff(geo.ci, lambda_nm);
        let t = geo.k * s * (geo.ci + geo.co);
        let kl = geo.k * c.length;
        let g = t * t;
        if !(g > 0.0) {
            return 0.0;
        }
        kl * kl * self.s_tilde_at(ln_u, libm::sqrt(geo.u2), g)
    }

    /// S̃(u; g) from the table, with the first order from the exact p(u)
    /// when the table leaves it out; (1 − e^{−g}) p(u) below the table.
    #[inline]
    fn s_tilde_at(&self, ln_u: f64, u: f64, g: f64) -> f64 {
        match self.table.s_tilde_rest_ln_u(ln_u, g) {
            Some(rest) if self.table.first_order_apart() => {
                rest + g * crate::numerics::math::exp(-g) * self.psd.unit_psd_u(u)
            }
            Some(v) => v,
            None => -libm::expm1(-g) * self.psd.unit_psd_u(u),
        }
    }

    /// Density in the u-plane (∫ d²u = 1) with which the glossy sampler
    /// draws u = L|ζ| for specular exponent `gs` (before the evanescent cut).
    #[inline]
    pub fn proposal_density(&self, gs: f64, u: f64) -> f64 {
        self.proposal_density_ln(gs, u, ln_or_neg_inf(u))
    }

    #[inline]
    fn proposal_density_ln(&self, gs: f64, u: f64, ln_u: f64) -> f64 {
        let p = self.psd.unit_psd_u(u);
        if gs < G_MIN {
            return p;
        }
        let mut q = 0.0;
        for (r, w, lw) in self.table.proposal_rows(gs) {
            if w > 0.0 {
                q += w * self.table.row_density(r, lw, ln_u);
            }
        }
        DEFENSIVE_WEIGHT * p + (1.0 - DEFENSIVE_WEIGHT) * q
    }

    /// Draws u from the glossy proposal with two uniforms (`v` selects the
    /// component and is reused).
    #[inline]
    pub(crate) fn proposal_sample(&self, gs: f64, v: f64, xi: f64) -> f64 {
        if gs < G_MIN || v < DEFENSIVE_WEIGHT {
            return self.psd.sample_u(xi);
        }
        let v = (v - DEFENSIVE_WEIGHT) / (1.0 - DEFENSIVE_WEIGHT);
        let rows = self.table.proposal_rows(gs);
        let (r, _, lw) = if v < rows[0].1 { rows[0] } else { rows[1] };
        self.table.row_sample(r, lw, xi)
    }

    /// (eval, pdf) sharing the geometry and ln u; `with_eval` false skips
    /// the BRDF.
    #[inline]
    fn eval_pdf_impl(&self, wi: DVec3, wo: DVec3, lambda_nm: f64, with_eval: bool) -> (f64, f64) {
        let Some(geo) = Geometry::new(wi, wo, lambda_nm, self.common.length) else {
            return (0.0, 0.0);
        };
        let ln_u = Self::ln_u(&geo);
        let u = libm::sqrt(geo.u2);
        let kl = geo.k * self.common.length;
        let (p_delta, gs) = self.common.choice(geo.ci, lambda_nm);
        let q = self.proposal_density_ln(gs, u, ln_u);
        let pdf = finite_nonneg((1.0 - p_delta) * kl * kl * geo.co * q);
        if !with_eval {
            return (0.0, pdf);
        }
        let f = self.raw_lobe_at(&self.common, &geo, lambda_nm, ln_u);
        let f = if f == 0.0 {
            0.0
        } else {
            finite_nonneg(
                f * self.common.r_scatter(wi, wo, lambda_nm)
                    * self.common.scatter_factor(geo.ci, lambda_nm),
            )
        };
        (f, pdf)
    }

    /// Reference sampler of the exact law of the scattered frequency for
    /// order-weights Pois(g | m ≥ 1): draws m, then sums m independent p₁
    /// vectors; returns |u|. Costs O(m) — for tests and validation.
    pub fn sample_orders_exact(&self, g: f64, mut next: impl FnMut() -> f64) -> f64 {
        let m = crate::numerics::poisson::sample_conditioned(g, next());
        let (mut x, mut y) = (0.0, 0.0);
        for _ in 0..m {
            let r = self.psd.sample_u(next());
            let (s, c) = libm::sincos(2.0 * core::f64::consts::PI * next());
            x += r * c;
            y += r * s;
        }
        libm::hypot(x, y)
    }
}

impl<P: TableSource> Bxdf for GhsFull<P> {
    fn eval(&self, wi: DVec3, wo: DVec3, lambda_nm: f64) -> f64 {
        let f = self.raw_lobe(&self.common, wi, wo, lambda_nm);
        if f == 0.0 {
            return 0.0;
        }
        finite_nonneg(
            f * self.common.r_scatter(wi, wo, lambda_nm)
                * self.common.scatter_factor(wi.z, lambda_nm),
        )
    }

    fn pdf(&self, wi: DVec3, wo: DVec3, lambda_nm: f64) -> f64 {
        self.eval_pdf_impl(wi, wo, lambda_nm, false).1
    }

    fn eval_pdf(&self, wi: DVec3, wo: DVec3, lambda_nm: f64) -> (f64, f64) {
        self.eval_pdf_impl(wi, wo, lambda_nm, true)
    }

    fn sample(&self, wi: DVec3, lambda_nm: f64, u: [f64; 3]) -> Option<BxdfSample> {
        if !(wi.z > 0.0) {
            return None;
        }
        let (v, gs) = match self.common.choose_lobe(wi, lambda_nm, u[0]) {
            LobeChoice::Delta(s) => return s,
            LobeChoice::Glossy { v, gs } => (v, gs),
        };
        let kl = wavenumber(lambda_nm) * self.common.length;
        let uu = self.proposal_sample(gs, v, u[1]);
        let wo = direction_from_u(wi, kl, uu, 2.0 * core::f64::consts::PI * u[2])?;
        super::glossy_sample(wo, self.eval_pdf_impl(wi, wo, lambda_nm, true))
    }

    fn specular(&self, wi: DVec3, lambda_nm: f64) -> Specular {
        self.common.specular(wi, lambda_nm)
    }
}
/// ln x, and −∞ at x = 0 (u = 0 is the mirror direction, which the tables treat as a limit).
#[inline]
fn ln_or_neg_inf(x: f64) -> f64 {
    if x > 0.0 {
        crate::numerics::math::ln(x)
    } else {
        f64::NEG_INFINITY
    }
}
