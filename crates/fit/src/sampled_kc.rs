//! Gaussian random maps whose values on the pixel lattice have the K-correlation covariance
//! `C(r) = σ² M(r/Lc)` of physics.md §2 (up to the period of the map): point samples of the
//! continuous surface, not its band-limited version.
//!
//! [`crate::synth::kc_surface`] filters white noise by `sqrt(P)` inside the Nyquist cell, so the
//! variance above the Nyquist frequency is missing: for γ = 1.5 and `Lc = 10 dx` that is 18 % of
//! σ², which changes `g = q²σ²` and the whole wave-optical answer. Point samples carry that
//! variance as aliases: on the lattice their spectrum is `Σ_m P(ζ + 2πm/dx)`. Here the alias sum
//! runs over `|mx|, |my| ≤ RINGS` explicitly; the mass beyond is added as a constant (white, the
//! sub-pixel nugget), the exact KC mass outside the disk with the area of the summed square.
//! The structure function on the lattice, `2(C(0) − C(r))`, which is all the field
//! `exp(−iqh)` depends on away from DC, then matches the continuous one.

use crate::Topography;
use crate::kc::KcParams;
use rustfft::FftPlanner;
use rustfft::num_complex::Complex;
use std::f64::consts::PI;

/// Alias rings summed explicitly on each side.
pub const RINGS: i32 = 4;

/// Spectral filter for point-sampled K-correlation maps; make once, realise many times.
#[derive(Debug, Clone)]
pub struct PointSampledKc {
    nx: usize,
    ny: usize,
    dx: f64,
    amp: Vec<f64>,
}

impl PointSampledKc {
    /// An `nx × ny` lattice with square pixels `dx` for the KC surface `params`.
    pub fn new(nx: usize, ny: usize, dx: f64, params: KcParams) -> PointSampledKc {
        let (zx, zy) = (2.0 * PI / dx, 2.0 * PI / dx);
        let (dzx, dzy) = (zx / nx as f64, zy / ny as f64);
        let nu = (params.gamma - 1.0) / 2.0;
        let r_eq = (2 * RINGS + 1) as f64 * zx / PI.sqrt();
        let tail = params.sigma.powi(2) * (1.0 + (params.lc * r_eq).powi(2)).powf(-nu) / (zx * zy);
        // The alias sum depends on |kx| and |ky| only.
        let (hx, hy) = (nx / 2 + 1, ny / 2 + 1);
        let mut folded = vec![0.0; hx * hy];
        for (j, row) in folded.chunks_mut(hx).enumerate() {
            let fy = j as f64 * dzy;
            for (i, v) in row.iter_mut().enumerate() {
                let fx = i as f64 * dzx;
                let mut s = tail;
                for my in -RINGS..=RINGS {
                    let y = fy + my as f64 * zy;
                    for mx in -RINGS..=RINGS {
                        let x = fx + mx as f64 * zx;
                        s += params.psd_2d((x * x + y * y).sqrt());
                    }
                }
                *v = s;
            }
        }
        let mut amp = vec![0.0; nx * ny];
        for ky in 0..ny {
            let j = ky.min(ny - ky);
            for kx in 0..nx {
                let i = kx.min(nx - kx);
                if kx == 0 && ky == 0 {
                    continue;
                }
                amp[ky * nx + kx] = (4.0 * PI * PI * folded[j * hx + i] / (dx * dx)).sqrt();
            }
        }
        PointSampledKc { nx, ny, dx, amp }
    }

    /// Lattice variance of a realisation in expectation (the DC term is zero).
    pub fn variance(&self) -> f64 {
        let n = (self.nx * self.ny) as f64;
        self.amp.iter().map(|a| a * a).sum::<f64>() / n
    }

    /// The covariance `E[h(x_j) h(0)]` of the lattice process at every lattice offset `j`
    /// (row-major, offsets modulo the map size): `(1/N) Σ_k a_k² e^{iζ_k·x_j}`.
    pub fn lattice_covariance(&self) -> Vec<f64> {
        let (nx, ny) = (self.nx, self.ny);
        let mut buf: Vec<Complex<f64>> =
            self.amp.iter().map(|a| Complex::new(a * a, 0.0)).collect();
        let mut planner = FftPlanner::<f64>::new();
        crate::fft::fft2(&mut buf, nx, ny, &mut planner, true);
        let n = (nx * ny) as f64;
        buf.iter().map(|c| c.re / n).collect()
    }

    /// The exact expectation of [`crate::field_spectrum::field_spectrum`] (rectangular window)
    /// of a realisation at phase scale `q`, bin by bin in FFT order, DC set to 0:
    /// `(dA/(2π)²) Σ_j exp(−q²(c_0 − c_j)) e^{−iζ_k·x_j}` with `c` the lattice covariance.
    pub fn expected_field_spectrum(&self, q: f64) -> Vec<f64> {
        let (nx, ny) = (self.nx, self.ny);
        let c = self.lattice_covariance();
        let mut buf: Vec<Complex<f64>> = c
            .iter()
            .map(|cj| Complex::new((-q * q * (c[0] - cj)).exp(), 0.0))
            .collect();
        let mut planner = FftPlanner::<f64>::new();
        crate::fft::fft2(&mut buf, nx, ny, &mut planner, false);
        let norm = self.dx * self.dx / (4.0 * PI * PI);
        let mut out: Vec<f64> = buf.iter().map(|v| v.re * norm).collect();
        out[0] = 0.0;
        out
    }

    /// One realisation (zero mean).
    pub fn realise(&self, seed: u64) -> Topography {
        let (nx, ny) = (self.nx, self.ny);
        let mut buf = crate::rng::white_noise(nx * ny, seed);
        let mut planner = FftPlanner::<f64>::new();
        crate::fft::fft2(&mut buf, nx, ny, &mut planner, false);
        for (b, a) in buf.iter_mut().zip(&self.amp) {
            *b *= *a;
        }
        crate::fft::fft2(&mut buf, nx, ny, &mut planner, true);
        let n = (nx * ny) as f64;
        Topography {
            nx,
            ny,
            dx: self.dx,
            dy: self.dx,
            heights: buf.iter().map(|c| c.re / n).collect(),
            channel: "synthetic point-sampled K-correlation".into(),
            format: "synthetic",
        }
    }
}
