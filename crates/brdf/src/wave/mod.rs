//! Wave-optical reflection from rough surfaces: the K-correlation PSD and the
//! generalized Harvey–Shack (GHS) models of `docs/physics.md` §2–5, 9–11.
//!
//! * [`KcPsd`] and [`TabulatedPsd`]: the surface statistics, behind the
//!   [`RadialPsd`] trait;
//! * [`GhsSsa`]: the smooth-surface approximation (specular delta R·A plus
//!   the scattered lobe R(1−A)k²P/σ²);
//! * [`GhsFull`]: all diffraction orders, from a per-surface table of the
//!   Hankel transform ([`ghs_table`]), needs the `alloc` feature;
//! * [`Energy`] and [`FresnelAngle`]: the switches of physics.md §5 and §3.2.

// `!(x > 0.0)` is used on purpose throughout: it rejects NaN together with
// the out-of-range values, which `x <= 0.0` would let through.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

#[cfg(feature = "alloc")]
mod albedo_cap;
pub mod bessel01;
pub mod energy;
pub mod epd;
pub mod ggx_kc;
#[cfg(feature = "alloc")]
pub mod ghs;
pub mod ghs_ssa;
#[cfg(feature = "alloc")]
pub mod ghs_table;
pub mod hankel;
pub mod kc;
pub mod matern;
#[cfg(feature = "alloc")]
pub mod measured_psd;
pub mod poisson;
#[cfg(feature = "alloc")]
mod quadrature;
pub mod special;
#[cfg(feature = "alloc")]
pub mod two_scale;

pub use energy::{Energy, FresnelAngle, GhsOptions};
#[cfg(feature = "alloc")]
pub use ghs::{GhsFull, TableSource};
pub use ghs_ssa::GhsSsa;
pub use kc::KcPsd;
#[cfg(feature = "alloc")]
pub use measured_psd::TabulatedPsd;

use glam::DVec3;

/// An isotropic surface height PSD as the GHS models use it: in the
/// dimensionless frequency u = L·ζ (ζ in rad/µm) with a length L of the
/// surface's choosing (Lc for [`KcPsd`]).
pub trait RadialPsd {
    /// rms height σ, µm.
    fn sigma_um(&self) -> f64;
    /// The length L, µm, with u = L·ζ.
    fn length_um(&self) -> f64;
    /// Unit-mass PSD in the u-plane, p(u) = P(u/L)/(σ²L²), ∫ p d²u = 1.
    fn unit_psd_u(&self, u: f64) -> f64;
    /// Mass of p inside radius u.
    fn cdf_u(&self, u: f64) -> f64;
    /// Inverse of [`RadialPsd::cdf_u`] (may return +∞).
    fn sample_u(&self, xi: f64) -> f64;
}

/// Shared per-query quantities of the GHS models.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Geometry {
    /// k = 2π/λ, rad/µm.
    pub k: f64,
    /// cosθi, cosθo
    pub ci: f64,
    pub co: f64,
    /// u² = (kL|o⊥ + i⊥|)²
    pub u2: f64,
}

impl Geometry {
    /// `None` below the horizon or for a bad wavelength.
    #[inline]
    pub fn new(wi: DVec3, wo: DVec3, lambda_nm: f64, length_um: f64) -> Option<Self> {
        if !(wi.z > 0.0 && wo.z > 0.0 && lambda_nm > 0.0 && lambda_nm.is_finite()) {
            return None;
        }
        let k = 2000.0 * core::f64::consts::PI / lambda_nm;
        let dx = wo.x + wi.x;
        let dy = wo.y + wi.y;
        let kl = k * length_um;
        Some(Geometry {
            k,
            ci: wi.z.min(1.0),
            co: wo.z.min(1.0),
            u2: kl * kl * (dx * dx + dy * dy),
        })
    }
}

/// k = 2π/λ in rad/µm for λ in nm (0 for a non-positive or non-finite λ):
/// the one definition every crate uses.
#[inline]
pub fn wavenumber(lambda_nm: f64) -> f64 {
    if lambda_nm > 0.0 && lambda_nm.is_finite() {
        2000.0 * core::f64::consts::PI / lambda_nm
    } else {
        0.0
    }
}

/// The glossy sample for a drawn `wo` with its `(f, pdf)`, or `None` when it
/// carries no energy.
#[inline]
pub(crate) fn glossy_sample(wo: DVec3, (f, pdf): (f64, f64)) -> Option<crate::BxdfSample> {
    if !(f > 0.0 && pdf > 0.0) {
        return None;
    }
    let weight = f * wo.z / pdf;
    weight.is_finite().then_some(crate::BxdfSample {
        wo,
        weight,
        pdf,
        is_delta: false,
    })
}

/// Outgoing direction for a frequency offset (u, φ) about the mirror
/// direction: o⊥ = (u/(kL))(cosφ, sinφ) − i⊥. `None` if evanescent.
#[inline]
pub(crate) fn direction_from_u(wi: DVec3, kl: f64, u: f64, phi: f64) -> Option<DVec3> {
    if !(u.is_finite() && kl > 0.0) {
        return None;
    }
    let r = u / kl;
    let (s, c) = libm::sincos(phi);
    let ox = r * c - wi.x;
    let oy = r * s - wi.y;
    let rho2 = ox * ox + oy * oy;
    if !(rho2 < 1.0) {
        return None;
    }
    let rho = libm::sqrt(rho2);
    let oz = libm::sqrt((1.0 - rho) * (1.0 + rho));
    if !(oz > 0.0) {
        return None;
    }
    Some(DVec3::new(ox, oy, oz))
}
