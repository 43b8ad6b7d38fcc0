//! A counter-seeded random number generator.
//!
//! Every camera sample owns a generator seeded from (scene seed, pixel,
//! sample index), so an image depends only on which samples were taken,
//! never on thread scheduling or on how sample ranges were split into shards.

use brdf::numerics::splitmix::{SplitMix64, mix};

/// SplitMix64 (Steele, Lea & Flood 2014; brdf's one implementation) seeded
/// per camera sample; passes BigCrush.
#[derive(Clone, Debug)]
pub struct Rng {
    inner: SplitMix64,
}

impl Rng {
    /// The generator of sample `sample` of pixel `pixel` under `seed`.
    #[inline]
    pub fn for_sample(seed: u64, pixel: u64, sample: u64) -> Rng {
        let a = mix(seed ^ 0x6a09_e667_f3bc_c909);
        let b = mix(a ^ pixel.wrapping_mul(0x9e37_79b9_7f4a_7c15));
        Rng {
            inner: SplitMix64::new(mix(b ^ sample.wrapping_mul(0xd1b5_4a32_d192_ed03))),
        }
    }

    /// Next 64 random bits.
    #[inline]
    pub fn next_u64(&mut self) -> u64 {
        self.inner.next_u64()
    }

    /// Uniform in [0, 1) with 53 random bits.
    #[inline]
    pub fn uniform(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
    }

    /// Three uniforms.
    #[inline]
    pub fn uniform3(&mut self) -> [f64; 3] {
        [self.uniform(), self.uniform(), self.uniform()]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn streams_differ_and_are_uniform() {
        let mut a = Rng::for_sample(1, 2, 3);
        let mut b = Rng::for_sample(1, 2, 4);
        assert_ne!(a.next_u64(), b.next_u64());
        let n = 100_000;
        let mut r = Rng::for_sample(0, 0, 0);
        let xs: Vec<f64> = (0..n).map(|_| r.uniform()).collect();
        let mean = xs.iter().sum::<f64>() / n as f64;
        let var = xs.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / n as f64;
        assert!((mean - 0.5).abs() < 0.005 && (var - 1.0 / 12.0).abs() < 0.002);
        assert!(xs.iter().all(|x| (0.0..1.0).contains(x)));
    }
}
