//! Two-scale split of a surface at a cutoff period Λ (a multiple of the wavelength):
//! the large scale is the ISO 16610-61 Gaussian low-pass (50 % transmission at 1/Λ) and is
//! described by the exponential slope distribution (β); the residual is described by a
//! K-correlation fit to its PSD above 1/Λ.
//!
//! When the map is shorter than 2Λ the large scale cannot be low-passed from the map;
//! β then comes from the slope variance in the (possibly stylus-merged) line PSD below
//! 1/Λ, `⟨|∇h|²⟩ = 2∫₀^{1/Λ}(2πf)² P1 df = 6β²` (isotropy assumed), and KC is fitted to
//! that PSD above 1/Λ.

use crate::fft::{for_each_column, signed};
use crate::kc::{self, KcFit};
use crate::psd::{self, Psd1d, WelchOptions};
use crate::{FitError, Topography, ndf};
use realfft::{ComplexToReal, RealFftPlanner, RealToComplex};
use rustfft::num_complex::Complex;
use std::sync::Arc;

/// Where β came from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BetaSource {
    /// Maximum likelihood on the low-passed map's slopes.
    Map,
    /// Slope variance of the line PSD below the cutoff.
    Psd,
    /// Neither the map nor the PSD reaches the cutoff period: β is not measured.
    Unresolved,
}

/// A surface split at one cutoff period into a large scale (its slope distribution, β) and
/// the residual roughness (its K-correlation fit): the parameters of the two-scale model.
#[derive(Debug, Clone, PartialEq)]
pub struct Split {
    /// Cutoff as a multiple of the wavelength.
    pub multiple: f64,
    /// Cutoff period Λ [m].
    pub cutoff: f64,
    /// Exponential-NDF β of the large scale (0 when unresolved).
    pub beta: f64,
    /// Origin of β.
    pub beta_source: BetaSource,
    /// K-correlation fit to the residual PSD above 1/Λ (1D form).
    pub kc: KcFit,
}

/// Split `t` (levelled, NaN-free) at `multiple × wavelength`. `line_psd` is the PSD used
/// when the map cannot resolve the cutoff (e.g. a stylus-merged PSD); every KC fit uses
/// frequencies in `[max(1/Λ, f_min), f_max]` [cycles/m] (the lowest Welch bins are biased by
/// the window, hence `f_min`).
pub fn split(
    t: &Topography,
    line_psd: &Psd1d,
    multiple: f64,
    wavelength: f64,
    (f_min, f_max): (f64, f64),
) -> Result<Split, FitError> {
    let cutoff = multiple * wavelength;
    if !(cutoff.is_finite() && cutoff > 0.0) {
        return Err(FitError::data(
            "two-scale split",
            format!("cutoff {cutoff} m is not positive"),
        ));
    }
    let f_cut = 1.0 / cutoff;
    let fits_map = t.size_x() >= 2.0 * cutoff && (t.is_profile() || t.size_y() >= 2.0 * cutoff);
    // Only the map branch computes a PSD of its own; it must outlive the branch.
    let residual_psd;
    let (beta, beta_source, kc_psd) = if fits_map {
        let mut large = gaussian_lowpass(t, cutoff);
        // The slopes (two map-sized arrays) are freed before the residual is made.
        let beta = {
            let (sx, sy) = ndf::slopes(&large);
            if t.is_profile() {
                // Isotropy: E|∇h|² = 2 E[sx²] and E|∇h|² = 6β² for the exponential NDF.
                (2.0 * sx.iter().map(|s| s * s).sum::<f64>() / sx.len().max(1) as f64 / 6.0).sqrt()
            } else {
                ndf::exponential_beta(&sx, &sy)
            }
        };
        // The residual reuses the low-pass buffer rather than a third copy of the map.
        for (l, h) in large.heights.iter_mut().zip(&t.heights) {
            *l = h - *l;
        }
        let residual = large;
        residual_psd = psd::welch(&residual, &WelchOptions::default())?;
        (beta, BetaSource::Map, &residual_psd)
    } else {
        let (beta, source) = line_psd_beta(line_psd, f_cut);
        (beta, source, line_psd)
    };
    let kc = kc::fit(
        kc::PsdForm::Profile1d,
        &kc_psd.f,
        &kc_psd.p,
        f_cut.max(f_min),
        f_max,
    )?;
    Ok(Split {
        multiple,
        cutoff,
        beta,
        beta_source,
        kc,
    })
}

