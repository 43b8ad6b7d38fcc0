//! The FFT helpers of fit: the in-place transform of a map (rows in parallel, columns in
//! gathered blocks) or profile, and the signed frequency index of a bin.

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
    for_each_column(buf, nx, ny, || (), |_, c| col.process(c));
}

/// Columns gathered per block by [`for_each_column`]: wide enough to read whole cache lines
/// of each row, narrow enough that the block stays a small fraction of a large map.
const COLUMN_BLOCK: usize = 64;

/// Run `f` on every column of a row-major `ny × nx` buffer, as a contiguous slice, with a
/// per-thread state from `init`. Columns are copied out and back in blocks: a full
/// transpose would need two more copies of the map, which is what made the two-scale
/// low-pass of an 8192² scan run out of memory.
pub(crate) fn for_each_column<T, S>(
    buf: &mut [T],
    nx: usize,
    ny: usize,
    init: impl Fn() -> S + Sync + Send,
    f: impl Fn(&mut S, &mut [T]) + Sync + Send,
) where
    T: Copy + Default + Send + Sync,
{
    use rayon::prelude::*;
    if nx == 0 || ny == 0 {
        return;
    }
    let width = COLUMN_BLOCK.min(nx);
    let mut block = vec![T::default(); width * ny];
    for x0 in (0..nx).step_by(width) {
        let w = width.min(nx - x0);
        let cols = &mut block[..w * ny];
        for y in 0..ny {
            for (j, v) in buf[y * nx + x0..y * nx + x0 + w].iter().enumerate() {
                cols[j * ny + y] = *v;
            }
        }
        cols.par_chunks_mut(ny).for_each_init(&init, &f);
        for y in 0..ny {
            for (j, v) in buf[y * nx + x0..y * nx + x0 + w].iter_mut().enumerate() {
                *v = cols[j * ny + y];
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn blocked_column_pass_gives_the_2d_dft() {
        // Wider than one column block, so a partial last block is exercised.
        let (nx, ny) = (COLUMN_BLOCK + 7, 5);
        let a: Vec<Complex<f64>> = (0..nx * ny)
            .map(|i| Complex::new((i as f64 * 0.37).sin(), (i as f64 * 0.11).cos()))
            .collect();
        let mut buf = a.clone();
        fft2(&mut buf, nx, ny, &mut FftPlanner::new(), false);
        let tau = 2.0 * std::f64::consts::PI;
        for (ky, kx) in [(0, 0), (1, 3), (4, COLUMN_BLOCK), (2, nx - 1)] {
            let mut want = Complex::new(0.0, 0.0);
            for y in 0..ny {
                for x in 0..nx {
                    let ph = -tau * (kx * x) as f64 / nx as f64 - tau * (ky * y) as f64 / ny as f64;
                    want += a[y * nx + x] * Complex::from_polar(1.0, ph);
                }
            }
            assert!((buf[ky * nx + kx] - want).norm() < 1e-9, "bin ({kx}, {ky})");
        }
    }
}
