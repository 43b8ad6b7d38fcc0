//! Spectral bands: N wavelength bands of equal width over 360–830 nm, each
//! holding the estimate of the mean spectral radiance in the band, beside
//! the film's XYZ (`--spectral N`, `[film] spectral_bands = N`).
//!
//! A camera sample's radiance estimate at wavelength λⱼ (wavelength pdf
//! and spectral MIS weight included, the value whose Σⱼ rⱼ·x̄(λⱼ) is the
//! sample's X) adds rⱼ / Δλ to the band that holds λⱼ: its expectation is
//! (1/Δλ)·∫_band L(λ) dλ, the band's mean spectral radiance, in the same
//! unit as the scene's radiance (a constant spectrum of `radiance = 1`
//! gives 1 in every band and Y = 1). The sums are in the film's 2⁻⁴⁰ fixed
//! point, like the XYZ sums, so they merge and resume exactly.
//!
//! The EXR channels are named as pbrt-v4's `SpectralFilm` names them (the
//! OpenEXR spectral layout): `S0.` and the band's centre wavelength with
//! three decimals and `,` for the decimal point (`.` separates EXR layers),
//! then `nm`: `S0.374,688nm` for the first of 16 bands. pbrt computes the
//! centre in `f32` as `(1 − t)·λmin + t·λmax`, t = (i + ½)/N, and prints it
//! with `%.3f`; [`BandLayout::channel_name`] does the same so that the names
//! agree digit for digit.

use crate::spectrum::{LAMBDA_MAX, LAMBDA_MIN};

/// Most bands a film holds.
pub const MAX_BANDS: usize = 256;

/// Most band sums (pixels × bands) of one film: 2²⁷ i128 sums, 2 GiB, e.g.
/// 1920 × 1080 with 64 bands or 800 × 600 with 256.
pub const MAX_BAND_SUMS: u64 = 1 << 27;

/// How a film divides 360–830 nm into bands.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BandLayout {
    n: usize,
    /// Bands per nm: N / (λmax − λmin).
    per_nm: f64,
    /// 1 / band width (nm⁻¹).
    inv_width_per_nm: f64,
}

impl BandLayout {
    /// `n` bands (1..=[`MAX_BANDS`]) over [360, 830] nm.
    pub fn new(n: usize) -> Result<BandLayout, String> {
        if !(1..=MAX_BANDS).contains(&n) {
            return Err(format!(
                "{n} spectral bands (expected 1..={MAX_BANDS}, or 0 for none)"
            ));
        }
        let per_nm = n as f64 / (LAMBDA_MAX - LAMBDA_MIN);
        Ok(BandLayout {
            n,
            per_nm,
            inv_width_per_nm: per_nm,
        })
    }

    /// Number of bands.
    pub fn len(&self) -> usize {
        self.n
    }

    /// Always false: a layout holds at least one band.
    pub fn is_empty(&self) -> bool {
        false
    }

    /// Width of every band, nm.
    pub fn width_nm(&self) -> f64 {
        (LAMBDA_MAX - LAMBDA_MIN) / self.n as f64
    }

    /// The bounds of band `i`, nm.
    pub fn bounds_nm(&self, i: usize) -> (f64, f64) {
        let w = self.width_nm();
        (LAMBDA_MIN + i as f64 * w, LAMBDA_MIN + (i + 1) as f64 * w)
    }

    /// The band holding `lambda_nm` (the last band holds λmax; wavelengths
    /// outside the range, which the sampler never draws, go to the nearest
    /// band, as pbrt's `LambdaToBucket` does).
    #[inline(always)]
    pub fn index(&self, lambda_nm: f64) -> usize {
        let b = ((lambda_nm - LAMBDA_MIN) * self.per_nm).max(0.0) as usize;
        b.min(self.n - 1)
    }

    /// 1 / band width, nm⁻¹: what one radiance estimate is scaled by.
    #[inline(always)]
    pub fn inv_width_per_nm(&self) -> f64 {
        self.inv_width_per_nm
    }

    /// The EXR channel name of band `i`, as pbrt-v4's `SpectralFilm` writes it.
    pub fn channel_name(&self, i: usize) -> String {
        // pbrt: Lerp((i + 0.5f) / nBuckets, lambdaMin, lambdaMax) in f32.
        let t = (i as f32 + 0.5f32) / self.n as f32;
        let centre = (1.0f32 - t) * LAMBDA_MIN as f32 + t * LAMBDA_MAX as f32;
        format!("S0.{}nm", format!("{:.3}", centre as f64).replace('.', ","))
    }
}

/// Adds one camera sample's radiance estimates to `out` (one value per
/// band, not cleared here): rⱼ/Δλ to the band of λⱼ.
#[inline]
pub(super) fn add_sample(layout: &BandLayout, lambdas: &[f64], radiance: &[f64], out: &mut [f64]) {
    let k = layout.inv_width_per_nm();
    for (&l, &r) in lambdas.iter().zip(radiance) {
        out[layout.index(l)] += r * k;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bands_cover_the_range_without_gaps() {
        for n in [1, 3, 16, 47, 256] {
            let b = BandLayout::new(n).unwrap();
            assert_eq!(b.index(LAMBDA_MIN), 0);
            assert_eq!(b.index(LAMBDA_MAX), n - 1);
            for i in 0..n {
                let (lo, hi) = b.bounds_nm(i);
                assert_eq!(b.index(lo + 1e-9), i, "n {n} band {i}");
                assert_eq!(b.index(hi - 1e-9), i, "n {n} band {i}");
            }
        }
        assert!(BandLayout::new(0).is_err());
        assert!(BandLayout::new(257).is_err());
    }
}
