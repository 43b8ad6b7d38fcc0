//! Power spectral densities.
//!
//! * [`welch`]: Welch's method along each x-line (Hann window, configurable segment length
//!   and overlap, constant detrend, one-sided density), averaged over lines. `f` in cycles/m,
//!   `p` in m³, `∫ p df ≈` variance. Matches `scipy.signal.welch(…, scaling='density')`.
//! * [`radial`]: radially averaged 2D PSD of a map in the rad convention of physics.md
//!   (`ζ` in rad/m, `P` in m⁴, `∫ P d²ζ ≈ σ²`).
//! * [`merge`]: an AFM PSD above a cutoff joined to a stylus PSD below it.
//! * [`radial_from_profile`]: a 1D PSD converted to an isotropic 2D PSD by the local
//!   power-law relation (approximate; see its docs).

use crate::ordered_sum::{map_blocks, sum_in_order};
use crate::{FitError, Topography};
use rayon::prelude::*;
use realfft::RealFftPlanner;
use realfft::num_complex::Complex;
use rustfft::FftPlanner;

/// A one-sided 1D PSD.
#[derive(Debug, Clone, PartialEq)]
pub struct Psd1d {
    /// Frequencies [cycles/m], starting at 0.
    pub f: Vec<f64>,
    /// Density [m³] (one-sided: `∫₀^{f_Nyquist} p df` = variance).
    pub p: Vec<f64>,
}

/// Welch parameters.
#[derive(Debug, Clone, Copy, Default)]
pub struct WelchOptions {
    /// Segment length (default: the whole line, `nx`).
    pub nperseg: Option<usize>,
    /// Overlap between segments (default `nperseg / 2`).
    pub noverlap: Option<usize>,
}

/// Periodic Hann window (`scipy.signal.get_window('hann', n)`).
pub fn hann(n: usize) -> Vec<f64> {
    (0..n)
        .map(|i| 0.5 - 0.5 * (2.0 * std::f64::consts::PI * i as f64 / n as f64).cos())
        .collect()
}

/// Welch PSD of every x-line, averaged over lines and segments. Needs a NaN-free map.
/// Segments may be as short as 2 points, so a tiny map still gives the PSD it holds.
pub fn welch(t: &Topography, opts: &WelchOptions) -> Result<Psd1d, FitError> {
    let nperseg = opts.nperseg.unwrap_or(t.nx);
    if nperseg < 2 || nperseg > t.nx {
        return Err(FitError::data(
            "Welch PSD",
            format!(
                "segment length {nperseg} must be between 2 and the line length {}",
                t.nx
            ),
        ));
    }
    let noverlap = opts.noverlap.unwrap_or(nperseg / 2);
    if noverlap >= nperseg {
        return Err(FitError::data(
            "Welch PSD",
            "overlap must be smaller than the segment length",
        ));
    }
    if t.heights.iter().any(|h| !h.is_finite()) {
        return Err(FitError::data(
            "Welch PSD",
            "the map has invalid points; fill them first",
        ));
    }
    let step = nperseg - noverlap;
    let nseg = (t.nx - nperseg) / step + 1;
    let win = hann(nperseg);
    let wss: f64 = win.iter().map(|w| w * w).sum();
    let nbin = nperseg / 2 + 1;
    let fft = RealFftPlanner::<f64>::new().plan_fft_forward(nperseg);
    let nx = t.nx;
    // Fixed blocks summed in order: the PSD is the same on any thread count.
    let parts = map_blocks(t.heights.len() / nx, |rows| {
        let mut acc = vec![0.0; nbin];
        let (mut inp, mut out, mut scratch) = (
            fft.make_input_vec(),
            fft.make_output_vec(),
            fft.make_scratch_vec(),
        );
        for y in rows {
            let line = &t.heights[y * nx..(y + 1) * nx];
            for s in 0..nseg {
                let seg = &line[s * step..s * step + nperseg];
                let mean = seg.iter().sum::<f64>() / nperseg as f64;
                for ((i, &v), w) in inp.iter_mut().zip(seg).zip(&win) {
                    *i = (v - mean) * w;
                }
                // Lengths match by construction, so this cannot fail.
                if fft
                    .process_with_scratch(&mut inp, &mut out, &mut scratch)
                    .is_ok()
                {
                    for (a, c) in acc.iter_mut().zip(&out) {
                        *a += c.norm_sqr();
                    }
                }
            }
        }
        acc
    });
    let sum = sum_in_order(parts, nbin);
    let scale = t.dx / wss / (nseg * t.ny) as f64;
    let last_doubled = if nperseg.is_multiple_of(2) {
        nbin - 1
    } else {
        nbin
    };
    let p = sum
        .iter()
        .enumerate()
        .map(|(k, s)| s * scale * if k > 0 && k < last_doubled { 2.0 } else { 1.0 })
        .collect();
    let f = (0..nbin)
        .map(|k| k as f64 / (nperseg as f64 * t.dx))
        .collect();
    Ok(Psd1d { f, p })
}

