//! Wave-optical reflection from rough surfaces: the K-correlation PSD and the
//! generalized Harvey–Shack (GHS) models of `docs/physics.md` §2–5, 9–11.

pub mod kc;
pub mod matern;
pub mod poisson;
pub mod special;

pub use kc::KcPsd;
