//! # brdf — spectral BRDFs of rough metals, from microfacets to wave optics
//!
//! A `no_std` crate (optional `alloc`) that evaluates, samples and gives the
//! pdf of reflection models for rough conductors, one wavelength at a time:
//!
//! * microfacet conductors: GGX (Trowbridge–Reitz) and Beckmann, isotropic and
//!   anisotropic, height-correlated Smith shadowing, visible-normal sampling;
//! * exact unpolarised conductor Fresnel with measured n + ik spectra;
//! * for the scene around a sample: a Lambertian reflector ([`Diffuse`]) and a
//!   rough dielectric coat over one ([`RoughPlastic`]).
//! * wave-optical models ([`wave`]: GHS, two-scale) driven by surface statistics
//!   ([`statistics`]: K-correlation and tabulated PSDs, the exponential NDF), on
//!   the transforms and quadratures of [`numerics`].
//!
//! Every model implements [`Bxdf`]. Directions live in the local shading
//! frame (normal = +z) and point *away* from the surface; wavelengths are in
//! nanometres; BRDF values are in sr⁻¹ (solid-angle measure). A model may
//! combine a specular delta lobe (returned by [`Bxdf::specular`]) with a
//! glossy lobe ([`Bxdf::eval`], [`Bxdf::pdf`]); [`Bxdf::sample`] draws from
//! both and flags delta samples.
//!
//! Conventions and formulas follow `docs/physics.md` in the repository.
#![no_std]
#![deny(missing_docs)]

#[cfg(feature = "alloc")]
extern crate alloc;
#[cfg(feature = "std")]
extern crate std;

pub use glam::DVec3;

pub mod diffuse;
mod error;
pub mod frame;
pub mod fresnel;
pub mod ior;
mod ior_data;
pub mod microfacet;
mod model;
pub mod numerics;
#[cfg(feature = "alloc")]
pub mod paper;
#[cfg(feature = "alloc")]
mod parallel;
pub mod roughplastic;
#[cfg(feature = "alloc")]
pub mod spec;
pub mod statistics;
#[cfg(feature = "testing")]
pub mod testing;
pub mod wave;

#[cfg(feature = "alloc")]
pub use diffuse::ReflectanceTable;
pub use diffuse::{Diffuse, Reflectance};
pub use error::BrdfError;
pub use fresnel::Fresnel;
pub use ior::{Ior, Metal};
pub use microfacet::{Distribution, MicrofacetConductor, NdfKind, SmoothConductor};
pub use model::{Bxdf, BxdfSample, Kept, Specular, WAVELENGTH_MAX_NM, WAVELENGTH_MIN_NM};
pub use roughplastic::{RoughPlastic, RoughPlasticParams};

/// Used by the `nostd-check` crate so that the linker keeps a whole model
/// evaluation path. Evaluates a copper GGX (α = 0.2) BRDF in the plane of
/// incidence; not part of the stable API.
#[doc(hidden)]
pub fn nostd_smoke(cos_i: f64, cos_o: f64, lambda_nm: f64) -> f64 {
    let Ok(dist) = microfacet::Distribution::ggx(0.2, 0.2) else {
        return 0.0;
    };
    let Ok(model) =
        microfacet::MicrofacetConductor::new(dist, Fresnel::conductor(Ior::metal(Metal::Cu)))
    else {
        return 0.0;
    };
    let wi = frame::spherical(libm::acos(cos_i.clamp(-1.0, 1.0)), 0.0);
    let wo = frame::spherical(libm::acos(cos_o.clamp(-1.0, 1.0)), core::f64::consts::PI);
    model.eval(wi, wo, lambda_nm)
}