/// A radially averaged isotropic 2D PSD, rad convention.
#[derive(Debug, Clone, PartialEq)]
pub struct RadialPsdTable {
    /// Bin-mean radial frequency ζ [rad/m].
    pub zeta: Vec<f64>,
    /// Mean PSD in the bin [m⁴]; `∫ P d²ζ = σ²`.
    pub p: Vec<f64>,
    /// Number of periodogram samples averaged in the bin (fit weights); empty when the
    /// table was not made from a 2D periodogram.
    pub count: Vec<f64>,
}

/// Radially averaged 2D PSD of a NaN-free map (separable Hann window, power-normalised).
/// Bins have the width of the coarser frequency step; the DC bin is dropped and the last
/// bin ends at the Nyquist frequency of the coarser axis.
pub fn radial(t: &Topography) -> Result<RadialPsdTable, FitError> {
    if t.is_profile() || t.nx < 8 || t.ny < 8 {
        return Err(FitError::data(
            "radial PSD",
            "needs a map of at least 8 × 8 points",
        ));
    }
    if t.heights.iter().any(|h| !h.is_finite()) {
        return Err(FitError::data(
            "radial PSD",
            "the map has invalid points; fill them first",
        ));
    }
    let (nx, ny) = (t.nx, t.ny);
    let (wx, wy) = (hann(nx), hann(ny));
    let mean = t.heights.iter().sum::<f64>() / (nx * ny) as f64;
    let w2 = wx.iter().map(|w| w * w).sum::<f64>() / nx as f64
        * wy.iter().map(|w| w * w).sum::<f64>()
        / ny as f64;
    let ncol = nx / 2 + 1;
    let rfft = RealFftPlanner::<f64>::new().plan_fft_forward(nx);
    // Row transforms, stored column-major for the column pass.
    let rows: Vec<Vec<Complex<f64>>> = (0..ny)
        .into_par_iter()
        .map(|y| {
            let mut inp: Vec<f64> = t
                .line(y)
                .iter()
                .zip(&wx)
                .map(|(h, w)| (h - mean) * w * wy[y])
                .collect();
            let mut out = rfft.make_output_vec();
            let _ = rfft.process(&mut inp, &mut out);
            out
        })
        .collect();
    let cfft = FftPlanner::<f64>::new().plan_fft_forward(ny);
    let dkx = 1.0 / (nx as f64 * t.dx);
    let dky = 1.0 / (ny as f64 * t.dy);
    let dz = 2.0 * std::f64::consts::PI * dkx.max(dky);
    let zmax = std::f64::consts::PI / t.dx.max(t.dy);
    let nbins = (zmax / dz).floor() as usize + 1;
    let norm = t.dx * t.dy / ((nx * ny) as f64 * w2) / (4.0 * std::f64::consts::PI.powi(2));
    // Fixed blocks of columns summed in order: the same on any thread count.
    // Each block's sums are laid out as [Σz | Σp | Σw], nbins each.
    let parts = map_blocks(ncol, |cols| {
        let mut acc = vec![0.0; 3 * nbins];
        let (sz, rest) = acc.split_at_mut(nbins);
        let (sp, sw) = rest.split_at_mut(nbins);
        for kx in cols {
            let mut col: Vec<Complex<f64>> = rows.iter().map(|r| r[kx]).collect();
            cfft.process(&mut col);
            let weight = if kx == 0 || (nx.is_multiple_of(2) && kx == nx / 2) {
                1.0
            } else {
                2.0
            };
            let fx = kx as f64 * dkx;
            for (ky, c) in col.iter().enumerate() {
                let kys = crate::fft::signed(ky, ny);
                let z = 2.0 * std::f64::consts::PI * (fx * fx + (kys * dky).powi(2)).sqrt();
                let b = (z / dz).round() as usize;
                if b == 0 || b >= nbins || z > zmax {
                    continue;
                }
                sz[b] += weight * z;
                sp[b] += weight * c.norm_sqr() * norm;
                sw[b] += weight;
            }
        }
        acc
    });
    let sums = sum_in_order(parts, 3 * nbins);
    let (sz, rest) = sums.split_at(nbins);
    let (sp, sw) = rest.split_at(nbins);
    let mut out = RadialPsdTable {
        zeta: Vec::new(),
        p: Vec::new(),
        count: Vec::new(),
    };
    for i in 0..nbins {
        if sw[i] > 0.0 {
            out.zeta.push(sz[i] / sw[i]);
            out.p.push(sp[i] / sw[i]);
            out.count.push(sw[i]);
        }
    }
    Ok(out)
}

