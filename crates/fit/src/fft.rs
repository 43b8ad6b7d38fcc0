//! The FFT helpers of fit: the in-place 2D transform (rows in parallel, columns through a
//! transpose), the 1D-or-2D transform of a map or profile, and the signed frequency index
//! of a bin.

use rustfft::FftPlanner;
use rustfft::num_complex::Complex;

/// Signed index of FFT bin `k` of `n`: k for k ≤ n/2, k − n above (the frequency in
/// units of the bin width).
pub(crate) fn signed(k: usize, n: usize) -> f64 {
    if k <= n / 2 {
        k as f64
    } else {
        k as f64 - n as f64
    }
}

/// In-place 2D complex FFT (unnormalised), row-major `ny × nx`.
pub(crate) fn fft2(
    buf: &mut [Complex<f64>],
    nx: usize,
    ny: usize,
    planner: &mut FftPlanner<f64>,
    inverse: bool,
) {
    use rayon::prelude::*;
    let row = if inverse {
        planner.plan_fft_inverse(nx)
    } else {
        planner.plan_fft_forward(nx)
    };
    buf.par_chunks_mut(nx).for_each(|r| row.process(r));
    let col = if inverse {
        planner.plan_fft_inverse(ny)
    } else {
        planner.plan_fft_forward(ny)
    };
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

/// In-place FFT of a row-major `ny × nx` map, or of a profile (`ny == 1`) by a 1D
/// transform (unnormalised).
pub(crate) fn fft_map(
    buf: &mut [Complex<f64>],
    nx: usize,
    ny: usize,
    planner: &mut FftPlanner<f64>,
    inverse: bool,
) {
    if ny == 1 {
        let p = if inverse {
            planner.plan_fft_inverse(nx)
        } else {
            planner.plan_fft_forward(nx)
        };
        p.process(buf);
    } else {
        fft2(buf, nx, ny, planner, inverse);
    }
}
