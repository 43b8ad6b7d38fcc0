//! Two-scale split of a surface at a cutoff period Λ (a multiple of the wavelength):
//! the large scale is the ISO 16610-61 Gaussian low-pass (50 % transmission at 1/Λ) and is
//! described by the exponential slope distribution (β); the residual is described by a
//! K-correlation fit to its PSD above 1/Λ.
//!
//! When the map is shorter than 2Λ the large scale cannot be low-passed from the map;
//! β then comes from the slope variance in the (possibly stylus-merged) line PSD below
//! 1/Λ, `⟨|∇h|²⟩ = 2∫₀^{1/Λ}(2πf)² P1 df = 6β²` (isotropy assumed), and KC is fitted to
//! that PSD above 1/Λ.

use crate::fft::{fft2, signed};
use crate::kc::{self, KcFit};
use crate::psd::{self, Psd1d, WelchOptions};
use crate::{FitError, Topography, ndf};
use rustfft::FftPlanner;
use rustfft::num_complex::Complex;

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

/// One two-scale split.
#[derive(Debug, Clone, PartialEq)]
pub struct TwoScale {
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
) -> Result<TwoScale, FitError> {
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
        let large = gaussian_lowpass(t, cutoff);
        let (sx, sy) = ndf::slopes(&large);
        let beta = if t.is_profile() {
            // Isotropy: E|∇h|² = 2 E[sx²] and E|∇h|² = 6β² for the exponential NDF.
            (2.0 * sx.iter().map(|s| s * s).sum::<f64>() / sx.len().max(1) as f64 / 6.0).sqrt()
        } else {
            ndf::exponential_beta(&sx, &sy)
        };
        let mut residual = t.clone();
        for (r, l) in residual.heights.iter_mut().zip(&large.heights) {
            *r -= l;
        }
        residual_psd = psd::welch(&residual, &WelchOptions::default())?;
        (beta, BetaSource::Map, &residual_psd)
    } else {
        let (beta, source) = line_psd_beta(line_psd, f_cut);
        (beta, source, line_psd)
    };
    let kc = kc::fit(
        kc::Form::Profile1d,
        &kc_psd.f,
        &kc_psd.p,
        f_cut.max(f_min),
        f_max,
    )?;
    Ok(TwoScale {
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
pub fn gaussian_lowpass(t: &Topography, cutoff: f64) -> Topography {
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