/// β from the slope variance of the line PSD below `f_cut`; unresolved when fewer than
/// three bins lie there.
fn line_psd_beta(line_psd: &Psd1d, f_cut: f64) -> (f64, BetaSource) {
    let below: Vec<(f64, f64)> = line_psd
        .f
        .iter()
        .zip(&line_psd.p)
        .filter(|(f, p)| **f > 0.0 && **f < f_cut && p.is_finite())
        .map(|(f, p)| (*f, *p))
        .collect();
    if below.len() < 3 {
        return (0.0, BetaSource::Unresolved);
    }
    // Trapezoid over the bins, starting from f = 0 with the first bin's value.
    let mut var_x = 0.0;
    let mut prev = (0.0, 0.0);
    for &(f, p) in &below {
        let g = (2.0 * std::f64::consts::PI * f).powi(2) * p;
        var_x += 0.5 * (g + prev.1) * (f - prev.0);
        prev = (f, g);
    }
    ((2.0 * var_x / 6.0).sqrt(), BetaSource::Psd)
}

/// ISO 16610-61 Gaussian low-pass with cutoff period `cutoff` [m], applied by FFT to the
/// mirror-extended map (so the map edges do not wrap around).
///
/// Both the Gaussian transfer function and the mirror extension factor into x and y, so
/// the 2D filter of the `2nx × 2ny` extension is the same as filtering each mirrored row
/// and then each mirrored column: this needs one real copy of the map instead of four
/// complex ones (plus two transposes), which an 8192² scan cannot afford.
pub fn gaussian_lowpass(t: &Topography, cutoff: f64) -> Topography {
    use rayon::prelude::*;
    let alpha2 = 2f64.ln() / std::f64::consts::PI;
    let k = std::f64::consts::PI * alpha2 * cutoff * cutoff;
    let mut out = t.clone();
    if t.nx == 0 || t.ny == 0 {
        return out;
    }
    let mut planner = RealFftPlanner::<f64>::new();
    let rows = MirrorLowpass::new(&mut planner, t.nx, t.dx, k);
    out.heights
        .par_chunks_mut(t.nx)
        .for_each_init(|| rows.scratch(), |s, line| rows.apply(s, line));
    if t.ny > 1 {
        let cols = MirrorLowpass::new(&mut planner, t.ny, t.dy, k);
        for_each_column(
            &mut out.heights,
            t.nx,
            t.ny,
            || cols.scratch(),
            |s, line| cols.apply(s, line),
        );
    }
    out
}

/// The 1D Gaussian low-pass of a line of `n` points mirror-extended to `2n`.
struct MirrorLowpass {
    forward: Arc<dyn RealToComplex<f64>>,
    inverse: Arc<dyn ComplexToReal<f64>>,
    /// Transfer function on the `n + 1` non-negative frequency bins.
    gain: Vec<f64>,
}

/// Per-thread buffers of [`MirrorLowpass::apply`].
struct LineScratch {
    line: Vec<f64>,
    spectrum: Vec<Complex<f64>>,
    work: Vec<Complex<f64>>,
}

impl MirrorLowpass {
    fn new(planner: &mut RealFftPlanner<f64>, n: usize, d: f64, k: f64) -> Self {
        let m = 2 * n;
        let gain = (0..=n)
            .map(|j| {
                let f = signed(j, m) / (m as f64 * d);
                (-k * f * f).exp()
            })
            .collect();
        MirrorLowpass {
            forward: planner.plan_fft_forward(m),
            inverse: planner.plan_fft_inverse(m),
            gain,
        }
    }

    fn scratch(&self) -> LineScratch {
        let a = self.forward.get_scratch_len();
        let b = self.inverse.get_scratch_len();
        LineScratch {
            line: self.forward.make_input_vec(),
            spectrum: self.forward.make_output_vec(),
            work: vec![Complex::new(0.0, 0.0); a.max(b)],
        }
    }

    fn apply(&self, s: &mut LineScratch, heights: &mut [f64]) {
        let n = heights.len();
        let m = 2 * n;
        s.line[..n].copy_from_slice(heights);
        for (i, h) in heights.iter().enumerate() {
            s.line[m - 1 - i] = *h;
        }
        let nf = self.forward.get_scratch_len();
        // Lengths come from the same plans, so these cannot fail.
        let _ = self
            .forward
            .process_with_scratch(&mut s.line, &mut s.spectrum, &mut s.work[..nf]);
        for (c, g) in s.spectrum.iter_mut().zip(&self.gain) {
            *c *= *g;
        }
        // The complex transform kept only the real part of its inverse; a real inverse
        // must be told that DC and Nyquist have no imaginary part (round-off only).
        s.spectrum[0].im = 0.0;
        s.spectrum[n].im = 0.0;
        let ni = self.inverse.get_scratch_len();
        let _ = self
            .inverse
            .process_with_scratch(&mut s.spectrum, &mut s.line, &mut s.work[..ni]);
        for (h, v) in heights.iter_mut().zip(&s.line) {
            *h = v / m as f64;
        }
    }
}

