//! Sampling wavelengths in proportion to the eye's sensitivity.
//!
//! The pdf is piecewise constant, proportional to x̄ + ȳ + z̄ on a fine grid
//! over the scene's emission range. With this choice the colour weights
//! x̄/p, ȳ/p, z̄/p stay bounded, so no wavelength can produce a firefly by
//! itself; and since λ is drawn per path, wavelength-dependent models (GHS,
//! whose roughness exponent g ∝ 1/λ²) see the full continuum.

use crate::spectrum::Cie;

/// Hero-wavelength count (Wilkie et al. 2014).
pub const HERO_COUNT: usize = 4;

/// A piecewise-constant wavelength distribution over `[lo, hi]` nm.
#[derive(Clone, Debug)]
pub struct WavelengthSampler {
    lo: f64,
    hi: f64,
    bin: f64,
    cdf: Vec<f64>,
    density: Vec<f64>,
}

impl WavelengthSampler {
    /// Builds the distribution over `[lo, hi]` ⊂ [360, 830] nm.
    pub fn new(lo: f64, hi: f64) -> WavelengthSampler {
        let cie = Cie::get();
        let n = ((hi - lo).ceil() as usize).clamp(64, 1024);
        let bin = (hi - lo) / n as f64;
        // Midpoint weight; a small floor keeps the pdf positive where the CMFs vanish.
        let weights: Vec<f64> = (0..n)
            .map(|i| {
                let c = cie.xyz(lo + (i as f64 + 0.5) * bin);
                c[0] + c[1] + c[2] + 1e-4
            })
            .collect();
        let total: f64 = weights.iter().sum();
        let mut cdf = Vec::with_capacity(n + 1);
        let mut acc = 0.0;
        cdf.push(0.0);
        for w in &weights {
            acc += w / total;
            cdf.push(acc);
        }
        cdf[n] = 1.0;
        let density = weights.iter().map(|w| w / (total * bin)).collect();
        WavelengthSampler {
            lo,
            hi,
            bin,
            cdf,
            density,
        }
    }

    /// The sampled interval in nm.
    pub fn range(&self) -> (f64, f64) {
        (self.lo, self.hi)
    }

    /// Draws λ from a uniform `u` ∈ [0, 1).
    pub fn sample(&self, u: f64) -> f64 {
        let i = (self.cdf.partition_point(|&c| c <= u) - 1).min(self.density.len() - 1);
        let span = self.cdf[i + 1] - self.cdf[i];
        let t = if span > 0.0 {
            ((u - self.cdf[i]) / span).clamp(0.0, 1.0)
        } else {
            0.5
        };
        (self.lo + (i as f64 + t) * self.bin).min(self.hi)
    }

    /// Density (per nm) of `lambda`.
    #[inline]
    pub fn pdf(&self, lambda: f64) -> f64 {
        if !(self.lo..=self.hi).contains(&lambda) {
            return 0.0;
        }
        let i = (((lambda - self.lo) / self.bin) as usize).min(self.density.len() - 1);
        self.density[i]
    }

    /// The hero set: `lambda0` and its rotations by multiples of
    /// (hi − lo)/count, wrapped into the range.
    pub fn rotations(&self, lambda0: f64, count: usize) -> [f64; HERO_COUNT] {
        let mut out = [lambda0; HERO_COUNT];
        let width = self.hi - self.lo;
        for (j, o) in out.iter_mut().enumerate().take(count).skip(1) {
            let x = lambda0 - self.lo + j as f64 * width / count as f64;
            *o = self.lo + x.rem_euclid(width);
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pdf_integrates_to_one_and_sampling_follows_it() {
        for &(lo, hi) in &[(360.0, 830.0), (520.0, 540.0)] {
            let s = WavelengthSampler::new(lo, hi);
            let n = 200_000;
            let integral: f64 = (0..n)
                .map(|i| s.pdf(lo + (i as f64 + 0.5) * (hi - lo) / n as f64))
                .sum::<f64>()
                * (hi - lo)
                / n as f64;
            assert!((integral - 1.0).abs() < 1e-6, "{integral}");
            // E[ȳ(λ)/p(λ)] = ∫ȳ dλ over the range (the ratio is bounded by construction).
            let cie = Cie::get();
            let m = 100_000;
            let mean: f64 = (0..m)
                .map(|i| {
                    let l = s.sample((i as f64 + 0.5) / m as f64);
                    cie.xyz(l)[1] / s.pdf(l)
                })
                .sum::<f64>()
                / m as f64;
            let exact: f64 = (0..200_000)
                .map(|i| cie.xyz(lo + (i as f64 + 0.5) * (hi - lo) / 2e5)[1])
                .sum::<f64>()
                * (hi - lo)
                / 2e5;
            assert!((mean / exact - 1.0).abs() < 1e-4, "{mean} vs {exact}");
        }
    }

    #[test]
    fn rotations_stay_in_range_and_are_evenly_spaced() {
        let s = WavelengthSampler::new(360.0, 830.0);
        let r = s.rotations(800.0, 4);
        assert_eq!(r[0], 800.0);
        assert!((r[1] - (800.0 + 117.5 - 470.0)).abs() < 1e-9);
        assert!(r.iter().all(|l| (360.0..830.0).contains(l)));
    }
}
