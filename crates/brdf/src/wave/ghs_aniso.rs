//! GHS (SSA and full) of an anisotropic K-correlation surface
//! ([`AnisotropicKc`], physics.md §15).
//!
//! The surface is the isotropic KC stretched by (Lx, Ly) along axes at φ₀,
//! so its GHS kernel is the isotropic one in the stretched frequency
//! u = (Lx ζ·a, Ly ζ·b), with Lc² → Lx Ly:
//!
//! ```text
//! f(i,o) = R_s A_s δ_ω(o − s)/cosθo + R · k² Lx Ly · S̃(|u|; g(i,o)),
//! SSA:  S̃ → (1 − e^{−g}) p₁(|u|),     ζ = k(o⊥ + i⊥),
//! ```
//!
//! (substitute r = A r' in the covariance integral: d²r = Lx Ly d²r' and
//! ζ·r = u·r'). A_s, g and the Fresnel and polarisation options are those of
//! the isotropic models; the full S̃ comes from the isotropic table of the
//! same γ. Sampling draws |u| as the isotropic model does (p₁ exactly for the
//! SSA, the table's proposal with the defensive p₁ mixture for the full
//! GHS), a uniform direction of u, and maps it back to ζ; the solid-angle pdf
//! is k² Lx Ly cosθo q(|u|). Energy: `raw` only — the renormalisations of §5
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
use crate::statistics::anisotropic::AnisotropicKc;
use crate::statistics::{KcPsd, RadialPsd};

/// GHS of an anisotropic K-correlation surface: the smooth-surface
/// approximation, or all orders from the isotropic S̃ table.
#[derive(Clone, Debug)]
pub struct GhsAnisotropic {
    surface: AnisotropicKc,
    /// The radial law in u (p₁, its CDF and sampler).
    radial: KcPsd,
    common: GhsCommon,
    /// The full model's isotropic table (u up to 2k(360 nm)·max(Lx, Ly));
    /// `None`: the SSA.
    full: Option<GhsFull<KcPsd>>,
}

impl GhsAnisotropic {
    /// The smooth-surface approximation.
    pub fn ssa(
        surface: AnisotropicKc,
        fresnel: Fresnel,
        opts: GhsOptions,
    ) -> Result<Self, BrdfError> {
        Self::build(surface, fresnel, opts, false)
    }

    /// All diffraction orders (γ ≥ 1.05, as the isotropic full GHS).
    pub fn full(
        surface: AnisotropicKc,
        fresnel: Fresnel,
        opts: GhsOptions,
    ) -> Result<Self, BrdfError> {
        Self::build(surface, fresnel, opts, true)
    }

    fn build(
        surface: AnisotropicKc,
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
        let (lx, ly) = (surface.lx_um(), surface.ly_um());
        let radial = surface.radial(lx.max(ly))?;
        if all_orders && surface.gamma() < crate::statistics::kc::GAMMA_MIN_FULL {
            return Err(BrdfError::OutOfRange {
                name: "gamma",
                value: surface.gamma(),
                valid: "≥ 1.05 for the full GHS (use the SSA below)",
            });
        }
        let full = if all_orders {
            Some(GhsFull::new(radial, Fresnel::One)?)
        } else {
            None
        };
        let common = GhsCommon::new(fresnel, opts, surface.sigma_um(), libm::sqrt(lx * ly));
        Ok(GhsAnisotropic {
            surface,
            radial,
            common,
            full,
        })
    }

    /// The surface.
    pub fn surface(&self) -> &AnisotropicKc {
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
        let area = k * k * self.surface.lx_um() * self.surface.ly_um();
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

impl Bxdf for GhsAnisotropic {
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
        let (zx, zy) = self.surface.from_u(r * c, r * s);
        let (ox, oy) = (zx / k - wi.x, zy / k - wi.y);
        let rho2 = ox * ox + oy * oy;
        if !(rho2 < 1.0) {
            return None;
        }
        let rho = libm::sqrt(rho2);
        let oz = libm::sqrt((1.0 - rho) * (1.0 + rho));
        if !(oz > 0.0) {
            return None;
        }
        let wo = DVec3::new(ox, oy, oz);
        super::glossy_sample(wo, self.eval_pdf_impl(wi, wo, lambda_nm))
    }

    fn specular(&self, wi: DVec3, lambda_nm: f64) -> Specular {
        self.common.specular(wi, lambda_nm)
    }
}
