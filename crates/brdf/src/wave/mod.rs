//! The wave-optical reflection models of `docs/physics.md` §3–11, driven by
//! the surface statistics of [`crate::statistics`]:
//!
//! * [`GhsSsa`]: the smooth-surface approximation of generalized
//!   Harvey–Shack (specular delta R·A plus the scattered lobe R(1−A)k²P/σ²);
//! * [`GhsFull`]: all diffraction orders, from a per-surface table of the
//!   Hankel transform ([`ghs_table`]), needs the `alloc` feature;
//! * [`two_scale::TwoScale`]: the Holzschuch–Pacanowski two-scale model (its
//!   D̃_eff table is built by the crate-internal `two_scale_table`), `alloc`;
//! * [`GhsAnisotropic`]: SSA and full GHS of a stretched surface: the
//!   anisotropic K-correlation, or a measured radial PSD constant on ellipses
//!   ([`crate::statistics::EllipticalPsd`]) (`alloc`);
//! * [`GhsSsaPsd2d`], [`GhsPsd2d`]: SSA and full GHS of a measured 2-D PSD
//!   on a grid ([`crate::statistics::TabulatedPsd2d`]; the full model's
//!   slices over ln g are [`ghs_psd2d_table`]) (`alloc`);
//! * [`RayleighRice`]: first-order vector perturbation theory for a
//!   conductor, with the polarisation factor Q of [`polarization`];
//! * [`ggx_kc`]: the GGX ↔ K-correlation identity;
//! * [`Energy`], [`FresnelAngle`], [`Polarization`] and
//!   [`PolarizationFactor`]: the switches of physics.md §5, §3.2 and §13.

// `!(x > 0.0)` is used on purpose throughout: it rejects NaN together with
// the out-of-range values, which `x <= 0.0` would let through.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

#[cfg(feature = "alloc")]
mod albedo_cap;
pub mod energy;
pub mod ggx_kc;
#[cfg(feature = "alloc")]
pub mod ghs;
#[cfg(feature = "alloc")]
pub mod ghs_aniso;
#[cfg(feature = "alloc")]
pub mod ghs_psd2d;
#[cfg(feature = "alloc")]
pub mod ghs_psd2d_full;
#[cfg(feature = "alloc")]
pub mod ghs_psd2d_table;
pub mod ghs_ssa;
#[cfg(feature = "alloc")]
pub mod ghs_table;
pub mod polarization;
pub mod rayleigh_rice;
#[cfg(feature = "alloc")]
pub mod two_scale;
#[cfg(feature = "alloc")]
mod two_scale_lambda;
#[cfg(feature = "alloc")]
mod two_scale_lanes;
#[cfg(feature = "alloc")]
mod two_scale_narrow;
#[cfg(feature = "alloc")]
mod two_scale_table;

pub use energy::{Energy, FresnelAngle, GhsOptions};
#[cfg(feature = "alloc")]
pub use ghs::{GhsFull, TableSource};
#[cfg(feature = "alloc")]
pub use ghs_aniso::GhsAnisotropic;
#[cfg(feature = "alloc")]
pub use ghs_psd2d::GhsSsaPsd2d;
#[cfg(feature = "alloc")]
pub use ghs_psd2d_full::GhsPsd2d;
pub use ghs_ssa::GhsSsa;
pub use polarization::{Polarization, PolarizationFactor};
pub use rayleigh_rice::RayleighRice;

use glam::DVec3;

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
    direction_from_offset(wi, r * c, r * s)
}

/// Outgoing direction whose tangential part is o⊥ = (px, py) − i⊥, (px, py)
/// the scattering vector's tangential part divided by the wavenumber. `None`
/// if evanescent.
#[inline]
pub(crate) fn direction_from_offset(wi: DVec3, px: f64, py: f64) -> Option<DVec3> {
    let ox = px - wi.x;
    let oy = py - wi.y;
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
