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
    /// `guide[k]` = number of CDF entries ≤ k/guide.len(): the start of the
    /// search for `u` in cell k (see [`WavelengthSampler::sample`]).
    guide: Vec<u32>,
}

/// Guide cells per wavelength bin: the densest bin (x̄+ȳ+z̄ near 445 nm) holds
/// ≈ 3× the mean probability, so with 4 cells per bin a cell spans at most
/// about one CDF step and the search walks one or two entries.
const GUIDE_CELLS_PER_BIN: usize = 4;

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
        let cells = n * GUIDE_CELLS_PER_BIN;
        let guide = (0..cells)
            .map(|k| {
                let u = k as f64 / cells as f64;
                cdf.partition_point(|&c| c <= u) as u32
            })
            .collect();
        WavelengthSampler {
            lo,
            hi,
            bin,
            cdf,
            density,
            guide,
        }
    }

    /// The sampled interval in nm.
    pub fn range(&self) -> (f64, f64) {
        (self.lo, self.hi)
    }

    /// Draws λ from a uniform `u` ∈ [0, 1).
    pub fn sample(&self, u: f64) -> f64 {
        let i = (self.cdf_count_le(u) - 1).min(self.density.len() - 1);
        let span = self.cdf[i + 1] - self.cdf[i];
        let t = if span > 0.0 {
            ((u - self.cdf[i]) / span).clamp(0.0, 1.0)
        } else {
            0.5
        };
        (self.lo + (i as f64 + t) * self.bin).min(self.hi)
    }

    /// The number of CDF entries ≤ `u` (`partition_point(|c| c <= u)`),
    /// started from the guide's cell and walked to the exact answer, so the
    /// result does not depend on how `u · cells` rounds.
    #[inline]
    fn cdf_count_le(&self, u: f64) -> usize {
        let cdf = &self.cdf[..];
        let cell = ((u * self.guide.len() as f64) as usize).min(self.guide.len() - 1);
        let mut p = self.guide[cell] as usize;
        while p < cdf.len() && cdf[p] <= u {
            p += 1;
        }
        while p > 0 && cdf[p - 1] > u {
            p -= 1;
        }
        p
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
            // For λ₀ in [lo, hi], x is in [0, 2·width): one conditional
            // subtraction, exact there (Sterbenz: width ≤ x < 2·width) and so
            // equal to `rem_euclid`, which is a libm `fmod` call.
            let wrapped = if x >= 0.0 && x < width {
                x
            } else if x >= width && x < 2.0 * width {
                x - width
            } else {
                x.rem_euclid(width)
            };
            *o = self.lo + wrapped;
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

    #[test]
    fn guided_sampling_and_wrap_match_the_reference_bit_for_bit() {
        use crate::rng::Rng;
        let mut rng = Rng::for_sample(3, 1, 2);
        for &(lo, hi) in &[(360.0, 830.0), (520.0, 540.0), (400.0, 401.5)] {
            let s = WavelengthSampler::new(lo, hi);
            let mut us: Vec<f64> = s
                .cdf
                .iter()
                .flat_map(|&c| [c, c.next_up(), c.next_down()])
                .filter(|u| (0.0..1.0).contains(u))
                .collect();
            us.extend((0..50_000).map(|_| rng.uniform()));
            us.extend([0.0, 1.0f64.next_down()]);
            for u in us {
                let want_i = (s.cdf.partition_point(|&c| c <= u) - 1).min(s.density.len() - 1);
                assert_eq!(
                    (s.cdf_count_le(u) - 1).min(s.density.len() - 1),
                    want_i,
                    "u = {u}"
                );
                let l0 = s.sample(u);
                let width = hi - lo;
                let got = s.rotations(l0, HERO_COUNT);
                for (j, g) in got.iter().enumerate().skip(1) {
                    let x = l0 - lo + j as f64 * width / HERO_COUNT as f64;
                    let want = lo + x.rem_euclid(width);
                    assert_eq!(g.to_bits(), want.to_bits(), "λ₀ = {l0}, j = {j}");
                }
            }
        }
    }
}
