//! Test harnesses shared by every model's tests (feature `testing`).
//!
//! * [`chi2`]: chi-square goodness-of-fit of [`crate::Bxdf::sample`] against
//!   [`crate::Bxdf::pdf`] and [`crate::Bxdf::specular`], with adaptive
//!   binning, pooling, and accounting for delta and lost samples.
//! * [`furnace`]: directional albedo by the model's own sampling and by
//!   deterministic adaptive cubature of `eval`.
//! * [`Pcg32`]: a dependency-free deterministic generator;
//!   [`gamma`]: the regularised incomplete gamma function behind p-values;
//!   [`quadrature`]: the adaptive 2-D cubature both harnesses use.
//!
//! Everything is `no_std` + `alloc` and deterministic for a fixed seed.

pub mod chi2;
mod domain;
pub mod furnace;
pub mod gamma;
pub mod quadrature;
mod rng;

pub use chi2::{Chi2Config, Chi2Report, chi2_test};
pub use furnace::{QuadratureAlbedo, SampledAlbedo, albedo_quadrature, albedo_sampled};
pub use gamma::{chi2_survival, sidak};
pub use rng::Pcg32;

#[cfg(test)]
mod self_test;
