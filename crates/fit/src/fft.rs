//! The FFT helpers of fit: the in-place transform of a map (rows in parallel, columns
//! through a transpose) or profile, and the signed frequency index of a bin.

use rustfft::num_complex::Complex;
use rustfft::{Fft, FftPlanner};
use std::sync::Arc;

/// Signed index of FFT bin `k` of `n`: k for k ≤ n/2, k − n above (the frequency in
/// units of the bin width).
pub(crate) fn signed(k: usize, n: usize) -> f64 {
    if k <= n / 2 {
        k as f64
    } else {
        k as f64 - n as f64
    }
}

/// The forward or inverse plan of length `n`.
fn plan(planner: &mut FftPlanner<f64>, n: usize, inverse: bool) -> Arc<dyn Fft<f64>> {
    if inverse {
        planner.plan_fft_inverse(n)
    } else {
        planner.plan_fft_forward(n)
    }
}

/// In-place complex FFT (unnormalised) of a row-major `ny × nx` map: 2D, or 1D for a
/// profile (`ny == 1`, the same numbers as 2D with its length-1 column transforms).
pub(crate) fn fft2(
    buf: &mut [Complex<f64>],
    nx: usize,
    ny: usize,
    planner: &mut FftPlanner<f64>,
    inverse: bool,
) {
    use rayon::prelude::*;
    if ny == 1 {
        plan(planner, nx, inverse).process(buf);
        return;
    }
    let row = plan(planner, nx, inverse);
    buf.par_chunks_mut(nx).for_each(|r| row.process(r));
    let col = plan(planner, ny, inverse);
    let mut t = transpose(buf, nx, ny);
    t.par_chunks_mut(ny).for_each(|c| col.process(c));
    let back = transpose(&t, ny, nx);
    buf.copy_from_slice(&back);
}

fn transpose(a: &[Complex<f64>], nx: usize, ny: usize) -> Vec<Complex<f64>> {
    let mut t = vec![Complex::new(0.0, 0.0); nx * ny];
    for y in 0..ny {
        for x in 0..nx {
            t[x * ny + y] = a[y * nx + x];
        }
    }
    t
}
