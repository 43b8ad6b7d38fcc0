//! Wave-optical reflection from rough surfaces: the K-correlation PSD and the
//! generalized Harvey–Shack (GHS) models of `docs/physics.md` §2–5, 9–11.

pub mod kc;

pub use kc::KcPsd;
