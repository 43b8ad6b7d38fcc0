//! The deterministic generator of synthesis and tests: brdf's SplitMix64 (one source for
//! the workspace's models and tests), with normal deviates; fixed seeds give identical
//! surfaces on every platform.

pub use brdf::numerics::splitmix::SplitMix64;

/// Standard normal deviates from a generator.
pub trait Normal {
    /// Standard normal deviate (Box–Muller).
    fn normal(&mut self) -> f64;
}

impl Normal for SplitMix64 {
    fn normal(&mut self) -> f64 {
        let (u, v) = (self.uniform(), self.uniform());
        (-2.0 * u.ln()).sqrt() * (2.0 * std::f64::consts::PI * v).cos()
    }
}
