//! The random-input ring of the per-call BRDF benches (`brdf_eval`, `ghs`):
//! 1024 pre-drawn (wi, wo, λ, u) tuples, so branch predictors and caches see
//! realistic variety while the per-iteration overhead stays ~1 ns.

use brdf::frame::spherical;
use brdf::{Bxdf, DVec3};

/// Ring length (a power of two: the index wraps with a mask).
pub const RING: usize = 1024;

/// Tiny xorshift generator: the benches must not depend on `brdf/testing`.
pub struct XorShift(pub u64);

impl XorShift {
    /// Uniform in [0, 1) with 53 bits.
    pub fn next(&mut self) -> f64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// One benchmark input.
pub struct Input {
    pub wi: DVec3,
    pub wo: DVec3,
    pub lambda: f64,
    pub u: [f64; 3],
}

/// The ring for `model`: wo is where the model itself samples (the
/// renderer's case), with `u0` replacing the lobe-choice number when given
/// (`Some(0.999_999)` keeps a mixture model on its glossy lobe); a lost
/// sample falls back to a uniform direction.
pub fn inputs(model: &dyn Bxdf, u0: Option<f64>) -> Vec<Input> {
    let mut rng = XorShift(0x9E37_79B9_7F4A_7C15);
    let mut out = Vec::with_capacity(RING);
    while out.len() < RING {
        let wi = spherical(rng.next().acos(), std::f64::consts::TAU * rng.next());
        let lambda = 360.0 + 470.0 * rng.next();
        let u = [rng.next(), rng.next(), rng.next()];
        let wo = model
            .sample(wi, lambda, [u0.unwrap_or(u[0]), u[1], u[2]])
            .map(|s| s.wo)
            .unwrap_or_else(|| spherical(rng.next().acos(), std::f64::consts::TAU * rng.next()));
        out.push(Input { wi, wo, lambda, u });
    }
    out
}
