//! Spectral synthesis of periodic random surfaces with a prescribed K-correlation PSD:
//! white Gaussian noise is filtered in Fourier space by `sqrt(PSD)`, so the expected
//! periodogram equals the target PSD at every resolved frequency.

use crate::Topography;
use crate::fft::{fft2, signed};
use crate::kc::KcParams;
use rustfft::FftPlanner;
use std::f64::consts::PI;

/// An `nx × ny` map with pixel `dx` (square pixels) whose 2D PSD is the K-correlation
/// `params` (physics.md form). The DC term is zero.
pub fn kc_surface(nx: usize, ny: usize, dx: f64, params: KcParams, seed: u64) -> Topography {
    let mut buf = crate::rng::white_noise(nx * ny, seed);
    let mut planner = FftPlanner::<f64>::new();
    fft2(&mut buf, nx, ny, &mut planner, false);
    let (dfx, dfy) = (1.0 / (nx as f64 * dx), 1.0 / (ny as f64 * dx));
    for ky in 0..ny {
        let fy = signed(ky, ny) * dfy;
        for kx in 0..nx {
            let fx = signed(kx, nx) * dfx;
            let f = (fx * fx + fy * fy).sqrt();
            let psd_cyc = 4.0 * PI * PI * params.psd_2d(2.0 * PI * f);
            let a = if kx == 0 && ky == 0 {
                0.0
            } else {
                (psd_cyc / (dx * dx)).sqrt()
            };
            buf[ky * nx + kx] *= a;
        }
    }
    fft2(&mut buf, nx, ny, &mut planner, true);
    let n = (nx * ny) as f64;
    Topography {
        nx,
        ny,
        dx,
        dy: dx,
        heights: buf.iter().map(|c| c.re / n).collect(),
        channel: "synthetic".into(),
        format: "synthetic",
    }
}

/// A profile of `n` points whose one-sided PSD is the 1D K-correlation form.
pub fn kc_profile(n: usize, dx: f64, params: KcParams, seed: u64) -> Topography {
    let mut buf = crate::rng::white_noise(n, seed);
    let mut planner = FftPlanner::<f64>::new();
    planner.plan_fft_forward(n).process(&mut buf);
    for (k, c) in buf.iter_mut().enumerate() {
        let f = signed(k, n).abs() / (n as f64 * dx);
        *c *= if k == 0 {
            0.0
        } else {
            (params.psd_1d(f) / (2.0 * dx)).sqrt()
        };
    }
    planner.plan_fft_inverse(n).process(&mut buf);
    Topography {
        nx: n,
        ny: 1,
        dx,
        dy: dx,
        heights: buf.iter().map(|c| c.re / n as f64).collect(),
        channel: "synthetic".into(),
        format: "synthetic",
    }
}
