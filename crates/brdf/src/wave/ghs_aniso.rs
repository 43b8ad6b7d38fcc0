//! GHS (SSA and full) of a stretched surface: the anisotropic K-correlation
//! ([`AnisotropicKc`], physics.md §15) or any radial PSD stretched along two
//! axes ([`EllipticalPsd`](crate::statistics::EllipticalPsd), §15.2, e.g. a
//! measured one).
//!
//! The surface is an isotropic one stretched along axes at φ₀, so its GHS
//! kernel is the isotropic one in the stretched frequency u = A ζ (for the KC,
//! u = (Lx ζ·a, Ly ζ·b), with Lc² → Lx Ly = |det A|):
//!
//! ```text
//! f(i,o) = R_s A_s δ_ω(o − s)/cosθo + R · k² |det A| · S̃(|u|; g(i,o)),
//! SSA:  S̃ → (1 − e^{−g}) p₁(|u|),     ζ = k(o⊥ + i⊥),
//! ```
//!
//! (substitute r = Aᵀ r' in the covariance integral: d²r = |det A| d²r' and
//! ζ·r = u·r'). A_s, g and the Fresnel and polarisation options are those of
//! the isotropic models; the full S̃ comes from the isotropic table of the
//! radial law, over |u| up to 2k(360 nm)·max|A|. Sampling draws |u| as the isotropic model does (p₁ exactly for the
//! SSA, the table's proposal with the defensive p₁ mixture for the full
//! GHS), a uniform direction of u, and maps it back to ζ; the solid-angle pdf
//! is k² |det A| cosθo q(|u|). Energy: `raw` only — the renormalisations of §5
//! are tabulated over (θi, λ) and an anisotropic lobe depends on the
//! incidence azimuth too.

use glam::DVec3;

use super::energy::{Energy, GhsOptions};
use super::ghs::GhsFull;
use super::ghs_ssa::{GhsCommon, LobeChoice};
use super::wavenumber;
use crate::BrdfError;
use crate::fresnel::Fresnel;
use crate::model::{Bxdf, BxdfSample, Specular, WAVELENGTH_MAX_NM, WAVELENGTH_MIN_NM};
use crate::numerics::math::finite_nonneg;
use crate::statistics::RadialPsd;
use crate::statistics::anisotropic::AnisotropicKc;
use crate::statistics::elliptical::StretchedPsd;

use super::ghs::{TableSource, hemisphere_g_max, hemisphere_u_max};
use super::ghs_table::TableResolution;

/// GHS of a stretched surface (by default the anisotropic K-correlation): the
/// smooth-surface approximation, or all orders from the isotropic S̃ table of
/// its radial law.
#[derive(Clone, Debug)]
pub struct GhsAnisotropic<S: StretchedPsd = AnisotropicKc>
where
    S::Radial: TableSource,
{
    surface: S,
    /// The radial law in u (p, its CDF and sampler).
    radial: S::Radial,
    common: GhsCommon,
    /// The full model's isotropic table (u up to 2k(360 nm)·max|A|);
    /// `None`: the SSA.
    full: Option<GhsFull<S::Radial>>,
}

