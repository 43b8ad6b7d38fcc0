//! Numerical building blocks of the models, with no physics of their own
//! beyond the kernels they transform: Hankel transforms of the GHS kernel
//! ([`hankel`]), Gauss–Legendre quadrature ([`quadrature`]), special
//! functions ([`special`]), Poisson weights of the diffraction orders
//! ([`poisson`]), sample warps ([`warp`]); crate-internal: K₀/K₁ Bessel functions, interpolation
//! weights and the `no_std` math shims.

// `!(x > 0.0)` is used on purpose throughout: it rejects NaN together with
// the out-of-range values, which `x <= 0.0` would let through.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

pub(crate) mod bessel01;
#[cfg(feature = "alloc")]
pub(crate) mod fft;
#[cfg(feature = "alloc")]
pub(crate) mod fft2;
pub mod hankel;
#[cfg(feature = "alloc")]
pub mod interp;
pub(crate) mod math;
pub mod poisson;
pub mod quadrature;
pub mod special;
#[doc(hidden)]
pub mod splitmix;
pub mod warp;
