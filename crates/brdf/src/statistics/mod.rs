//! Surface statistics the wave-optical models are driven by: the
//! K-correlation PSD ([`KcPsd`], with its validated domain) and its Matérn
//! correlation ([`matern`]), its anisotropic stretch ([`AnisotropicKc`]) and the stretch of any radial
//! law ([`EllipticalPsd`]), a measured, tabulated PSD ([`TabulatedPsd`],
//! feature `alloc`) and a measured 2-D one ([`TabulatedPsd2d`]), and the exponential NDF of the two-scale model's macro
//! surface ([`epd`]). [`RadialPsd`] is what the GHS models need of a PSD,
//! [`Correlation`](crate::numerics::hankel::Correlation) what the Hankel
//! transforms need of its covariance.

// `!(x > 0.0)` is used on purpose throughout: it rejects NaN together with
// the out-of-range values, which `x <= 0.0` would let through.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

pub mod anisotropic;
pub mod elliptical;
pub mod epd;
pub mod kc;
pub mod matern;
#[cfg(feature = "alloc")]
pub mod measured_psd;
#[cfg(feature = "alloc")]
pub mod psd2d;

pub use anisotropic::AnisotropicKc;
pub use elliptical::{EllipticalPsd, StretchedPsd};
pub use kc::KcPsd;
#[cfg(feature = "alloc")]
pub use measured_psd::TabulatedPsd;
#[cfg(feature = "alloc")]
pub use psd2d::TabulatedPsd2d;

/// An isotropic surface height PSD as the GHS models use it: in the
/// dimensionless frequency u = L·ζ (ζ in rad/µm) with a length L of the
/// surface's choosing (Lc for [`KcPsd`]). `Sync`, because the energy
/// tables of a model over it are built on several threads.
pub trait RadialPsd: Sync {
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