impl<S: StretchedPsd> GhsAnisotropic<S>
where
    S::Radial: TableSource,
{
    /// The smooth-surface approximation.
    pub fn ssa(surface: S, fresnel: Fresnel, opts: GhsOptions) -> Result<Self, BrdfError> {
        Self::build(surface, fresnel, opts, false)
    }

    /// All diffraction orders (for the KC, γ ≥ 1.05, as the isotropic full GHS).
    pub fn full(surface: S, fresnel: Fresnel, opts: GhsOptions) -> Result<Self, BrdfError> {
        Self::build(surface, fresnel, opts, true)
    }

    fn build(
        surface: S,
        fresnel: Fresnel,
        opts: GhsOptions,
        all_orders: bool,
    ) -> Result<Self, BrdfError> {
        fresnel.check_covers(WAVELENGTH_MIN_NM, WAVELENGTH_MAX_NM)?;
        if opts.energy != Energy::Raw {
            return Err(BrdfError::OutOfRange {
                name: "energy",
                value: f64::NAN,
                valid: "\"raw\" for an anisotropic surface (the krywonos and sigma_rel tables \
                        are over θi and λ, and an anisotropic lobe depends on the incidence \
                        azimuth too)",
            });
        }
        let radial = surface.radial()?;
        let full = if all_orders {
            surface.check_full()?;
            let table = radial.build_table(
                hemisphere_u_max(surface.reach_um()),
                hemisphere_g_max(surface.sigma_um()),
                TableResolution::default(),
            )?;
            Some(GhsFull::with_table(
                radial.clone(),
                Fresnel::One,
                GhsOptions::default(),
                alloc::sync::Arc::new(table),
            )?)
        } else {
            None
        };
        let common = GhsCommon::new(
            fresnel,
            opts,
            surface.sigma_um(),
            libm::sqrt(surface.area_um2()),
        );
        Ok(GhsAnisotropic {
            surface,
            radial,
            common,
            full,
        })
    }

    /// The surface.
    pub fn surface(&self) -> &S {
        &self.surface
    }

    /// Whether this is the full GHS (else the SSA).
    pub fn is_full(&self) -> bool {
        self.full.is_some()
    }

    /// The options in use.
    pub fn options(&self) -> GhsOptions {
        self.common.opts
    }

    /// S̃(u; g) of the radial law: the table's, or the SSA's (1 − e^{−g}) p₁(u).
    pub fn s_tilde(&self, u: f64, g: f64) -> f64 {
        match &self.full {
            Some(m) => m.s_tilde(u, g),
            None => -libm::expm1(-g) * self.radial.unit_psd_u(u),
        }
    }

    /// |u| of the pair of directions and k, or `None` below the horizon.
    #[inline]
    fn stretched(&self, wi: DVec3, wo: DVec3, lambda_nm: f64) -> Option<(f64, f64)> {
        let k = wavenumber(lambda_nm);
        if !(wi.z > 0.0 && wo.z > 0.0 && k > 0.0) {
            return None;
        }
        let (ux, uy) = self.surface.to_u(k * (wo.x + wi.x), k * (wo.y + wi.y));
        Some((libm::hypot(ux, uy), k))
    }

    /// Radial density in the u-plane (∫ d²u = 1) of the glossy proposal.
    #[inline]
    fn proposal(&self, gs: f64, u: f64) -> f64 {
        match &self.full {
            Some(m) => m.proposal_density(gs, u),
            None => self.radial.unit_psd_u(u),
        }
    }

    fn eval_pdf_impl(&self, wi: DVec3, wo: DVec3, lambda_nm: f64) -> (f64, f64) {
        let Some((u, k)) = self.stretched(wi, wo, lambda_nm) else {
            return (0.0, 0.0);
        };
        let (ci, co) = (wi.z.min(1.0), wo.z.min(1.0));
        let area = k * k * self.surface.area_um2();
        let (p_delta, gs) = self.common.choice(ci, lambda_nm);
        let pdf = finite_nonneg((1.0 - p_delta) * area * co * self.proposal(gs, u));
        let t = k * self.common.sigma * (ci + co);
        let g = t * t;
        if !(g > 0.0) {
            return (0.0, pdf);
        }
        let f = area * self.s_tilde(u, g);
        let f = if f > 0.0 {
            finite_nonneg(f * self.common.r_scatter(wi, wo, lambda_nm))
        } else {
            0.0
        };
        (f, pdf)
    }
}

impl<S: StretchedPsd> Bxdf for GhsAnisotropic<S>
where
    S::Radial: TableSource,
{
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
        let r = match &self.full {
            Some(m) => m.proposal_sample(gs, v, u[1]),
            None => self.radial.sample_u(u[1]),
        };
        if !(r.is_finite() && k > 0.0) {
            return None;
        }
        let (s, c) = libm::sincos(2.0 * core::f64::consts::PI * u[2]);
        let (zx, zy) = self.surface.u_to_zeta(r * c, r * s);
        let wo = super::direction_from_offset(wi, zx / k, zy / k)?;
        super::glossy_sample(wo, self.eval_pdf_impl(wi, wo, lambda_nm))
    }

    fn specular(&self, wi: DVec3, lambda_nm: f64) -> Specular {
        self.common.specular(wi, lambda_nm)
    }
}
