//! ISO 25178-2 height parameters, the areal autocorrelation function and its correlation
//! length, and the height histogram, of a levelled (NaN-free) map or profile.
//!
//! Conventions (checked against SurfaceTopography 1.27.1 in
//! `data/surfaces/reference/statistics.json`, see its script for the same definitions):
//! - heights are taken about their mean (the mean plane of the levelled map);
//! - `Sa = ⟨|z|⟩`, `Sz = max z − min z` (ISO's maximum height, peak plus pit),
//!   `Ssk = ⟨z³⟩/Sq³`, `Sku = ⟨z⁴⟩/Sq⁴` (so 3 for Gaussian heights);
//! - the ACF is SurfaceTopography's non-periodic estimator, the height-difference
//!   function `A(k, l) = ½⟨[z(i + k, j + l) − z(i, j)]²⟩` over the `(nx − k)(ny − |l|)`
//!   overlapping pairs, normalised as `ρ = 1 − A/Sq²` (1 at zero lag), but over lags
//!   `k ≥ 0` and `l` of either sign (every direction once): SurfaceTopography keeps only
//!   `k, l ≥ 0`, which makes its radial average of an anisotropic scan depend on the image
//!   orientation (its value on the Park sample example_ps.tiff is 5 % off this one);
//! - it is averaged radially in bins one pixel (`min(dx, dy)`) wide, bin `b` holding the
//!   lags with `round(r / min(dx, dy)) = b`, out to half the shorter side of the scan;
//! - the correlation length is where that radial ρ first falls to 0.2 (ISO 25178-2's
//!   threshold for Sal), interpolated linearly between bins. Sal itself takes the fastest
//!   decaying direction; this is the direction average, which an isotropic model uses.

use crate::Topography;
use crate::fft::fft2;
use rustfft::FftPlanner;
use rustfft::num_complex::Complex;

/// The ACF threshold of the correlation length (ISO 25178-2's default for Sal).
pub const ACF_THRESHOLD: f64 = 0.2;

/// ISO 25178-2 height parameters (Ra, Rz, Rsk, Rku for a profile).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HeightParams {
    /// Arithmetic mean height ⟨|z|⟩ [m].
    pub sa: f64,
    /// Maximum height, highest peak to lowest pit [m].
    pub sz: f64,
    /// Skewness ⟨z³⟩/Sq³ (0 for symmetric heights).
    pub ssk: f64,
    /// Kurtosis ⟨z⁴⟩/Sq⁴ (3 for Gaussian heights).
    pub sku: f64,
}

/// The height parameters of a map or profile (NaN points skipped). Ssk and Sku are NaN
/// for constant heights.
pub fn height_params(t: &Topography) -> HeightParams {
    let v: Vec<f64> = t
        .heights
        .iter()
        .copied()
        .filter(|h| h.is_finite())
        .collect();
    let n = v.len().max(1) as f64;
    let mean = v.iter().sum::<f64>() / n;
    let (mut a, mut m2, mut m3, mut m4) = (0.0, 0.0, 0.0, 0.0);
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for &h in &v {
        let z = h - mean;
        let z2 = z * z;
        a += z.abs();
        m2 += z2;
        m3 += z2 * z;
        m4 += z2 * z2;
        lo = lo.min(z);
        hi = hi.max(z);
    }
    let sq = (m2 / n).sqrt();
    HeightParams {
        sa: a / n,
        sz: if v.is_empty() { f64::NAN } else { hi - lo },
        ssk: (m3 / n) / sq.powi(3),
        sku: (m4 / n) / sq.powi(4),
    }
}

/// The radially averaged normalised ACF.
#[derive(Debug, Clone, PartialEq)]
pub struct Acf {
    /// Lag distance of each bin [m] (`b · min(dx, dy)`).
    pub r: Vec<f64>,
    /// Mean normalised ACF `1 − A/Sq²` in each bin (bins without lags are left out).
    pub rho: Vec<f64>,
}

impl Acf {
    /// Where ρ first falls to `threshold`, interpolated linearly; `None` when it stays
    /// above it out to half the scan (the correlation is longer than the scan resolves).
    pub fn length(&self, threshold: f64) -> Option<f64> {
        let i = self.rho.iter().position(|&v| v <= threshold)?;
        if i == 0 {
            return Some(0.0);
        }
        let (r0, v0, r1, v1) = (self.r[i - 1], self.rho[i - 1], self.r[i], self.rho[i]);
        Some(r0 + (v0 - threshold) / (v0 - v1) * (r1 - r0))
    }
}

/// Largest padded FFT grid of [`acf`] (points; 16 bytes each, 1 GiB): a 6000 × 6000
/// scan. Larger maps get no ACF rather than several GiB of scratch memory.
pub const MAX_ACF_POINTS: u64 = 1 << 26;