/// Join two 1D PSDs at `f_cut` [cycles/m]: `low` (e.g. a stylus profile) below the cutoff,
/// `high` (e.g. AFM) at and above it. The DC bins are dropped.
pub fn merge(low: &Psd1d, high: &Psd1d, f_cut: f64) -> Psd1d {
    let mut out = Psd1d {
        f: Vec::new(),
        p: Vec::new(),
    };
    for (&f, &p) in low.f.iter().zip(&low.p) {
        if f > 0.0 && f < f_cut {
            out.f.push(f);
            out.p.push(p);
        }
    }
    for (&f, &p) in high.f.iter().zip(&high.p) {
        if f > 0.0 && f >= f_cut {
            out.f.push(f);
            out.p.push(p);
        }
    }
    out
}

/// Convert a one-sided 1D PSD (cycles, m³) to an isotropic 2D PSD (rad, m⁴) with the
/// local power-law relation `C2(f) = P1(f)·Γ((a+1)/2) / (2√π Γ(a/2) f)`, where
/// `a = −d ln P1/d ln f` is estimated over ±`half_window` bins and clamped to [0.5, 10].
/// Exact for a power law; near a PSD roll-off (small `a`) it is only indicative.
pub fn radial_from_profile(psd: &Psd1d, half_window: usize) -> RadialPsdTable {
    let pts: Vec<(f64, f64)> = psd
        .f
        .iter()
        .zip(&psd.p)
        .filter(|(f, p)| **f > 0.0 && **p > 0.0)
        .map(|(f, p)| (f.ln(), p.ln()))
        .collect();
    let mut out = RadialPsdTable {
        zeta: Vec::new(),
        p: Vec::new(),
        count: Vec::new(),
    };
    for i in 0..pts.len() {
        let lo = i.saturating_sub(half_window.max(1));
        let hi = (i + half_window.max(1)).min(pts.len() - 1);
        let w = &pts[lo..=hi];
        let mx = w.iter().map(|p| p.0).sum::<f64>() / w.len() as f64;
        let my = w.iter().map(|p| p.1).sum::<f64>() / w.len() as f64;
        let sxx: f64 = w.iter().map(|p| (p.0 - mx).powi(2)).sum();
        let sxy: f64 = w.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
        let a = if sxx > 0.0 {
            (-sxy / sxx).clamp(0.5, 10.0)
        } else {
            0.5
        };
        let (lf, lp) = pts[i];
        let f = lf.exp();
        let ratio = (libm::lgamma((a + 1.0) / 2.0) - libm::lgamma(a / 2.0)).exp()
            / (2.0 * std::f64::consts::PI.sqrt() * f);
        out.zeta.push(2.0 * std::f64::consts::PI * f);
        out.p
            .push(lp.exp() * ratio / (4.0 * std::f64::consts::PI.powi(2)));
    }
    out
}