/// `t` as a complex `(buffer, mx, my)` for an FFT: mirror-extended to `2nx × 2ny` (`2nx × 1`
/// for a profile) when `mirror`, so a non-periodic map has no edge jump; as it is otherwise.
pub(crate) fn extended(t: &Topography, mirror: bool) -> (Vec<Complex<f64>>, usize, usize) {
    let (nx, ny) = (t.nx, t.ny);
    let f = if mirror { 2 } else { 1 };
    let (mx, my) = (f * nx, if ny > 1 { f * ny } else { 1 });
    let mut buf = vec![Complex::new(0.0, 0.0); mx * my];
    for y in 0..my {
        let sy = if y < ny { y } else { my - 1 - y };
        for x in 0..mx {
            let sx = if x < nx { x } else { mx - 1 - x };
            buf[y * mx + x] = Complex::new(t.heights[sy * nx + sx], 0.0);
        }
    }
    (buf, mx, my)
}

/// The `nx × ny` block of an unnormalised inverse FFT of an [`extended`] buffer, as a copy
/// of `t` with those heights.
pub(crate) fn first_block(
    t: &Topography,
    buf: &[Complex<f64>],
    mx: usize,
    my: usize,
) -> Topography {
    let n = (mx * my) as f64;
    let mut out = t.clone();
    for y in 0..t.ny {
        for x in 0..t.nx {
            out.heights[y * t.nx + x] = buf[y * mx + x].re / n;
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fft::fft2;
    use crate::rng::{Normal, SplitMix64};
    use rustfft::FftPlanner;

    /// The low-pass by its definition, the reference for the separable one: one complex
    /// 2D FFT of the whole mirrored map.
    fn lowpass_2d_fft(t: &Topography, cutoff: f64) -> Topography {
        let (mut buf, mx, my) = extended(t, true);
        let mut planner = FftPlanner::<f64>::new();
        fft2(&mut buf, mx, my, &mut planner, false);
        let alpha2 = 2f64.ln() / std::f64::consts::PI;
        let k = std::f64::consts::PI * alpha2 * cutoff * cutoff;
        for ky in 0..my {
            let fy = signed(ky, my) / (my as f64 * t.dy);
            for kx in 0..mx {
                let fx = signed(kx, mx) / (mx as f64 * t.dx);
                buf[ky * mx + kx] *= (-k * (fx * fx + fy * fy)).exp();
            }
        }
        fft2(&mut buf, mx, my, &mut planner, true);
        first_block(t, &buf, mx, my)
    }

    fn noisy(nx: usize, ny: usize, dx: f64, dy: f64) -> Topography {
        let mut rng = SplitMix64::new(7);
        Topography {
            nx,
            ny,
            dx,
            dy,
            // A tilt as well as noise, so the mirror extension matters.
            heights: (0..nx * ny)
                .map(|i| 1e-7 * rng.normal() + 3e-9 * (i % nx) as f64)
                .collect(),
            channel: "test".into(),
            format: "test",
        }
    }

    #[test]
    fn separable_lowpass_equals_the_2d_fft_of_the_mirrored_map() {
        // Odd sizes, a profile, and widths either side of the column block.
        for (nx, ny) in [(97, 1), (70, 33), (64, 65), (130, 129), (5, 3)] {
            let t = noisy(nx, ny, 1e-8, 1.3e-8);
            for cutoff in [2e-8, 2e-7, 5e-6] {
                let want = lowpass_2d_fft(&t, cutoff);
                let got = gaussian_lowpass(&t, cutoff);
                let scale = want.heights.iter().fold(0.0f64, |m, v| m.max(v.abs()));
                let err = want
                    .heights
                    .iter()
                    .zip(&got.heights)
                    .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
                assert!(
                    err <= 1e-12 * scale,
                    "{nx}×{ny} cutoff {cutoff}: max difference {err:e} of {scale:e}"
                );
                assert_eq!((got.nx, got.ny), (nx, ny));
            }
        }
    }
}