/// The ACF of a levelled, NaN-free map or profile (see the module docs); `None` for
/// constant heights and maps above [`MAX_ACF_POINTS`] once padded.
pub fn acf(t: &Topography) -> Option<Acf> {
    let (nx, ny) = (t.nx, t.ny);
    let n = nx * ny;
    if n < 2 || t.heights.len() != n || t.heights.iter().any(|h| !h.is_finite()) {
        return None;
    }
    let mean = t.heights.iter().sum::<f64>() / n as f64;
    let z: Vec<f64> = t.heights.iter().map(|h| h - mean).collect();
    let sq2 = z.iter().map(|v| v * v).sum::<f64>() / n as f64;
    if sq2 <= 0.0 || !sq2.is_finite() {
        return None;
    }
    // Σ z(i, j) z(i + k, j + l) by a zero-padded FFT: lags reach half the scan, so half
    // a side of zeros keeps the circular correlation from wrapping onto them.
    let (px, py) = (nx + nx / 2 + 1, if ny == 1 { 1 } else { ny + ny / 2 + 1 });
    if (px * py) as u64 > MAX_ACF_POINTS {
        return None;
    }
    let mut buf = vec![Complex::new(0.0, 0.0); px * py];
    for y in 0..ny {
        for x in 0..nx {
            buf[y * px + x].re = z[y * nx + x];
        }
    }
    let mut planner = FftPlanner::new();
    fft2(&mut buf, px, py, &mut planner, false);
    for c in &mut buf {
        *c = Complex::new(c.norm_sqr(), 0.0);
    }
    fft2(&mut buf, px, py, &mut planner, true);
    let scale = 1.0 / (px * py) as f64;
    // Prefix sums of z² for the two squared terms over each overlap.
    let mut pre = vec![0.0; (nx + 1) * (ny + 1)];
    for y in 0..ny {
        for x in 0..nx {
            pre[(y + 1) * (nx + 1) + x + 1] =
                z[y * nx + x].powi(2) + pre[y * (nx + 1) + x + 1] + pre[(y + 1) * (nx + 1) + x]
                    - pre[y * (nx + 1) + x];
        }
    }
    let rect = |x0: usize, y0: usize, x1: usize, y1: usize| {
        pre[y1 * (nx + 1) + x1] - pre[y0 * (nx + 1) + x1] - pre[y1 * (nx + 1) + x0]
            + pre[y0 * (nx + 1) + x0]
    };
    let step = if ny == 1 { t.dx } else { t.dx.min(t.dy) };
    let rmax = if ny == 1 {
        nx as f64 * t.dx / 2.0
    } else {
        (nx as f64 * t.dx).min(ny as f64 * t.dy) / 2.0
    };
    let nb = (rmax / step).round() as usize + 1;
    let (mut sum, mut count) = (vec![0.0; nb], vec![0usize; nb]);
    let ly = ny as i64 - 1;
    for l in -ly..=ly {
        let la = l.unsigned_abs() as usize;
        for k in 0..nx {
            let r = ((k as f64 * t.dx).powi(2) + (la as f64 * t.dy).powi(2)).sqrt();
            if r > rmax {
                continue;
            }
            let pairs = ((nx - k) * (ny - la)) as f64;
            let c = buf[l.rem_euclid(py as i64) as usize * px + k].re * scale / pairs;
            let (s1, s2) = if l >= 0 {
                (rect(0, 0, nx - k, ny - la), rect(k, la, nx, ny))
            } else {
                (rect(0, la, nx - k, ny), rect(k, 0, nx, ny - la))
            };
            let (s1, s2) = (s1 / pairs, s2 / pairs);
            let a = 0.5 * (s1 + s2) - c;
            let b = (r / step).round() as usize;
            if b < nb {
                sum[b] += 1.0 - a / sq2;
                count[b] += 1;
            }
        }
    }
    let (r, rho) = (0..nb)
        .filter(|&b| count[b] > 0)
        .map(|b| (b as f64 * step, sum[b] / count[b] as f64))
        .unzip();
    Some(Acf { r, rho })
}

/// A histogram of heights about their mean.
#[derive(Debug, Clone, PartialEq)]
pub struct Histogram {
    /// Bin edges [m] (one more than the bins), from min to max height.
    pub edges: Vec<f64>,
    /// Points per bin.
    pub counts: Vec<usize>,
    /// Probability density per bin [1/m] (integrates to 1).
    pub density: Vec<f64>,
}

/// The histogram of heights about their mean in `bins` equal bins from the lowest to the
/// highest (NaN points skipped); `None` without two distinct heights.
pub fn histogram(t: &Topography, bins: usize) -> Option<Histogram> {
    let v: Vec<f64> = t
        .heights
        .iter()
        .copied()
        .filter(|h| h.is_finite())
        .collect();
    if v.len() < 2 || bins == 0 {
        return None;
    }
    let mean = v.iter().sum::<f64>() / v.len() as f64;
    let (lo, hi) = v
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), h| {
            (a.min(h - mean), b.max(h - mean))
        });
    let w = (hi - lo) / bins as f64;
    if !(w > 0.0 && w.is_finite()) {
        return None;
    }
    let mut counts = vec![0usize; bins];
    for h in &v {
        let b = (((h - mean - lo) / w) as usize).min(bins - 1);
        counts[b] += 1;
    }
    let total = v.len() as f64;
    Some(Histogram {
        edges: (0..=bins).map(|i| lo + i as f64 * w).collect(),
        density: counts.iter().map(|&c| c as f64 / (total * w)).collect(),
        counts,
    })
}
