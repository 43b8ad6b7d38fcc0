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

/// `n` standard normal deviates from `seed` as complex numbers (zero imaginary part): the
/// white noise that spectral synthesis filters by the square root of a PSD.
pub(crate) fn white_noise(n: usize, seed: u64) -> Vec<rustfft::num_complex::Complex<f64>> {
    let mut rng = SplitMix64::new(seed);
    (0..n)
        .map(|_| rustfft::num_complex::Complex::new(rng.normal(), 0.0))
        .collect()
}
